"""How firmly Hugger hugs objects that fit the hand, with both rule sets.

Random cases (seeded, so every run makes the same plans): a random hand (M in 3..6 fingers, N in
3..6 links, link radius 0 in a third of the cases) and a random object that fits it -- its largest
bounding-box extent at most 1.6 x the finger length, its smallest at least the palm diameter:
spheres, ellipsoids, boxes, cylinders and smooth non-convex blobs, randomly rotated, T near the
centre (off it by up to a quarter of the smallest half-extent), the palm started at a safe distance
in a random direction with a random orientation (so Phase 1 turns it). Each case is planned with
``rules="paper"`` and ``rules="hug"``; per rule set the script reports

* mean fraction of links in contact (gap <= 1 mm) at the end, and the share of plans with at
  least 30% of their links in contact;
* the share of plans whose palm is in contact at the end;
* the plans' statuses (``done``, ``stalled``, ``max_iterations``) and, with ``--check``, how many
  pass ``../shared/tools/check_trajectory.py`` (motion check included).

    python bench/hug_metrics.py [--cases 200] [--check] [--json]
"""
from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import hugger
from hugger import analysis, scenarios

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from helpers import checker_or_note, random_rotation as _rotation  # noqa: E402

KINDS = ("sphere", "ellipsoid", "box", "cylinder", "blob")
RULES = ("paper", "hug")


def fits(extents: np.ndarray, hand: hugger.Hand) -> bool:
    """The object fits the hand: largest extent <= 1.6 x the finger length, smallest >= the palm diameter."""
    return float(np.max(extents)) <= 1.6 * hand.reach + 1e-12 and float(np.min(extents)) >= 2 * hand.palm_radius - 1e-12


def random_case(seed: int) -> tuple[str, hugger.Hand, hugger.Object, np.ndarray, np.ndarray]:
    """(kind, hand, object, T, start pose) of case ``seed``; the object fits the hand."""
    rng = np.random.default_rng(10_000 + seed)
    kind = KINDS[seed % len(KINDS)]
    M, N = int(rng.integers(3, 7)), int(rng.integers(3, 7))
    finger = rng.uniform(0.05, 0.12)
    palm = finger * rng.uniform(0.2, 0.4)
    link = finger / N
    radius = 0.0 if rng.random() < 1 / 3 else min(rng.uniform(0.05, 0.2) * link, 0.45 * palm * math.sin(math.pi / M))
    hand = hugger.Hand(fingers=M, links=N, link_length=link, link_radius=radius, palm_radius=palm,
                       palm_thickness=0.3 * palm)
    lo, hi = 2 * palm, 1.6 * hand.reach
    o = hugger.objects
    for _ in range(100):
        ext = rng.uniform(lo, hi, size=3)
        if kind == "sphere":
            ext[:] = ext[0]
            obj = o.sphere(ext[0] / 2, subdivisions=3)
        elif kind == "ellipsoid":
            obj = o.ellipsoid(ext / 2, subdivisions=3)
        elif kind == "box":
            obj = o.box(ext, divisions=3)
        elif kind == "cylinder":
            ext[1] = ext[0]
            obj = o.cylinder(ext[0] / 2, ext[2], sections=32, rings=4)
        else:
            obj = o.blob(ext[0] / 2 / 1.3, amplitude=rng.uniform(0.15, 0.3), seed=int(rng.integers(1 << 30)),
                         subdivisions=3)
        v = obj.vertices
        extents = v.max(axis=0) - v.min(axis=0)
        if fits(extents, hand):
            break
    else:  # pragma: no cover - the ranges above always give a fitting object quickly
        raise RuntimeError(f"no fitting object for case {seed}")
    centre = (v.max(axis=0) + v.min(axis=0)) / 2
    R = _rotation(rng)
    obj = hugger.Object((v - centre) @ R.T, obj.faces)
    target = np.zeros(3)
    for _ in range(20):  # T off the centre by up to a quarter of the smallest half-extent, inside O
        t = rng.uniform(-1, 1, size=3) * 0.25 * float(extents.min()) / 2
        if obj.inside(t):
            target = t
            break
    d = rng.normal(size=3)
    d /= np.linalg.norm(d)
    pose = np.eye(4)
    pose[:3, :3] = _rotation(rng)
    pose[:3, 3] = target + (scenarios.safe_distance(obj, hand, target) + rng.uniform(0.0, 0.03)) * d
    return kind, hand, obj, target, pose


def run_case(seed: int, rules: str, checker=None) -> dict:
    """Plan case ``seed`` with ``rules``; its status, contacts and (with a checker) verdict."""
    kind, hand, obj, target, pose = random_case(seed)
    t0 = time.perf_counter()
    traj = hugger.Planner(hand, obj, target, pose, rules=rules).plan()
    seconds = time.perf_counter() - t0
    found = analysis.contacts(traj, obj=obj)
    row = {"seed": seed, "kind": kind, "rules": rules, "status": traj.status, "configurations": len(traj),
           "links": hand.fingers * hand.links, "links_in_contact": found.links_in_contact,
           "palm_contact": bool(found.palm_contact), "seconds": seconds}
    if checker is not None:
        with tempfile.TemporaryDirectory() as d:
            path = Path(d) / "plan.npz"
            traj.save(path)
            with contextlib.redirect_stdout(io.StringIO()):
                row["checker"] = checker.main([str(path)]) == 0
    return row


def summarize(rows: list[dict]) -> dict:
    frac = np.array([r["links_in_contact"] / r["links"] for r in rows])
    statuses: dict[str, int] = {}
    for r in rows:
        statuses[r["status"]] = statuses.get(r["status"], 0) + 1
    out = {"plans": len(rows), "mean_links_in_contact": float(frac.mean()),
           "plans_with_30pct_links": float(np.mean(frac >= 0.3)),
           "palm_contact": float(np.mean([r["palm_contact"] for r in rows])), "statuses": statuses,
           "mean_plan_ms": 1000 * float(np.mean([r["seconds"] for r in rows]))}
    if rows and "checker" in rows[0]:
        out["checker_pass"] = int(sum(r["checker"] for r in rows))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=200, help="number of random cases (default 200)")
    ap.add_argument("--check", action="store_true", help="run the independent checker on every plan")
    ap.add_argument("--json", action="store_true", help="print one JSON object instead of the table")
    args = ap.parse_args(argv)
    if args.cases < 1:
        ap.error(f"--cases must be at least 1, got {args.cases}")
    checker = checker_or_note() if args.check else None
    result = {}
    for rules in RULES:
        rows = [run_case(seed, rules, checker) for seed in range(args.cases)]
        result[rules] = summarize(rows)
    if args.json:
        print(json.dumps(result, indent=2))
        return 0
    print("| rules | plans | mean links in contact | plans with >= 30% links | palm in contact | statuses | mean plan (ms) |"
          + (" checker |" if args.check else ""))
    print("|---|---:|---:|---:|---:|---|---:|" + ("---:|" if args.check else ""))
    for rules, s in result.items():
        st = ", ".join(f"{k} {v}" for k, v in sorted(s["statuses"].items()))
        print(f"| {rules} | {s['plans']} | {100 * s['mean_links_in_contact']:.1f}% | {100 * s['plans_with_30pct_links']:.1f}% "
              f"| {100 * s['palm_contact']:.1f}% | {st} | {s['mean_plan_ms']:.1f} |"
              + (f" {s.get('checker_pass', '-')}/{s['plans']} |" if args.check else ""))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
