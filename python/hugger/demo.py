"""A short end-to-end example: plan one grasp of a built-in object and print its summary.

    python -m hugger.demo [--out DIR]
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

import hugger


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="demo-out", help="folder for plan.npz and summary.json (default demo-out)")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    hand = hugger.Hand(fingers=5, links=5, link_length=0.02, link_radius=0.004, palm_radius=0.03,
                       palm_thickness=0.01)
    obj = hugger.objects.blob(radius=0.04, amplitude=0.25, seed=3, subdivisions=5)
    target = obj.centroid
    # Start 20 cm away, turned 60 degrees from T, so that Phase 1 has work to do.
    start = hugger.look_at(target + [0.0, 0.0, 0.2], target)
    c, s = np.cos(np.radians(60)), np.sin(np.radians(60))
    start[:3, :3] = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]) @ start[:3, :3]

    t0 = time.perf_counter()
    planner = hugger.Planner(hand, obj, target, start)
    traj = planner.plan()
    elapsed = time.perf_counter() - t0
    traj.save(out / "plan.npz")
    summary = {"object": f"blob, {len(obj.faces)} triangles", "hand": repr(hand), "plan_time_s": round(elapsed, 4),
               "configurations_per_s": round(len(traj) / elapsed), **traj.summary()}
    (out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    for key, value in summary.items():
        print(f"{key:24s} {value}")
    print(f"trajectory written to {out / 'plan.npz'}")
    return 0 if traj.status == "done" else 1


if __name__ == "__main__":
    raise SystemExit(main())
