"""The hand: construction, counts and sizes, their refusals and warnings, kinematics."""
from __future__ import annotations

import json
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

import hugger
from helpers import BAD_POSES, no_warnings, start
from hugger.hand import MAX_FINGERS, MAX_LENGTH, MAX_LINKS, MIN_LENGTH

HERE = Path(__file__).resolve()


# --- hand ---------------------------------------------------------------------------------

def test_hand_properties_and_json(hand):
    assert hand.fingers == 5 and hand.links == 5
    assert hand.link_lengths.shape == (5, 5) and np.all(hand.link_lengths == 0.02)
    d = hand.to_dict()
    assert hugger.Hand.from_dict(d).to_dict() == d
    per_link = hugger.Hand(fingers=2, links=3, link_length=[[0.01, 0.02, 0.03], [0.03, 0.02, 0.01]], link_radius=0)
    assert per_link.link_lengths[1, 0] == 0.03


def test_hand_json_is_its_dict_and_follows_its_name():
    # to_json is made once per hand and name (every trajectory records it): it must still be
    # to_dict's text, and follow a name given after the hand was made (as presets do).
    hand = hugger.Hand(fingers=3, links=2)
    assert json.loads(hand.to_json()) == hand.to_dict() and "name" not in hand.to_dict()
    assert hand.to_json() is hand.to_json()
    hand.name = "mine"
    assert json.loads(hand.to_json())["name"] == "mine"
    hand.name = None
    assert json.loads(hand.to_json()) == hugger.Hand(fingers=3, links=2).to_dict()


@pytest.mark.parametrize("kwargs, match", [
    ({"fingers": 0}, "fingers"),
    ({"fingers": 2.5}, "fingers"),
    ({"links": -1}, "links"),
    ({"link_length": 0.0}, "link_length"),
    ({"link_length": -0.02}, "link_length"),
    ({"link_length": np.ones((2, 2))}, "link_length"),
    ({"link_radius": -0.001}, "link_radius"),
    ({"link_radius": float("nan")}, "link_radius"),
    ({"palm_radius": 0}, "palm_radius"),
    ({"palm_thickness": -1}, "palm_thickness"),
    ({"palm_radius": "big"}, "palm_radius"),
])
def test_hand_rejects_bad_sizes(kwargs, match):
    with pytest.raises(ValueError, match=match):
        hugger.Hand(**kwargs)


def test_forward_and_inverse_kinematics(hand):
    rng = np.random.default_rng(0)
    pose = start()
    angles = rng.uniform(-1, 1, size=(5, 5))
    joints = hand.forward(pose, angles)
    assert joints.shape == (5, 6, 3)
    np.testing.assert_allclose(joints[:, 0], hand.roots(pose), atol=1e-15)
    np.testing.assert_allclose(hand.angles_from_joints(pose, joints), angles, atol=1e-12)


# --- implausible sizes: a UserWarning, pointing at the caller --------------------------------

def test_hand_in_millimetres_warns_at_the_caller():
    with pytest.warns(UserWarning, match="millimetres") as rec:
        hugger.Hand(link_length=20.0, link_radius=4.0, palm_radius=30.0, palm_thickness=10.0)
    assert len(rec) == 1 and rec[0].filename == str(HERE)
    with pytest.warns(UserWarning, match="small"):
        hugger.Hand(fingers=3, links=2, link_length=2e-4, link_radius=0, palm_radius=3e-4, palm_thickness=1e-4)
    no_warnings(hugger.Hand)


# --- hands: counts, sizes, huge M and N --------------------------------------------------------

@pytest.mark.parametrize("kwargs, match", [
    ({"fingers": -3}, "fingers"),
    ({"links": 0}, "links"),
    ({"fingers": "5"}, "fingers must be a whole number"),
    ({"links": None}, "links must be a whole number"),
    ({"fingers": np.float64(5)}, "fingers must be a whole number"),
    ({"link_length": "long"}, "link_length must be an array of real numbers"),
    ({"link_length": 0.02 + 1j}, "link_length must be an array of real numbers"),
    ({"link_length": None}, "link_length"),
    ({"link_length": np.full((5, 5), 0.02) * [1, 1, -1, 1, 1]}, "link_length must be a positive"),
    ({"link_length": np.where(np.eye(5) > 0, np.nan, 0.02)}, "link_length must be a positive finite"),
    ({"link_length": 0.5 * MIN_LENGTH, "link_radius": 0}, "smaller than"),
    ({"link_length": 2 * MAX_LENGTH}, "larger than"),
    ({"link_radius": 2 * MAX_LENGTH}, "link_radius .* larger than"),
    ({"palm_radius": float("inf")}, "palm_radius"),
    ({"palm_thickness": 0.5 * MIN_LENGTH}, "palm_thickness .* smaller than"),
    ({"palm_thickness": True}, "palm_thickness must be a number"),
    ({"link_radius": [0.001]}, "link_radius must be a number"),
    ({"link_radius": 0.011}, "exceed twice link_radius"),
    ({"link_radius": 0.03, "link_length": 0.1, "links": 2}, "smaller than palm_radius"),
    ({"fingers": 32, "link_radius": 0.004}, "too close"),
])
def test_hand_refuses_bad_counts_and_sizes(kwargs, match):
    with pytest.raises(ValueError, match=match):
        hugger.Hand(**kwargs)


@pytest.mark.parametrize("kwargs, match", [
    ({"fingers": 10 ** 6}, f"fingers must be between 1 and {MAX_FINGERS}"),
    ({"links": 10 ** 6}, f"links must be between 1 and {MAX_LINKS}"),
    ({"fingers": 10 ** 6, "links": 10 ** 6}, "fingers must be between"),
    ({"fingers": 10 ** 100}, "fingers must be between"),
    ({"fingers": MAX_FINGERS + 1, "link_radius": 0}, "fingers must be between"),
    ({"links": MAX_LINKS + 1}, "links must be between"),
])
def test_huge_hands_are_refused_before_anything_is_allocated(kwargs, match):
    tracemalloc.start()
    try:
        with pytest.raises(ValueError, match=match):
            hugger.Hand(**kwargs)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 1 << 20  # under 1 MB: no (M, N) array was built


def test_the_largest_allowed_hand_works(sphere):
    h = hugger.Hand(fingers=MAX_FINGERS, links=4, link_length=0.02, link_radius=0.0005, palm_radius=0.03)
    p = hugger.Planner(h, sphere, [0, 0, 0], start(), max_iterations=3)
    traj = p.plan()  # the approach before the first contact emits several configurations per iteration
    assert traj.joints.shape[1:] == (MAX_FINGERS, 5, 3) and p.stats["phase2_iterations"] == 3


def test_hand_from_dict_places_fingers_at_the_given_finger_angles():
    # finger_angles (docs/file-format.md) without the other layout keys was dropped: the fingers
    # stayed at 2 pi m / M, and a list of the wrong length was accepted.
    d = hugger.Hand(fingers=3, links=2).to_dict()
    assert hugger.Hand.from_dict(d).same_as(hugger.Hand(fingers=3, links=2))  # the default angles: the rim hand
    for tol in (-1.0, float("nan")):
        with pytest.raises(ValueError, match="tol must be a non-negative finite number"):
            hugger.Hand().same_as(hugger.Hand(), tol)
    angles = [0.0, 0.5 * np.pi, np.pi]
    h = hugger.Hand.from_dict({**d, "finger_angles": angles})
    np.testing.assert_allclose(h.finger_roots, 0.03 * np.stack([np.cos(angles), np.sin(angles), np.zeros(3)], axis=1),
                               atol=1e-12)
    with pytest.raises(ValueError, match="finger_angles must hold 3 angles"):
        hugger.Hand.from_dict({**d, "finger_angles": [0.0, 1.0]})
    with pytest.raises(ValueError, match="finger_angles"):
        hugger.Hand.from_dict({**d, "finger_angles": ["a", "b", "c"]})


def test_hand_from_dict_refuses_incomplete_descriptions(hand):
    d = hand.to_dict()
    for key in ("fingers", "link_lengths", "palm_thickness"):
        with pytest.raises(ValueError, match=key):
            hugger.Hand.from_dict({k: v for k, v in d.items() if k != key})
    with pytest.raises(ValueError, match="dict"):
        hugger.Hand.from_dict([1, 2, 3])
    assert hugger.Hand.from_dict({**d, "fingers": 5.0}).fingers == 5  # JSON may write 5.0


# --- palm poses that are not rigid -------------------------------------------------------------

@pytest.mark.parametrize("pose, match", BAD_POSES + [(np.full((4, 4), "x"), "real numbers"),
                                                     (start().astype(complex), "real numbers")])
def test_kinematics_refuses_non_rigid_palm_poses(hand, pose, match):
    with pytest.raises(ValueError, match=match):
        hand.forward(pose, np.zeros((5, 5)))
    with pytest.raises(ValueError, match=match):
        hand.roots(pose)


def test_kinematics_refuses_bad_angles_and_joints(hand):
    with pytest.raises(ValueError, match="non-finite"):
        hand.forward(start(), np.full((5, 5), np.nan))
    with pytest.raises(ValueError, match=r"\(5, 5\)"):
        hand.forward(start(), np.zeros((5, 4)))
    with pytest.raises(ValueError, match="real numbers"):
        hand.forward(start(), np.zeros((5, 5), dtype=complex))
    with pytest.raises(ValueError, match=r"\(5, 6, 3\)"):
        hand.angles_from_joints(start(), np.zeros((5, 5, 3)))
    with pytest.raises(ValueError, match="non-finite"):
        hand.angles_from_joints(start(), np.full((5, 6, 3), np.inf))
