"""Every candidate of the approach search through the robust verdict: is ANY of the K robustly held?

    python bench/robust_candidates.py [--approaches 26] [--workers 2] [--objects NAME...] [--save DIR] [--json]

For every built-in and shared mesh that fits the hand (or ``--objects``), it runs hugger.search
with K approaches (every candidate judged), then puts every candidate through the six-direction
test at nominal settings and, when that holds, through the other eight perturbations of
hugger.physics.PERTURBATIONS one at a time, stopping at the first one lost (``robust`` is exact
for every candidate; ``first_lost_under`` names the perturbation that stopped it). The simulations run in a pool of ``--workers``
processes. Prints, per object, how many candidates are held and robustly held, the ranking
position of the first robust one, and the AUC over all candidates of the ranking's figures for
the robust verdict. ``--save DIR`` writes every candidate's plan (DIR/OBJECT/NN.npz) and the
figures (DIR/OBJECT.json) for later analysis.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import hugger  # noqa: E402
from generation_common import auc, fitting_objects, ranking_value  # noqa: E402
from hugger import physics  # noqa: E402
from hugger._pool import running_pool  # noqa: E402
from hugger.physics.hold import NOMINAL_FORCE, PERTURBATIONS  # noqa: E402
from hugger.scenarios import default_case  # noqa: E402
from hugger.search import _default_key  # noqa: E402



def _held(job: tuple[hugger.Trajectory, dict]) -> bool:
    traj, kwargs = job
    return bool(physics.validate(traj, force=NOMINAL_FORCE, **kwargs)["held"])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--approaches", type=int, default=26)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--objects", nargs="*", default=None)
    ap.add_argument("--save", default=None)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    hand = hugger.Hand()
    # the perturbations most often lost first, so that a candidate that is not robust stops early
    others = sorted((n for n in PERTURBATIONS if n != "nominal"),
                    key=lambda n: ["mu=0.5", "squeeze=0.03", "mass+10%", "kp-20%"].index(n)
                    if n in ["mu=0.5", "squeeze=0.03", "mass+10%", "kp-20%"] else 9)
    everything = []
    with running_pool(args.workers, args.workers) as pool:  # (stopped at once when interrupted)
        for spec in fitting_objects():
            name = Path(spec).stem
            if args.objects is not None and name not in args.objects:
                continue
            t0 = time.perf_counter()
            case = default_case(spec, hand)
            res = hugger.search(hand, case.obj, case.target, approaches=args.approaches, threads=args.threads,
                                pole=case.palm_pose[:3, 3] - case.target, keep_all=True,
                                score=lambda c: 0.0)  # judges every candidate; the ranking is re-made below
            trajs = res.trajectories
            assert trajs is not None
            cands = [c for c in res.candidates if c.ok]
            order = sorted(cands, key=_default_key, reverse=True)
            nominal = list(pool.map(_held, [(trajs[c.index], {}) for c in cands]))
            held = {c.index: h for c, h in zip(cands, nominal)}
            alive = [c.index for c in cands if held[c.index]]
            lost_under: dict[int, str | None] = {c.index: None if held[c.index] else "nominal" for c in cands}
            for n in others:  # one perturbation at a time over the survivors: a candidate stops at its first loss
                verdicts = list(pool.map(_held, [(trajs[i], PERTURBATIONS[n]) for i in alive]))
                for i, v in zip(alive, verdicts):
                    if not v:
                        lost_under[i] = n
                alive = [i for i, v in zip(alive, verdicts) if v]
            rows = []
            for rank_pos, c in enumerate(order):
                rows.append({**c.to_dict(), "rank": rank_pos, "held": held[c.index],
                             "robust": lost_under[c.index] is None, "first_lost_under": lost_under[c.index]})
            first = next((r["rank"] for r in rows if r["robust"]), None)
            out = {"object": name, "candidates": rows, "held": sum(r["held"] for r in rows),
                   "robust": sum(r["robust"] for r in rows), "first_robust_rank": first,
                   "time_s": time.perf_counter() - t0}
            everything.append(out)
            if args.save:
                d = Path(args.save) / name
                d.mkdir(parents=True, exist_ok=True)
                for c in cands:
                    trajs[c.index].save(d / f"{c.index:02d}.npz")
                (Path(args.save) / f"{name}.json").write_text(json.dumps(out))
            if args.json:
                print(json.dumps(out), flush=True)
            else:
                print(f"| {name} | {len(rows)} | {out['held']} | {out['robust']} | "
                      f"{'-' if first is None else first + 1} | {out['time_s']:.0f} |", flush=True)
    rows = [r for o in everything for r in o["candidates"]]
    robust = [r["robust"] for r in rows]
    key = [ranking_value(r["force_closure"], r["firmness"]) for r in rows]
    if not args.json and rows:
        print(f"\n{len(rows)} candidates, {sum(robust)} robustly held; AUC for robust: "
              f"epsilon {auc([r['epsilon'] for r in rows], robust):.3f}, "
              f"links {auc([r['links_in_contact'] for r in rows], robust):.3f}, "
              f"hug {auc([r['hug'] for r in rows], robust):.3f}, "
              f"escape {auc([-r['escape'] for r in rows], robust):.3f}, "
              f"firmness {auc([r['firmness'] for r in rows], robust):.3f}, ranking key {auc(key, robust):.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
