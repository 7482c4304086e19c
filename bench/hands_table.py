"""docs/hands.md's table: every hand preset and the test suite's opposed-thumb URDF hand on every
built-in object, with both rule sets, each plan run through every check of the independent
checker (structure, kinematics with limits, algorithm, collision and motion) less its rest = 0
rule for hands with non-zero rest angles (the checker does not read rest_angles; see
docs/hands.md).

    python bench/hands_table.py [--out hands.md] [--rules paper,hug] [--hands NAME,...]

Columns: hand, object, rules, status, configurations, links in contact and palm contact (gap
<= 1 mm), Ferrari-Canny epsilon (mu 0.5), the checker's verdict and, when it fails, its failing
checks (the first message of each kind, shortened).
"""
from __future__ import annotations

import argparse
import importlib.util
import sys
import tempfile
from pathlib import Path

import numpy as np

import hugger
from hugger import analysis, hands, objects, scenarios
from hugger._files import write_atomic
from hugger.planner import RULES

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT / "bench"))
import helpers  # noqa: E402
from bench_args import comma_names  # noqa: E402


def _test_hands():
    spec = importlib.util.spec_from_file_location("test_hands", ROOT / "tests" / "test_hands.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _short(failure: str) -> str:
    check, _, msg = failure.partition(": ")
    head = msg.split(":")[0] if check == "motion" else msg[:60]
    return f"{check}: {head}"


#: The test suite's opposed-thumb URDF hand: its row name, and the name --hands knows it by.
THUMB, THUMB_OPTION = "thumb URDF", "thumb_urdf"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=None, help="also write the markdown table and its summary here")
    ap.add_argument("--rules", type=comma_names(RULES, "rule sets"), default="paper,hug",
                    help=f"comma-separated rule sets, of {', '.join(RULES)} (default paper,hug)")
    ap.add_argument("--hands", type=comma_names([*hands.PRESETS, THUMB_OPTION], "hands"), default=None,
                    help=f"comma-separated hands, of {', '.join([*hands.PRESETS, THUMB_OPTION])} (default all)")
    args = ap.parse_args(argv)
    rule_sets = args.rules
    keep = None if args.hands is None else set(args.hands)
    th = _test_hands()
    checker = helpers.load_checker()
    tmp = Path(tempfile.mkdtemp())
    hand_list = [(n, hands.preset(n)) for n in hands.PRESETS]
    hand_list.append((THUMB, hugger.Hand.from_urdf(
        th.thumb_urdf(tmp / "thumb.urdf"), fixed_joints={f"{p}_spread": 0.0 for p in ("f0", "f1", "f2", "thumb")})))
    if keep is not None:
        hand_list = [(n, h) for n, h in hand_list if n.replace(" ", "_").lower() in keep]
    rows = ["| hand | object | rules | status | configurations | links in contact | palm | ε | checker |",
            "|---|---|---|---|---:|---:|---|---:|---|"]
    print("\n".join(rows), flush=True)
    tally: dict[str, list[int]] = {}
    for name, hand in hand_list:
        rest_nonzero = bool(np.any(hand.rest_angles != 0))
        for obj_name in objects.BUILTINS:
            case = scenarios.default_case(obj_name, hand)
            for rules in rule_sets:
                traj = hugger.Planner(hand, case.obj, case.target, case.palm_pose, rules=rules).plan()
                a = analysis.analyze(traj)
                fails, _ = th.full_check(checker, traj, tmp / "p.npz", rest_nonzero)
                kinds = sorted({_short(f) for f in fails})
                verdict = "pass" if not fails else "FAIL (" + "; ".join(kinds) + ")"
                t = tally.setdefault(rules, [0, 0])
                t[0] += not fails
                t[1] += 1
                row = (f"| {name} | {obj_name} | {rules} | {traj.status} | {len(traj)} | "
                       f"{a['links_in_contact']}/{a['links']} | {'yes' if a['palm_contact'] else 'no'} | "
                       f"{a['epsilon']:.3f} | {verdict} |")
                rows.append(row)
                print(row, flush=True)
    summary = ", ".join(f"{r}: {p} of {n} pass" for r, (p, n) in tally.items())
    print(summary)
    if args.out:
        write_atomic(args.out, "\n".join(rows) + "\n\n" + summary + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
