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
    assert hugger.Planner(hand, obj, np.zeros(3), pose, rules=None).params["rules"] == "hug"  # None: the default
    for bad in ("Paper", "", 1):
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


def _root_angles(traj: hugger.Trajectory) -> np.ndarray:
    """(K, M): each finger's root joint angle (flexion positive) at every configuration."""
    return np.array([np.asarray(traj.configuration(k).angles)[:, 0] for k in range(len(traj))])


def test_h5_fingers_open_then_close_again_after_palm_contact(checker, tmp_path):
    """Hug rule H5 on a random fitting case (a sphere, 5 fingers): fingers turn their root
    joints back (open) before the palm lands, and after palm contact the same fingers close
    their root joints again; the paper's rules open none. The plan passes the checker, motion
    included."""
    kind, hand, obj, target, pose = hug_metrics.random_case(25)
    planner = hugger.Planner(hand, obj, target, pose)
    traj = planner.plan()
    stats = planner.stats
    assert stats["fingers_opened"] > 0 and stats["palm_contact_iteration"] >= 0 and stats["reclose_steps"] > 0, stats
    roots = _root_angles(traj)
    delta = traj.params["contact_tolerance"]
    first = next(k for k in range(len(traj)) if traj.palm_gap(k) <= delta)  # the palm lands
    opened = np.max(roots[: first + 1], axis=0) - roots[first]  # how far each root turned back before
    closed = np.max(roots[first:], axis=0) - roots[first]  # how far it closed again after
    both = (opened > 0.3) & (closed > 0.15)
    assert both.sum() >= 3, (opened, closed)
    helpers.save_and_check(checker, traj, tmp_path / "h5.npz", motion=True)
    paper = hugger.Planner(hand, obj, target, pose, rules="paper")
    paper.plan()
    assert paper.stats["fingers_opened"] == 0 and paper.stats["reclose_steps"] == 0


def test_h5_fingers_close_again_at_rest_without_palm_contact():
    """Hug rule H5 on the default box case: the palm never lands, and the opened fingers close
    their root joints again once the hand is at rest."""
    case = hugger.scenarios.default_case("box")
    planner = hugger.Planner(case.hand, case.obj, case.target, case.palm_pose)
    planner.plan()
    stats = planner.stats
    assert stats["palm_contact_iteration"] == -1 and stats["fingers_opened"] > 0 and stats["reclose_steps"] > 0, stats


def _retries_while_blocked(planner):
    """Step a plan to its end; per iteration whose palm stayed still although palm steps were
    asked (retries rose): the number of steps refused."""
    out, retries, palm = [], 0, None
    while (c := planner.step()) is not None:
        s = planner.stats
        if c.phase == 2 and palm is not None and s["sigma_retries"] > retries and np.array_equal(c.palm_pose, palm):
            out.append((s["phase2_iterations"], s["sigma_retries"] - retries))
        retries, palm = s["sigma_retries"], c.palm_pose
    return out


def test_a_blocked_hand_asks_the_shortest_palm_step_first():
    """The default cylinder case, whose fingers block the palm for many iterations: the first
    blocked iteration refuses every palm step down to the shortest, each one after it only the
    shortest (docs/algorithm.md, "Motion between configurations")."""
    case = hugger.scenarios.default_case("cylinder")
    blocked = _retries_while_blocked(hugger.Planner(case.hand, case.obj, case.target, case.palm_pose))
    runs = [b for a, b in zip(blocked, blocked[1:]) if b[0] == a[0] + 1]  # blocked after a blocked one
    assert len(runs) >= 10, blocked
    assert all(n == 1 for _, n in runs), blocked
    assert blocked[0][1] >= 4, blocked  # the whole ladder refused first: sigma, sigma/4, ...
