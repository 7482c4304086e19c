"""Grasp success against the skin's sensing range, noise and taxel spacing (hugger.skins.SensorModel).

Each setting is swept alone, the others ideal, on the default cases of the built-in objects. Per plan:
status, links in contact and force closure (against the true object), the MuJoCo six-direction hold
test, and the independent checker against the true object (collision-free: structure, kinematics,
algorithm and collision on every other configuration, every plan must pass; motion check: DONE
angles, joint moves <= 4 steps, the swept motion of every other step).

    .venv/bin/python bench/sensor_sweep.py [--objects ...] [--json out.json] [--plot sweep.png]
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import numpy as np  # noqa: E402

import hugger  # noqa: E402
from hugger._files import atomic_path, write_atomic  # noqa: E402
from hugger import analysis, physics, skins  # noqa: E402
from hugger.scenarios import default_case  # noqa: E402
from helpers import CHECKER, check_file, load_checker  # noqa: E402

STEP = 0.001  # the default step of the 5 x 5 hand of 2 cm links (link / 20)
SWEEPS = {
    "range_mm": [math.inf, 10.0, 3.0, 1.5, 0.5],
    "gap_noise_um": [0.0, 20.0, 50.0, 100.0, 200.0],
    "normal_noise_deg": [0.0, 3.0, 6.0, 12.0],
    "taxel_spacing_mm": [0.0, 2.0, 5.0, 10.0, 20.0],
}


def model_kwargs(name: str, value: float) -> dict:
    if name == "range_mm":
        return {"range": value / 1000.0}
    if name == "gap_noise_um":
        return {"gap_noise": value * 1e-6}
    if name == "normal_noise_deg":
        return {"normal_noise": math.radians(value)}
    return {"taxel_spacing": value / 1000.0 if value > 0 else None}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--objects", nargs="+", default=["sphere", "ellipsoid", "cylinder", "curvy"])
    ap.add_argument("--json", help="write the rows here")
    ap.add_argument("--plot", help="draw success against each setting here (.png; needs hugger[viz])")
    ap.add_argument("--compare", help="with --plot: also draw the rows of this --json file of a --matched run, dashed")
    ap.add_argument("--no-physics", action="store_true", help="skip the MuJoCo hold test")
    ap.add_argument("--matched", action="store_true",
                    help="contact tolerance matched to the sensor: min(0.9 step, max(1e-4, 4 x its uncertainty))")
    args = ap.parse_args()
    if not CHECKER.exists():
        print("the checker (../shared/tools/check_trajectory.py) is missing", file=sys.stderr)
        return 2
    checker = load_checker()
    hand = hugger.Hand(fingers=5, links=5, link_length=0.02, link_radius=0.004, palm_radius=0.03, palm_thickness=0.01)
    cases = {name: default_case(name, hand) for name in args.objects}
    rows, seen = [], {}
    with tempfile.TemporaryDirectory() as tmp:
        for sweep, values in SWEEPS.items():
            for value in values:
                for name, case in cases.items():
                    kw = model_kwargs(sweep, value)
                    key = (name, tuple(sorted((k, v) for k, v in kw.items() if v not in (None, 0.0, math.inf))))
                    if key in seen:  # the ideal skin, measured once
                        rows.append({**seen[key], "sweep": sweep, "value": value})
                        continue
                    t0 = time.perf_counter()
                    skin = skins.SensorModel(case.obj, seed=0, **kw)
                    delta = None
                    if args.matched:  # a contact tolerance matched to the sensor (default 1e-4 m)
                        delta = min(0.9 * STEP, max(1e-4, 4.0 * skin.uncertainty(hand.link_radius)))
                    traj = hugger.Planner(hand, skin, case.target, case.palm_pose, record_object=case.obj,
                                          max_iterations=4000, contact_tolerance=delta).plan()
                    path = Path(tmp) / "plan.npz"
                    traj.save(path)
                    _, failures, _ = check_file(checker, path, every=2, motion=True, swept_every=2)
                    ok = not [f for f in failures if not f.startswith("motion:")]
                    a = analysis.analyze(traj, obj=case.obj)
                    held = None if args.no_physics else bool(physics.validate(traj)["held"])
                    row = {"object": name, "sweep": sweep, "value": value, "status": traj.status,
                           "contact_tolerance": traj.params["contact_tolerance"],
                           "links_in_contact": int(a["links_in_contact"]), "force_closure": bool(a["force_closure"]),
                           "held": held, "collision_free": bool(ok), "motion_ok": not failures, "failures": failures[:2],
                           "queries": skin.queries, "seconds": round(time.perf_counter() - t0, 2)}
                    seen[key] = row
                    rows.append(row)
                    print(json.dumps(row), flush=True)
    print()
    print("| setting | value | links in contact (mean) | force closure | held (6 directions) | collision-free | motion check |")
    print("|---|---|---|---|---|---|---|")
    for sweep, values in SWEEPS.items():
        for value in values:
            rs = [r for r in rows if r["sweep"] == sweep and r["value"] == value]
            n = len(rs)
            held = "-" if args.no_physics else f"{sum(r['held'] for r in rs)}/{n}"
            shown = {"range_mm": "inf" if math.isinf(value) else f"{value:g} mm", "gap_noise_um": f"{value:g} um",
                     "normal_noise_deg": f"{value:g} deg", "taxel_spacing_mm": "exact" if value == 0 else f"{value:g} mm"}[sweep]
            label = {"range_mm": "range", "gap_noise_um": "gap noise (sd)", "normal_noise_deg": "normal noise (sd)",
                     "taxel_spacing_mm": "taxel spacing"}[sweep]
            print(f"| {label} | {shown} | {np.mean([r['links_in_contact'] for r in rs]):.1f} | "
                  f"{sum(r['force_closure'] for r in rs)}/{n} | {held} | {sum(r['collision_free'] for r in rs)}/{n} | "
                  f"{sum(r['motion_ok'] for r in rs)}/{n} |")
    if args.json:
        write_atomic(args.json, json.dumps(rows))
    if args.plot:
        matched = None
        if args.compare:
            with open(args.compare) as fh:
                matched = json.load(fh)
        plot(rows, args.plot, not args.no_physics, matched)
    return 0 if all(r["collision_free"] for r in rows) else 1


def plot(rows: list[dict], path: str, physics_done: bool, matched: list[dict] | None = None) -> None:
    """Success against each setting; with ``matched`` (rows of a --matched run) dashed lines for
    the contact tolerance matched to the sensor."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(SWEEPS), figsize=(4 * len(SWEEPS), 3.2), sharey=True)
    titles = {"range_mm": "sensing range (mm)", "gap_noise_um": "gap noise sd (um)",
              "normal_noise_deg": "normal noise sd (deg)", "taxel_spacing_mm": "taxel spacing (mm, 0 = exact)"}
    for ax, (sweep, values) in zip(axes, SWEEPS.items()):
        xs = list(range(len(values)))
        for data, style, note in ((rows, "-", ""), (matched, "--", ", matched delta")):
            if not data:
                continue

            def pick(key, data=data):
                return [[r[key] for r in data if r["sweep"] == sweep and r["value"] == v] for v in values]

            ax.plot(xs, [np.mean(x) / 25 for x in pick("links_in_contact")], "o" + style, color="C0",
                    label="links in contact / 25" + note)
            ax.plot(xs, [np.mean(x) for x in pick("force_closure")], "s" + style, color="C1", label="force closure" + note)
            if physics_done:
                ax.plot(xs, [np.mean(x) for x in pick("held")], "^" + style, color="C2", label="held (6 directions)" + note)
        ax.set_xticks(xs, ["inf" if math.isinf(v) else f"{v:g}" for v in values])
        ax.set_xlabel(titles[sweep])
        ax.set_ylim(-0.05, 1.05)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("fraction of the 4 objects")
    axes[0].legend(fontsize=7, loc="lower left")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=90)


if __name__ == "__main__":
    sys.exit(main())
