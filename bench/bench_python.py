#!/usr/bin/env python3
"""Python-side benchmarks of hugger: a plan end to end, the cost of the binding, and plan_many.

    python bench/bench_python.py [--repeat R] [--cases C] [--threads K] [--json]

Figures (medians over R repeats, wall-clock seconds; inputs built before any clock starts):

  plan            Planner(...) + .plan() end to end for the paper's 5x5 hand on ``curvy``
                  (20480 triangles), the palm 20 cm away along +z, turned 60 degrees about its y axis
  core_plan       its C++ part (constructor and _core plan): the cost of planning; and
                  trajectory_conversion, the trajectory handed to Python, timed apart in the same run
  step_loop       the same plan driven from Python one configuration at a time (Planner.step()),
                  i.e. what streaming to a robot costs; step_overhead_us is the per-configuration
                  difference to core_plan within each repeat (its median; noise can make it
                  negative where the overhead is small); in a loop of its own, constructor_s the Planner's
                  constructor (checks, Phase 1, the section skin's regions), step_p50_phase2_us and
                  step_max_ms one step() call's time
                  (the median over Phase 2's configurations, the largest over the plan's (the
                  configurations of Phase 1, planned by the constructor, are handed out at once);
                  medians over the repeats)
  plan_many       C independent cases (the paper's scenario from C start directions) with
                  hugger.plan_many on 1 thread and on K threads; speedup = t(1) / t(K)

Speed is reported, never asserted. Build Release (the default of ``pip install``). The machine's
load average is printed: shared machines make figures noisy, so compare medians.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time

import numpy as np

import hugger


def start_pose(obj, hand, direction=(0.0, 0.0, 1.0)) -> np.ndarray:
    """The palm 20 cm from T = 0 along ``direction``, facing T, turned 60 degrees about its y axis."""
    return hugger.scenarios.start_pose(obj, hand, np.zeros(3), direction, turn_deg=60.0, distance=0.2)


def timed(fn, repeat: int) -> tuple[float, object]:
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5, help="repeats per figure (median reported; default 5)")
    ap.add_argument("--cases", type=int, default=16, help="cases for plan_many (default 16)")
    ap.add_argument("--threads", type=int, default=2, help="threads for plan_many (default 2)")
    ap.add_argument("--json", action="store_true", help="print the figures as JSON")
    args = ap.parse_args(argv)
    if args.repeat < 1 or args.cases < 1 or args.threads < 1:
        ap.error("--repeat, --cases and --threads must be at least 1")

    hand = hugger.Hand(fingers=5, links=5, link_length=0.02, link_radius=0.004, palm_radius=0.03, palm_thickness=0.01)
    obj = hugger.objects.curvy()
    target = np.zeros(3)
    pose = start_pose(obj, hand)
    rng = np.random.default_rng(0)
    dirs = rng.normal(size=(args.cases, 3))
    cases = [{"hand": hand, "obj": obj, "target": target, "palm_pose": start_pose(obj, hand, d)} for d in dirs]

    # Each repeat times one plan in its two parts (the C++ plan, then the trajectory handed to
    # Python, as Planner.plan() makes it), then the same plan driven by step(): the parts are
    # measured, not told apart by subtracting figures of other runs, and the step loop's overhead
    # is the difference within one repeat (the median of those: noise can still make it negative).
    core_t, conversion_t, step_t, overhead_t = [], [], [], []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        planner = hugger.Planner(hand, obj, target, pose)
        planner._core.plan(None)
        t1 = time.perf_counter()
        traj = planner.plan()  # planned already: what is left is handing the trajectory to Python
        t2 = time.perf_counter()
        p = hugger.Planner(hand, obj, target, pose)
        n_steps = 0
        while p.step() is not None:
            n_steps += 1
        t3 = time.perf_counter()
        core_t.append(t1 - t0)
        conversion_t.append(t2 - t1)
        step_t.append(t3 - t2)
        overhead_t.append((t3 - t2 - (t1 - t0)) / max(n_steps, 1))
    t_core = statistics.median(core_t)
    t_plan = statistics.median(c + v for c, v in zip(core_t, conversion_t))
    t_step = statistics.median(step_t)

    # Each step() timed, in a loop of its own (its clocks would weigh on step_loop's figure).
    constructor, step_p50, step_max = [], [], []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        p = hugger.Planner(hand, obj, target, pose)
        constructor.append(time.perf_counter() - t0)
        times, phase2 = [], []
        while True:
            t = time.perf_counter()
            c = p.step()
            times.append(time.perf_counter() - t)
            if c is None:
                break
            if c.phase == 2:
                phase2.append(times[-1])
        step_p50.append(statistics.median(phase2))
        step_max.append(max(times))
    t_many1, res1 = timed(lambda: hugger.plan_many(cases, threads=1), max(1, args.repeat // 2))
    t_manyk, resk = timed(lambda: hugger.plan_many(cases, threads=args.threads), max(1, args.repeat // 2))
    same = all(np.array_equal(a.joints, b.joints) for a, b in zip(res1, resk))
    confs = int(sum(len(t) for t in res1))
    stats = planner.stats
    figures = {
        "load_average": os.getloadavg() if hasattr(os, "getloadavg") else None,
        "repeats": args.repeat,
        "scenario": "paper: 5x5 hand, curvy (20480 triangles), palm 20 cm along +z turned 60 deg",
        "status": traj.status,
        "configurations": len(traj),
        "phase2_iterations": stats["phase2_iterations"],
        "plan_s": t_plan,
        "core_plan_s": t_core,
        "trajectory_conversion_s": statistics.median(conversion_t),
        "step_loop_s": t_step,
        "step_configurations": n_steps,
        "step_overhead_us": statistics.median(overhead_t) * 1e6,
        "constructor_s": statistics.median(constructor),
        "step_p50_phase2_us": statistics.median(step_p50) * 1e6,
        "step_max_ms": statistics.median(step_max) * 1e3,
        "configurations_per_s_plan": len(traj) / t_plan,
        "plan_many_cases": args.cases,
        "plan_many_configurations": confs,
        "plan_many_1_thread_s": t_many1,
        f"plan_many_{args.threads}_threads_s": t_manyk,
        "plan_many_speedup": t_many1 / t_manyk,
        "plan_many_identical_results": same,
    }
    if args.json:
        json.dump(figures, sys.stdout, indent=2)
        print()
    else:
        for k, v in figures.items():
            print(f"{k:32s} {v:.6g}" if isinstance(v, float) else f"{k:32s} {v}")
    return 0 if same and traj.status == "done" else 1


if __name__ == "__main__":
    raise SystemExit(main())
