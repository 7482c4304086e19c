"""The reference grasp: the 5x5 hand on a 4 cm sphere with T at its centre."""
from __future__ import annotations

import numpy as np

import hugger


def test_sphere_hug_has_palm_and_most_links_in_contact(tmp_path):
    hand = hugger.Hand(fingers=5, links=5, link_length=0.02, link_radius=0.004, palm_radius=0.03,
                       palm_thickness=0.01)
    obj = hugger.objects.sphere(radius=0.04, subdivisions=5)
    rot = np.array([[np.cos(0.8), 0, np.sin(0.8)], [0, 1, 0], [-np.sin(0.8), 0, np.cos(0.8)]])
    start = hugger.look_at([0.0, 0.0, 0.2], [0, 0, 0])
    start[:3, :3] = rot @ start[:3, :3]  # turned away from T, so Phase 1 has work to do
    planner = hugger.Planner(hand, obj, [0, 0, 0], start)
    traj = planner.plan()
    s = traj.summary(contact_distance=1e-3)
    assert traj.status == "done"
    assert s["phase1_configurations"] > 0
    assert s["palm_contact"], s
    assert s["links_in_contact"] >= 15, s
    # no link penetrates: every final gap is non-negative
    assert traj.link_gaps().min() >= 0.0
