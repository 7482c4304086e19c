"""Skins as plug-ins: a Python skin drives the planner; analytic skins agree with the mesh world on a
fine mesh of the same shape; the sensor model stays a lower bound of the true gap and safe."""
from __future__ import annotations

import gc
import importlib.util
import math
import os

import numpy as np
import pytest

import hugger
from hugger import skins
from helpers import SHARED_MISSING, CHECKER, check_file, random_rotation, save_and_check

#: Long runs (minutes): with HUGGER_SLOW=1 (bench/skins_agreement.py prints the same figures).
LONG = pytest.mark.skipif(not os.environ.get("HUGGER_SLOW"), reason="long run: set HUGGER_SLOW=1")


# A skin written from docs/skins.md alone: a ball of radius R about c.
class Ball(hugger.Sensing):
    def __init__(self, c, R):
        super().__init__()
        self.c, self.R = np.asarray(c, float), float(R)

    def capsule(self, a, b, radius, cap):
        ab = b - a
        t = 0.0 if not ab.any() else float(np.clip((self.c - a) @ ab / (ab @ ab), 0.0, 1.0))
        p = a + t * ab  # nearest point of the axis
        d = np.linalg.norm(p - self.c)
        n = (p - self.c) / d
        return hugger.Touch(gap=d - self.R - radius, on_hand=p, on_object=self.c + self.R * n, normal=n)

    def palm(self, pose, radius, thickness, cap):
        q = pose[:3, :3].T @ (self.c - pose[:3, 3])  # the ball's centre in the palm frame
        rho, z = math.hypot(q[0], q[1]), q[2]
        dr, dz = rho - radius, max(z, -thickness - z)
        return math.hypot(max(dr, 0.0), max(dz, 0.0)) + min(max(dr, dz), 0.0) - self.R


def start():
    return hugger.look_at([0.2, 0.0, 0.0], [0.0, 0.0, 0.0])


def test_python_skin_from_the_docs_plans_a_grasp(hand):
    traj = hugger.Planner(hand, Ball([0, 0, 0], 0.04), [0, 0, 0], start(),
                          record_object=hugger.objects.sphere(0.04, subdivisions=6)).plan()
    assert traj.status == "done"
    s = traj.summary()
    assert s["palm_contact"] and s["links_in_contact"] >= 10


class Boom(RuntimeError):
    pass


class Failing(Ball):
    def __init__(self, after):
        super().__init__([0, 0, 0], 0.04)
        self.after, self.calls = after, 0

    def capsule(self, a, b, radius, cap):
        self.calls += 1
        if self.calls > self.after:
            raise Boom(f"the skin failed at call {self.calls}")
        return super().capsule(a, b, radius, cap)


@pytest.mark.parametrize("after", [0, 50, 3000])
def test_exception_in_a_skin_reaches_plan_unchanged(hand, after):
    skin = Failing(after)
    if after == 0:  # during the checks of C_init, in the constructor
        with pytest.raises(Boom, match="call 1"):
            hugger.Planner(hand, skin, [0, 0, 0], start())
        return
    planner = hugger.Planner(hand, skin, [0, 0, 0], start())
    with pytest.raises(Boom, match=f"call {after + 1}$"):
        planner.plan()
    assert planner.status == "error"
    assert planner.step() is None  # the plan has ended; the planner still answers
    traj = planner.trajectory()
    assert len(traj) >= 1 and traj.status == "error"
    assert not traj.has_object


def test_exception_in_a_skin_reaches_step(hand):
    skin = Failing(3000)
    planner = hugger.Planner(hand, skin, [0, 0, 0], start())
    with pytest.raises(Boom):
        for _ in planner:
            pass
    assert planner.status == "error" and planner.step() is None


@pytest.mark.parametrize("bad, error", [
    (lambda self, a, b, r, c: 0.5, TypeError),
    (lambda self, a, b, r, c: hugger.Touch(float("nan")), ValueError),
    (lambda self, a, b, r, c: hugger.Touch(0.1, normal=[0, 0, 0]), ValueError),
])
def test_bad_answers_are_python_errors(hand, bad, error):
    cls = type("Bad", (Ball,), {"capsule": bad})
    with pytest.raises(error):
        hugger.Planner(hand, cls([0, 0, 0], 0.04), [0, 0, 0], start())


@pytest.mark.parametrize("answer", [True, np.bool_(False), "0.1", None])
def test_a_palm_gap_must_be_a_number(hand, answer):
    cls = type("Bad", (Ball,), {"palm": lambda self, pose, r, t, c: answer})
    with pytest.raises(TypeError, match="Sensing.palm must return a float"):
        hugger.Planner(hand, cls([0, 0, 0], 0.04), [0, 0, 0], start())


class _Scalar:
    """A number of another array library: a dtype that is no NumPy dtype, and a float value."""
    dtype = "other.float64"

    def __init__(self, x):
        self.x = x

    def __float__(self):
        return self.x


def test_a_palm_gap_of_another_librarys_scalar_is_taken(hand):
    ball = Ball([0, 0, 0], 0.04)
    cls = type("Other", (Ball,), {"palm": lambda self, *a: _Scalar(Ball.palm(self, *a))})
    assert hugger.Planner(hand, cls([0, 0, 0], 0.04), [0, 0, 0], start()).plan().status == "done"
    assert ball.palm(start(), 0.03, 0.01, math.inf) > 0


def test_incomplete_skin_and_missing_super_init(hand):
    class NoPalm(hugger.Sensing):
        def capsule(self, a, b, radius, cap):
            return hugger.Touch(1.0)

    with pytest.raises(TypeError, match="palm"):
        hugger.Planner(hand, NoPalm(), [0, 0, 0], start())

    class NoInit(Ball):
        def __init__(self):
            pass

    with pytest.raises(TypeError):
        hugger.Planner(hand, NoInit(), [0, 0, 0], start())


def test_planner_keeps_a_python_skin_alive(hand):
    planner = hugger.Planner(hand, Ball([0, 0, 0], 0.04), [0, 0, 0], start())
    gc.collect()
    assert planner.plan().status == "done"


def test_skin_answers_are_callable_from_python():
    obj = hugger.objects.sphere(0.04, subdivisions=5)
    mesh = skins.MeshSkin(obj)
    t = mesh.capsule(np.array([0.1, 0, 0]), np.array([0.1, 0.01, 0]), 0.004)
    assert t.gap == pytest.approx(0.1 - 0.04 - 0.004, abs=2e-4)
    np.testing.assert_allclose(t.normal, [1, 0, 0], atol=1e-2)
    assert mesh.palm(start(), 0.03, 0.01) == pytest.approx(0.2 - 0.04, abs=2e-4)
    with pytest.raises(ValueError):
        mesh.capsule(np.zeros(2), np.zeros(3), 0.0)
    with pytest.raises(ValueError):
        mesh.capsule(np.zeros(3), np.zeros(3), -1.0)


def test_a_sensor_model_of_an_object_records_it(hand):
    obj = hugger.objects.sphere(0.04, subdivisions=3)
    traj = hugger.Planner(hand, skins.SensorModel(obj), [0, 0, 0], start()).plan()
    assert traj.has_object and np.array_equal(traj.object_faces, obj.faces)
    assert traj.summary()["links_in_contact"] > 0
    other = hugger.objects.sphere(0.04, subdivisions=2)  # a record_object given wins
    traj = hugger.Planner(hand, skins.SensorModel(obj), [0, 0, 0], start(), record_object=other).plan()
    assert np.array_equal(traj.object_faces, other.faces)
    assert not hugger.Planner(hand, skins.SensorModel(Ball([0, 0, 0], 0.04)), [0, 0, 0], start()).plan().has_object
    assert skins.SensorModel(skins.SensorModel(obj)).object is obj  # a model of a model of it


def test_a_mesh_skin_records_its_object_as_the_mesh_planner_does(hand):
    obj = hugger.objects.sphere(0.04, subdivisions=3)
    direct = hugger.Planner(hand, obj, [0, 0, 0], start(), skin="mesh").plan()
    through = hugger.Planner(hand, skins.MeshSkin(obj), [0, 0, 0], start()).plan()
    assert through.has_object and np.array_equal(through.object_faces, obj.faces)
    assert np.array_equal(through.object_vertices, direct.object_vertices)
    assert np.array_equal(through.joints, direct.joints) and through.summary() == direct.summary()
    # and a sensor model of that skin
    assert np.array_equal(hugger.Planner(hand, skins.SensorModel(skins.MeshSkin(obj)), [0, 0, 0], start()).plan()
                          .object_faces, obj.faces)
    # a bare SimulatedWorld made without MeshSkin knows no Object: the plan is object-free
    assert not hugger.Planner(hand, hugger._core.SimulatedWorld(obj._core), [0, 0, 0], start()).plan().has_object


def test_plan_many_takes_record_object_as_the_planner_does(hand):
    # plan_many had no record_object: a batch through a skin without a mesh made object-free plans
    obj = hugger.objects.sphere(0.04, subdivisions=3)
    skin = Ball([0, 0, 0], 0.04)
    one = hugger.Planner(hand, skin, [0, 0, 0], start(), record_object=obj).plan()
    many = hugger.plan_many([{"obj": skin, "target": [0, 0, 0], "palm_pose": start(), "record_object": obj},
                             (hand, skin, [0, 0, 0], start(), {"record_object": obj})], hand=hand, threads=1)
    for traj in many:
        assert traj.has_object and np.array_equal(traj.object_faces, obj.faces)
        assert np.array_equal(traj.joints, one.joints)
    assert hugger.plan_many([(hand, skin, [0, 0, 0], start())], record_object=obj, threads=1)[0].has_object
    with pytest.raises(ValueError, match="case 0: record_object must be a hugger.Object"):
        hugger.plan_many([(hand, skin, [0, 0, 0], start(), {"record_object": obj.faces})])
    with pytest.raises(ValueError, match="case 0: record_object must be .* for a skin without a mesh"):
        hugger.plan_many([(hand, obj, [0, 0, 0], start(), {"record_object": obj})])


def test_object_free_plan_saves_and_hugger_info_reads_it(hand, tmp_path):
    traj = hugger.Planner(hand, Ball([0, 0, 0], 0.04), [0, 0, 0], start()).plan()
    path = tmp_path / "free.npz"
    traj.save(path)
    back = hugger.Trajectory.load(path)
    assert not back.has_object and len(back) == len(traj)
    with pytest.raises(ValueError, match="object-free"):
        back.object()
    from hugger.cli import main

    assert main(["info", str(path), "--json"]) == 0
    if importlib.util.find_spec("mujoco") is not None:  # the hold test says why it cannot run
        assert main(["validate", str(path)]) == 2
        with pytest.raises(ValueError, match="object-free"):
            hugger.physics.validate(back)
        assert main(["export-mjcf", str(path), "--out", str(tmp_path / "free.xml")]) == 2
        with pytest.raises(ValueError, match="object-free"):
            hugger.physics.export_mjcf(back)
    with pytest.raises(ValueError, match="object-free"):
        back.summary()
    if importlib.util.find_spec("matplotlib") is not None:  # every figure says why it cannot be drawn
        for out in ("free.png", "free.gif"):
            assert main(["render", str(path), "--out", str(tmp_path / out)]) == 2
            assert not (tmp_path / out).exists()
    with pytest.raises(ValueError, match="record_object"):
        hugger.Planner(hand, hugger.objects.sphere(0.04), [0, 0, 0], start(), record_object=hugger.objects.sphere(0.04))


# --- analytic skins against the mesh world -------------------------------------------------------------------


def _gap_pairs(rng, skin, obj, n=200, scale=0.08):
    a = rng.uniform(-scale, scale, size=(n, 3))
    b = a + rng.normal(scale=0.01, size=(n, 3))
    mesh = skins.MeshSkin(obj)
    out = []
    for p, q in zip(a, b):
        r = float(rng.uniform(0.0, 0.005))
        out.append((skin.capsule(p, q, r, np.inf).gap, mesh.capsule(p, q, r, np.inf).gap))
    return np.array(out)


@pytest.mark.parametrize("make", [
    lambda: skins.SphereSkin(0.035, (0.01, -0.005, 0.002)),
    lambda: skins.BoxSkin((0.05, 0.04, 0.03), (0.004, 0.0, -0.003), random_rotation(np.random.default_rng(3))),
    lambda: skins.SpheresSkin([[0, 0, 0], [0.02, 0.01, 0], [0, -0.015, 0.01]], [0.035, 0.03, 0.03]),
])
def test_analytic_gaps_match_the_mesh_of_the_same_shape(make):
    skin = make()
    g = _gap_pairs(np.random.default_rng(0), skin, skin.mesh())
    outside = (g[:, 0] > 0) & (g[:, 1] > 0)
    assert outside.sum() > 100
    # the fine mesh is inscribed: within the tessellation error (~0.1 mm) of the analytic gap
    np.testing.assert_allclose(g[outside, 0], g[outside, 1], atol=2e-4)
    assert np.all(np.sign(g[:, 0]) == np.sign(g[:, 1])) or np.mean(np.sign(g[:, 0]) == np.sign(g[:, 1])) > 0.98


@pytest.mark.parametrize("make", [
    lambda: skins.SphereSkin(0.035),
    lambda: skins.BoxSkin((0.05, 0.04, 0.03)),
    lambda: skins.SpheresSkin([[0, 0, 0], [0.02, 0.01, 0]], [0.035, 0.03]),
    lambda: skins.SensorModel(skins.SphereSkin(0.035), gap_noise=1e-5, seed=2),
])
def test_cap_is_optional_as_in_the_base_class(make):
    """Like hugger.Sensing's own queries, a skin's capsule() and palm() default cap to infinity."""
    a, b = np.array([0.05, 0.0, 0.0]), np.array([0.07, 0.01, 0.0])
    pose = hugger.look_at([0.0, 0.0, 0.08], [0.0, 0.0, 0.0])
    t, u = make().capsule(a, b, 0.004), make().capsule(a, b, 0.004, math.inf)
    assert t.gap == u.gap and np.array_equal(t.normal, u.normal)
    assert make().palm(pose, 0.03, 0.01) == make().palm(pose, 0.03, 0.01, math.inf)


def test_box_palm_gap_matches_the_mesh():
    rng = np.random.default_rng(1)
    skin = skins.BoxSkin((0.05, 0.04, 0.03), (0.0, 0.01, 0.0), random_rotation(rng))
    mesh = skins.MeshSkin(skin.mesh())
    for _ in range(60):
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        pose = np.eye(4)
        pose[:3, :3] = random_rotation(rng)
        pose[:3, 3] = d * rng.uniform(0.03, 0.1)
        g, ref = skin.palm(pose, 0.03, 0.01, np.inf), mesh.palm(pose, 0.03, 0.01, np.inf)
        if ref > 0:
            # the mesh world's palm gap (FCL's libccd GJK) errs by up to a few micrometres, above
            assert ref - 5e-6 <= g <= ref + 1e-9
        else:
            assert g < 0


def _case(rng, kind):
    if kind == "sphere":
        skin = skins.SphereSkin(rng.uniform(0.025, 0.045), rng.uniform(-0.01, 0.01, 3))
        target = skin.center + rng.uniform(-0.005, 0.005, 3)
    elif kind == "box":
        skin = skins.BoxSkin(rng.uniform(0.03, 0.07, 3), rng.uniform(-0.01, 0.01, 3), random_rotation(rng))
        target = skin.center + rng.uniform(-0.005, 0.005, 3)
    else:
        c0 = rng.uniform(-0.01, 0.01, 3)
        k = int(rng.integers(2, 4))
        radii = rng.uniform(0.022, 0.035, k)
        directions = rng.normal(size=(k - 1, 3))
        directions /= np.linalg.norm(directions, axis=1, keepdims=True)
        # every ball contains c0, so that the union is star-shaped about it (SpheresSkin.mesh)
        centers = [c0] + [c0 + u * rng.uniform(0.0, 0.8 * r) for u, r in zip(directions, radii[1:])]
        skin = skins.SpheresSkin(np.array(centers), radii)
        target = c0
    d = rng.normal(size=3)
    d /= np.linalg.norm(d)
    pose = hugger.look_at(target + d * rng.uniform(0.15, 0.2), target + rng.normal(scale=0.01, size=3))
    return skin, target, pose


#: Phase 2 iterations of one agreement case (the same bound for both plans; most end by 500).
AGREEMENT_ITERATIONS = 3000


def _agreement(hand, checker, tmp_path, seed, kind):
    rng = np.random.default_rng(seed)
    skin, target, pose = _case(rng, kind)
    mesh = skin.mesh()
    a = hugger.Planner(hand, skin, target, pose, record_object=mesh, max_iterations=AGREEMENT_ITERATIONS).plan()
    m = hugger.Planner(hand, mesh, target, pose, max_iterations=AGREEMENT_ITERATIONS, skin="mesh").plan()
    path = tmp_path / f"{kind}-{seed}.npz"
    a.save(path)
    _, fail_a, _ = check_file(checker, path, every=2, motion=True, swept_every=2)
    m.save(path)
    _, fail_m, _ = check_file(checker, path, every=2, motion=True, swept_every=2)
    static = [[f for f in fails if not f.startswith("motion:")] for fails in (fail_a, fail_m)]
    # ok: the checker's structure, kinematics, algorithm and collision checks (every other
    # configuration); motion_ok: its motion check too (DONE angles, joint moves <= 4 steps, the
    # swept motion of every other step)
    r = dict(status=(a.status, m.status), links=_links(a, m, mesh), palm=_palm(a, m),
             ok=(not static[0], not static[1]), motion_ok=(not fail_a, not fail_m), failures=(fail_a, fail_m))
    r["agree"] = _agree(r)
    r["mesh_unstable"] = False
    if not r["agree"]:
        # Is the planner itself sensitive here? Plan on other tessellations of the same shape
        # (coarser and finer, or the box with other triangles): if a mesh plan disagrees with the
        # mesh plan as well, the outcome hangs on micrometres (a discrete rule flips), not on the skin.
        for level in (5, 7) if kind != "box" else (2, 7):
            other = skin.mesh(level) if kind != "box" else skin.mesh(divisions=level)
            o = hugger.Planner(hand, other, target, pose, max_iterations=AGREEMENT_ITERATIONS, skin="mesh").plan()
            if not _agree(dict(status=(o.status, m.status), links=_links(o, m, mesh), palm=_palm(o, m))):
                r["mesh_unstable"] = True
                break
    return r


def _links(a, b, mesh):
    return a.summary(obj=mesh)["links_in_contact"], b.summary(obj=mesh)["links_in_contact"]


def _palm(a, b):
    return float(np.linalg.norm(a.palm_pose[-1, :3, 3] - b.palm_pose[-1, :3, 3]))


def _agree(r):
    """Same status; links in contact within +-2; final palm position within 1 mm."""
    return r["status"][0] == r["status"][1] and abs(r["links"][0] - r["links"][1]) <= 2 and r["palm"] <= 1e-3


def _assert_agrees(r):
    assert r["agree"] or r["mesh_unstable"], r
    # The analytic plan passes the independent checker against the fine mesh wherever the mesh
    # world's own plan does (a failing mesh plan is the planner's, not the skin's).
    assert r["ok"][0] or not r["ok"][1], r
    assert r["motion_ok"][0] or not r["motion_ok"][1], r


@pytest.mark.skipif(not CHECKER.exists(), reason=SHARED_MISSING)
@pytest.mark.parametrize("kind", ["sphere", "box", "spheres"])
@pytest.mark.parametrize("seed", range(3))
def test_analytic_skin_plans_agree_with_the_mesh_world(hand, checker, tmp_path, kind, seed):
    _assert_agrees(_agreement(hand, checker, tmp_path, seed, kind))


@pytest.mark.slow
@LONG
@pytest.mark.skipif(not CHECKER.exists(), reason=SHARED_MISSING)
@pytest.mark.parametrize("kind", ["sphere", "box", "spheres"])
def test_analytic_skin_plans_agree_many(hand, checker, tmp_path, kind):
    results = {seed: _agreement(hand, checker, tmp_path, seed, kind) for seed in range(100, 134)}
    unexplained = set()
    for seed, r in results.items():
        if not (r["agree"] or r["mesh_unstable"]):
            unexplained.add((kind, seed))
            r = {**r, "agree": True}  # judged below, against the known list; the checker rules still hold
        _assert_agrees(r)
    # Disagreements that no tessellation explains, known and stated in docs/skins.md: strict both ways,
    # so a new one fails here and a fixed one asks for this list to be updated.
    assert unexplained == {k for k in KNOWN_DISAGREEMENTS if k[0] == kind}, unexplained
    assert sum(r["agree"] for r in results.values()) >= 0.8 * len(results)


#: (shape, seed) of the long agreement run whose analytic and fine-mesh plans disagree although
#: coarser and finer meshes agree with the fine mesh's plan: the same palm position (within
#: 0.001 mm), but 12 links in contact on the analytic union of balls against 9 on the mesh.
#: Cause not found. (Before hug rule H5 the one such case was seed 121; it now agrees.)
KNOWN_DISAGREEMENTS = {("spheres", 110)}


# --- the sensor model ----------------------------------------------------------------------------------------


def test_sensor_model_is_a_lower_bound_of_the_true_gap():
    rng = np.random.default_rng(5)
    truth = skins.SphereSkin(0.04)
    model = skins.SensorModel(truth, range=0.005, gap_noise=2e-4, normal_noise=0.1, taxel_spacing=0.004, seed=1)
    for _ in range(300):
        a = rng.uniform(-0.07, 0.07, 3)
        b = a + rng.normal(scale=0.01, size=3)
        r = float(rng.uniform(0, 0.005))
        cap = float(rng.choice([0.0, 1e-3, np.inf]))
        t, ref = model.capsule(a, b, r, cap), truth.capsule(a, b, r, np.inf)
        assert t.gap <= ref.gap + 1e-12
        assert t.gap <= 0.005
        assert abs(np.linalg.norm(t.normal) - 1) < 1e-9
        assert t.gap >= min(ref.gap, 0.005) - model.uncertainty(r) - 1e-12  # never lower than its uncertainty
        if ref.gap > 0.005 + model.uncertainty(r):
            assert t.gap == 0.005  # nothing within range
    pose = start()
    assert model.palm(pose, 0.03, 0.01, np.inf) == 0.005


def test_sensor_model_capped_reading_is_the_uncapped_one():
    # A skin's capped answer is exact up to the cap (beyond it, any value above). Under a skin that
    # answers just above the cap, a reading at most the cap must be the reading of the true gap
    # (the same noise draw, uncapped), and a true reading above the cap must read above it.
    class JustAbove(skins.SphereSkin):
        def capsule(self, a, b, radius, cap=math.inf):
            t = super().capsule(a, b, radius, math.inf)
            return t if t.gap <= cap else skins.Touch(float(np.nextafter(cap, np.inf)), t.on_hand, t.on_object, t.normal)

        def palm(self, pose, radius, thickness, cap=math.inf):
            g = super().palm(pose, radius, thickness, math.inf)
            return g if g <= cap else float(np.nextafter(cap, np.inf))

    rng = np.random.default_rng(8)
    truth = JustAbove(0.04)
    checked = below = 0
    for i in range(400):
        a = rng.uniform(-0.06, 0.06, 3)
        b = a + rng.normal(scale=0.01, size=3)
        r, cap = float(rng.uniform(0, 0.005)), float(rng.choice([0.0, 2e-4, 1e-3, 3e-3]))
        for kw in (dict(gap_noise=2e-4), dict(gap_noise=2e-4, taxel_spacing=0.004), dict(gap_noise=1e-4, range=0.002)):
            capped = skins.SensorModel(truth, seed=i, **kw).capsule(a, b, r, cap).gap
            uncapped = skins.SensorModel(truth, seed=i, **kw).capsule(a, b, r, math.inf).gap
            checked += 1
            if capped <= cap:
                below += 1
                assert capped == uncapped, (i, kw, cap)
            else:
                assert uncapped > cap, (i, kw, cap)
        pose = start()
        pose[:3, 3] = rng.uniform(-0.1, 0.1, 3)
        capped = skins.SensorModel(truth, seed=i, gap_noise=2e-4).palm(pose, 0.03, 0.01, cap)
        uncapped = skins.SensorModel(truth, seed=i, gap_noise=2e-4).palm(pose, 0.03, 0.01, math.inf)
        assert capped == uncapped if capped <= cap else uncapped > cap
    assert checked == 1200 and below >= 100  # the cap decided a fair share


def test_sensor_model_is_deterministic(hand):
    def run():
        sk = skins.SensorModel(hugger.objects.sphere(0.04), gap_noise=5e-5, normal_noise=0.05, taxel_spacing=0.005, seed=7)
        return hugger.Planner(hand, sk, [0, 0, 0], start()).plan()

    a, b = run(), run()
    assert np.array_equal(a.joints, b.joints) and a.status == b.status


def test_sensor_model_range_within_the_contact_tolerance_is_refused_as_such(hand):
    # The engine would report the hand touching at the start, and advise moving the palm.
    for rng, kw, delta in ((5e-5, dict(), 1e-4), (2e-4, dict(contact_tolerance=2e-4), 2e-4)):
        with pytest.raises(ValueError, match=f"range .* must exceed the planner's contact_tolerance \\({delta:g} m\\)"):
            hugger.Planner(hand, skins.SensorModel(skins.SphereSkin(0.04), range=rng), [0, 0, 0], start(), **kw)
    assert hugger.Planner(hand, skins.SensorModel(skins.SphereSkin(0.04), range=2e-4), [0, 0, 0], start(),
                          max_iterations=1).plan().status == "max_iterations"
    assert hugger._core.DEFAULT_CONTACT_TOLERANCE == hugger.Planner(hand, skins.SphereSkin(0.04), [0, 0, 0],
                                                                    start()).params["contact_tolerance"]


@pytest.mark.parametrize("bad", ["yes", None, 1])
def test_capsule_clear_must_answer_a_bool(hand, bad):
    # Any other answer was cast (None read as False) or failed with pybind11's own message.
    cls = type("BadClear", (Ball,), {"capsule_clear": lambda self, a, b, radius, a_outside: bad})
    with pytest.raises(TypeError, match="capsule_clear must return a bool"):
        hugger.Planner(hand, cls([0, 0, 0], 0.04), [0, 0, 0], start()).plan()
    good = type("NumpyClear", (Ball,), {"capsule_clear": lambda self, a, b, radius, a_outside: np.bool_(
        Ball.capsule(self, a, b, radius, 0.0).gap > 0.0)})
    assert hugger.Planner(hand, good([0, 0, 0], 0.04), [0, 0, 0], start(), max_iterations=3).plan().status in (
        "max_iterations", "done")


def test_sensor_model_refuses_bad_settings():
    for kw in (dict(range=0), dict(range=-1), dict(gap_noise=float("nan")), dict(taxel_spacing=0), dict(normal_noise=-1)):
        with pytest.raises(ValueError):
            skins.SensorModel(skins.SphereSkin(), **kw)
    with pytest.raises(ValueError):
        skins.SensorModel("sphere")


@pytest.mark.skipif(not CHECKER.exists(), reason=SHARED_MISSING)
@pytest.mark.parametrize("kw", [dict(range=0.0015), dict(gap_noise=1e-4, normal_noise=0.1), dict(taxel_spacing=0.005)])
def test_sensor_model_plans_are_collision_free(hand, checker, tmp_path, kw):
    obj = hugger.objects.sphere(0.04)
    traj = hugger.Planner(hand, skins.SensorModel(obj, seed=3, **kw), [0, 0, 0], start(), record_object=obj).plan()
    assert traj.status in ("done", "max_iterations")
    save_and_check(checker, traj, tmp_path / "s.npz", every=2, motion=True, swept_every=2)


def test_a_touch_takes_no_nan_gap_by_its_setter_either():
    t = hugger.Touch(0.1)
    with pytest.raises(ValueError, match="Touch was given a gap of nan"):
        t.gap = float("nan")
    assert t.gap == 0.1
    t.gap = -np.inf  # inside, depth not measured: an answer
    assert t.gap == -np.inf


class InfInside(skins.SphereSkin):
    """A sphere read a little below the truth, answering -inf (allowed, docs/skins.md) once a
    part's axis is inside; it refuses any query at a non-finite point."""

    def __init__(self, radius):
        super().__init__(radius)
        self.rng = np.random.default_rng(0)
        self.inf_answers = 0

    def capsule(self, a, b, radius, cap=math.inf):
        assert np.isfinite(a).all() and np.isfinite(b).all(), f"asked about {a}, {b}"
        t = super().capsule(a, b, radius, cap)
        g = t.gap - self.rng.uniform(0, 2e-5)
        if g < -radius:
            self.inf_answers += 1
            g = -math.inf
        return skins.Touch(g, t.on_hand, t.on_object, t.normal)


def test_a_skin_answering_minus_inf_is_never_asked_about_nan_points():
    skin = InfInside(0.04)
    traj = hugger.Planner(hugger.Hand(link_radius=0.0), skin, [0, 0, 0], start()).plan()
    assert skin.inf_answers > 0  # the case exercises the -inf answers (boundary following's probes)
    assert traj.status == "done"


@pytest.mark.parametrize("normal", [[1e200, 1e200, 0.0], [3e-162, 0.0, 0.0], [1e-170, 1e-170, 0.0], [2.0, 0.0, 0.0]])
def test_a_python_skins_normal_of_any_finite_size_is_made_unit(normal):
    class S(hugger.Sensing):
        def capsule(self, a, b, radius, cap=math.inf):
            return hugger.Touch(0.01, a, a, normal)

        def palm(self, pose, radius, thickness, cap=math.inf):
            return 1.0

    # the base class's method asks the skin as the planner does, through the engine's checks
    n = hugger.Sensing.capsule(S(), np.zeros(3), np.ones(3), 0.001).normal
    u = np.asarray(normal) / max(normal)
    np.testing.assert_allclose(n, u / np.linalg.norm(u), rtol=1e-12)
    assert abs(np.linalg.norm(n) - 1.0) < 1e-15
