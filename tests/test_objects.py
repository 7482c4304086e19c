"""Built-in objects, mesh files and default scenarios."""
from __future__ import annotations

import os
import warnings

import numpy as np
import pytest

import hugger
from hugger import objects, scenarios

from helpers import OBJECTS_DIR, SHARED_MISSING

trimesh = pytest.importorskip("trimesh", reason="mesh files need the mesh extra (trimesh)")


@pytest.mark.parametrize("name", objects.names())
def test_builtin_is_closed_outward_and_holds_its_target(name):
    b = objects.BUILTINS[name]
    obj = objects.get(name)
    mesh = trimesh.Trimesh(obj.vertices, obj.faces, process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert obj.volume > 0 and mesh.volume == pytest.approx(obj.volume, rel=1e-9)
    assert obj.inside(np.array([b.target]))[0]
    assert -obj.signed_distance(np.array([b.target]))[0] > 0.005  # T well inside
    extent = obj.bounds[1] - obj.bounds[0]
    assert 0.02 < extent.min() and extent.max() < 0.15  # all fit a hand of about 10 cm


def test_documented_sizes_match_the_meshes():
    ext = lambda n: np.round(100 * (objects.get(n).bounds[1] - objects.get(n).bounds[0]), 1)  # noqa: E731 (cm)
    assert np.allclose(ext("apple"), [8.4, 8.4, 6.9], atol=0.06)
    assert np.allclose(ext("curvy"), [8.7, 8.1, 8.1], atol=0.06)
    assert np.allclose(ext("torus"), [11, 11, 3], atol=0.06)
    assert np.allclose(ext("box"), [6, 5, 4], atol=1e-9)


def test_curvy_and_apple_are_not_convex():
    from scipy.spatial import ConvexHull

    for name in ("curvy", "apple", "torus"):
        obj = objects.get(name)
        hull = ConvexHull(obj.vertices)
        depth = -(obj.vertices @ hull.equations[:, :3].T + hull.equations[:, 3]).max(axis=1)  # inside the hull, m
        assert depth.max() > 0.003, name  # a dent at least 3 mm deep


def test_torus_centre_is_outside():
    assert not objects.torus().inside(np.zeros((1, 3)))[0]
    with pytest.raises(ValueError, match="minor_radius"):
        objects.torus(0.01, 0.02)


@pytest.mark.parametrize("make, kwargs, message", [
    (objects.sphere, {"radius": -0.04}, "radius must be a positive finite number"),
    (objects.sphere, {"radius": 0.0}, "radius must be a positive finite number"),
    (objects.blob, {"radius": float("inf")}, "radius must be a positive finite number"),
    (objects.ellipsoid, {"radii": (0.05, -0.04, 0.03)}, "radii must be a positive finite number"),
    (objects.ellipsoid, {"radii": (0.05, 0.04)}, "radii must be 3 numbers"),
    (objects.box, {"extents": (0.06, 0.0, 0.04)}, "extents must be a positive finite number"),
    (objects.cylinder, {"radius": -0.035}, "radius must be a positive finite number"),
    (objects.cylinder, {"height": float("nan")}, "height must be a positive finite number"),
])
def test_builtin_sizes_must_be_positive(make, kwargs, message):
    # A negative size would mirror the mesh (and be refused for its inward faces, the wrong reason).
    with pytest.raises(ValueError, match=message):
        make(**kwargs)


@pytest.mark.parametrize("make, kwargs, message", [
    (objects.sphere, {"subdivisions": 20}, "subdivisions must be a whole number from 0 to 8, got 20"),
    (objects.sphere, {"subdivisions": -1}, "subdivisions must be a whole number from 0 to 8"),
    (objects.ellipsoid, {"subdivisions": 2.5}, "subdivisions must be a whole number"),
    (objects.blob, {"subdivisions": "a"}, "subdivisions must be a whole number"),
    (objects.apple, {"subdivisions": True}, "subdivisions must be a whole number"),
    (objects.blob, {"seed": -1}, "seed must be a whole number >= 0"),
    (objects.blob, {"seed": "a"}, "seed must be a whole number >= 0"),
    (objects.box, {"divisions": 0}, "divisions must be a whole number >= 1"),
    (objects.box, {"divisions": 1000}, "the box would have 12,000,000 triangles"),
    (objects.cylinder, {"sections": 2}, "sections must be a whole number >= 3"),
    (objects.cylinder, {"rings": 0}, "rings must be a whole number >= 1"),
    (objects.torus, {"sections": 5000, "rings": 1000}, "the torus would have 10,000,000 triangles"),
    (objects.torus, {"major_radius": "x"}, "major_radius must be a number"),
    (objects.torus, {"major_radius": 0.01, "minor_radius": 0.02}, "minor_radius < major_radius"),
    (objects.curvy, {"size": -0.04}, "size must be a positive finite number"),
    (objects.apple, {"radius": 0.0}, "radius must be a positive finite number"),
])
def test_builtin_counts_and_seeds_are_checked(make, kwargs, message):
    # Before any work: an unchecked count of subdivisions grows the mesh fourfold per level.
    with pytest.raises(ValueError, match=message):
        make(**kwargs)


@pytest.mark.parametrize("make, kwargs", [
    (objects.sphere, {"radius": -1.0}), (objects.sphere, {"center": (0, 0)}),
    (objects.ellipsoid, {"center": (0, float("nan"), 0)}), (objects.blob, {"seed": -1}),
    (objects.blob, {"amplitude": -0.1}), (objects.blob, {"center": "x"}), (objects.apple, {"radius": 0.0}),
    (objects.apple, {"center": (1, 2)}), (objects.curvy, {"size": -0.04}), (objects.curvy, {"center": (0,)}),
])
def test_builtin_arguments_are_checked_before_the_mesh_is_made(make, kwargs, monkeypatch):
    def made(*args, **kw):
        raise AssertionError("the mesh was made before the arguments were checked")

    monkeypatch.setattr(objects, "icosphere", made)
    with pytest.raises(ValueError):
        make(**kwargs)


def test_builtin_counts_take_numpy_integers():
    assert len(objects.sphere(subdivisions=np.int64(1)).faces) == 80
    assert len(objects.box(divisions=np.int32(2)).faces) == 48
    assert len(objects.blob(seed=np.int64(3), subdivisions=1).faces) == 80


@pytest.mark.parametrize("call, shown", [
    (lambda: objects.box(extents=np.array([0.1, -0.1, 0.1])), "got -0.1$"),
    (lambda: scenarios.default_case("sphere", hugger.Hand(), turn_deg=np.float64(200.0)), "got 200.0$"),
    (lambda: hugger.skins.SensorModel(objects.sphere(subdivisions=1), gap_noise=np.float64(-0.5)), "got -0.5$"),
    (lambda: hugger.objects.sphere(radius=np.array(-0.02)), "got -0.02$"),  # a 0-d array
])
def test_numpy_numbers_in_messages_read_as_plain_numbers(call, shown):
    """A NumPy scalar in a refusal is shown as the number it holds, not as np.float64(...)."""
    with pytest.raises(ValueError, match=shown) as err:
        call()
    assert "np." not in str(err.value)


def test_a_float32_is_shown_at_its_own_precision():
    from hugger._checks import shown

    assert shown(np.float32(-0.1)) == "-0.1" and shown(np.int64(9)) == "9" and shown("x") == "'x'"


def test_unknown_builtin_names_the_choices():
    with pytest.raises(ValueError, match="choose from sphere, apple"):
        objects.get("banana")


@pytest.mark.parametrize("suffix", [".stl", ".obj", ".ply", ".off", ".glb"])
def test_mesh_files_round_trip(tmp_path, suffix):
    src = objects.sphere(0.03, subdivisions=2)
    path = tmp_path / f"ball{suffix}"
    trimesh.Trimesh(src.vertices, src.faces, process=False).export(path)
    obj = objects.load(path)
    assert len(obj.faces) == len(src.faces)
    assert obj.volume == pytest.approx(src.volume, rel=1e-6)


def test_a_mesh_path_that_is_no_mesh_file_says_what_it_is(tmp_path):
    src = objects.sphere(0.03, subdivisions=2)
    bare = tmp_path / "ball"
    trimesh.Trimesh(src.vertices, src.faces, process=False).export(bare, file_type="stl")
    with pytest.raises(ValueError, match="has no extension: name it by its format"):
        objects.load(bare)
    if hasattr(os, "mkfifo"):
        pipe = tmp_path / "pipe.stl"
        os.mkfifo(pipe)
        with pytest.raises(ValueError, match="is not a regular file"):
            objects.load(pipe)
    with pytest.raises(FileNotFoundError, match="no such mesh file"):
        objects.load(tmp_path / "missing.stl")


def test_scale_turns_millimetres_into_metres(tmp_path):
    with pytest.warns(UserWarning, match="millimetres"):
        src = objects.box((60.0, 50.0, 40.0))  # a box "in millimetres"
    path = tmp_path / "box_mm.stl"
    trimesh.Trimesh(src.vertices, src.faces, process=False).export(path)
    obj = objects.load(path, scale=0.001)
    assert np.allclose(obj.bounds[1] - obj.bounds[0], [0.06, 0.05, 0.04])
    with pytest.raises(ValueError, match="scale"):
        objects.load(path, scale=0)
    # A scale that shrinks it below what vertices can be told apart at: refused in one message,
    # without trimesh's warnings on the collapsed mesh.
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for scale in (1e-300, 1e-9):
            with pytest.raises(ValueError, match=r"box_mm.stl is .* m across \(scale .*\): too small to read"):
                objects.load(path, scale=scale)


def test_safe_repairs_are_made_and_reported(tmp_path):
    src = objects.sphere(0.03, subdivisions=2)
    v, f = src.vertices, src.faces
    # A fin (a face and its reverse), a repeated face, a face repeating a vertex, inward orientation.
    extra = np.array([[0, 1, 2], [2, 1, 0], f[5, ::-1], [3, 3, 4]])
    bad = np.concatenate([f[:, ::-1], extra])
    path = tmp_path / "messy.obj"
    trimesh.Trimesh(v, bad, process=False).export(path)
    obj, repairs = objects.load_mesh(path)
    assert obj.volume == pytest.approx(src.volume, rel=1e-6)
    text = " ".join(repairs)
    for phrase in ("repeat a vertex", "zero-volume fins", "duplicate", "inward"):
        assert phrase in text


def test_a_mesh_with_a_hole_is_refused(tmp_path):
    src = objects.sphere(0.03, subdivisions=2)
    path = tmp_path / "open.stl"
    trimesh.Trimesh(src.vertices, src.faces[1:], process=False).export(path)
    with pytest.raises(ValueError, match="open.stl: .*cannot be repaired safely"):
        objects.load(path)


@pytest.mark.parametrize("index", [99, -7])
def test_a_face_indexing_no_vertex_is_refused(tmp_path, index):
    # An ASCII PLY whose last face names a vertex the file does not have.
    path = tmp_path / "oob.ply"
    path.write_text("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                    "property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n"
                    "0 0 0\n0.05 0 0\n0 0.05 0\n0 0 0.05\n3 0 2 1\n3 0 1 3\n3 0 3 2\n" + f"3 1 2 {index}\n")
    with pytest.raises(ValueError, match=f"oob.ply: object face 3 indexes vertex {index}, outside 0..3"):
        objects.load(path)


def test_unreadable_and_missing_files(tmp_path):
    bad = tmp_path / "junk.stl"
    bad.write_bytes(b"\x00\x01 not a mesh")
    with pytest.raises(ValueError):
        objects.load(bad)
    with pytest.raises(FileNotFoundError):
        objects.load(tmp_path / "absent.obj")


@pytest.mark.skipif(not OBJECTS_DIR.is_dir(), reason=SHARED_MISSING)
def test_the_scanned_mug_is_repaired():
    obj, repairs = objects.load_mesh(OBJECTS_DIR / "ycb_mug.obj")
    assert obj.volume > 0 and repairs


def test_default_case_is_clear_of_the_object_and_faces_t():
    hand = hugger.Hand()
    for name in objects.names():
        case = scenarios.default_case(name, hand)
        assert case.obj.inside(case.target[None])[0]
        roots = hand.roots(case.palm_pose)
        assert np.all(case.obj.signed_distance(roots) > hand.reach)
        to_t = case.target - case.palm_pose[:3, 3]
        assert np.dot(case.palm_pose[:3, 2], to_t / np.linalg.norm(to_t)) == pytest.approx(1.0)


def test_default_case_options():
    hand = hugger.Hand()
    case = scenarios.default_case("sphere", hand, start=[0.0, 0.3, 0.0])
    assert np.allclose(case.palm_pose[:3, 3], [0, 0.3, 0]) and np.allclose(case.palm_pose[:3, 2], [0, -1, 0])
    case = scenarios.default_case("sphere", hand, normal=[1.0, 0.0, 0.0])
    assert case.palm_pose[0, 3] < -0.1 and np.allclose(case.palm_pose[:3, 2], [1, 0, 0])
    turned = scenarios.default_case("sphere", hand, turn_deg=60)
    assert np.dot(turned.palm_pose[:3, 2], [0, 0, -1]) == pytest.approx(0.5)
    with pytest.raises(ValueError, match="not inside"):
        scenarios.default_case("torus", hand, target=[0, 0, 0])
    with pytest.raises(ValueError, match="non-zero"):
        scenarios.default_case("sphere", hand, normal=[0, 0, 0])
    # a normal whose square over- or underflows is a direction all the same (no numpy warning:
    # pytest makes warnings errors)
    for scale in (1e300, 1e-320):
        case = scenarios.default_case("sphere", hand, normal=[scale, scale, 0.0])
        assert np.allclose(case.palm_pose[:3, 2], [2 ** -0.5, 2 ** -0.5, 0])


def test_interior_target_of_a_ring_is_in_the_tube():
    t = scenarios.interior_target(objects.torus())
    assert objects.torus().inside(t[None])[0]
    assert np.hypot(t[0], t[1]) == pytest.approx(0.04, abs=0.006)


@pytest.mark.parametrize("scale", [1e7, 1e300])
def test_a_mesh_scaled_beyond_the_coordinate_bound_is_refused_by_its_vertex(tmp_path, scale):
    path = tmp_path / "ico.stl"
    trimesh.creation.icosphere().export(path)
    with pytest.raises(ValueError, match="ico.stl: object vertex .* lies beyond 1e\\+06 m"):
        objects.load(path, scale=scale)
