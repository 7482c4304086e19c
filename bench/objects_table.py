"""The README's per-object table: `hugger plan OBJECT` with default options on every built-in
object and every mesh in ../shared/data/objects/, with both rule sets (`--rules paper` and the
default `--rules hug`), each plan checked by the independent checker (motion check included).

    python bench/objects_table.py [--out bench/results/objects.md] [--check] [--rules paper,hug]

Columns: triangles, rules, status, configurations, links in contact (of 25) and palm contact (gap
<= 1 mm), Ferrari-Canny epsilon (mu 0.5, torques about T over the object's radius), the whole
plan time (object loading excluded; planner construction, i.e. setup, included) and, with
--check, the checker's verdict.
"""
from __future__ import annotations

import argparse
import contextlib
import io
import sys
import tempfile
import time
from pathlib import Path

import hugger
from hugger import analysis, scenarios
from hugger._files import write_atomic
from hugger.planner import RULES

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_args import comma_names  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from helpers import SHARED, checker_unavailable, load_checker  # noqa: E402


def checker_verdict(path: Path) -> str:
    mod = load_checker()
    with contextlib.redirect_stdout(io.StringIO()):
        return "pass" if mod.main([str(path)]) == 0 else "FAIL"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, help="also write the markdown table here")
    ap.add_argument("--check", action="store_true", help="run ../shared/tools/check_trajectory.py on every plan")
    ap.add_argument("--rules", type=comma_names(RULES, "rule sets"), default="paper,hug",
                    help=f"comma-separated rule sets, of {', '.join(RULES)} (default paper,hug)")
    args = ap.parse_args(argv)
    if args.check and (reason := checker_unavailable()):
        print(f"note: {reason}", file=sys.stderr)
        args.check = False
    rule_sets = args.rules
    specs = list(hugger.objects.names())
    meshes = sorted((SHARED / "data" / "objects").glob("*.obj"))
    if not meshes:
        print("note: ../shared/data/objects is absent; built-in objects only", file=sys.stderr)
    specs += [str(p) for p in meshes]
    hand = hugger.Hand()
    rows = ["| object | triangles | rules | status | configurations | links in contact | palm | ε | plan (ms) |"
            + (" checker |" if args.check else ""),
            "|---|---:|---|---|---:|---:|---|---:|---:|" + ("---|" if args.check else "")]
    print("\n".join(rows), flush=True)  # stdout carries the whole table, as --out does
    passed = 0
    for spec in specs:
        case = scenarios.default_case(spec, hand)
        for rules in rule_sets:
            t0 = time.perf_counter()
            traj = hugger.Planner(hand, case.obj, case.target, case.palm_pose, rules=rules).plan()
            ms = 1000 * (time.perf_counter() - t0)
            a = analysis.analyze(traj, obj=case.obj, volume=False)  # the volume is not printed
            row = (f"| {Path(case.name).stem} | {len(case.obj.faces)} | {rules} | {traj.status} | {len(traj)} | "
                   f"{a['links_in_contact']}/{a['links']} | {'yes' if a['palm_contact'] else 'no'} | "
                   f"{a['epsilon']:.3f} | {ms:.1f} |")
            if args.check:
                with tempfile.TemporaryDirectory() as d:
                    path = Path(d) / "plan.npz"
                    traj.save(path)
                    verdict = checker_verdict(path)
                    passed += verdict == "pass"
                    row += f" {verdict} |"
            rows.append(row)
            print(row, flush=True)
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        write_atomic(args.out, "\n".join(rows) + "\n")
    plans = len(specs) * len(rule_sets)
    print(f"{len(specs)} objects, rules {','.join(rule_sets)}: {plans} plans"
          + (f", {passed} of {plans} pass the checker" if args.check else ""), file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
