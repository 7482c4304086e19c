"""Closed-loop hugging in MuJoCo against open-loop replay of a plan made on the static mesh.

For each object: T told to the planner off by 0, 5 and 10 mm (across the approach), and an object
pushed mid-grasp (at the first touch); both modes end in the six-direction hold test.

    .venv/bin/python bench/closed_loop.py [--objects sphere ellipsoid cylinder curvy] [--offsets 0 0.005 0.01] [--push 0.5] [--json out.json]
"""
from __future__ import annotations

import argparse
import json
import sys
import time

import hugger
from hugger._files import write_atomic
from hugger import mujoco_skin
from hugger.scenarios import default_case


def _cells(run: dict) -> str:
    """A run's held, links and object moved; a simulation that went unstable has no figures."""
    if run["hold"].get("diverged"):
        return "no (diverged) | — | —"
    return f"{'yes' if run['held'] else 'no'} | {run['links_in_contact']} | {1000 * run['object_moved_m']:.1f}"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--objects", nargs="+", default=["sphere", "ellipsoid", "cylinder", "curvy"])
    ap.add_argument("--offsets", nargs="*", type=float, default=[0.0, 0.005, 0.01], help="T offsets (m)")
    ap.add_argument("--push", type=float, default=0.5, help="push (N) of the pushed case (default 0.5; 0: no pushed case)")
    ap.add_argument("--json", help="write the rows here")
    args = ap.parse_args()
    hand = hugger.Hand(fingers=5, links=5, link_length=0.02, link_radius=0.004, palm_radius=0.03, palm_thickness=0.01)
    rows = []
    print("| object | case | closed loop: held | links | object moved (mm) | open loop: held | links | object moved (mm) |")
    print("|---|---|---|---|---|---|---|---|")
    for name in args.objects:
        case = default_case(name, hand)
        across = case.palm_pose[:3, 0]  # the palm's x axis: across the approach
        cases = [(f"T off by {1000 * d:g} mm", d * across, 0.0) for d in args.offsets]
        if args.push > 0:
            cases.append((f"pushed {args.push:g} N", 0 * across, args.push))
        for label, offset, push in cases:
            t0 = time.perf_counter()
            c = mujoco_skin.simulate(hand, case.obj, case.target, case.palm_pose, offset=offset, push=push).as_dict()
            o = mujoco_skin.replay(hand, case.obj, case.target, case.palm_pose, offset=offset, push=push).as_dict()
            rows.append({"object": name, "case": label, "closed": c, "open": o, "seconds": time.perf_counter() - t0})
            print(f"| {name} | {label} | {_cells(c)} | {_cells(o)} |", flush=True)
    held_c = sum(r["closed"]["held"] for r in rows)
    held_o = sum(r["open"]["held"] for r in rows)
    print(f"\nheld: closed loop {held_c}/{len(rows)}, open loop {held_o}/{len(rows)}")
    if args.json:
        write_atomic(args.json, json.dumps(rows, default=str))
    return 0


if __name__ == "__main__":
    sys.exit(main())
