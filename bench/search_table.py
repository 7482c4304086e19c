"""Default single approach vs the best of K approaches, object by object (the README table).

    python bench/search_table.py [--approaches 26] [--robust] [--verify V [--robust-verify]] [--blobs 30]
                                 [--rules hug|paper] [--json]

For every built-in and shared mesh that fits the hand (generation_common.fits), and with
``--blobs N`` for N random bodies (hugger.objects.blob(seed=s), s = 0..N-1, radius 3-4.5 cm, and
random ellipsoids and boxes that fit), it plans the default single approach and runs
hugger.search with K approaches, and reports links in contact, palm, epsilon and the physics
verdict of both: the six-direction test for the single approach, and with ``--robust`` the robust
verdict (every perturbation of hugger.physics.validate_robust) of the chosen grasp, its held
fraction and largest push held. ``--verify V`` passes verify=V to hugger.search, and
``--robust-verify`` also robust=True (the V best-ranked checked with the robust verdict): the
robust columns of the chosen grasp then come from the search's own check (the largest push is only
measured with ``--max-push``), or from hugger.physics.validate_robust when the search did not
measure them. Search time is the wall time of hugger.search (planning, ranking and any
verification; ``--workers`` simulation processes) on ``--threads`` threads. Every chosen plan is checked by ../shared/tools/check_trajectory.py
when that is present (``--check``).
"""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import hugger  # noqa: E402
from generation_common import fits, fitting_objects, object_specs  # noqa: E402
from hugger import analysis, physics  # noqa: E402
from hugger.planner import RULES  # noqa: E402
from hugger.scenarios import default_case, interior_target, load_object, start_pose  # noqa: E402

#: The table's header, the columns of every row printed (the single approach, then the search's choice).
HEADER = ("| object | single: links | ε | held | best: links | ε | held | robust | held fraction | max push (N) "
          "| search (s) | verified | checker |")
RULE = "|---|---|---:|---|---|---:|---|---|---:|---:|---:|---:|---|"


def generated(count: int) -> list[tuple[str, hugger.Object]]:
    """Random bodies that fit the hand: blobs, ellipsoids and boxes, deterministic."""
    rng = np.random.default_rng(15)
    out = []
    seed = 0
    while len(out) < count:
        kind = len(out) % 3
        if kind == 0:
            obj = hugger.objects.blob(radius=float(rng.uniform(0.03, 0.045)), seed=seed)
            name = f"blob(seed={seed})"
            seed += 1
        elif kind == 1:
            r = rng.uniform(0.025, 0.055, size=3)
            obj, name = hugger.objects.ellipsoid(radii=r), "ellipsoid(" + ",".join(f"{1000 * x:.0f}" for x in r) + ")"
        else:
            e = rng.uniform(0.045, 0.11, size=3)
            obj, name = hugger.objects.box(extents=e), "box(" + ",".join(f"{1000 * x:.0f}" for x in e) + ")"
        if fits(obj):
            out.append((name, obj))
    return out


def known_objects() -> dict[str, str]:
    """Every object the table may plan (fitting or not), by its name in the table (a mesh's stem)
    -> the spec to load it."""
    return {Path(s).stem: s for s in object_specs()}


def row(name, obj, target, pole, hand, args, checker) -> dict:
    params = {"rules": args.rules} if args.rules else {}
    single = hugger.Planner(hand, obj, target, start_pose(obj, hand, target, pole), **params).plan()
    a1 = analysis.analyze(single, obj=obj, volume=False)
    res = hugger.search(hand, obj, target, approaches=args.approaches, threads=args.threads, pole=pole,
                        rules=args.rules, verify=args.verify, robust=args.robust_verify,
                        workers=args.workers if args.robust_verify else None)  # (the search takes them only so)
    best = res.trajectory
    a2 = analysis.analyze(best, obj=obj, volume=False)
    out = {"object": name, "triangles": len(obj.faces),
           "single": {"status": single.status, "links": a1["links_in_contact"], "palm": a1["palm_contact"],
                      "epsilon": a1["epsilon"]},
           "best": {"index": res.best, "status": best.status, "links": a2["links_in_contact"],
                    "palm": a2["palm_contact"], "epsilon": a2["epsilon"]},
           "search_time_s": res.time_s, "judged": sum(c.firmness is not None for c in res.candidates),
           "verified": [{"index": i, "held": res.candidates[i].held, "robust": res.candidates[i].robust,
                         "held_fraction": res.candidates[i].held_fraction} for i in res.verified]}
    if args.physics:
        out["single"]["held"] = physics.validate(single)["held"]
        chosen = res.chosen
        if args.robust and chosen.held_fraction is not None and not args.max_push:
            out["best"].update({"held": chosen.held, "robust": chosen.robust, "held_fraction": chosen.held_fraction,
                                "max_force_N": float("nan")})
        elif args.robust:
            r = physics.validate_robust(best, workers=args.workers)
            out["best"].update({"held": r["held"], "robust": r["robust"], "held_fraction": r["held_fraction"],
                                "max_force_N": r["max_force_N"]})
        else:
            out["best"]["held"] = physics.validate(best)["held"]
    if checker is not None:
        from helpers import check_file

        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "best.npz"
            best.save(path)
            ok, failures, _ = check_file(checker, path, every=2)
        out["checker"] = "pass" if ok else "FAIL: " + "; ".join(failures[:2])
    return out


def _num(x: float | None, digits: int) -> str:
    return "-" if x is None or x != x else f"{x:.{digits}f}"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--approaches", type=int, default=26, help="approaches searched (default 26)")
    ap.add_argument("--threads", type=int, default=2, help="threads of the search (default 2)")
    ap.add_argument("--workers", type=int, default=None, help="processes of the robust verdict (default: the CPUs)")
    ap.add_argument("--rules", default=None, choices=RULES, help="the Phase 2 rule set: hug (the default) or paper")
    ap.add_argument("--verify", type=int, default=0, help="hugger.search(verify=V): physics check of the V best-ranked")
    ap.add_argument("--robust-verify", action="store_true",
                    help="hugger.search(verify=V, robust=True): the V best-ranked checked with the robust verdict")
    ap.add_argument("--max-push", action="store_true",
                    help="measure the largest push even where the search's check gave the robust verdict")
    ap.add_argument("--objects", nargs="*", default=None, help="only these (names as in the table, without .obj)")
    ap.add_argument("--no-physics", dest="physics", action="store_false")
    ap.add_argument("--robust", action="store_true", help="the robust verdict of the chosen grasp")
    ap.add_argument("--blobs", type=int, default=0, help="also N generated bodies that fit the hand")
    ap.add_argument("--only-generated", action="store_true")
    ap.add_argument("--check", action="store_true", help="run the independent checker on every chosen plan")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    if args.approaches < 1 or args.threads < 1:
        ap.error(f"--approaches and --threads must be at least 1, got {args.approaches} and {args.threads}")
    if args.workers is not None and args.workers < 1:
        ap.error(f"--workers must be at least 1, got {args.workers}")
    if args.verify < 0 or args.blobs < 0:
        ap.error(f"--verify and --blobs must be at least 0, got {args.verify} and {args.blobs}")
    if args.robust_verify and not args.verify:
        ap.error("--robust-verify checks the --verify V best-ranked: give --verify V >= 1")
    if args.only_generated and not args.blobs:
        ap.error("--only-generated plans the --blobs N generated bodies only: give --blobs N >= 1")
    known = known_objects()
    if args.objects is not None and not args.only_generated:
        unknown = [s for s in args.objects if s not in known]
        if unknown or not args.objects:
            ap.error(f"--objects: unknown {', '.join(unknown) or '(none given)'}; known objects: {', '.join(known)}")
        misfits = [s for s in dict.fromkeys(args.objects) if not fits(load_object(known[s])[1])]
        if misfits:
            ap.error(f"--objects: not fitting the hand (generation_common.fits): {', '.join(misfits)}")
    hand = hugger.Hand()
    checker = None
    if args.check:
        from helpers import checker_or_note

        checker = checker_or_note()
    rows = []
    cases = []
    if not args.only_generated:
        specs = fitting_objects() if args.objects is None else [s for n, s in known.items() if n in args.objects]
        for spec in specs:
            c = default_case(spec, hand)
            cases.append((c.name, c.obj, c.target, c.palm_pose[:3, 3] - c.target))
    for name, obj in generated(args.blobs):
        cases.append((name, obj, interior_target(obj), np.array([0.0, 0.0, 1.0])))
    if not args.json:
        print(HEADER + "\n" + RULE, flush=True)
    for name, obj, target, pole in cases:
        r = row(name, obj, target, pole, hand, args, checker)
        rows.append(r)
        if args.json:
            print(json.dumps(r), flush=True)
        else:
            s, b = r["single"], r["best"]
            print(f"| {name} | {s['links']}{'+palm' if s['palm'] else ''} | {s['epsilon']:.3f} | "
                  f"{'yes' if s.get('held') else 'no' if 'held' in s else '-'} | "
                  f"{b['links']}{'+palm' if b['palm'] else ''} | {b['epsilon']:.3f} | "
                  f"{'yes' if b.get('held') else 'no' if 'held' in b else '-'} | "
                  f"{'yes' if b.get('robust') else 'no' if 'robust' in b else '-'} | "
                  f"{_num(b.get('held_fraction'), 2)} | {_num(b.get('max_force_N'), 1)} | "
                  f"{r['search_time_s']:.2f} | {len(r['verified'])} | {r.get('checker', '-')} |", flush=True)
    n = len(rows)
    if n and not args.json:
        held1 = sum(bool(r["single"].get("held")) for r in rows)
        held2 = sum(bool(r["best"].get("held")) for r in rows)
        robust = sum(bool(r["best"].get("robust")) for r in rows)
        print(f"\n{n} objects: single approach held {held1}/{n}; best of {args.approaches} held {held2}/{n}"
              + (f", robustly held {robust}/{n}" if args.robust else "")
              + f"; median search time {np.median([r['search_time_s'] for r in rows]):.2f} s")
        if args.robust_verify:  # the ranking's best is the first one checked
            first = sum(bool(r["verified"] and r["verified"][0]["robust"]) for r in rows)
            print(f"the ranking's best alone robustly held {first}/{n}; candidates checked "
                  f"{sum(len(r['verified']) for r in rows)}; total search time "
                  f"{sum(r['search_time_s'] for r in rows):.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
