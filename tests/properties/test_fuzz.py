"""Fuzzing the Python boundary with hypothesis: Hand, Object, Planner and Trajectory.load fed
generated arrays and parameters (any float incl. nan, inf, huge and tiny; any shape; many dtypes).
Each call either builds a valid object or raises ValueError/TypeError with a message; never
anything else (no other exception, no crash, no warning but the documented size UserWarning).
Then light planner fuzzing: random valid hands, objects and starts plan to a known status, and a
``done`` plan passes the independent checker.

Profiles (registered here, chosen by the environment variable HUGGER_FUZZ_PROFILE):
``ci`` (the default: a few dozen examples a test, derandomized, about 20 s in all) and ``long``
(thousands of examples, random; ``make fuzz``). Neither writes an example database.
"""
from __future__ import annotations

import math
import os
import tempfile
import warnings
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, Phase, assume, event, given, note, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import helpers
import hugger

# no example database and no explain phase: nothing is written into the project (.hypothesis/);
# a failure prints its @reproduce_failure blob instead, so that a rare one found by a long run can
# be replayed from its output
_QUIET = {"deadline": None, "database": None, "phases": [p for p in Phase if p is not Phase.explain],
          "suppress_health_check": [HealthCheck.too_slow, HealthCheck.filter_too_much], "print_blob": True}
settings.register_profile("ci", max_examples=40, derandomize=True, **_QUIET)
settings.register_profile("long", max_examples=3000, **_QUIET)
PROFILE = os.environ.get("HUGGER_FUZZ_PROFILE", "ci")
if PROFILE not in ("ci", "long"):
    raise ValueError(f"HUGGER_FUZZ_PROFILE must be 'ci' or 'long', got {PROFILE!r}")
FUZZ = settings.get_profile(PROFILE)  # applied per test: loading it would change other files' settings
PLANS = settings(FUZZ, max_examples=6 if PROFILE == "ci" else 300)  # whole plans: fewer examples

# --- strategies ------------------------------------------------------------------------------

#: any float, weighted toward the awkward ones
any_float = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, -0.0, 1e-300, 5e-324, 1e300, -1e-9, 1e-5, 1e-3, 0.004, 0.02, 0.03, 1.0, 1e6, 1e7]),
    st.floats(min_value=1e-4, max_value=0.2),
)
#: anything a user might pass where a number belongs
any_scalar = st.one_of(any_float, st.integers(min_value=-(2 ** 70), max_value=2 ** 70), st.booleans(), st.none(),
                       st.text(max_size=3), st.just([0.01]), st.just(np.float32(0.01)), st.just(1 + 2j))
any_count = st.one_of(st.integers(min_value=-3, max_value=10), st.integers(min_value=-(2 ** 70), max_value=2 ** 70),
                      st.sampled_from([64, 65, 256, 257, 10 ** 6]), any_float, st.booleans(), st.none(),
                      st.just("5"), st.just(np.int64(3)), st.just(np.uint8(4)))

DTYPES = [np.float64, np.float32, np.float16, np.int64, np.int32, np.uint8, np.uint64, np.bool_, np.complex128]


def arrays_of(shape, dtypes=DTYPES, elements=None):
    """Arrays of the given shape strategy in any of ``dtypes``, elements including nan/inf."""
    def cast(x, dtype):
        with np.errstate(all="ignore"):
            return np.array(x).astype(dtype).item()

    def build(dtype):
        if elements is not None and np.dtype(dtype).kind == "f":
            return hnp.arrays(dtype, shape, elements=elements.map(lambda x: cast(x, dtype)))
        return hnp.arrays(dtype, shape)
    return st.sampled_from(dtypes).flatmap(build)


def small_shape(max_dims=3, max_side=6):
    return hnp.array_shapes(min_dims=0, max_dims=max_dims, min_side=0, max_side=max_side)


def outcome(fn, *args, **kwargs):
    """fn's result, or the ValueError/TypeError it raised (which must say something). Any other
    exception propagates and fails the test; so does any warning other than the size warning."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            result = fn(*args, **kwargs)
        except (ValueError, TypeError) as exc:
            assert str(exc).strip(), f"{type(exc).__name__} without a message"
            event(f"{fn.__name__ if hasattr(fn, '__name__') else fn}: {type(exc).__name__}")
            result = exc
    for w in caught:
        assert issubclass(w.category, UserWarning) and "implausibly" in str(w.message), \
            f"unexpected {w.category.__name__}: {w.message}"
    return result


# --- Hand ------------------------------------------------------------------------------------

good_count = st.integers(min_value=1, max_value=8)
good_length = st.floats(min_value=1e-3, max_value=0.1)
BAD_HAND_ARGS = {
    "fingers": any_count,
    "links": any_count,
    "link_length": st.one_of(any_scalar, arrays_of(small_shape(), elements=any_float),
                             arrays_of(st.just((2, 3)), elements=st.one_of(good_length, any_float))),
    "link_radius": any_scalar,
    "palm_radius": any_scalar,
    "palm_thickness": any_scalar,
}


@st.composite
def hand_args(draw):
    """Hand arguments: valid ones, valid but one, or all of them anything."""
    m, n = draw(good_count), draw(good_count)
    args = {"fingers": m, "links": n,
            "link_length": draw(st.one_of(good_length, hnp.arrays(np.float64, (m, n), elements=good_length))),
            "link_radius": draw(st.one_of(st.just(0.0), st.floats(min_value=1e-5, max_value=2e-3))),
            "palm_radius": draw(st.floats(min_value=0.01, max_value=0.1)), "palm_thickness": draw(good_length)}
    mode = draw(st.sampled_from(["valid", "one bad", "one bad", "all bad"]))
    bad = list(args) if mode == "all bad" else [draw(st.sampled_from(list(args)))] if mode == "one bad" else []
    for key in bad:
        args[key] = draw(BAD_HAND_ARGS[key])
    event(f"hand arguments: {mode}")
    return args


@FUZZ
@given(args=hand_args())
def test_hand_builds_or_says_why(args):
    hand = outcome(hugger.Hand, **args)
    if isinstance(hand, Exception):
        return
    event("hand accepted")
    m, n = hand.fingers, hand.links
    assert 1 <= m <= hugger.hand.MAX_FINGERS and 1 <= n <= hugger.hand.MAX_LINKS
    ll = hand.link_lengths
    assert ll.shape == (m, n) and np.all(np.isfinite(ll)) and np.all(ll >= hugger.hand.MIN_LENGTH)
    assert 0 <= hand.link_radius < hand.palm_radius and hand.palm_thickness > 0
    # the model it built is usable: round trip and exact link lengths in the extended pose
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # the size warning, once is enough
        assert hugger.Hand.from_dict(hand.to_dict()).to_dict() == hand.to_dict()
    j = hand.forward(np.eye(4), np.zeros((m, n)))
    np.testing.assert_allclose(np.linalg.norm(np.diff(j, axis=1), axis=-1), ll, rtol=1e-12)


@FUZZ
@given(pose=st.one_of(arrays_of(small_shape(3, 5), elements=any_float),
                      arrays_of(st.just((4, 4)), dtypes=[np.float64, np.float32, np.int64], elements=any_float)),
       angles=st.one_of(arrays_of(st.just((3, 2)), dtypes=[np.float64, np.int64, np.bool_], elements=any_float),
                        arrays_of(small_shape(2, 4), elements=any_float)))
def test_kinematics_computes_or_says_why(pose, angles):
    hand = hugger.Hand(fingers=3, links=2, link_length=0.02, link_radius=0.002)
    joints = outcome(hand.forward, pose, angles)
    if isinstance(joints, Exception):
        return
    assert joints.shape == (3, 3, 3) and np.all(np.isfinite(joints))
    np.testing.assert_allclose(joints[:, 0], hand.roots(pose), atol=1e-12)


# --- Object ----------------------------------------------------------------------------------

BASE_V, BASE_F = hugger.objects.icosphere(1)  # 42 vertices, 80 faces


def _mutated_mesh(draw):
    """A valid closed mesh, affinely moved, then (maybe) broken in one of many ways; and whether
    it is surely embedded (no self-intersection: then "inside" is well defined)."""
    scale = draw(st.one_of(st.floats(0.005, 0.2),
                           st.sampled_from([1e-300, 1e-6, 1e-4, 0.02, 0.05, 1.0, 50.0, 1e5, 1e7, 1e300])))
    spread = draw(st.sampled_from([0.5, 0.5, 3.0]))  # mostly a proper (det > 0) map, sometimes anything
    a = np.array(draw(hnp.arrays(np.float64, (3, 3), elements=st.floats(-spread, spread)))) + 2 * np.eye(3)
    v = BASE_V @ a.T * scale + draw(st.sampled_from([0.0, 0.0, 1.0, 1e6, -1e5]))
    f = BASE_F.copy()
    how = draw(st.sampled_from(["none", "none", "none", "flip", "drop", "dup", "index", "swap", "nan", "collapse",
                                "pinch", "transpose", "reverse_one", "extra_vertex"]))
    i = draw(st.integers(0, len(f) - 1))
    k = draw(st.integers(0, 2))
    if how == "flip":
        f = f[:, ::-1]
    elif how == "drop":
        f = np.delete(f, i, axis=0)
    elif how == "dup":
        f = np.vstack([f, f[i:i + 1]])
    elif how == "index":
        f[i, k] = draw(st.sampled_from([-1, len(v), 2 ** 31, -(2 ** 40), f[i, (k + 1) % 3]]))
    elif how == "swap":
        f[i] = f[i, [1, 0, 2]]
    elif how == "nan":
        v = v.copy()
        v[f[i, k], draw(st.integers(0, 2))] = draw(st.sampled_from([np.nan, np.inf, -np.inf]))
    elif how == "collapse":
        v = v.copy()
        v[f[i, 0]] = v[f[i, 1]]
    elif how == "pinch":  # move a vertex onto another vertex far across the mesh
        v = v.copy()
        v[f[i, 0]] = v[(f[i, 0] + 20) % len(v)]
    elif how == "transpose":
        f = f.T
    elif how == "reverse_one":
        f[i] = f[i, ::-1]
    elif how == "extra_vertex":
        v = np.vstack([v, draw(hnp.arrays(np.float64, (1, 3), elements=any_float))])
    event(f"mesh mutation: {how}")
    embedded = how == "none" and np.linalg.det(a) > 0  # a convex body under a proper linear map
    return v, f, embedded


@st.composite
def meshes(draw):
    kind = draw(st.sampled_from(["mutated", "mutated", "mutated", "random", "dtype"]))
    if kind == "mutated":
        return _mutated_mesh(draw)
    if kind == "dtype":  # casts may wrap or round the coordinates: no longer surely embedded
        v, f, _ = _mutated_mesh(draw)
        vd = draw(st.sampled_from(DTYPES + [object]))
        fd = draw(st.sampled_from(DTYPES + [object, np.int8]))
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return v.astype(vd), f.astype(fd), False
    v = draw(st.one_of(arrays_of(hnp.array_shapes(min_dims=1, max_dims=3, min_side=0, max_side=8), elements=any_float),
                       arrays_of(st.tuples(st.integers(0, 8), st.just(3)), elements=any_float)))
    f = draw(st.one_of(arrays_of(hnp.array_shapes(min_dims=1, max_dims=3, min_side=0, max_side=8)),
                       hnp.arrays(np.int64, st.tuples(st.integers(0, 12), st.just(3)),
                                  elements=st.integers(-2, 10))))
    return v, f, False


def _winding(points, tri):
    """Reference inside test: the generalized winding number (1 inside, 0 outside)."""
    a, b, c = (tri[None, :, i] - points[:, None] for i in range(3))
    la, lb, lc = (np.linalg.norm(x, axis=-1) for x in (a, b, c))
    num = np.einsum("pti,pti->pt", a, np.cross(b, c))
    den = (la * lb * lc + np.einsum("pti,pti->pt", a, b) * lc + np.einsum("pti,pti->pt", b, c) * la
           + np.einsum("pti,pti->pt", c, a) * lb)
    return np.sum(np.arctan2(num, den), axis=1) / (2 * np.pi)


@FUZZ
@given(mesh=meshes(), probe=st.integers(0, 2 ** 32 - 1))
def test_object_builds_or_says_why(mesh, probe):
    v, f, embedded = mesh
    obj = outcome(hugger.Object, v, f)
    if isinstance(obj, Exception):
        return
    event("object accepted")
    assert obj.volume > 0 and np.all(np.isfinite(obj.bounds))
    assert obj.faces.dtype == np.int64 and obj.faces.min() >= 0 and obj.faces.max() < len(obj.vertices)
    # its queries answer; on a surely embedded surface "inside" agrees with an independent
    # winding number away from the surface (self-intersecting meshes are not detected, and on
    # them "inside" is not defined: see test_world)
    rng = np.random.default_rng(probe)
    lo, hi = obj.bounds
    pts = lo + (hi - lo) * rng.uniform(-0.2, 1.2, size=(40, 3))
    d = obj.signed_distance(pts)
    assert np.all(np.isfinite(d))
    assert np.all(np.isfinite(obj.segment_distance(pts[:20], pts[20:])))
    if embedded:
        event("object accepted, embedded: inside cross-checked")
        w = _winding(pts, obj.vertices[obj.faces])
        sure = np.abs(d) > 1e-6 * float(np.ptp(obj.bounds, axis=0).max())
        np.testing.assert_array_equal(obj.inside(pts[sure]), w[sure] > 0.5)
        np.testing.assert_array_equal(d[sure] < 0, w[sure] > 0.5)


# --- Planner: bad inputs -----------------------------------------------------------------------

HAND = hugger.Hand(fingers=3, links=3, link_length=0.02, link_radius=0.002, palm_radius=0.02, palm_thickness=0.01)
BALL = hugger.objects.sphere(radius=0.03, subdivisions=2)
GOOD_POSE = hugger.look_at([0.0, 0.0, 0.15], [0, 0, 0])


@st.composite
def poses(draw):
    kind = draw(st.sampled_from(["good", "good", "good", "perturbed", "entry", "random", "shape", "away", "away"]))
    pose = GOOD_POSE.copy()
    if kind == "perturbed":  # scaled, sheared or reflected linear part
        m = np.eye(3) + np.array(draw(hnp.arrays(np.float64, (3, 3), elements=st.floats(-1e-3, 1e-3))))
        m = m * draw(st.sampled_from([1.0, -1.0, 1.0 + 1e-9, 2.0]))
        pose[:3, :3] = pose[:3, :3] @ m
    elif kind == "entry":
        pose[draw(st.integers(0, 3)), draw(st.integers(0, 3))] = draw(any_float)
    elif kind == "random":
        pose = draw(hnp.arrays(np.float64, (4, 4), elements=any_float))
    elif kind == "shape":
        return draw(arrays_of(small_shape(3, 5), dtypes=[np.float64, np.int64, np.bool_, np.complex128],
                              elements=any_float))
    elif kind == "away":  # a valid pose at a random place and direction, maybe too close or inside
        pos = np.array(draw(hnp.arrays(np.float64, 3, elements=st.floats(-0.2, 0.2))))
        aim = np.array(draw(hnp.arrays(np.float64, 3, elements=st.floats(-1, 1))))
        assume(np.linalg.norm(aim - pos) > 1e-6 and np.linalg.norm(pos) > 1e-6)
        pose = hugger.look_at(pos, aim)
    return pose


#: planner parameters: None (default), or anything; tiny steps only where they are refused or
#: cheap (the tests below stop planning after a few iterations)
param = st.one_of(st.none(), st.none(), any_float, st.sampled_from([0, -1, "0.001", True, [0.001]]))
max_iter = st.one_of(st.none(), st.integers(min_value=-5, max_value=50),
                     st.sampled_from([0, 2 ** 62, 2 ** 64, 10 ** 30, 2.5, "3"]))


@FUZZ
@given(target=st.one_of(hnp.arrays(np.float64, 3, elements=st.floats(-0.02, 0.02)),
                         hnp.arrays(np.float64, 3, elements=st.one_of(any_float, st.floats(-0.05, 0.05))),
                         arrays_of(small_shape(2, 4), dtypes=[np.float64, np.int64, np.bool_, np.complex128],
                                   elements=any_float),
                         st.sampled_from([None, "centre", [0, 0], [[0, 0, 0]]])),
       pose=poses(), step=param, epsilon=param, contact_tolerance=param, max_iterations=max_iter)
def test_planner_starts_or_says_why(target, pose, step, epsilon, contact_tolerance, max_iterations):
    # Phase 1 runs in the constructor: keep it short when the pose is rigid but the step tiny
    if isinstance(step, float) and 0 < step < 1e-4:
        assume(contact_tolerance is None or not isinstance(contact_tolerance, float) or contact_tolerance >= step)
    planner = outcome(hugger.Planner, HAND, BALL, target, pose, step=step, epsilon=epsilon,
                      contact_tolerance=contact_tolerance, max_iterations=max_iterations)
    if isinstance(planner, Exception):
        return
    event("planner accepted")
    p = planner.params
    assert 0 < p["contact_tolerance"] < p["step"] <= 0.02 and 0 < p["epsilon"] <= p["step"]
    assert BALL.inside(planner.target)
    for _ in range(5):  # a few configurations: finite, rigid palm, exact link lengths
        c = planner.step()
        if c is None:
            break
        assert np.all(np.isfinite(c.joints)) and np.all(np.isfinite(c.palm_pose))
        r = c.palm_pose[:3, :3]
        assert np.abs(r.T @ r - np.eye(3)).max() < 1e-12
        # Exact up to the rounding of the joints' coordinates: a pose 2,294 km away (an "entry"
        # pose) puts them at 2.3e6 m, where a 2 cm link's length is good to about 1e-9 of it.
        scale = float(np.abs(c.joints).max())
        np.testing.assert_allclose(np.linalg.norm(np.diff(c.joints, axis=1), axis=-1), HAND.link_lengths, rtol=1e-9,
                                   atol=1e-15 * scale)
    assert planner.status in ("running", "done", "max_iterations")


# --- Trajectory.load ----------------------------------------------------------------------------

_SAVED: dict[str, bytes] = {}


def saved_bytes(compressed: bool) -> tuple[hugger.Trajectory, bytes]:
    """A real small plan, saved (compressed or not); built once."""
    key = "z" if compressed else "plain"
    if "traj" not in _SAVED:
        _SAVED["traj"] = hugger.Planner(HAND, BALL, [0, 0, 0], GOOD_POSE, max_iterations=12).plan()
    traj = _SAVED["traj"]
    if key not in _SAVED:
        with tempfile.TemporaryDirectory() as d:
            traj.save(Path(d) / "t.npz")
            if compressed:
                _SAVED[key] = (Path(d) / "t.npz").read_bytes()
            else:
                with np.load(Path(d) / "t.npz", allow_pickle=False) as z:
                    np.savez(Path(d) / "p.npz", **{k: z[k] for k in z.files})
                _SAVED[key] = (Path(d) / "p.npz").read_bytes()
    return traj, _SAVED[key]


def _load_bytes(data: bytes):
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "t.npz"
        path.write_bytes(data)
        return outcome(hugger.Trajectory.load, path)


def _same(a, b):
    """Every array and the hand, bit for bit."""
    return helpers.same(a, b, helpers.FILE_ARRAYS, ("hand_json",))


@FUZZ
@given(compressed=st.booleans(), data=st.data())
def test_damaged_file_is_refused_or_unchanged(compressed, data):
    traj, raw = saved_bytes(compressed)
    b = bytearray(raw)
    how = data.draw(st.sampled_from(["flip", "truncate", "insert", "delete", "zero_run"]))
    at = data.draw(st.integers(0, len(b) - 1))
    if how == "flip":
        for k in data.draw(st.lists(st.integers(0, len(b) - 1), min_size=1, max_size=8)):
            b[k] ^= data.draw(st.integers(1, 255))
    elif how == "truncate":
        del b[at:]
    elif how == "insert":
        b[at:at] = data.draw(st.binary(min_size=1, max_size=16))
    elif how == "delete":
        del b[at:at + data.draw(st.integers(1, 64))]
    else:
        n = data.draw(st.integers(1, 256))
        b[at:at + n] = bytes(len(b[at:at + n]))
    event(f"file damage: {how}")
    back = _load_bytes(bytes(b))
    if isinstance(back, ValueError):
        return
    assert not isinstance(back, TypeError), back  # a damaged file is a ValueError
    event("damage was harmless")
    assert _same(back, traj)  # only metadata the reader ignores was hit


KEYS = ["format_version", "hand_json", "params_json", "status", "object_vertices", "object_faces", "target",
        "palm_pose", "joints", "angles", "tip_state", "phase"]


@FUZZ
@given(data=st.data())
def test_file_with_generated_arrays_is_refused_or_valid(data):
    traj, raw = saved_bytes(True)
    with tempfile.TemporaryDirectory() as d:
        (Path(d) / "t.npz").write_bytes(raw)
        with np.load(Path(d) / "t.npz", allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
    for key in data.draw(st.lists(st.sampled_from(KEYS), min_size=1, max_size=3, unique=True)):
        choice = data.draw(st.sampled_from(["drop", "random", "reshape", "cast", "string"]))
        if choice == "drop":
            del arrays[key]
        elif choice == "random":
            arrays[key] = data.draw(arrays_of(small_shape(4, 4), elements=any_float))
        elif choice == "reshape":
            arrays[key] = arrays[key].reshape(-1) if arrays[key].ndim != 1 else arrays[key][:, None]
        elif choice == "cast":
            dtype = data.draw(st.sampled_from(DTYPES + [np.str_]))
            with np.errstate(all="ignore"), warnings.catch_warnings():
                warnings.simplefilter("ignore")
                try:
                    arrays[key] = arrays[key].astype(dtype)
                except (ValueError, TypeError):  # a JSON string is no number: leave it
                    pass
        else:
            arrays[key] = np.array(data.draw(st.text(max_size=40)))
        event(f"array edit: {choice}")
    with tempfile.TemporaryDirectory() as d:
        np.savez(Path(d) / "g.npz", **arrays)
        back = outcome(hugger.Trajectory.load, Path(d) / "g.npz")
    if isinstance(back, Exception):
        assert isinstance(back, ValueError), back
        return
    event("edited file still valid")
    # accepted: then it is a consistent format-1 trajectory
    k, m, n = len(back), back.hand["fingers"], back.hand["links"]
    assert back.joints.shape == (k, m, n + 1, 3) and back.tip_state.dtype == np.int8
    assert back.tip_state.min() >= 0 and back.tip_state.max() <= 2 and np.all(np.isfinite(back.joints))


# --- light planner fuzzing: random valid cases plan to the end ----------------------------------

KNOWN_STATUS = {"done", "max_iterations"}


@PLANS
@given(kind=st.sampled_from(["sphere", "ellipsoid", "box", "cylinder", "blob"]), seed=st.integers(0, 2 ** 32 - 1),
       size=st.floats(0.01, 0.08), step_fraction=st.sampled_from([None, 0.05, 0.1, 0.25]),
       inner=st.floats(0.0, 0.6))
def test_random_valid_case_plans_to_a_known_end(checker, kind, seed, size, step_fraction, inner):
    rng = np.random.default_rng(seed)
    obj, _ = helpers.random_object(rng, kind, size)
    # a target anywhere well inside: the centre pulled toward a random surface point
    surface = obj.vertices[rng.integers(len(obj.vertices))]
    target = inner * surface
    assume(bool(obj.inside(target)) and obj.signed_distance(target) < -1e-4)
    hand = helpers.random_hand(rng, size)
    pose = helpers.safe_start(rng, obj, hand, target)
    step = None if step_fraction is None else step_fraction * float(hand.link_lengths.min())
    # The default contact tolerance (0.1 mm) must be below the step: links under 2 mm need less.
    s = float(hand.link_lengths.min()) / 20.0 if step is None else step
    tolerance = None if s > 1e-4 else 0.5 * s
    planner = hugger.Planner(hand, obj, target, pose, step=step, contact_tolerance=tolerance)
    traj = planner.plan()
    note(f"{kind} size {size:.3f}, {hand}, step {step}: {traj.status}, {planner.stats}")
    event(f"plan status: {traj.status}")
    assert traj.status in KNOWN_STATUS
    assert traj.summary()["configurations"] == len(traj) >= 1
    with tempfile.TemporaryDirectory() as d:
        helpers.save_and_check(checker, traj, Path(d) / "plan.npz", samples=15)
        back = hugger.Trajectory.load(Path(d) / "plan.npz")
        assert _same(back, traj)
    if traj.status == "done":
        assert np.all(traj.tip_state[-1] == hugger.DONE)
    else:
        assert traj.stats["phase2_iterations"] == traj.params["max_iterations"]


def test_profiles_are_registered():
    assert settings.get_profile("ci").max_examples < settings.get_profile("long").max_examples
    assert FUZZ.database is None and FUZZ.deadline is None and FUZZ.print_blob
    assert math.isfinite(PLANS.max_examples)
