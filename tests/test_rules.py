"""The two rule sets of Phase 2: ``rules="paper"`` (the 1994 method with the documented
decisions) and ``rules="hug"`` (the default: extensions for firmer grasps on objects that fit).

A small sample of bench/hug_metrics.py's random fitting cases runs here; the full figures
(200 cases) come from ``python bench/hug_metrics.py --check``.
"""
from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

import helpers
import hugger

sys.path.insert(0, str(helpers.ROOT / "bench"))
import hug_metrics  # noqa: E402

SAMPLE = range(24)


def test_rules_parameter():
    hand = hugger.Hand()
    obj = hugger.objects.sphere(0.04, subdivisions=3)
    pose = hugger.scenarios.start_pose(obj, hand, np.zeros(3))
    assert hugger.Planner(hand, obj, np.zeros(3), pose).params["rules"] == "hug"
    assert hugger.Planner(hand, obj, np.zeros(3), pose, rules="paper").params["rules"] == "paper"
    for bad in ("Paper", "", None, 1):
        with pytest.raises(ValueError, match="rules must be one of"):
            hugger.Planner(hand, obj, np.zeros(3), pose, rules=bad)
    traj = hugger.Planner(hand, obj, np.zeros(3), pose, rules="paper").plan()
    assert traj.params["rules"] == "paper"  # recorded in params_json


@pytest.mark.parametrize("rules", ["paper", "hug"])
def test_plans_are_bit_identical(rules):
    kind, hand, obj, target, pose = hug_metrics.random_case(3)
    a = hugger.Planner(hand, obj, target, pose, rules=rules).plan()
    b = hugger.Planner(hand, obj, target, pose, rules=rules).plan()
    assert helpers.same(a, b)  # status, palm poses, joints, angles and TipStates


def test_fitting_cases_fit():
    for seed in SAMPLE:
        kind, hand, obj, target, pose = hug_metrics.random_case(seed)
        # the object was centred on its own bounding box, then rotated about the origin: its
        # farthest vertex is within that box's half-diagonal, sqrt(3)/2 x its largest extent
        assert 2 * np.linalg.norm(obj.vertices, axis=1).max() <= np.sqrt(3) * 1.6 * hand.reach * (1 + 1e-9)
        assert obj.inside(target)


def test_hug_rules_hug_firmer_than_the_papers(checker):
    """On a sample of fitting objects, the hug rules put more links and the palm in contact;
    every plan of both rule sets passes the checker (motion included) and ends done or stalled."""
    rows = {r: [hug_metrics.run_case(seed, r, checker) for seed in SAMPLE] for r in ("paper", "hug")}
    for r, rs in rows.items():
        assert all(x["checker"] for x in rs), [x for x in rs if not x["checker"]]
        assert all(x["status"] in ("done", "stalled") for x in rs), r
    paper, hug = (hug_metrics.summarize(rows[r]) for r in ("paper", "hug"))
    assert hug["mean_links_in_contact"] >= paper["mean_links_in_contact"] + 0.1, (paper, hug)
    assert hug["palm_contact"] >= paper["palm_contact"] + 0.2, (paper, hug)
    assert hug["plans_with_30pct_links"] >= 0.8, hug


def test_cli_rules(tmp_path):
    out = tmp_path / "p.npz"
    r = subprocess.run([sys.executable, "-m", "hugger", "plan", "sphere", "--rules", "paper", "--out", str(out), "--json"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout)["status"] in ("done", "stalled")
    assert hugger.Trajectory.load(out).params["rules"] == "paper"
    r = subprocess.run([sys.executable, "-m", "hugger", "plan", "sphere", "--rules", "nope", "--out", str(out)],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "--rules" in r.stderr
