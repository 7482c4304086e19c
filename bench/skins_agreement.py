"""Analytic skins against the mesh world: plan each random case twice, with the analytic skin and on a
fine mesh of the same shape, and compare (status; links in contact within +-2; final palm within 1 mm);
run the independent checker on both plans against the mesh (every other configuration; the motion
check on every other step).

    .venv/bin/python bench/skins_agreement.py [--cases 34] [--json out.json]
"""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import numpy as np  # noqa: E402

import hugger  # noqa: E402
from hugger._files import write_atomic  # noqa: E402
from helpers import CHECKER, load_checker  # noqa: E402
from test_skins import _agreement  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=34, help="random cases per shape (default 34)")
    ap.add_argument("--json", help="write the per-case results here")
    ap.add_argument("--kinds", nargs="+", default=["sphere", "box", "spheres"], help="shapes (default all three)")
    ap.add_argument("--first-seed", type=int, default=100, help="seed of the first case (default 100)")
    args = ap.parse_args()
    if not CHECKER.exists():
        print("the checker (../shared/tools/check_trajectory.py) is missing", file=sys.stderr)
        return 2
    checker = load_checker()
    hand = hugger.Hand()  # the paper's hand (tests/conftest.py's)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for kind in args.kinds:
            for seed in range(args.first_seed, args.first_seed + args.cases):
                r = _agreement(hand, checker, Path(tmp), seed, kind)
                r.update(kind=kind, seed=seed)
                rows.append(r)
                print(json.dumps({k: r[k] for k in ("kind", "seed", "agree", "mesh_unstable", "status", "links", "palm", "ok",
                                                    "motion_ok")}), flush=True)
                for who, fails in zip(("skin", "mesh"), r["failures"]):
                    for f in fails:
                        print(f"  {who} plan: {f[:160]}", flush=True)
    print("| shape | cases | agree | disagree, two meshes disagree too | skin plan passes checker (less motion / all) "
          "| mesh plan passes checker (less motion / all) |")
    print("|---|---|---|---|---|---|")
    for kind in args.kinds:
        k = [r for r in rows if r["kind"] == kind]
        print(f"| {kind} | {len(k)} | {sum(r['agree'] for r in k)} | {sum(r['mesh_unstable'] for r in k)} | "
              f"{sum(r['ok'][0] for r in k)} / {sum(r['motion_ok'][0] for r in k)} | "
              f"{sum(r['ok'][1] for r in k)} / {sum(r['motion_ok'][1] for r in k)} |")
    if args.json:
        write_atomic(args.json, json.dumps(rows, default=str))
    return 0


if __name__ == "__main__":
    sys.exit(main())
