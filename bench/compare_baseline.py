"""Hugger against the close-until-contact baseline, from the same start, on every object that fits.

For each built-in object and each mesh in ``../shared/data/objects/`` that fits the hand (largest
bounding-box extent at most ``--max-extent``, default 16 cm = 2 x (palm radius + half the finger
length) of the 5x5 hand), Hugger with each rule set (`hug`, the default, and `paper`) and the
baseline start from :func:`hugger.scenarios.default_case`'s pose;
the table gives, per planner:

* time to grasp: wall-clock of the planning itself (Hugger: ``Planner.plan()``, Phase 2; baseline:
  its loop of MuJoCo collision queries) and of its setup (Hugger: constructing the Planner, i.e.
  its checks, Phase 1 and the section skin's regions of the finger planes (the Object is built
  before the clock); baseline: building and compiling the MuJoCo model, convex pieces from cache);
* links in contact and palm contact (gap <= 1 mm), the Ferrari-Canny epsilon and the grasp wrench
  space volume over all contacts (:func:`hugger.analysis.analyze`, mu 0.5, torques about T);
* the six-direction hold test of :func:`hugger.physics.validate` (0.1 kg, mu 0.6, 10x weight).

    python bench/compare_baseline.py [--objects sphere,ycb_apple] [--out bench/results/compare_baseline.md]

Progress goes to stdout, one line per object and planner; the markdown table to ``--out``.
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

import sys

import hugger
from hugger import physics
from hugger._files import write_atomic

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_args import split_names  # noqa: E402

from hugger import baselines  # noqa: E402

HERE = Path(__file__).resolve().parent

ROOT = HERE.parent
SHARED_OBJECTS = ROOT.parent / "shared" / "data" / "objects"
DIRS = list(physics.DIRECTIONS)
#: Hugger with each rule set (``hug``: the default; ``paper``: the 1994 method), then the baseline.
PLANNERS = ("hug", "paper", "baseline")


def candidates(selection: list[str] | None) -> list[tuple[str, str]]:
    """(name, spec) pairs: built-ins by name, meshes by path; a ValueError names any unknown object."""
    from hugger import objects

    items = [(name, name) for name in objects.names()]
    if SHARED_OBJECTS.is_dir():
        items += [(p.stem, str(p)) for p in sorted(SHARED_OBJECTS.glob("*.obj"))]
    if selection:
        known = dict(items)
        missing = [s for s in selection if s not in known and not Path(s).is_file()]
        if missing:
            raise ValueError(f"unknown objects: {', '.join(missing)} (built-ins: {', '.join(objects.names())}; "
                             f"meshes: the .obj files in {SHARED_OBJECTS})")
        items = [(s, known[s]) if s in known else (Path(s).stem, s) for s in selection]
    return items


def run_one(name: str, spec: str, hand: hugger.Hand, max_extent: float, do_validate: bool) -> dict:
    from hugger import analysis, scenarios

    row: dict = {"object": name}
    try:
        case = scenarios.default_case(spec, hand)
    except ValueError as exc:
        return {**row, "skipped": f"cannot load: {exc}"}
    extent = float(np.ptp(case.obj.bounds, axis=0).max())
    row["extent_m"] = extent
    row["triangles"] = int(len(case.obj.faces))
    if extent > max_extent:
        return {**row, "skipped": f"too large for the hand ({extent * 100:.1f} cm > {max_extent * 100:.0f} cm)"}
    results = {}
    for planner in PLANNERS:
        r: dict = {}
        try:
            if planner != "baseline":
                t0 = time.perf_counter()
                p = hugger.Planner(hand, case.obj, case.target, case.palm_pose, rules=planner)
                t1 = time.perf_counter()
                traj = p.plan()
                t2 = time.perf_counter()
                r["setup_s"], r["plan_s"] = t1 - t0, t2 - t1
            else:
                run = baselines.run_baseline(hand, case.obj, case.target, case.palm_pose)
                traj = run.trajectory
                r["setup_s"], r["plan_s"] = run.setup_time_s, run.plan_time_s
        except ValueError as exc:
            results[planner] = {"error": str(exc)}
            print(f"  {name:24s} {planner:8s} error: {exc}", flush=True)
            continue
        r["status"] = traj.status
        r["configurations"] = len(traj)
        a = analysis.analyze(traj, obj=case.obj)
        for key in ("links_in_contact", "links", "palm_contact", "epsilon", "volume", "force_closure"):
            r[key] = a[key]
        if do_validate:
            t3 = time.perf_counter()
            v = physics.validate(traj)
            r["validate_s"] = time.perf_counter() - t3
            r["held"] = v["held"]
            r["directions"] = v["directions"]
            r["settle_displacement_m"] = v["settle"]["displacement_m"]
        results[planner] = r
        held = "" if not do_validate else " held " + "".join("+" if r["directions"][d]["held"] else "-" for d in DIRS)
        print(f"  {name:24s} {planner:8s} {r['status']:14s} plan {r['plan_s'] * 1e3:8.1f} ms  links "
              f"{r['links_in_contact']:2d}/{r['links']}  palm {'yes' if r['palm_contact'] else 'no ':3s}  "
              f"eps {r['epsilon']:.3g}{held}", flush=True)
    row["results"] = results
    return row


def markdown(rows: list[dict], do_validate: bool, command: str) -> str:
    import mujoco

    lines = [
        "# Hugger vs close-until-contact baseline",
        "",
        f"Generated by `{command}` (MuJoCo {mujoco.__version__}). Hand: 5 fingers x 5 links of 2 cm, link radius 4 mm, "
        "palm radius 3 cm, thickness 1 cm. Planners: Hugger with `rules=\"hug\"` (hug, the default) and "
        "`rules=\"paper\"` (paper), and the baseline; all start from `hugger.scenarios.default_case` "
        "(palm on the approach "
        "direction at a safe distance, facing T). Plan = wall-clock of the planning itself; setup = Hugger's planner "
        "construction / the baseline's MuJoCo model (convex pieces from the cache). Links (of 25) and palm in contact: "
        "gap <= 1 mm. eps, volume: `hugger.analysis.analyze` (all contacts, mu 0.5, torques about T). Hold: "
        "`hugger.physics.validate` (0.1 kg, mu 0.6, squeeze 0.05 rad, gravity off, 10x weight for 2 s along each "
        "axis; held = moved < 5 cm and turned < 15 deg).",
        "",
    ]
    head = "| object | planner | status | plan (ms) | setup (ms) | configs | links | palm | eps | volume |"
    sep = "|---|---|---|---:|---:|---:|---:|---|---:|---:|"
    if do_validate:
        head += " " + " | ".join(DIRS) + " | held |"
        sep += "---|" * (len(DIRS) + 1)
    lines += [head, sep]
    skipped = []
    for row in rows:
        if "skipped" in row:
            skipped.append(f"- {row['object']}: {row['skipped']}")
            continue
        for planner, r in row["results"].items():
            if "error" in r:
                empty = " |" * (7 + (7 if do_validate else 0))
                lines.append(f"| {row['object']} | {planner} | error: {r['error']} |" + empty)
                continue
            cells = [row["object"], planner, r["status"], f"{r['plan_s'] * 1e3:.1f}", f"{r['setup_s'] * 1e3:.0f}",
                     str(r["configurations"]), str(r["links_in_contact"]), "yes" if r["palm_contact"] else "no",
                     f"{r['epsilon']:.3g}", f"{r['volume']:.3g}"]
            if do_validate:
                cells += ["✓" if r["directions"][d]["held"] else "✗" for d in DIRS]
                cells.append("**yes**" if r["held"] else "no")
            lines.append("| " + " | ".join(cells) + " |")
    lines.append("")
    done = [r for row in rows if "results" in row for r in row["results"].items()]
    for planner in PLANNERS:
        rs = [r for p, r in done if p == planner and "error" not in r]
        if rs:
            mean_links = np.mean([r["links_in_contact"] for r in rs])
            text = (f"- {planner}: {len(rs)} objects, mean links in contact {mean_links:.1f}, "
                    f"palm contact {sum(r['palm_contact'] for r in rs)}/{len(rs)}, "
                    f"median plan time {np.median([r['plan_s'] for r in rs]) * 1e3:.1f} ms")
            if do_validate:
                text += (f", held in all six directions {sum(r['held'] for r in rs)}/{len(rs)}, "
                         f"directions held {sum(r['directions'][d]['held'] for r in rs for d in DIRS)}/{6 * len(rs)}")
            lines.append(text)
    if skipped:
        lines += ["", "Not compared:", *skipped]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--objects", default=None,
                    help="comma-separated subset: built-in names, mesh stems from ../shared/data/objects, "
                         "or mesh paths")
    ap.add_argument("--out", default=str(HERE / "results" / "compare_baseline.md"),
                    help="markdown table (default %(default)s)")
    ap.add_argument("--json", default=None, help="also write every figure as JSON here")
    ap.add_argument("--max-extent", type=float, default=0.16, help="largest bounding-box extent (m) that fits the hand")
    ap.add_argument("--no-validate", action="store_true", help="skip the MuJoCo hold test")
    args = ap.parse_args(argv)
    selection = None
    if args.objects is not None:  # names or paths: no list of them to check against
        selection = split_names(args.objects)
        if not selection:
            ap.error("--objects: no object named (give built-in names, mesh stems or mesh paths)")
    try:
        items = candidates(selection)
    except ValueError as exc:
        ap.error(f"--objects: {exc}")
    hand = hugger.Hand()
    rows = []
    t0 = time.perf_counter()
    for name, spec in items:
        print(f"{name} ...", flush=True)
        row = run_one(name, spec, hand, args.max_extent, not args.no_validate)
        if "skipped" in row:
            print(f"  {name:24s} skipped: {row['skipped']}", flush=True)
        rows.append(row)
    command = "python bench/compare_baseline.py" + (f" --objects {args.objects}" if args.objects else "")
    text = markdown(rows, not args.no_validate, command)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    write_atomic(out, text)
    if args.json:
        write_atomic(args.json, json.dumps(rows, indent=2) + "\n")
    print(text)
    print(f"written to {out} in {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
