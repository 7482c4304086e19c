"""Trajectory files: save and load, and the refusal of truncated, corrupt, pickled or malformed files."""
from __future__ import annotations

import io
import json
import tracemalloc
import zipfile

import numpy as np
import pytest

import hugger
from helpers import FILE_ARRAYS, same, start


# --- trajectory file -----------------------------------------------------------------------

def test_an_empty_trajectory_is_neither_saved_nor_summed_up(hand, tmp_path):
    planner = hugger.Planner(hand, hugger.objects.sphere(0.04, subdivisions=2), [0, 0, 0],
                             hugger.look_at([0, 0, 0.2], [0, 0, 0]))
    empty = planner.trajectory()  # before the first step()
    with pytest.raises(ValueError, match="holds no configuration"):
        empty.save(tmp_path / "empty.npz")
    assert not (tmp_path / "empty.npz").exists()
    with pytest.raises(ValueError, match="holds no configuration"):
        empty.summary()
    traj = planner.plan()
    for bad in (-1.0, float("nan"), "x"):
        with pytest.raises(ValueError, match="contact_distance must be"):
            traj.summary(contact_distance=bad)


def test_save_load_round_trip(hand, fine_sphere_plan, tmp_path):
    traj = fine_sphere_plan
    traj.save(tmp_path / "plan.npz")
    back = hugger.Trajectory.load(tmp_path / "plan.npz")
    for name in FILE_ARRAYS:
        np.testing.assert_array_equal(getattr(back, name), getattr(traj, name))
    assert back.status == "done" and back.hand == hand.to_dict() and back.params == traj.params
    with np.load(tmp_path / "plan.npz", allow_pickle=False) as z:
        assert int(z["format_version"]) == 1 and z["tip_state"].dtype == np.int8


def test_repr_is_one_short_line(fine_sphere_plan):
    text = repr(fine_sphere_plan)  # the arrays stay attributes; printed, a plan is its summary
    assert "\n" not in text and len(text) < 200, text
    assert text == (f"Trajectory(status='done', configurations={len(fine_sphere_plan)}, fingers=5, links=5, "
                    f"object={len(fine_sphere_plan.object_vertices)} vertices/"
                    f"{len(fine_sphere_plan.object_faces)} faces)")


def test_load_refuses_corrupt_and_pickled_files(tmp_path):
    (tmp_path / "junk.npz").write_bytes(b"not a zip file at all")
    with pytest.raises(ValueError, match="cannot read"):
        hugger.Trajectory.load(tmp_path / "junk.npz")
    np.savez(tmp_path / "pickled.npz", format_version=np.array([{"evil": 1}], dtype=object))
    with pytest.raises(ValueError):
        hugger.Trajectory.load(tmp_path / "pickled.npz")
    np.savez(tmp_path / "partial.npz", format_version=np.int64(1))
    with pytest.raises(ValueError, match="missing keys"):
        hugger.Trajectory.load(tmp_path / "partial.npz")


def test_truncated_file_is_refused(hand, fine_sphere, tmp_path):
    traj = hugger.Planner(hand, fine_sphere, [0, 0, 0], start(), max_iterations=20).plan()
    traj.save(tmp_path / "plan.npz")
    data = (tmp_path / "plan.npz").read_bytes()
    (tmp_path / "cut.npz").write_bytes(data[: len(data) // 2])
    with pytest.raises(ValueError, match="cannot read"):
        hugger.Trajectory.load(tmp_path / "cut.npz")


# --- trajectory files ---------------------------------------------------------------------------

@pytest.fixture(scope="module")
def saved(tmp_path_factory, hand, sphere):
    traj = hugger.Planner(hand, sphere, [0, 0, 0], start(), max_iterations=25).plan()
    path = tmp_path_factory.mktemp("traj") / "plan.npz"
    traj.save(path)
    with np.load(path, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    return traj, path, arrays


def _same(a: hugger.Trajectory, b: hugger.Trajectory) -> bool:
    """Every array, the hand, the parameters and the status, bit for bit."""
    return same(a, b, FILE_ARRAYS, ("hand_json", "params_json", "status"))


def _write(tmp_path, arrays, compressed=True):
    path = tmp_path / "t.npz"
    (np.savez_compressed if compressed else np.savez)(path, **arrays)
    return path


def _write_raw(path, arrays, key, raw: bytes):
    """An .npz of ``arrays`` whose member ``key`` is the bytes ``raw`` instead (a forged .npy)."""
    with zipfile.ZipFile(path, "w") as zf:
        for name, value in arrays.items():
            member = io.BytesIO()
            np.lib.format.write_array(member, value)
            zf.writestr(f"{name}.npy", raw if name == key else member.getvalue())
    return path


def test_truncated_files_are_refused_at_every_offset(saved, tmp_path):
    traj, path, _ = saved
    data = path.read_bytes()
    offsets = sorted(set(np.linspace(0, len(data) - 1, 41).astype(int)) | {1, 4, 30, len(data) - 22, len(data) - 1})
    for cut in offsets:
        (tmp_path / "cut.npz").write_bytes(data[:cut])
        with pytest.raises(ValueError, match="cannot read"):
            hugger.Trajectory.load(tmp_path / "cut.npz")


@pytest.mark.parametrize("compressed", [True, False])
def test_flipped_bytes_are_refused_or_harmless(saved, tmp_path, compressed):
    traj, _, arrays = saved
    data = _write(tmp_path, arrays, compressed).read_bytes()
    rng = np.random.default_rng(1994)
    refused = harmless = 0
    for _ in range(150):
        b = bytearray(data)
        for k in rng.integers(0, len(b), size=int(rng.integers(1, 4))):
            b[k] ^= int(rng.integers(1, 256))
        (tmp_path / "flip.npz").write_bytes(bytes(b))
        try:
            back = hugger.Trajectory.load(tmp_path / "flip.npz")
        except ValueError:
            refused += 1
            continue
        # a flip in zip metadata the reader ignores (timestamps, comments) changes nothing
        assert _same(back, traj)
        harmless += 1
    assert refused > 100 and refused + harmless == 150


def test_every_required_key_is_required(saved, tmp_path):
    _, _, arrays = saved
    for key in ("format_version", "hand_json", "params_json", "status", "object_vertices", "object_faces", "target",
                "palm_pose", "joints", "angles", "tip_state", "phase"):
        with pytest.raises(ValueError, match=f"missing keys.*{key}"):
            hugger.Trajectory.load(_write(tmp_path, {k: v for k, v in arrays.items() if k != key}))


def test_extra_keys_are_fine(saved, tmp_path):
    traj, _, arrays = saved
    back = hugger.Trajectory.load(_write(tmp_path, {**arrays, "my_notes": np.arange(3), "comment": np.array("hi")}))
    assert _same(back, traj)


def _edit(key, fn):
    return lambda a: {**a, key: fn(a[key])}


@pytest.mark.parametrize("edit, match", [
    (_edit("joints", lambda x: x.astype(np.int64)), "joints .* dtype"),
    (_edit("joints", lambda x: x.astype(complex)), "joints .* dtype"),
    (_edit("joints", lambda x: x[..., :2]), "joints has shape"),
    (_edit("joints", lambda x: x[:-1]), "joints has shape"),
    (_edit("joints", lambda x: np.where(x == x.max(), np.nan, x)), "joints holds non-finite"),
    (_edit("palm_pose", lambda x: x[:0]), "no configuration"),
    (_edit("palm_pose", lambda x: 2 * x), r"palm_pose\[0\] must be a homogeneous transform"),
    (_edit("palm_pose", lambda x: np.concatenate([x[:1], x[1:] * np.diag([1.0, 1.0, 1.5, 1.0])])),
     r"palm_pose\[1\] .*(rotation|orthonormal)"),
    (_edit("angles", lambda x: x[:, :, :-1]), "angles has shape"),
    (_edit("joints", lambda x: x + 1e300), r"joints holds numbers beyond \+-2e\+06"),
    (_edit("target", lambda x: x + 2e6), r"target holds numbers beyond \+-1e\+06"),
    (_edit("palm_pose", lambda x: x + np.pad(np.full((len(x), 3, 1), 2e6), ((0, 0), (0, 1), (3, 0)))),
     r"palm_pose\[0\]'s translation lies beyond 1e\+06 m"),
    (_edit("angles", lambda x: x + 1e7), "angles holds numbers beyond"),
    (_edit("tip_state", lambda x: x.astype(float)), "tip_state .* dtype"),
    (_edit("tip_state", lambda x: x + 7), r"tip_state holds [7-9]"),
    (_edit("tip_state", lambda x: x.astype(np.int64) + 256), "tip_state holds"),  # would wrap to int8 0
    (_edit("phase", lambda x: x - 1), "phase holds -1"),
    (_edit("target", lambda x: x[:2]), "target has shape"),
    (_edit("object_faces", lambda x: x + 10 ** 6), "object_faces index vertices outside"),
    (_edit("object_faces", lambda x: x[:0]), "non-empty"),
    (_edit("object_vertices", lambda x: x[:, :2]), "object_vertices"),
    (_edit("format_version", lambda x: np.int64(2)), r"format_version must be 1, got 2 \(int64\)$"),
    (_edit("format_version", lambda x: np.float64(1.5)), r"format_version must be 1, got 1.5 \(float64\)"),
    (_edit("format_version", lambda x: np.arange(10 ** 5)), r"got an array of shape \(100000,\)$"),
    (_edit("format_version", lambda x: np.float64(1)), "format_version must be 1"),
    (_edit("status", lambda x: np.array(b"done")), "status must be a string"),
    (_edit("status", lambda x: np.array(["done", "x"])), "status must be a string"),
    (_edit("hand_json", lambda x: np.array("{not json")), "hand_json is not valid JSON"),
    (_edit("hand_json", lambda x: np.array('{"fingers": -1}')), r"hand_json lacks \['links'\]"),
    (_edit("hand_json", lambda x: np.array("[1, 2]")), "hand_json must be a JSON object"),
    (_edit("stats_json", lambda x: np.array("{oops")), "stats_json is not valid JSON"),
    (_edit("hand_json", lambda x: np.array("[" * 100000 + "]" * 100000)), "not valid"),
    (_edit("hand_json", lambda x: np.array(json.dumps({**json.loads(str(x)), "fingers": "five"}))), "fingers"),
    (_edit("hand_json", lambda x: np.array(str(x).replace('"fingers": 5', '"fingers": Infinity'))), "fingers"),
    (_edit("hand_json", lambda x: np.array(json.dumps({**json.loads(str(x)), "fingers": 10 ** 9}))), "fingers"),
    (_edit("hand_json", lambda x: np.array(json.dumps({**json.loads(str(x)), "link_radius": -1}))), "link_radius"),
    (_edit("hand_json", lambda x: np.array(json.dumps({**json.loads(str(x)), "link_lengths": [[1]]}))),
     r"link_lengths must be a \(5, 5\) list"),
    (_edit("hand_json", lambda x: np.array(json.dumps({**json.loads(str(x)), "link_lengths": 0.02}))),
     r"link_lengths must be a \(5, 5\) list"),  # a hand takes a scalar; the format does not
    (_edit("hand_json", lambda x: np.array(json.dumps({**json.loads(str(x)), "link_lengths": [[-1.0] * 5] * 5}))),
     "link_length must be a positive"),
    # the hand's own rules (Hand.from_dict): what tools read, and everything else
    (_edit("hand_json", lambda x: np.array(json.dumps({**json.loads(str(x)), "finger_angles": [0.0, 1.0]}))),
     "finger_angles must hold 5"),
    (_edit("hand_json", lambda x: np.array(json.dumps({**json.loads(str(x)), "palm_radius": 0}))), "palm_radius"),
    (_edit("hand_json", lambda x: np.array(json.dumps({**json.loads(str(x)), "links": 4}))), r"\(5, 4\)"),
    (_edit("params_json", lambda x: np.array("[1, 2]")), "params_json"),
    # angles and joints that disagree: the analysis reads one, the physics test the other
    (_edit("angles", np.degrees), "angles and joints disagree at configuration"),
    (_edit("joints", lambda x: x + 1e-4), "angles and joints disagree at configuration 0"),
    (_edit("hand_json", lambda x: np.array(json.dumps({**json.loads(str(x)), "link_lengths": [[0.025] * 5] * 5}))),
     r"angles and joints disagree .*\(angles in degrees, or joints of another hand\?\)"),
])
def test_wrong_dtypes_shapes_and_values_are_refused(saved, tmp_path, edit, match):
    _, _, arrays = saved
    with pytest.raises(ValueError, match=match):
        hugger.Trajectory.load(_write(tmp_path, edit(dict(arrays))))


def test_angles_are_checked_to_the_precision_of_the_file(saved, tmp_path):
    # a float16 or float32 file's angles and joints agree only to their own rounding: loaded (it
    # was refused as "in degrees?"); its angles in degrees still refused; and save() refuses what
    # load() would, rather than write it
    import dataclasses

    traj, _, arrays = saved
    for dtype in (np.float16, np.float32):
        low = {**arrays, **{k: arrays[k].astype(dtype) for k in ("palm_pose", "joints", "angles")}}
        assert len(hugger.Trajectory.load(_write(tmp_path, low))) == len(traj)
        low["angles"] = np.degrees(arrays["angles"]).astype(dtype)
        with pytest.raises(ValueError, match="angles and joints disagree"):
            hugger.Trajectory.load(_write(tmp_path, low))
    with pytest.raises(ValueError, match="the trajectory: angles and joints disagree"):
        dataclasses.replace(traj, angles=np.degrees(traj.angles)).save(tmp_path / "deg.npz")
    assert not (tmp_path / "deg.npz").exists()


def test_half_precision_arrays_load_without_a_warning(saved, tmp_path):
    # (warnings are errors in the tests) the bound on coordinates is compared in double precision
    _, _, arrays = saved
    half = _edit("object_vertices", lambda x: x.astype(np.float16))
    assert hugger.Trajectory.load(_write(tmp_path, half(dict(arrays)))).object_vertices.dtype == np.float64


def test_a_hand_of_implausible_size_is_not_warned_of_again_on_loading(saved, tmp_path):
    # (warnings are errors in the tests) the whole scene scaled by 45, links of 0.9 m: the file
    # loads as it is, its size warned of when it was made
    _, _, arrays = saved
    big = dict(arrays)
    hand = json.loads(str(big["hand_json"]))
    for key in ("link_radius", "palm_radius", "palm_thickness"):
        hand[key] *= 45
    hand["link_lengths"] = (45 * np.asarray(hand["link_lengths"])).tolist()
    big["hand_json"] = np.array(json.dumps(hand))
    pose = big["palm_pose"].copy()
    pose[:, :3, 3] *= 45
    big.update(palm_pose=pose, joints=45 * big["joints"], target=45 * big["target"],
               object_vertices=45 * big["object_vertices"])
    traj = hugger.Trajectory.load(_write(tmp_path, big))
    assert traj.hand["link_lengths"][0][0] == pytest.approx(0.9)


def test_pickled_objects_are_refused_not_unpickled(saved, tmp_path):
    _, _, arrays = saved
    ran = []

    class Bomb:
        def __reduce__(self):
            return (ran.append, ("unpickled!",))

    for key in ("joints", "hand_json", "my_extra_key"):
        path = tmp_path / f"pickled_{key}.npz"
        np.savez(path, **{**arrays, key: np.array([Bomb()], dtype=object)})
        with pytest.raises(ValueError, match="pickled"):
            hugger.Trajectory.load(path)
    assert ran == []


def test_a_decompression_bomb_is_refused_unread(saved, tmp_path):
    # 96 MiB of zeros packed into about 100 kB: refused from the zip's own sizes, before numpy
    # allocates anything (a larger one would have the reader killed for lack of memory); beside
    # 8 MiB of numbers that do not pack, so that the members' total alone would pass
    import tracemalloc
    import zipfile

    _, _, arrays = saved
    path = tmp_path / "bomb.npz"
    rows = (96 << 20) // 24
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for key, a in arrays.items():
            if key != "object_vertices":
                with zf.open(f"{key}.npy", "w") as fh:
                    np.lib.format.write_array(fh, np.asarray(a), allow_pickle=False)
        with zf.open("noise.npy", "w") as fh:
            np.lib.format.write_array(fh, np.random.default_rng(0).random((1 << 20,)), allow_pickle=False)
        with zf.open("object_vertices.npy", "w", force_zip64=True) as fh:
            np.lib.format.write_array_header_1_0(fh, {"descr": "<f8", "fortran_order": False, "shape": (rows, 3)})
            chunk = bytes(1 << 20)
            for _ in range(96):
                fh.write(chunk)
    assert path.stat().st_size < 9 << 20
    tracemalloc.start()
    try:
        with pytest.raises(ValueError, match=r"object_vertices: \d+ bytes packed into \d+, over 100 times smaller: "
                                             "refused unread, as a decompression bomb"):
            hugger.Trajectory.load(path)
        assert tracemalloc.get_traced_memory()[1] < 16 << 20
    finally:
        tracemalloc.stop()


def test_a_decompression_bomb_split_over_many_members_is_refused_too(saved, tmp_path):
    # each member under the member's limit, together 480 MiB from well under a megabyte
    import zipfile

    _, _, arrays = saved
    path = tmp_path / "bombs.npz"
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for key, a in arrays.items():
            with zf.open(f"{key}.npy", "w") as fh:
                np.lib.format.write_array(fh, np.asarray(a), allow_pickle=False)
        for i in range(8):  # extra keys, which a reader ignores, but must not unpack
            with zf.open(f"extra{i}.npy", "w", force_zip64=True) as fh:
                np.lib.format.write_array_header_1_0(fh, {"descr": "<f8", "fortran_order": False,
                                                          "shape": ((60 << 20) // 8,)})
                chunk = bytes(1 << 20)
                for _ in range(60):
                    fh.write(chunk)
    assert path.stat().st_size < 1 << 20
    with pytest.raises(ValueError, match=r"its members: \d+ bytes packed into \d+, over 100 times smaller"):
        hugger.Trajectory.load(path)


def test_a_header_declaring_a_huge_array_is_refused_without_allocating(saved, tmp_path):
    _, _, arrays = saved
    joints = arrays["joints"]
    # the joints member of a real file, its header edited to declare 10**11 configurations (12 TB)
    bomb = io.BytesIO()
    np.lib.format.write_array_header_1_0(bomb, {"descr": "<f8", "fortran_order": False,
                                                "shape": (10 ** 11, *joints.shape[1:])})
    bomb.write(joints.tobytes())
    path = _write_raw(tmp_path / "bomb.npz", arrays, "joints", bomb.getvalue())
    tracemalloc.start()
    try:
        with pytest.raises(ValueError, match="declares"):
            hugger.Trajectory.load(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 50 << 20


def test_a_damaged_npy_header_is_a_value_error(saved, tmp_path):
    # found by test_fuzz: numpy parses the header with tokenize, which raises TokenError, not ValueError
    _, _, arrays = saved
    text = "{'descr': '<i8', 'fortran_order': False, 'shape': (320der': Fas, }"
    text += " " * (117 - len(text)) + "\n"
    header = b"\x93NUMPY\x01\x00" + len(text).to_bytes(2, "little") + text.encode("latin1")
    path = _write_raw(tmp_path / "header.npz", arrays, "object_faces", header + bytes(8 * 960))
    with pytest.raises(ValueError, match="cannot read"):
        hugger.Trajectory.load(path)


@pytest.mark.parametrize("header", [b"PK\x01\x02", b"PK\x03\x04"])  # the central directory's flags, a member's own
def test_a_member_flagged_encrypted_is_a_value_error(saved, tmp_path, header):
    # found by test_fuzz: a flipped flag bit makes zipfile ask for a password (a RuntimeError)
    _, path, _ = saved
    b = bytearray(path.read_bytes())
    flags = b.index(header) + (8 if header == b"PK\x01\x02" else 6)  # the first member's general-purpose flags
    b[flags] |= 0x1
    (tmp_path / "flagged.npz").write_bytes(bytes(b))
    try:
        back = hugger.Trajectory.load(tmp_path / "flagged.npz")
    except ValueError as exc:
        assert "cannot read" in str(exc)
    else:  # a reader that takes a member's flags from its directory entry alone: harmless
        assert header == b"PK\x03\x04" and np.array_equal(back.joints, saved[0].joints)


@pytest.mark.parametrize("content, match", [
    (b"", "cannot read"),
    (b"PK\x05\x06" + b"\0" * 18, "missing keys"),  # an empty zip
    (b"\x93NUMPY\x01\x00", "single array"),
    (b"\x80\x04\x95\x05\x00\x00\x00\x00\x00\x00\x00]\x94.", "cannot read"),  # a pickle
])
def test_files_that_are_not_trajectories(tmp_path, content, match):
    (tmp_path / "x.npz").write_bytes(content)
    with pytest.raises(ValueError, match=match):
        hugger.Trajectory.load(tmp_path / "x.npz")


def test_missing_file_and_directory(tmp_path):
    with pytest.raises(FileNotFoundError):
        hugger.Trajectory.load(tmp_path / "nothing.npz")
    with pytest.raises(ValueError, match="cannot read"):
        hugger.Trajectory.load(tmp_path)


def test_a_valid_file_from_another_writer_loads(saved, tmp_path):
    traj, _, arrays = saved
    # int64 states, uint8 phases, uncompressed: still format 1; loaded as int8
    edited = {**arrays, "tip_state": arrays["tip_state"].astype(np.int64), "phase": arrays["phase"].astype(np.uint8)}
    back = hugger.Trajectory.load(_write(tmp_path, edited, compressed=False))
    assert _same(back, traj) and back.tip_state.dtype == np.int8


def test_pickles_after_object_was_built(tmp_path):
    # A trajectory whose object() was asked (analysis, link gaps) still goes to worker processes.
    import pickle

    case = hugger.scenarios.default_case("sphere")
    traj = hugger.plan(case.hand, case.obj, case.target, case.palm_pose)
    gaps = traj.link_gaps()  # builds and caches the Object
    back = pickle.loads(pickle.dumps(traj))
    assert same(back, traj, arrays=FILE_ARRAYS) and back._object is None and traj._object is not None
    np.testing.assert_array_equal(back.link_gaps(), gaps)


def test_configuration_index_is_checked_as_analysis_checks_it(sphere_plan):
    n = len(sphere_plan)
    assert sphere_plan.configuration(-1).iteration == n - 1
    with pytest.raises(IndexError, match=f"configuration k={n} is out of range for a trajectory of {n} configurations"):
        sphere_plan.configuration(n)
    with pytest.raises(ValueError, match="k must be a whole configuration index"):
        sphere_plan.configuration(1.5)


def test_a_save_that_fails_names_the_file_asked_for(sphere_plan, tmp_path):
    # not the temporary file the write goes through
    (tmp_path / "plan.npz").mkdir()
    with pytest.raises(OSError) as err:
        sphere_plan.save(tmp_path / "plan.npz")
    assert err.value.filename == str(tmp_path / "plan.npz") and ".part" not in str(err.value)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plan.npz"]  # nothing left beside it
