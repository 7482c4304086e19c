#!/usr/bin/env python3
"""A digest of many plans, to check that a change of the engine plans bit for bit as before.

    python bench/plan_digest.py [--skins mesh,section] [--rules paper,hug] [--objects sphere,box] [--json]

Plans every built-in object (:func:`hugger.scenarios.default_case`) with the default hand and the
presets ``barrett_bh8``, ``robotiq_3f`` and ``parallel_3link``, under each rule set and each skin
(by default 7 x 4 x 2 x 2 = 112 plans), and prints one SHA-256 digest per skin over every emitted
configuration (palm pose, joints, angles, tip states, iteration, phase) and each plan's summary. A
pure speed-up must leave every digest unchanged: run it before and after, and compare.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

import hugger
from hugger import scenarios
from hugger.planner import RULES

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_args import comma_names  # noqa: E402

HANDS = (None, "barrett_bh8", "robotiq_3f", "parallel_3link")
FIELDS = ("palm_pose", "joints", "angles", "tip_state", "iteration", "phase")
#: The summary's figures hashed, in the order and under the names of the digests quoted since
#: they began, so that the same plans keep their digests ...
SUMMARY = ("status", "configurations", "phase1_configurations", "phase2_iterations", "palm_contact", "palm_gap_m",
           "links_in_contact", "links", "fingers_done", "first_contact_iteration")
#: ... where ``phase2_iterations`` was the count of Phase 2 configurations, the summary's
#: ``phase2_configurations`` since a8fba36.
RENAMED = {"phase2_iterations": "phase2_configurations"}


def update(h: Any, traj: hugger.Trajectory) -> None:
    """Feed one plan to the hash ``h``: every configuration's fields, bit for bit, and its summary."""
    for k in range(len(traj)):
        c = traj.configuration(k)
        for field in FIELDS:
            h.update(np.ascontiguousarray(getattr(c, field)).tobytes())
    s = traj.summary()
    h.update(repr({name: s[RENAMED.get(name, name)] for name in SUMMARY}).encode())


def digest(skin: str, rules: list[str], objects: list[str]) -> str:
    """The digest of the plans of every object, hand and rule set with this skin."""
    h = hashlib.sha256()
    for name in objects:
        for preset in HANDS:
            hand = None if preset is None else hugger.hands.preset(preset)
            case = scenarios.default_case(name, hand=hand)
            for rule in rules:
                update(h, hugger.plan(case.hand, case.obj, case.target, case.palm_pose, rules=rule, skin=skin))
    return h.hexdigest()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    builtins = list(hugger.objects.names())
    parser.add_argument("--skins", type=comma_names(["mesh", "section"], "skins"), default=["mesh", "section"],
                        help="comma-separated skins, of mesh, section (default mesh,section: one digest each)")
    parser.add_argument("--rules", type=comma_names(RULES, "rule sets"), default=["paper", "hug"],
                        help="comma-separated rule sets, of paper, hug (default paper,hug)")
    parser.add_argument("--objects", type=comma_names(builtins, "objects"), default=builtins,
                        help=f"comma-separated built-in objects, of {', '.join(builtins)} (default all of them)")
    parser.add_argument("--json", action="store_true", help="print JSON")
    args = parser.parse_args(argv)
    plans = len(args.objects) * len(HANDS) * len(args.rules)
    result = {skin: digest(skin, args.rules, args.objects) for skin in args.skins}
    if args.json:
        print(json.dumps({"plans_per_skin": plans, "digests": result}))
    else:
        for skin, d in result.items():
            print(f"{skin:8s} {d}  ({plans} plans)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
