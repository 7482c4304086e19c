"""hugger.analysis: contacts over the palm and every link, wrap angles, grasp wrench space."""
from __future__ import annotations

import builtins
import itertools
import dataclasses
import json
import math
import subprocess
import sys

import numpy as np
import pytest

import hugger
import hugger.analysis as A
from helpers import random_rotation

DIST = 1e-3  # contact distance (m) used throughout, as in Trajectory.summary()


# --- fixtures and helpers ----------------------------------------------------------------------

@pytest.fixture(scope="module")
def reference_plan(fine_sphere_plan, fine_sphere):
    """The reference plan (conftest's fine_sphere_plan: the 5x5 hand around the 4 cm sphere,
    approaching from +z) and its object."""
    return fine_sphere_plan, fine_sphere


@pytest.fixture(scope="module")
def sphere_contacts(reference_plan):
    traj, obj = reference_plan
    return A.contacts(traj, -1, DIST, obj)


def point_segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance of points p (n, 3) to segments [a_i, b_i] (n, 3)."""
    ab = b - a
    t = np.clip(np.einsum("ij,ij->i", p - a, ab) / np.einsum("ij,ij->i", ab, ab), 0.0, 1.0)
    return np.linalg.norm(p - (a + t[:, None] * ab), axis=1)


def point_palm_distance(p: np.ndarray, pose: np.ndarray, radius: float, thickness: float) -> np.ndarray:
    """Distance of points p (n, 3) to the solid palm cylinder: front face at the pose origin, body
    behind it (local z in [-thickness, 0]), docs/model.md."""
    q = (p - pose[:3, 3]) @ pose[:3, :3]
    rho = np.hypot(q[:, 0], q[:, 1])
    dr = np.maximum(rho - radius, 0.0)
    dz = np.maximum(np.maximum(q[:, 2], -thickness - q[:, 2]), 0.0)
    return np.hypot(dr, dz)


def one_configuration(hand: dict, obj: hugger.Object, palm_pose, joints, target) -> hugger.Trajectory:
    """A one-configuration trajectory of a hand-made configuration: joints placed by hand, which
    no hand's kinematics gives (its angles are zeros), so made directly, not by from_arrays,
    which checks a file's angles against its joints."""
    m, n1 = np.asarray(joints).shape[:2]
    hand = {**hand, "link_lengths": np.linalg.norm(np.diff(np.asarray(joints), axis=1), axis=2).tolist()}
    data = {
        "hand_json": json.dumps(hand),
        "params_json": "{}",
        "status": "done",
        "object_vertices": obj.vertices,
        "object_faces": obj.faces,
        "target": np.asarray(target, dtype=float),
        "palm_pose": np.asarray(palm_pose, dtype=float)[None],
        "joints": np.asarray(joints, dtype=float)[None],
        "angles": np.zeros((1, m, n1 - 1)),
        "tip_state": np.full((1, m), 2, dtype=np.int8),
        "phase": np.zeros(1, dtype=np.int8),
    }
    return hugger.Trajectory(**data)


def hand_dict(fingers=1, links=1, link_radius=0.004, palm_radius=0.03, palm_thickness=0.01) -> dict:
    return {"fingers": fingers, "links": links, "link_lengths": [[0.02] * links] * fingers,
            "link_radius": link_radius, "palm_radius": palm_radius, "palm_thickness": palm_thickness,
            "finger_angles": [2 * math.pi * i / fingers for i in range(fingers)]}


def axis_contacts() -> A.Contacts:
    """Six contacts at +-x, +-y, +-z on the unit sphere (outward normals = positions)."""
    p = np.concatenate([np.eye(3), -np.eye(3)])
    return A.Contacts.from_arrays(p, p)


def epsilon_by_enumeration(w: np.ndarray) -> float:
    """Ferrari-Canny epsilon of the hull of the points w (P, 6), without Qhull: enumerate every
    hyperplane through 6 of the points, keep those with all points on one side (the supporting
    hyperplanes, i.e. the facets' planes) and return the origin's smallest distance to one."""
    idx = np.array(list(itertools.combinations(range(len(w)), 6)))
    pts = w[idx]
    edges = pts[:, 1:] - pts[:, :1]  # (S, 5, 6)
    # normal of the hyperplane through the 6 points: the generalised cross product of the 5 edges
    normal = np.stack([(-1) ** i * np.linalg.det(np.delete(edges, i, axis=2)) for i in range(6)], axis=1)
    length = np.linalg.norm(normal, axis=1)
    spans = length > 1e-9  # the 6 points span a hyperplane
    normal = normal[spans] / length[spans, None]
    offset = np.einsum("ij,ij->i", normal, pts[spans, 0])
    side = w @ normal.T - offset
    below, above = (side <= 1e-9).all(axis=0), (side >= -1e-9).all(axis=0)
    dist = np.where(below, offset, -offset)  # signed distance of the origin, inward positive
    return float(dist[below | above].min())


# --- grasp wrench space: known answers --------------------------------------------------------

def test_primitive_wrenches_push_into_the_object():
    # One contact at p = (0.02, 0, 0.04) with outward normal +z, torques about the origin, scale 0.04.
    p, n = np.array([[0.02, 0.0, 0.04]]), np.array([[0.0, 0.0, 1.0]])
    w = A.primitive_wrenches(p, n, np.zeros(3), 0.0, 8, 0.04)
    # frictionless: f = -n, tau = p x f / 0.04 = (0, 0.02, 0) / 0.04
    assert w == pytest.approx(np.array([[0.0, 0.0, -1.0, 0.0, 0.5, 0.0]]))
    w = A.primitive_wrenches(p, n, np.zeros(3), 0.5, 4, 0.04)
    f = w[:, :3]
    assert w.shape == (4, 6)
    assert np.allclose(f[:, 2], -1.0)  # unit normal force, into the object
    assert np.allclose(np.hypot(f[:, 0], f[:, 1]), 0.5)  # on the friction cone's edge
    assert np.allclose(f.mean(axis=0), [0, 0, -1])  # edges evenly around the normal
    assert np.allclose(w[:, 3:], np.cross(p, f) / 0.04)


@pytest.mark.parametrize("mu", [0.2, 0.5, 1.0, 2.0])
def test_epsilon_of_symmetric_sphere_grasp_closed_form(mu):
    # Six contacts at p = a for the signed unit axes a of the unit sphere, torques about its centre,
    # torque scale 1, cone_edges = 4. The force at p = a pushes along d = -a; by the documented tangent
    # rule (t1 = d x e_k, e_k the world axis least aligned with d; t2 = d x t1) its cone edges point
    # along the other two axes, so the contact's 4 primitive wrenches are, for b a signed axis orthogonal to a,
    #     w(a, b) = (f, p x f) = (-a + mu b, a x (-a + mu b)) = (-a + mu b, mu a x b),
    # 24 wrenches in all.
    # Upper bound: take the unit direction u* = (0, g), g = (1, 1, 1)/sqrt(3). Each a x b is a signed
    # unit axis, so u*.w = mu g.(a x b) <= mu/sqrt(3), with equality for the 12 wrenches whose a x b is
    # +e_x, +e_y or +e_z. So the hyperplane u*.w = mu/sqrt(3) supports the GWS: epsilon <= mu/sqrt(3).
    # Lower bound: no facet is nearer. The 12 wrenches above span that hyperplane (their forces
    # -a + mu b take 4 independent directions per torque axis), so it is a facet; and
    # epsilon_by_enumeration, which checks every hyperplane through 6 of the 24 wrenches without
    # Qhull, finds the same value (test below). Hence epsilon = mu / sqrt(3) for every mu; the
    # volume is 5/16 at mu = 1/2.
    expected = mu / math.sqrt(3.0)
    q = A.grasp_quality(axis_contacts(), [0.0, 0.0, 0.0], mu=mu, cone_edges=4, torque_scale=1.0)
    assert q.force_closure
    assert q.wrenches == 24
    assert q.epsilon == pytest.approx(expected, rel=1e-7)
    if mu == 0.5:
        assert q.volume == pytest.approx(5.0 / 16.0, rel=1e-7)


@pytest.mark.parametrize("mu", [0.5, 2.0])
def test_epsilon_of_symmetric_sphere_grasp_by_facet_enumeration(mu):
    w = A.primitive_wrenches(axis_contacts().points, axis_contacts().normals, np.zeros(3), mu, 4, 1.0)
    assert w.shape == (24, 6)
    assert epsilon_by_enumeration(w) == pytest.approx(mu / math.sqrt(3.0), rel=1e-9)


def test_frictionless_sphere_grasp_is_not_force_closure():
    # Every normal of a sphere passes through its centre: no contact can exert a torque about it,
    # so the frictionless GWS is flat (3D): no force closure, epsilon 0, volume 0, no exception.
    q = A.grasp_quality(axis_contacts(), [0.0, 0.0, 0.0], mu=0.0, torque_scale=1.0)
    assert (q.force_closure, q.epsilon, q.volume) == (False, 0.0, 0.0)


def test_one_sided_grasp_has_no_force_closure():
    # Contacts on a polar cap (polar angle <= 45 deg) of a sphere. Each pushes along -n with
    # n_z >= cos 45 deg; with mu = 0.5 the tangential part adds at most 0.5 sin 45 deg to f_z, so
    # every wrench has f_z < 0: the origin is outside the GWS.
    rng = np.random.default_rng(3)
    polar = np.radians(rng.uniform(0, 45, 14))
    azim = rng.uniform(0, 2 * np.pi, 14)
    n = np.column_stack([np.sin(polar) * np.cos(azim), np.sin(polar) * np.sin(azim), np.cos(polar)])
    q = A.grasp_quality(A.Contacts.from_arrays(0.04 * n, n), [0.0, 0.0, 0.0], mu=0.5)
    assert not q.force_closure
    assert q.epsilon == 0.0
    assert q.volume > 0.0  # a full-dimensional hull, so this is the "origin outside" case
    assert q.torque_scale == pytest.approx(0.04)  # no object: the contacts' largest distance from center


@pytest.mark.parametrize("points", [np.zeros((0, 3)), np.array([[0.04, 0.0, 0.0]])])
def test_too_few_contacts_give_zero_quality(points):
    q = A.grasp_quality(A.Contacts.from_arrays(points, points + 1.0), [0.0, 0.0, 0.0], mu=0.0, torque_scale=0.04)
    assert (q.force_closure, q.epsilon, q.volume) == (False, 0.0, 0.0)


def random_grasp(seed: int, count: int = 10) -> tuple[A.Contacts, hugger.Object]:
    """Contacts at random points of an ellipsoid, with its normals."""
    obj = hugger.objects.ellipsoid((0.05, 0.035, 0.025), subdivisions=3)
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(count, 3))
    near = obj.closest(d / np.linalg.norm(d, axis=1, keepdims=True) * 0.1)
    return A.Contacts.from_arrays(near["point"], near["normal"]), obj


def test_volume_and_epsilon_non_decreasing_in_mu():
    grasp, obj = random_grasp(1)
    mus = [0.0, 0.1, 0.25, 0.5, 0.8, 1.2]
    qs = [A.grasp_quality(grasp, [0.0, 0.0, 0.0], mu=mu, cone_edges=6, obj=obj) for mu in mus]
    vol = np.array([q.volume for q in qs])
    eps = np.array([q.epsilon for q in qs])
    # Joggled Qhull input moves figures by ~1e-10 relative: allow that much, no more.
    assert np.all(np.diff(vol) >= -1e-9 * vol[1:]), vol
    assert np.all(np.diff(eps) >= -1e-9), eps
    assert vol[-1] > 10 * vol[1] > 0.0
    assert eps[-1] > eps[1] > 0.0


def test_epsilon_invariant_under_rotation_frictionless():
    grasp, _ = random_grasp(2, count=12)
    rng = np.random.default_rng(7)
    q0 = A.grasp_quality(grasp, [0.0, 0.0, 0.0], mu=0.0, torque_scale=0.05)
    assert q0.force_closure and q0.epsilon > 0  # non-vacuous
    for _ in range(3):
        r = random_rotation(rng)
        turned = A.Contacts.from_arrays(grasp.points @ r.T, grasp.normals @ r.T)
        q = A.grasp_quality(turned, [0.0, 0.0, 0.0], mu=0.0, torque_scale=0.05)
        assert q.epsilon == pytest.approx(q0.epsilon, rel=1e-7)
        assert q.volume == pytest.approx(q0.volume, rel=1e-7)


def test_epsilon_invariant_under_symmetry_rotation_with_friction():
    # A signed permutation with det +1 maps the axis grasp and its axis-aligned cone edges onto
    # themselves, so with friction too epsilon must not change at all (up to joggle).
    rng = np.random.default_rng(11)
    grasp, _ = random_grasp(4, count=8)
    r = np.eye(3)[[2, 0, 1]] * np.array([1.0, -1.0, -1.0])[:, None]
    assert np.linalg.det(r) == pytest.approx(1.0)
    shift = rng.normal(size=3) * 0.01  # and translate everything, center included
    for contacts in (axis_contacts(), grasp):
        q0 = A.grasp_quality(contacts, [0.0, 0.0, 0.0], mu=0.4, cone_edges=8, torque_scale=0.05)
        turned = A.Contacts.from_arrays(contacts.points @ r.T + shift, contacts.normals @ r.T)
        q = A.grasp_quality(turned, shift, mu=0.4, cone_edges=8, torque_scale=0.05)
        assert q0.epsilon > 0
        assert q.epsilon == pytest.approx(q0.epsilon, rel=1e-7)
        assert q.volume == pytest.approx(q0.volume, rel=1e-7)


def test_epsilon_under_any_rotation_stays_within_the_cone_linearisation():
    # An E-edge cone of friction mu lies between the circular cones of mu cos(pi/E) and mu, whatever
    # its turn about the normal; epsilon grows with the cones and is rotation invariant for circular
    # cones. So eps(mu cos(pi/E)) <= eps(mu, rotated) <= eps(mu / cos(pi/E)).
    grasp, _ = random_grasp(5, count=8)
    e, mu = 6, 0.5
    c = math.cos(math.pi / e)
    lo = A.grasp_quality(grasp, np.zeros(3), mu=mu * c, cone_edges=e, torque_scale=0.05).epsilon
    hi = A.grasp_quality(grasp, np.zeros(3), mu=mu / c, cone_edges=e, torque_scale=0.05).epsilon
    assert 0 < lo < hi
    r = random_rotation(np.random.default_rng(9))
    turned = A.Contacts.from_arrays(grasp.points @ r.T, grasp.normals @ r.T)
    eps = A.grasp_quality(turned, np.zeros(3), mu=mu, cone_edges=e, torque_scale=0.05).epsilon
    assert lo - 1e-9 <= eps <= hi + 1e-9


def test_scaling_object_and_torque_scale_leaves_quality_unchanged():
    grasp, obj = random_grasp(6)
    centre = np.array([0.004, -0.002, 0.001])
    q0 = A.grasp_quality(grasp, centre, mu=0.5, obj=obj)
    assert q0.force_closure
    assert q0.torque_scale == pytest.approx(np.linalg.norm(obj.vertices - centre, axis=1).max())
    for s in (0.1, 3.0):
        big = hugger.Object(obj.vertices * s, obj.faces)
        scaled = A.Contacts.from_arrays(grasp.points * s, grasp.normals)
        q = A.grasp_quality(scaled, centre * s, mu=0.5, obj=big)
        assert q.torque_scale == pytest.approx(q0.torque_scale * s, rel=1e-12)
        assert q.epsilon == pytest.approx(q0.epsilon, rel=1e-7)
        assert q.volume == pytest.approx(q0.volume, rel=1e-7)


# --- contacts ---------------------------------------------------------------------------------

def test_contacts_of_real_plan_lie_on_surface_and_on_their_link(reference_plan, sphere_contacts, hand):
    traj, obj = reference_plan
    c = sphere_contacts
    r = hand.link_radius
    assert len(c) > 0 and c.points.shape == (len(c), 3)
    # on the surface
    assert np.abs(obj.signed_distance(c.points)).max() < 1e-9
    # outward unit normals (a sphere about the origin: along the position)
    assert np.allclose(np.linalg.norm(c.normals, axis=1), 1.0)
    radial = c.points / np.linalg.norm(c.points, axis=1, keepdims=True)
    assert np.einsum("ij,ij->i", c.normals, radial).min() > 0.99
    # within distance + r of the link axis it is assigned to
    links = c.finger >= 0
    j = traj.joints[-1]
    a, b = j[c.finger[links], c.link[links]], j[c.finger[links], c.link[links] + 1]
    assert point_segment_distance(c.points[links], a, b).max() <= r + DIST + 1e-9
    # within distance of the palm when assigned to it
    assert c.palm_contact
    palm = point_palm_distance(c.points[~links], traj.palm_pose[-1], hand.palm_radius, hand.palm_thickness)
    assert 1 <= palm.size <= 8
    assert palm.max() <= DIST + 1e-9
    # gaps: in reach, and no penetration beyond the collision tolerance of docs/validation.md
    assert c.gap.max() <= DIST + 1e-9
    assert c.gap.min() >= -max(0.02 * r, 5e-5)


@pytest.mark.parametrize("distance", [DIST, 2.5e-3])
def test_contacts_agree_with_trajectory_summary(reference_plan, distance):
    traj, obj = reference_plan
    c = A.contacts(traj, -1, distance, obj)
    s = traj.summary(contact_distance=distance)
    assert c.links_in_contact == s["links_in_contact"]
    assert c.palm_contact == s["palm_contact"]
    touching = {tuple(x) for x in np.argwhere(traj.link_gaps(-1, obj) <= distance).tolist()}
    assert {(int(f), int(n)) for f, n in zip(c.finger, c.link) if f >= 0} == touching
    per = c.per_finger()
    assert per.shape == (5,) and per.sum() == s["links_in_contact"]
    # each link in contact gives one or two contacts per run; both ends of a run are distinct
    for f, n in touching:
        assert 1 <= np.count_nonzero((c.finger == f) & (c.link == n)) <= 4


def test_link_along_a_face_contributes_its_interval_ends():
    # A box top face z = 0.02 over x in [-0.03, 0.03]. A link parallel to it, 0.5 mm above its
    # surface (axis at r + 0.5 mm), from x = 0.01 to x = 0.05: the contact run starts at the tail
    # and ends just past the edge, where the nearest surface point is on the edge x = 0.03.
    box = hugger.objects.box((0.06, 0.06, 0.04))
    r = 0.004
    z = 0.02 + r + 0.0005
    joints = np.array([[[0.01, 0.0, z], [0.05, 0.0, z]]])
    pose = hugger.look_at([0.0, 0.0, 0.3], [0.0, 0.0, 0.4])  # palm far away, facing away
    c = A.contacts_of(hand_dict(link_radius=r), box, pose, joints, DIST)
    assert len(c) == 2 and not c.palm_contact and c.links_in_contact == 1
    assert c.points[0] == pytest.approx([0.01, 0.0, 0.02], abs=1e-9)
    assert c.points[1] == pytest.approx([0.03, 0.0, 0.02], abs=1e-9)
    assert c.gap[0] == pytest.approx(0.0005, abs=1e-9)
    assert 0.0005 < c.gap[1] <= DIST
    assert np.allclose(c.normals[0], [0, 0, 1])
    # a link whose whole axis is out of reach has no contacts
    far = A.contacts_of(hand_dict(link_radius=r), box, pose, joints + [0, 0, 0.01], DIST)
    assert len(far) == 0 and far.links_in_contact == 0 and far.per_finger().tolist() == [0]


def test_palm_flat_on_a_face_gives_the_extremes_of_the_touching_disc():
    box = hugger.objects.box((0.1, 0.1, 0.04))
    h = hand_dict(palm_radius=0.03)
    pose = hugger.look_at([0.0, 0.0, 0.0205], [0.0, 0.0, 0.0])  # front face 0.5 mm above the top face
    joints = np.array([[[0.0, 0.0, 0.2], [0.0, 0.0, 0.22]]])  # finger out of the way
    c = A.contacts_of(h, box, pose, joints, DIST)
    assert c.palm_contact and len(c) == 8 and c.links_in_contact == 0
    assert np.all(c.finger == -1) and np.all(c.link == -1)
    assert np.allclose(c.points[:, 2], 0.02, atol=1e-9)
    assert np.allclose(np.hypot(c.points[:, 0], c.points[:, 1]), 0.03, atol=1e-9)
    assert np.allclose(c.gap, 0.0005, atol=1e-9)
    assert np.allclose(c.normals, [0, 0, 1])
    # out of reach: no palm contact
    lifted = hugger.look_at([0.0, 0.0, 0.0225], [0.0, 0.0, 0.0])
    assert not A.contacts_of(h, box, lifted, joints, DIST).palm_contact


def test_link_nearest_approach_between_samples_still_counts():
    # A link crossing a box's ridge at 45 deg to both faces, its axis r + 0.998 mm from the ridge at a
    # point midway between two axis samples (1 mm apart): the samples, 0.5 mm either side, are
    # sqrt(4.998^2 + 0.5^2) - 4 = 1.023 mm away, out of reach; the link still counts (as in
    # Trajectory.link_gaps) and its one contact is the ridge point nearest the axis.
    box = hugger.objects.box((0.06, 0.06, 0.04))
    r = 0.004
    ridge, out, along = np.array([0.03, 0.0, 0.02]), np.array([1.0, 0, 1]) / 2 ** 0.5, np.array([1.0, 0, -1]) / 2 ** 0.5
    near = ridge + (r + DIST - 2e-6) * out
    joints = np.array([[near - 0.0105 * along, near + 0.0095 * along]])
    pose = hugger.look_at([0.0, 0.0, 0.3], [0.0, 0.0, 0.4])
    c = A.contacts_of(hand_dict(link_radius=r), box, pose, joints, DIST)
    assert len(c) == 1 and c.links_in_contact == 1
    assert c.points[0] == pytest.approx(ridge, abs=1e-8)
    assert c.gap[0] == pytest.approx(DIST - 2e-6, abs=1e-9)


def test_palm_nearest_approach_between_samples_still_counts():
    # A box whose vertical edge points at the palm's axis, 0.998 mm outside its rim, at an angle
    # midway between two rim samples (2 pi / 189 apart for a 3 cm palm): the samples miss, the
    # palm's gap is within reach, so the palm gets one contact on that edge.
    radius, gap = 0.03, DIST - 2e-6
    angle = math.pi / math.ceil(2 * math.pi * radius / 1e-3)
    side = 0.02
    turn = lambda a: np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])  # noqa: E731
    block = hugger.objects.box((side, side, 0.05))
    v = block.vertices @ turn(math.pi / 4).T + [side / 2 ** 0.5 + radius + gap, 0.0, 0.0]
    obj = hugger.Object(v @ turn(angle).T, block.faces)
    joints = np.array([[[0.0, 0.0, 0.2], [0.0, 0.0, 0.22]]])
    c = A.contacts_of(hand_dict(palm_radius=radius), obj, np.eye(4), joints, DIST)
    assert len(c) == 1 and c.palm_contact
    assert c.gap[0] == pytest.approx(gap, abs=1e-8)
    assert c.points[0, :2] == pytest.approx((radius + gap) * np.array([math.cos(angle), math.sin(angle)]), abs=1e-8)
    assert -0.01 <= c.points[0, 2] <= 0.0  # beside the palm's rim


def test_zero_radius_links():
    box = hugger.objects.box((0.06, 0.06, 0.04))
    joints = np.array([[[0.0, 0.0, 0.0205], [0.01, 0.0, 0.0205]]])
    pose = hugger.look_at([0.0, 0.0, 0.3], [0.0, 0.0, 0.4])
    c = A.contacts_of(hand_dict(link_radius=0.0), box, pose, joints, DIST)
    assert len(c) == 2 and np.allclose(c.gap, 0.0005, atol=1e-9)


# --- wrap angle -------------------------------------------------------------------------------

def test_wrap_angle_of_a_finger_from_pole_to_equator_is_90_degrees():
    # One finger of 6 links whose joints lie on the circle of radius R + r about T = 0 in the
    # finger plane (xz: u_0 = x, p = z), from the pole (90 deg) down to the equator (0 deg). Every
    # link touches; the first contact is at the pole and the last at the equator.
    obj = hugger.objects.sphere(radius=0.04, subdivisions=5)
    r = 0.002
    ang = np.radians(np.linspace(90.0, 0.0, 7))
    joints = (0.04 + r) * np.column_stack([np.cos(ang), np.zeros(7), np.sin(ang)])[None]
    pose = np.eye(4)
    pose[:3, 3] = [0.0, 0.0, 0.3]  # x axis = u_0, z axis = p; the palm is far from the sphere
    traj = one_configuration(hand_dict(links=6, link_radius=r), obj, pose, joints, [0.0, 0.0, 0.0])
    found = A.contacts(traj)
    assert found.links_in_contact == 6
    w = A.wrap_angle(traj, found=found)
    assert w.shape == (1,)
    assert w[0] == pytest.approx(90.0, abs=0.5)
    assert A.wrap_angle(traj)[0] == w[0]


def test_penetration_is_the_deepest_point_of_a_link_not_of_its_contacts():
    # a straight 2-link finger of 8 cm links whose second link runs through a 4 cm sphere at
    # x = 3 cm: its contacts (the ends of its touching run) lie outside, 0.6 mm off the surface,
    # and its middle 14 mm deep, which the contacts' gaps did not show
    hand = hugger.Hand(fingers=1, links=2, link_length=0.08, palm_radius=0.03)
    obj = hugger.objects.sphere(0.04, subdivisions=4)
    pose = hugger.look_at([0, 0, 0.12], [0, 0, 0])
    joints = hand.forward(pose, np.zeros((1, 2)))
    traj = hugger.Trajectory(hand_json=hand.to_json(), params_json="{}", object_vertices=obj.vertices,
                             object_faces=obj.faces, target=np.zeros(3), palm_pose=pose[None], joints=joints[None],
                             angles=np.zeros((1, 1, 2)), tip_state=np.zeros((1, 1), np.int8),
                             phase=np.zeros(1, np.int8), status="done")
    assert A.contacts(traj).gap.min() > 0  # every contact outside
    axis = joints[0, 1] + np.linspace(0, 1, 4001)[:, None] * (joints[0, 2] - joints[0, 1])
    deepest = float(np.max(hand.link_radius - obj.signed_distance(axis)))
    assert deepest > 0.013
    assert A.penetration(traj) == pytest.approx(deepest, abs=1e-5)
    assert A.analyze(traj)["penetration_m"] == A.penetration(traj)
    moved = dataclasses.replace(traj, object_vertices=obj.vertices + [0.2, 0, 0])  # away: none
    assert A.penetration(moved) == 0.0


def test_wrap_angles_of_real_plan(reference_plan):
    traj, obj = reference_plan
    w = A.wrap_angle(traj, obj=obj)
    per = A.contacts(traj, obj=obj).per_finger()
    assert w.shape == (5,)
    assert np.all((w >= 0) & (w < 180))
    assert np.all(w[per >= 2] > 20.0)  # several links along a 4 cm sphere wrap well around it


# --- analyze ----------------------------------------------------------------------------------

def test_analyze_real_plan(reference_plan):
    traj, _ = reference_plan
    r = A.analyze(traj)
    assert set(r) == {"contacts", "links_in_contact", "links", "palm_contact", "per_finger_contacts",
                      "wrap_angle_deg", "force_closure", "epsilon", "volume", "mu", "torque_scale_m",
                      "penetration_m"}
    assert json.loads(json.dumps(r)) == r  # plain JSON types
    s = traj.summary()
    assert r["links_in_contact"] == s["links_in_contact"] and r["links"] == s["links"] == 25
    assert r["palm_contact"] == s["palm_contact"]
    assert sum(r["per_finger_contacts"]) == r["links_in_contact"]
    assert len(r["wrap_angle_deg"]) == 5
    assert r["force_closure"] is True and r["epsilon"] > 0 and r["volume"] > 0
    assert r["mu"] == 0.5
    assert r["torque_scale_m"] == pytest.approx(0.04, rel=1e-6)  # the sphere's radius about T
    assert 0.0 <= r["penetration_m"] <= 5e-5  # the plan's own contacts: within the checker's tolerance
    assert A.analyze(traj) == r  # deterministic


def test_analyze_frictionless_real_plan_is_weak(reference_plan):
    # Without friction a true sphere grasp could not resist torques about its centre. The mesh is
    # faceted: triangle normals miss the centre by a few degrees, leaving only small torques, so the
    # frictionless epsilon is a small fraction of the mu = 0.5 one.
    traj, _ = reference_plan
    r0, r = A.analyze(traj, mu=0.0), A.analyze(traj, mu=0.5)
    assert r0["mu"] == 0.0 and r0["contacts"] == r["contacts"]
    assert r0["epsilon"] < 0.1 * r["epsilon"]
    assert r0["volume"] < 1e-3 * r["volume"]


# --- input checks and the optional extra -----------------------------------------------------

def test_bad_input_raises_clear_errors(reference_plan, sphere_contacts):
    traj, obj = reference_plan
    c = sphere_contacts
    origin = np.zeros(3)
    for kwargs, match in [({"mu": -0.1}, "mu"), ({"mu": float("nan")}, "mu"), ({"cone_edges": 2}, "cone_edges"),
                          ({"cone_edges": 4.0}, "cone_edges"), ({"torque_scale": 0.0}, "torque_scale"),
                          ({"volume": "no"}, "volume must be True or False")]:
        with pytest.raises(ValueError, match=match):
            A.grasp_quality(c, origin, **kwargs)
    with pytest.raises(ValueError, match="center"):
        A.grasp_quality(c, [0.0, 0.0])
    with pytest.raises(ValueError, match="contacts"):
        A.grasp_quality(np.zeros((3, 3)), origin)
    with pytest.raises(ValueError, match="distance"):
        A.contacts(traj, distance=-1e-3, obj=obj)
    with pytest.raises(ValueError, match="Trajectory"):
        A.contacts("plan.npz")
    with pytest.raises(IndexError, match="out of range"):
        A.contacts(traj, k=len(traj), obj=obj)
    with pytest.raises(ValueError, match="k must"):
        A.analyze(traj, k=1.5)
    with pytest.raises(ValueError, match="joints"):
        A.contacts_of(traj.hand, obj, traj.palm_pose[-1], traj.joints[-1][:, :-1], DIST)
    with pytest.raises(ValueError, match="palm_pose"):
        A.contacts_of(traj.hand, obj, np.eye(3), traj.joints[-1], DIST)
    with pytest.raises(ValueError, match="obj"):
        A.contacts_of(traj.hand, obj.vertices, traj.palm_pose[-1], traj.joints[-1], DIST)
    with pytest.raises(ValueError, match="normals"):
        A.Contacts.from_arrays(np.zeros((2, 3)), np.zeros((2, 3)))
    with pytest.raises(ValueError, match="finite"):
        A.Contacts.from_arrays([[np.nan, 0, 0]], [[1.0, 0, 0]])
    bad = A.Contacts(np.full((8, 3), np.nan), np.ones((8, 3)), np.zeros(8), np.zeros(8), np.zeros(8))
    with pytest.raises(ValueError, match="finite"):
        A.grasp_quality(bad, origin, torque_scale=1.0)
    with pytest.raises(ValueError, match=r"\(C, 3\)"):
        A.Contacts(np.zeros((2, 2)), np.zeros((2, 2)), np.zeros(2), np.zeros(2), np.zeros(2))


def test_analysis_needs_no_scipy(monkeypatch, reference_plan, sphere_contacts):
    traj, obj = reference_plan
    real_import = builtins.__import__

    def no_scipy(name, *args, **kwargs):
        if name == "scipy" or name.startswith("scipy."):
            raise ImportError(f"No module named {name!r}")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_scipy)
    for mod in [m for m in sys.modules if m == "scipy" or m.startswith("scipy.")]:
        monkeypatch.setitem(sys.modules, mod, None)
    # grasp quality is compiled (Qhull in the core): everything works without scipy
    assert A.grasp_quality(sphere_contacts, np.zeros(3)).force_closure
    assert A.analyze(traj, obj=obj)["force_closure"]
    assert A.contacts(traj, obj=obj).links_in_contact == sphere_contacts.links_in_contact
    assert A.wrap_angle(traj, obj=obj).shape == (5,)


def test_importing_analysis_stays_light():
    code = ("import sys, hugger, hugger.analysis; "
            "print(sorted(m for m in ('scipy', 'trimesh', 'matplotlib') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
