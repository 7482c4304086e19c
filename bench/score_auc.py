"""How well the search's figures predict the physics verdict, over every grasp of a dataset.

    hugger generate OBJECT... --approaches 8 --validate --out DIR     # every grasp validated
    python bench/score_auc.py DIR [--json]

Prints the AUC (probability that a held grasp outscores a lost one) of: epsilon alone, links in
contact, hug (links + 2 for the palm), the escape (the largest free slide, smaller is better),
firmness (epsilon less the escape penalty) and the search's ranking key (force closure, then
firmness), and how often the chosen grasp of each (object, hand) is held against the single default
approach (direction 0).
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import hugger  # noqa: E402
from generation_common import auc, ranking_value  # noqa: E402
from hugger.search import firmness  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dataset")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    try:
        ds = hugger.Dataset(args.dataset)
    except (ValueError, OSError) as exc:  # no dataset there: argparse's one-line error, exit 2
        ap.error(str(exc))
    eps, links, hug, slide, firm, key, held = [], [], [], [], [], [], []
    chosen_held = default_held = 0
    shards = 0
    for s in range(len(ds.shards)):
        z = ds.shard(s)
        if "held" not in z:
            raise SystemExit(f"{args.dataset} was made without --validate")
        if "escape" not in z:
            raise SystemExit(f"{args.dataset} has shards of format 1 (no escape): make it again")
        shards += 1
        ok = z["status"] != "error"
        chosen_held += bool(z["held"][int(z["best"])])
        default_held += bool(z["held"][0])
        for i in np.flatnonzero(ok):
            h = int(z["links_in_contact"][i]) + 2 * bool(z["palm_contact"][i])
            eps.append(float(z["epsilon"][i]))
            links.append(int(z["links_in_contact"][i]))
            hug.append(h)
            slide.append(-float(z["escape"][i]))  # less is firmer
            firm.append(firmness(z["epsilon"][i], z["escape"][i]))
            key.append(ranking_value(z["force_closure"][i], firm[-1]))
            held.append(bool(z["held"][i]))
    out = {"grasps": len(held), "held": int(sum(held)), "objects_x_hands": shards,
           "auc_epsilon": auc(eps, held), "auc_links_in_contact": auc(links, held), "auc_hug": auc(hug, held),
           "auc_escape": auc(slide, held), "auc_firmness": auc(firm, held), "auc_search_key": auc(key, held), "chosen_held": chosen_held, "default_held": default_held}
    if args.json:
        print(json.dumps(out))
    else:
        print(f"{out['grasps']} grasps ({out['held']} held) over {shards} (object, hand) pairs")
        print("| figure | AUC |\n|---|---:|")
        for k in ("auc_epsilon", "auc_links_in_contact", "auc_hug", "auc_escape", "auc_firmness",
                  "auc_search_key"):
            print(f"| {k[4:]} | {out[k]:.3f} |")
        print(f"held: chosen {chosen_held}/{shards}, default single approach {default_held}/{shards}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
