"""Speed of the approach search and of the grasp quality (Release build of the extension).

    python bench/bench_search.py [--repeat 5] [--threads 2] [--approaches 26]

1. hugger.search of K approaches on `curvy` (20,480 triangles), planning and ranking included,
   wall time on ``--threads`` threads: median and minimum over ``--repeat`` runs (target: <= 1.5 s
   for 26 approaches on 2 threads).
2. Grasp quality (force closure + epsilon) of every candidate's final grasp: the compiled cutting-
   plane epsilon (volume=False) against the full hull (volume=True), per grasp, median and max.
Inputs (objects, hands) are made before any clock starts.
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time

import numpy as np

import hugger
from hugger import analysis


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=5, help="timed runs of the search (default 5)")
    ap.add_argument("--threads", type=int, default=2, help="threads of the search (default 2)")
    ap.add_argument("--approaches", type=int, default=26, help="approaches searched (default 26)")
    args = ap.parse_args(argv)
    if args.repeat < 1 or args.threads < 1 or args.approaches < 1:
        ap.error(f"--repeat, --threads and --approaches must be at least 1, got {args.repeat}, {args.threads} "
                 f"and {args.approaches}")
    hand = hugger.Hand()
    case = hugger.scenarios.default_case("curvy", hand)
    pole = case.palm_pose[:3, 3] - case.target
    hugger.search(hand, case.obj, case.target, approaches=2, threads=1, pole=pole)  # warm up
    times = []
    result = None
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        result = hugger.search(hand, case.obj, case.target, approaches=args.approaches, threads=args.threads,
                               pole=pole, keep_all=True)
        times.append(time.perf_counter() - t0)
    plan = sorted(c.plan_time_s for c in result.candidates)
    print(f"search of {args.approaches} approaches on curvy ({len(case.obj.faces)} triangles), {args.threads} threads: "
          f"median {statistics.median(times):.3f} s, min {min(times):.3f} s over {args.repeat} runs; "
          f"per plan median {1000 * statistics.median(plan):.1f} ms; judged {sum(c.firmness is not None for c in result.candidates)}")
    torque_scale = float(np.linalg.norm(case.obj.vertices - case.target, axis=1).max())
    fast, full = [], []
    for traj in result.trajectories:
        found = analysis.contacts(traj, obj=case.obj)
        for volume, bucket in ((False, fast), (True, full)):
            t0 = time.perf_counter()
            q = analysis.grasp_quality(found, case.target, torque_scale=torque_scale, volume=volume)
            bucket.append(time.perf_counter() - t0)
        _ = q
    print(f"grasp quality over {len(fast)} grasps: epsilon by cutting planes median {1000 * statistics.median(fast):.2f} ms "
          f"(max {1000 * max(fast):.2f}); full hull with volume median {1000 * statistics.median(full):.1f} ms "
          f"(max {1000 * max(full):.1f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
