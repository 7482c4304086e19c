"""Planner.plan(timeout=...) and hugger.plan(..., timeout=...): a wall-clock bound on planning."""
from __future__ import annotations

import math

import numpy as np
import pytest

import helpers
import hugger

# Start clear of the sphere, turned away from T so that Phase 1 has work to do.
START = hugger.look_at([0.0, 0.0, 0.2], [0, 0, 0])


def slow_planner(hand, sphere):
    """A plan of thousands of iterations (a step 1/400 of a link): far longer than a millisecond."""
    return hugger.Planner(hand, sphere, [0, 0, 0], START, step=5e-5, contact_tolerance=1e-5, max_iterations=100000)


@pytest.mark.parametrize("bad", [0, 0.0, -1.0, float("nan"), float("inf"), -float("inf"), True, "1", [1.0]])
def test_bad_timeouts_are_refused(hand, sphere, bad):
    p = hugger.Planner(hand, sphere, [0, 0, 0], START)
    with pytest.raises(ValueError, match="timeout"):
        p.plan(timeout=bad)
    assert p.status == "running"  # nothing was planned
    with pytest.raises(ValueError, match="timeout"):
        hugger.plan(hand, sphere, [0, 0, 0], START, timeout=bad)


def test_core_refuses_bad_timeouts_too(hand, sphere):
    p = hugger.Planner(hand, sphere, [0, 0, 0], START)
    for bad in (0.0, -2.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="timeout"):
            p._core.plan(bad)


def test_generous_timeout_changes_nothing(hand, sphere):
    a = hugger.Planner(hand, sphere, [0, 0, 0], START).plan()
    b = hugger.Planner(hand, sphere, [0, 0, 0], START).plan(timeout=600)
    c = hugger.plan(hand, sphere, [0, 0, 0], START, timeout=600.0)
    assert a.status == b.status == c.status == "done"
    for t in (b, c):
        assert np.array_equal(a.joints, t.joints) and np.array_equal(a.palm_pose, t.palm_pose)
        assert np.array_equal(a.tip_state, t.tip_state)


def test_timeout_stops_with_a_valid_partial_trajectory(hand, sphere, checker, tmp_path):
    full = slow_planner(hand, sphere).plan()
    assert full.status == "done"
    planner = slow_planner(hand, sphere)
    part = planner.plan(timeout=1e-3)
    assert part.status == "timeout" == planner.status
    assert 1 <= len(part) < len(full)
    # the partial plan is the full plan's beginning, bit for bit (plans are deterministic)
    k = len(part)
    assert np.array_equal(part.joints, full.joints[:k]) and np.array_equal(part.palm_pose, full.palm_pose[:k])
    assert np.array_equal(part.tip_state, full.tip_state[:k])
    # a timed-out plan has ended: planning again or stepping adds nothing
    assert planner.plan().status == "timeout" and len(planner.trajectory()) == k
    assert planner.step() is None
    path = tmp_path / "partial.npz"
    part.save(path)
    assert hugger.Trajectory.load(path).status == "timeout"
    ok, failures, _ = helpers.check_file(checker, path, every=max(1, k // 40))
    assert ok, failures


def test_timeout_through_hugger_plan(hand, sphere):
    t = hugger.plan(hand, sphere, [0, 0, 0], START, timeout=1e-3, step=5e-5, contact_tolerance=1e-5,
                    max_iterations=100000)
    assert t.status == "timeout"
    assert math.isclose(t.params["step"], 5e-5)
