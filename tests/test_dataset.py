"""hugger generate / hugger.Dataset: determinism over workers and backends, resuming after a kill,
the loader, the MJCF export, and the independent checker on every saved grasp."""
from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import hugger
from hugger import analysis, dataset
from hugger.cli import main

from helpers import children, proc_file, save_and_check, write_ball

OBJECTS = ["box", "torus", "cylinder"]


def shard_bytes(root: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted((root / "shards").iterdir())}


def index_without_command(root: Path) -> dict:
    d = json.loads((root / "index.json").read_text())
    d.pop("command")
    return d


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> Path:
    """The uninterrupted run, one worker."""
    out = tmp_path_factory.mktemp("ref") / "ds"
    assert main(["generate", *OBJECTS, "--approaches", "3", "--out", str(out), "--workers", "1"]) == 0
    return out


def test_shards_are_byte_identical_whatever_the_workers(reference, tmp_path):
    out = tmp_path / "ds"
    assert main(["generate", *OBJECTS, "--approaches", "3", "--out", str(out), "--workers", "2"]) == 0
    assert shard_bytes(out) == shard_bytes(reference)
    assert index_without_command(out) == index_without_command(reference)
    index = json.loads((out / "index.json").read_text())
    assert index["command"][:2] == ["hugger", "generate"] and "--workers" in index["command"]
    assert [o["name"] for o in index["objects"]] == OBJECTS and all(len(o["sha256"]) == 64 for o in index["objects"])
    assert index["hugger_version"] == hugger.__version__


def _finished(out: Path) -> list[Path]:
    """Shards under their final names (a temporary also ends .npz, but starts with a dot)."""
    return [p for p in (out / "shards").iterdir() if p.suffix == ".npz" and not p.name.startswith(".")]


def _child_setup() -> None:
    # A suite started in the background by a non-interactive shell ignores SIGINT, and a child
    # inherits that (Python then installs no KeyboardInterrupt handler): the run would ignore the
    # test's SIGINT and finish. The run is also niced, so that on a busy machine it, not the
    # polling loop below, waits for the CPU.
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    os.nice(10)


def _run_until_first_shard(out: Path, sig: int) -> int:
    cmd = [sys.executable, "-m", "hugger", "generate", *OBJECTS, "--approaches", "3", "--out", str(out),
           "--workers", "1"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True,
                            preexec_fn=_child_setup)
    deadline = time.monotonic() + 120
    try:
        while time.monotonic() < deadline and proc.poll() is None:
            if (out / "shards").is_dir() and _finished(out):
                break
            time.sleep(0.01)
        os.killpg(proc.pid, sig)
    except ProcessLookupError:
        pass
    proc.wait(timeout=60)
    return proc.returncode


@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGINT])
def test_a_killed_run_resumes_to_the_same_dataset(reference, tmp_path, sig):
    out = tmp_path / "ds"
    code = _run_until_first_shard(out, sig)
    assert code != 0, "the run finished before it could be killed"
    assert not (out / "index.json").exists()
    finished = _finished(out)
    assert 1 <= len(finished) < len(OBJECTS)  # killed part-way
    for p in finished:  # whatever has its final name is whole
        assert p.read_bytes() == (reference / "shards" / p.name).read_bytes()
    before = {p.name: p.stat().st_mtime_ns for p in finished}
    assert main(["generate", *OBJECTS, "--approaches", "3", "--out", str(out), "--workers", "1"]) == 0
    assert shard_bytes(out) == shard_bytes(reference)
    assert index_without_command(out) == index_without_command(reference)
    assert not any(p.name.startswith(".") for p in (out / "shards").iterdir())  # no temporary files left
    for p in finished:  # done shards were kept, not made again
        assert (out / "shards" / p.name).stat().st_mtime_ns == before[p.name]


def _running(pid: int) -> bool:
    """The process exists and is not a zombie (one left unreaped by a container's first process)."""
    stat = proc_file(pid, "stat")
    return bool(stat) and stat.rsplit(")", 1)[1].split()[0] != "Z"


def _start_with_two_workers(cmd: list[str], **popen: Any) -> tuple[subprocess.Popen[bytes], set[int]]:
    """Start ``cmd`` (a run of two workers) in its own session; it and its workers' pids once both run."""
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True, **popen)
    deadline = time.monotonic() + 120
    workers: set[int] = set()
    while time.monotonic() < deadline and proc.poll() is None and len(workers) < 2:
        workers = {p for p in children(proc.pid) if "spawn_main" in proc_file(p, "cmdline")}
        time.sleep(0.05)
    return proc, workers


def _left_running(workers: set[int], within: float = 30.0) -> list[int]:
    """The workers still running after up to ``within`` seconds."""
    deadline = time.monotonic() + within
    while time.monotonic() < deadline and any(_running(p) for p in workers):
        time.sleep(0.05)
    return [p for p in workers if _running(p)]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="workers end with their parent through Linux's prctl")
def test_workers_end_when_their_run_is_killed_outright(tmp_path):
    # SIGKILL to the run alone (not its process group): it cannot shut its pool down.
    proc, workers = _start_with_two_workers([sys.executable, "-m", "hugger", "generate", *OBJECTS, "--approaches",
                                             "3", "--out", str(tmp_path / "ds"), "--workers", "2"])
    try:
        assert len(workers) == 2, "the run ended before its workers started"
        proc.kill()
        proc.wait(timeout=60)
        left = _left_running(workers)
        assert not left, f"workers {left} outlived their run"
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads the workers from Linux's /proc")
def test_sigint_to_the_run_alone_stops_it_and_its_workers_at_once(tmp_path):
    # A scheduler or `kill -INT` signals the run, not its workers: they are stopped, not waited
    # for (each of these shards takes tens of seconds).
    proc, workers = _start_with_two_workers([sys.executable, "-m", "hugger", "generate", "curvy", "apple",
                                             "--approaches", "26", "--validate", "--out", str(tmp_path / "ds"),
                                             "--workers", "2"], preexec_fn=_child_setup)
    try:
        assert len(workers) == 2, "the run ended before its workers started"
        time.sleep(1.0)  # into the shards' work
        t0 = time.monotonic()
        proc.send_signal(signal.SIGINT)
        assert proc.wait(timeout=60) == 130
        assert time.monotonic() - t0 < 10, "the run waited for its workers' shards"
        assert not _left_running(workers)
        assert not (tmp_path / "ds" / "index.json").exists()
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)


def test_other_settings_in_the_same_folder_are_refused(reference, tmp_path):
    import shutil

    out = tmp_path / "ds"
    shutil.copytree(reference, out)
    with pytest.raises(ValueError, match="other settings"):
        dataset.generate(OBJECTS, out, approaches=4, workers=1)


def test_a_run_that_would_leave_shards_out_of_the_index_is_refused(reference, tmp_path):
    # Fewer objects, or other settings with no shard name in common (before, the new index simply
    # replaced the old one, whose shards were then listed nowhere).
    import shutil

    out = tmp_path / "ds"
    shutil.copytree(reference, out)
    index = (out / "index.json").read_bytes()
    with pytest.raises(ValueError, match="other settings or objects: 1 of its 3 shards"):
        dataset.generate(OBJECTS[:2], out, approaches=3, workers=1)
    with pytest.raises(ValueError, match="3 of its 3 shards.*or remove index.json"):
        dataset.generate(OBJECTS, out, approaches=3, hands=["4x4"], workers=1)
    assert (out / "index.json").read_bytes() == index
    older = json.loads(index)
    older["hugger_version"] = "0.0.1"
    (out / "index.json").write_text(json.dumps(older))
    with pytest.raises(ValueError, match=r"made by hugger 0\.0\.1; this is"):
        dataset.generate(OBJECTS[:1], out, approaches=3, workers=1)
    (out / "index.json").write_text("[1, 2]")
    with pytest.raises(ValueError, match="not the index of a hugger dataset"):
        dataset.generate(OBJECTS, out, approaches=3, workers=1)


def test_the_rule_set_is_honoured_from_the_cli_and_from_params(tmp_path):
    # --rules reached search() twice (as rules= and among the parameters): every run crashed.
    cli_out, api_out, hug_out = tmp_path / "cli", tmp_path / "api", tmp_path / "hug"
    assert main(["generate", "box", "--approaches", "2", "--rules", "paper", "--out", str(cli_out), "--workers", "1"]) == 0
    index = dataset.generate(["box"], api_out, approaches=2, params={"rules": "paper"}, workers=1)
    assert index["parameters"]["rules"] == "paper"
    assert shard_bytes(cli_out) == shard_bytes(api_out)
    dataset.generate(["box"], hug_out, approaches=2, workers=1)
    assert shard_bytes(hug_out) != shard_bytes(api_out)  # the rule set made a difference
    with pytest.raises(ValueError, match="given twice"):
        dataset.generate(["box"], tmp_path / "x", approaches=2, rules="hug", params={"rules": "paper"})
    with pytest.raises(ValueError, match="rules must be one of"):
        dataset.generate(["box"], tmp_path / "x", approaches=2, rules="papr")


def test_a_hand_of_implausible_size_is_refused_unless_forced(tmp_path, capsys):
    # --hands 5x5:link_length=20 (millimetres) only warned, and made the dataset
    code = main(["generate", "box", "--approaches", "1", "--hands", "5x5:link_length=20", "--out", str(tmp_path / "d")])
    err = capsys.readouterr().err
    assert code == 2 and "hand spec '5x5:link_length=20': the hand is 100 m across, implausibly large" in err
    assert "--force" in err and not (tmp_path / "d").exists()
    with pytest.warns(UserWarning, match="the hand is 100 m across"):
        assert dataset.parse_hand("5x5:link_length=20", force=True) == ("5x5_link_length20", {
            "fingers": 5, "links": 5, "link_length": 20.0})


def test_the_skin_is_chosen_from_the_cli_and_recorded(tmp_path):
    # hugger generate had no --skin: a dataset of the reference (mesh) skin needed Python
    cli_out, api_out = tmp_path / "cli", tmp_path / "api"
    assert main(["generate", "box", "--approaches", "2", "--skin", "mesh", "--out", str(cli_out), "--workers", "1"]) == 0
    index = dataset.generate(["box"], api_out, approaches=2, params={"skin": "mesh"}, workers=1)
    assert json.loads((cli_out / "index.json").read_text())["parameters"]["planner"]["skin"] == "mesh"
    assert index["parameters"]["planner"]["skin"] == "mesh"
    assert shard_bytes(cli_out) == shard_bytes(api_out)
    ds = hugger.Dataset(cli_out)
    assert json.loads(str(ds.shard(0)["params_json"]))["skin"] == "mesh"
    ds.trajectory(0)  # re-planned with the recorded skin, it ends in the stored grasp (else it raises)


def test_a_run_may_add_objects_to_a_dataset(reference, tmp_path):
    import shutil

    out = tmp_path / "ds"
    shutil.copytree(reference, out)
    before = shard_bytes(out)
    index = dataset.generate([*OBJECTS, "sphere"], out, approaches=3, workers=1)
    assert [s["object"] for s in index["shards"]] == [*OBJECTS, "sphere"]
    after = shard_bytes(out)
    assert {k: after[k] for k in before} == before  # the shards made before are kept as they were
    assert len(hugger.Dataset(out)) == 3 * (len(OBJECTS) + 1)


def test_loader_and_every_saved_grasp_passes_the_checker(reference, tmp_path, checker):
    ds = hugger.Dataset(reference)
    assert len(ds) == 3 * len(OBJECTS)
    assert [ds.shards[i]["object"] for i in range(len(ds.shards))] == OBJECTS
    for i, g in enumerate(ds):
        z = ds.shard(g.shard)
        assert g.status != "error"
        assert g.joints.shape == (5, 6, 3) and g.angles.shape == (5, 5) and g.palm_pose.shape == (4, 4)
        assert len(g.contact_points) == len(g.contact_normals) == len(g.contact_finger)
        assert np.allclose(np.linalg.norm(g.contact_normals, axis=1), 1.0)
        assert (g.epsilon > 0) == g.force_closure
        assert g.best == (g.index == int(z["best"]))
        traj = ds.trajectory(i)  # re-planned from the stored start, checked against the stored grasp
        assert np.array_equal(traj.angles[-1], g.angles)
        # the stored escape is the ranking's figure, capped at the reach
        assert g.escape == analysis.escape(traj.hand, traj.object(), g.palm_pose, g.joints)
        save_and_check(checker, traj, tmp_path / f"g{i}.npz", context=i)
    with pytest.raises(IndexError):
        ds[len(ds)]


def test_a_shard_index_out_of_range_says_so(reference):
    ds = hugger.Dataset(reference)
    assert ds.shard(-1) is ds.shard(len(ds.shards) - 1)  # negative counts from the end, as for grasps
    for bad in (len(ds.shards), -len(ds.shards) - 1):
        with pytest.raises(IndexError, match="out of range for a dataset of"):
            ds.shard(bad)
    for bad in (1.0, True, "0"):  # as for grasps (ds[1.5]) and Python's lists: not an index at all
        with pytest.raises(TypeError, match="a shard index must be an integer"):
            ds.shard(bad)


def test_export_mjcf_keyframe(reference, tmp_path):
    mujoco = pytest.importorskip("mujoco")
    ds = hugger.Dataset(reference)
    path = tmp_path / "grasp.xml"
    xml = ds.export_mjcf(0, path, decompose=False)
    assert path.read_text() == xml
    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    assert np.allclose(data.qpos[:25], ds[0].angles.ravel())


def test_validate_stores_physics_verdicts(tmp_path):
    pytest.importorskip("mujoco")
    out = tmp_path / "ds"
    dataset.generate(["box"], out, approaches=2, validate=True, workers=1)
    z = hugger.Dataset(out).shard(0)
    assert z["held"].shape == (2,) and z["held_directions"].shape == (2, 6)
    assert np.array_equal(z["held"], z["held_directions"].all(axis=1))
    assert list(z["validate_directions"]) == ["+x", "-x", "+y", "-y", "+z", "-z"]
    assert hugger.Dataset(out)[0].held == bool(z["held"][0])


def test_ray_backend_gives_the_same_shards(reference, tmp_path):
    pytest.importorskip("ray", reason="the Ray backend needs ray (pip install 'hugger[cluster]')")
    out = tmp_path / "ds"
    dataset.generate(OBJECTS, out, approaches=3, workers=2, backend="ray")
    assert shard_bytes(out) == shard_bytes(reference)


def test_bad_input(tmp_path, capsys, monkeypatch):
    assert main(["generate", "box", "--out", str(tmp_path), "--hands", "5y5"]) == 2
    assert "hand spec" in capsys.readouterr().err
    a_file = tmp_path / "plan.npz"
    a_file.write_bytes(b"")
    assert main(["generate", "box", "--out", str(a_file)]) == 2  # a file is not a folder: no traceback
    err = capsys.readouterr().err
    assert "is a file" in err and "Traceback" not in err and err.count("\n") == 1
    # Every object is checked before any shard is made: an open mesh after a good object.
    open_mesh = tmp_path / "open.obj"
    open_mesh.write_text("v 0 0 0\nv 0.05 0 0\nv 0 0.05 0\nv 0 0 0.05\nf 1 2 3\nf 1 2 4\nf 1 3 4\n")
    assert main(["generate", "box", str(open_mesh), "--out", str(tmp_path / "ds")]) == 2
    assert not (tmp_path / "ds").exists()
    assert main(["generate", "nothing.stl", "--out", str(tmp_path)]) == 2
    assert main(["generate", "box", "--out", str(tmp_path), "--address", "x:1"]) == 2
    assert "applies to the Ray backend" in capsys.readouterr().err
    # An address where nothing answers is refused at once, not retried for minutes by ray.init
    # (before Ray is asked for anything: a stand-in where the extra is not installed).
    import types

    monkeypatch.setattr(dataset, "_ray", lambda: types.SimpleNamespace())
    for address, message in (("nonsense", "HOST:PORT"), ("127.0.0.1:1", "no Ray cluster answers at 127.0.0.1:1"),
                             ("ray://127.0.0.1:1", "no Ray cluster answers"), ("host:99999", "HOST:PORT"),
                             ("http://127.0.0.1:1", "HOST:PORT"), ("a:b:1", "HOST:PORT"),
                             ("[::1]:1", "no Ray cluster answers at [::1]:1")):
        assert main(["generate", "box", "--out", str(tmp_path / "r"), "--backend", "ray", "--address", address]) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1, err
        assert not (tmp_path / "r").exists()
    # Something answers the address, but ray.init finds no cluster there: one line too.
    import socket

    def no_cluster(**_kwargs):
        raise ConnectionError("Failed to connect to Ray cluster at that address")

    fake = types.SimpleNamespace(is_initialized=lambda: False, init=no_cluster)
    with socket.create_server(("127.0.0.1", 0)) as server, pytest.MonkeyPatch.context() as mp:
        mp.setattr(dataset, "_ray", lambda: fake)
        mp.setattr(dataset, "_probe_ray", lambda address: None)  # (its own test: below)
        address = f"127.0.0.1:{server.getsockname()[1]}"
        assert main(["generate", "box", "--out", str(tmp_path / "r2"), "--backend", "ray", "--address", address]) == 2
        err = capsys.readouterr().err
        assert f"no Ray cluster answers at {address}: Failed to connect" in err and err.count("\n") == 1, err
    with pytest.raises(ValueError, match="twice"):
        dataset.generate(["box"], tmp_path, hands=["5x5", "5x5"])
    for kwargs, message in (({"objects": "box"}, "objects must be a list of names"),
                            ({"hands": "5x5"}, "hands must be a list of names"), ({"hands": []}, "at least one hand"),
                            ({"validate": "yes"}, "validate must be True or False"),
                            ({"progress": 5}, "progress must be callable"), ({"log": 5}, "log must be callable"),
                            ({"params": {"step": -1.0}}, "step must be a positive finite number")):
        with pytest.raises(ValueError, match=message):
            dataset.generate(**{"objects": ["box"], "out": tmp_path / "refused", **kwargs})
        assert not (tmp_path / "refused").exists()  # refused before the folder is made
    assert main(["generate", "box", "--out", str(tmp_path / "neg"), "--step", "-1"]) == 2
    assert "step must be a positive finite number" in capsys.readouterr().err and not (tmp_path / "neg").exists()
    with pytest.raises(ValueError, match="link_length is given twice"):
        dataset.parse_hand("5x5:link_length=0.02,link_length=0.03")
    assert dataset.parse_hand("4x3:link_length=0.025,palm_radius=0.035") == (
        "4x3_link_length0.025_palm_radius0.035",
        {"fingers": 4, "links": 3, "link_length": 0.025, "palm_radius": 0.035})


def test_an_implausible_size_is_refused_unless_forced_and_repairs_are_told(tmp_path, capsys):
    mm = write_ball(tmp_path / "ball_mm.obj", 40.0)  # a 4 cm ball in millimetres, read as metres
    assert main(["generate", str(mm), "--out", str(tmp_path / "ds")]) == 2
    err = capsys.readouterr().err
    assert "ball_mm.obj is" in err and "implausibly large" in err and err.count("\n") == 1
    assert "(give --scale, or --force to make its shards anyway)" in err and "force=True" not in err
    assert not (tmp_path / "ds").exists()  # refused before anything is made
    assert main(["generate", str(mm), "--scale", "1e-6", "--out", str(tmp_path / "ds")]) == 2
    assert "implausibly small" in capsys.readouterr().err
    with pytest.raises(ValueError, match=r"implausibly large.*refused \(give a scale, or force=True"):
        dataset.generate([str(mm)], tmp_path / "ds")
    with pytest.warns(UserWarning, match="ball_mm.obj is .*making its shards anyway"):
        entry = dataset._object_entry(str(mm), 1.0, force=True)
    assert entry["name"] == "ball_mm"
    with pytest.raises(ValueError, match="force must be True or False"):
        dataset.generate([str(mm)], tmp_path / "ds", force="yes")
    # An inside-out mesh is repaired, and the repair told, as hugger plan tells it.
    inverted = write_ball(tmp_path / "inside_out.obj", inside_out=True)
    with pytest.warns(UserWarning, match="repaired inside_out.obj: flipped"):
        dataset._object_entry(str(inverted), 1.0)


def test_a_damaged_shard_is_named_and_made_again(reference, tmp_path):
    import shutil
    import warnings

    out = tmp_path / "ds"
    shutil.copytree(reference, out)
    shard = out / "shards" / f"{OBJECTS[0]}__5x5.npz"
    shard.write_bytes(shard.read_bytes()[:3000])  # a truncated copy
    with pytest.raises(ValueError, match=f"{shard.name} is not a whole shard"):
        hugger.Dataset(out)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the damaged file is closed (it was left open: a ResourceWarning)
        assert main(["generate", *OBJECTS, "--approaches", "3", "--out", str(out), "--workers", "1"]) == 0
    assert shard_bytes(out) == shard_bytes(reference)
    ds = hugger.Dataset(out)
    with pytest.raises(TypeError, match="integer"):
        ds["0"]
    with pytest.raises(TypeError, match="integer"):
        ds[1.0]
    with pytest.raises(IndexError, match="out of range"):
        ds[len(ds)]


def _edit_index(index: dict, how: str) -> Any:
    if how == "deep":
        return "[" * 100000 + "]" * 100000
    if how == "shard is a string":
        index["shards"][0] = "shards/x.npz"
    elif how == "shard without file":
        del index["shards"][0]["file"]
    elif how == "file is a number":
        index["shards"][0]["file"] = 5
    elif how == "hands not a list":
        index["hands"] = {"5x5": {}}
    elif how == "no hands":
        del index["hands"]
    elif how == "no parameters":
        del index["parameters"]
    elif how == "scale is a string":
        index["objects"][0]["scale"] = "1"
    return json.dumps(index)


@pytest.mark.parametrize("how", ["deep", "shard is a string", "shard without file", "file is a number", "hands not a list",
                                 "no hands", "no parameters", "scale is a string"])
def test_a_malformed_index_is_a_value_error(reference, tmp_path, how):
    import shutil

    out = tmp_path / "ds"
    shutil.copytree(reference, out)
    (out / "index.json").write_text(_edit_index(json.loads((out / "index.json").read_text()), how))
    with pytest.raises(ValueError, match="is not the index of a hugger dataset"):
        hugger.Dataset(out)


def _rewrite_shard(path: Path, edit) -> None:
    with np.load(path, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    edit(arrays)
    with open(path, "wb") as fh:
        np.savez(fh, **arrays)


@pytest.mark.parametrize("edit, why", [
    (lambda a: a.update(status=np.array("done")), "no status per approach"),
    (lambda a: a.pop("contact_offsets"), "no contact_offsets"),
    (lambda a: a.update(contact_offsets=a["contact_offsets"] + 10 ** 6), "contact offsets do not split"),
    (lambda a: a.update(contact_offsets=a["contact_offsets"][::-1].copy()), "contact offsets do not split"),
    (lambda a: a.update(joints=a["joints"][:1]), "joints has shape"),
    (lambda a: a.update(best=np.int64(99)), "best is"),
])
def test_a_malformed_shard_is_a_value_error_naming_it(reference, tmp_path, edit, why):
    import shutil

    out = tmp_path / "ds"
    shutil.copytree(reference, out)
    shard = out / "shards" / f"{OBJECTS[0]}__5x5.npz"
    _rewrite_shard(shard, edit)
    with pytest.raises(ValueError, match=f"{shard.name} is not a (whole )?shard.*{why}"):
        ds = hugger.Dataset(out)
        ds[0]


def test_a_grasp_whose_hand_the_index_lacks_is_a_value_error(reference, tmp_path):
    import shutil

    out = tmp_path / "ds"
    shutil.copytree(reference, out)
    index = json.loads((out / "index.json").read_text())
    hands = index["hands"]
    index["hands"] = []
    (out / "index.json").write_text(json.dumps(index))
    with pytest.raises(ValueError, match="grasp 0: its hand '5x5' is not among the index's hands"):
        hugger.Dataset(out).trajectory(0)
    index["hands"] = [{**hands[0], "kwargs": {"nope": 1}}]
    (out / "index.json").write_text(json.dumps(index))
    with pytest.raises(ValueError, match="grasp 0: the index's hand '5x5' is not a hugger.Hand's keywords"):
        hugger.Dataset(out).trajectory(0)


def test_a_folder_another_run_is_writing_is_refused(tmp_path):
    # The other run holds the folder (here, this process): a second run would mix its shards with
    # the other's and write its own index. Refused at once, nothing written; then made as usual.
    out = tmp_path / "ds"
    holder = subprocess.Popen([sys.executable, "-c", "import sys, pathlib\nfrom hugger.dataset import _exclusive\n"
                               f"with _exclusive(pathlib.Path({str(out)!r})):\n print('held', flush=True)\n"
                               " sys.stdin.readline()"], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        r = subprocess.run([sys.executable, "-m", "hugger", "generate", "sphere", "--approaches", "2", "--out", str(out)],
                           capture_output=True, text=True, timeout=120)
        assert r.returncode == 2 and "is being written by another hugger generate" in r.stderr, r.stderr
        assert [p.name for p in out.iterdir()] == [dataset.LOCK_FILE]  # the holder's alone
    finally:
        holder.communicate("\n", timeout=60)
    assert main(["generate", "sphere", "--approaches", "2", "--out", str(out), "--workers", "1"]) == 0
    assert hugger.Dataset(out)[0].status == "done"


def test_a_run_refused_or_interrupted_before_a_shard_leaves_no_folder_it_made(tmp_path, monkeypatch):
    out = tmp_path / "a" / "b" / "ds"
    monkeypatch.setattr(dataset, "_check_index", lambda root, tasks: (_ for _ in ()).throw(ValueError("refused")))
    with pytest.raises(ValueError, match="refused"):
        dataset.generate(["sphere"], out, approaches=2, workers=1)
    assert list(tmp_path.iterdir()) == []  # nor the parents it made
    monkeypatch.undo()
    monkeypatch.setattr(dataset, "make_shard", lambda task: (_ for _ in ()).throw(KeyboardInterrupt))
    with pytest.raises(KeyboardInterrupt):
        dataset.generate(["sphere"], out, approaches=2, workers=1)
    assert list(tmp_path.iterdir()) == []  # its empty shards folder and lock file too
    (tmp_path / "kept").mkdir()
    with pytest.raises(KeyboardInterrupt):
        dataset.generate(["sphere"], tmp_path / "kept", approaches=2, workers=1)
    assert (tmp_path / "kept").is_dir()  # a folder it did not make stays


def test_a_filesystem_without_locks_is_written_unguarded_with_a_warning(tmp_path, monkeypatch):
    import errno
    import fcntl

    def no_lock(fd, op):
        raise OSError(errno.EBADF, "Bad file descriptor")  # NFS without its lock service, say

    monkeypatch.setattr(fcntl, "flock", no_lock)
    with pytest.warns(UserWarning, match="this filesystem takes no lock"):
        dataset.generate(["sphere"], tmp_path / "ds", approaches=2, workers=1)
    assert hugger.Dataset(tmp_path / "ds")[0].status == "done"


def test_a_temporary_left_by_a_killed_writer_is_removed_on_resume(reference, tmp_path):
    import shutil

    out = tmp_path / "ds"
    shutil.copytree(reference, out)
    (out / "index.json").unlink()
    left = out / "shards" / f".{OBJECTS[0]}__5x5.npz.4242-0123456789ab.part.npz"
    left.write_bytes(b"PK\x03\x04 half a shard")
    assert main(["generate", *OBJECTS, "--approaches", "3", "--out", str(out), "--workers", "1"]) == 0
    assert not left.exists()
    assert shard_bytes(out) == shard_bytes(reference)


def test_settings_no_hand_can_plan_with_and_a_hand_given_twice_are_refused_before_any_shard(tmp_path, capsys):
    out = tmp_path / "ds"
    # the 5x5 hand takes a 15 mm step, the 4x3 one of 1 cm links does not: nothing is made
    assert main(["generate", "sphere", "box", "--hands", "5x5", "4x3:link_length=0.01", "--step", "0.015",
                 "--approaches", "3", "--workers", "1", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "hand '4x3_link_length0.01': step (0.015 m) must not exceed the shortest link (0.01 m)" in err
    assert err.count("\n") == 1 and not out.exists()
    assert main(["generate", "sphere", "--epsilon", "1", "--approaches", "3", "--out", str(out)]) == 2
    assert "epsilon (1 m) must not exceed step" in capsys.readouterr().err and not out.exists()
    # one hand under two specs
    assert main(["generate", "sphere", "--hands", "5x5", "5x5:link_length=0.02", "--approaches", "2",
                 "--out", str(out)]) == 2
    assert "the hands '5x5' and '5x5_link_length0.02' are the same hand" in capsys.readouterr().err
    assert not out.exists()


@pytest.mark.parametrize("kwargs, message", [
    ({"scale": None}, "scale must be a number"), ({"scale": "a"}, "scale must be a number"),
    ({"objects": [None]}, "each object must be a built-in name or a mesh file's path"),
    ({"objects": [3]}, "each object must be"), ({"out": None}, "out must be a folder's path"),
    ({"params": [1]}, "params must be a mapping"), ({"command": "hugger generate"}, "command must be a list"),
    ({"command": ["hugger", 3]}, "command must be a list of strings"), ({"command": 3}, "command must be a list"),
    ({"objects": 3}, "objects must be a list"), ({"hands": 3}, "hands must be a list"),
])
def test_bad_python_arguments_are_value_errors(tmp_path, kwargs, message):
    args = {"objects": ["sphere"], "out": tmp_path / "ds", "approaches": 2, **kwargs}
    with pytest.raises(ValueError, match=message):
        dataset.generate(**args)
    assert not (tmp_path / "ds").exists()


def test_repeated_hands_are_all_made_and_a_file_is_no_dataset_folder(tmp_path, capsys):
    from hugger.cli import main

    # --hands 5x5 --hands 3x3 made the 3x3 hand's shard alone
    assert main(["generate", "sphere", "--hands", "5x5", "--hands", "3x3", "--approaches", "1", "--workers", "1",
                 "--out", str(tmp_path / "d")]) == 0
    assert sorted(p.name for p in (tmp_path / "d" / "shards").iterdir()) == ["sphere__3x3.npz", "sphere__5x5.npz"]
    (tmp_path / "f").write_text("x")
    for out in (tmp_path / "f", tmp_path / "f" / "d"):  # were NotADirectoryError and FileExistsError
        with pytest.raises(ValueError, match="f is a file; a dataset is a folder"):
            dataset.generate(["sphere"], out, approaches=1, workers=1)


def test_a_shard_records_its_rule_set(tmp_path):
    out = tmp_path / "ds"
    # (objects and the command line as iterators: read once, recorded whole)
    dataset.generate(iter(["sphere"]), out, approaches=2, rules="paper", workers=1, command=iter(["hugger", "x"]))
    assert json.loads((out / "index.json").read_text())["command"] == ["hugger", "x"]
    ds = hugger.Dataset(out)
    assert json.loads(str(ds.shard(0)["params_json"]))["rules"] == "paper"
    assert ds.trajectory(0).params["rules"] == "paper"
    # a shard is no trajectory file: hugger info says what it is
    with pytest.raises(ValueError, match="it is a shard of a dataset: read it with hugger.Dataset"):
        hugger.Trajectory.load(out / "shards" / "sphere__5x5.npz")


def test_a_dataset_of_a_relative_mesh_path_reads_from_any_folder_and_a_missing_shard_is_named(tmp_path, monkeypatch):
    import trimesh

    monkeypatch.chdir(tmp_path)
    (tmp_path / "meshes").mkdir()
    trimesh.creation.icosphere(subdivisions=2, radius=0.04).export(tmp_path / "meshes" / "ball.stl")
    dataset.generate(["meshes/ball.stl"], "ds", approaches=2, workers=1)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    ds = hugger.Dataset(tmp_path / "ds")
    assert ds.trajectory(0).status == ds[0].status
    (tmp_path / "ds" / "shards" / "ball__5x5.npz").unlink()
    with pytest.raises(ValueError, match="ball__5x5.npz is missing; 'hugger generate' with the command in index.json"):
        hugger.Dataset(tmp_path / "ds")


def test_a_shard_depends_on_the_mesh_s_content_not_how_its_path_is_spelled(tmp_path, monkeypatch):
    # objs/ball.stl and ./objs/ball.stl made different shards, and one could not resume the other
    import shutil

    import trimesh

    monkeypatch.chdir(tmp_path)
    (tmp_path / "objs").mkdir()
    trimesh.creation.icosphere(subdivisions=2, radius=0.04).export(tmp_path / "objs" / "ball.stl")
    dataset.generate(["objs/ball.stl"], "a", approaches=2, workers=1)
    dataset.generate(["./objs/ball.stl"], "b", approaches=2, workers=1)
    shard = Path("shards") / "ball__5x5.npz"
    assert (tmp_path / "a" / shard).read_bytes() == (tmp_path / "b" / shard).read_bytes()
    made = (tmp_path / "a" / shard).stat().st_mtime_ns
    (tmp_path / "moved").mkdir()
    shutil.copy(tmp_path / "objs" / "ball.stl", tmp_path / "moved" / "ball.stl")  # the same content elsewhere
    lines: list[str] = []
    index = dataset.generate([str(tmp_path / "moved" / "ball.stl")], "a", approaches=2, workers=1, log=lines.append)
    assert "1 of 1 shards already done; making 0" in lines and (tmp_path / "a" / shard).stat().st_mtime_ns == made
    assert index["objects"][0]["abspath"] == str(tmp_path / "moved" / "ball.stl")
    assert hugger.Dataset(tmp_path / "a")[0].status == hugger.Dataset(tmp_path / "b")[0].status


def test_a_shard_keyed_by_its_path_as_given_is_still_resumed(tmp_path, monkeypatch):
    # shards of earlier versions hashed the mesh's path as given into their key
    import trimesh

    monkeypatch.chdir(tmp_path)
    trimesh.creation.icosphere(subdivisions=2, radius=0.04).export(tmp_path / "ball.stl")
    keyed = dataset._task_key
    monkeypatch.setattr(dataset, "_task_key", lambda task, spelled=False: keyed(task, spelled=True))
    dataset.generate(["ball.stl"], "ds", approaches=2, workers=1)
    monkeypatch.setattr(dataset, "_task_key", keyed)
    shard = tmp_path / "ds" / "shards" / "ball__5x5.npz"
    made = shard.stat().st_mtime_ns
    lines: list[str] = []
    dataset.generate(["ball.stl"], "ds", approaches=2, workers=1, log=lines.append)
    assert "1 of 1 shards already done; making 0" in lines and shard.stat().st_mtime_ns == made
    assert hugger.Dataset(tmp_path / "ds")[0].status in ("done", "stalled", "max_iterations")
    with pytest.raises(ValueError, match="other settings or objects"):  # other settings are still refused
        dataset.generate(["ball.stl"], "ds", approaches=3, workers=1)


def test_opening_what_is_no_dataset_says_what_it_is(tmp_path):
    (tmp_path / "file").write_text("x")
    for path, error, match in ((tmp_path / "nowhere", FileNotFoundError, "no such dataset folder: .*nowhere"),
                               (tmp_path / "file", NotADirectoryError, "is not a folder"),
                               (tmp_path, ValueError, "holds no dataset index")):
        with pytest.raises(error, match=match):
            hugger.Dataset(path)


def test_a_moved_dataset_finds_its_mesh_beside_it_by_name(tmp_path):
    # made from an absolute path; then the mesh and the dataset move, the mesh into the dataset's folder
    import shutil

    import trimesh

    mesh = tmp_path / "meshes" / "ball.stl"
    mesh.parent.mkdir()
    trimesh.creation.icosphere(subdivisions=2, radius=0.04).export(mesh)
    dataset.generate([str(mesh)], str(tmp_path / "ds"), approaches=2, workers=1)
    moved = tmp_path / "moved"
    shutil.move(tmp_path / "ds", moved)
    shutil.move(mesh, tmp_path / "away.stl")
    with pytest.raises(ValueError, match="is not found"):
        hugger.Dataset(moved).trajectory(0)
    shutil.move(tmp_path / "away.stl", moved / "ball.stl")
    ds = hugger.Dataset(moved)
    assert ds.trajectory(0).status == ds[0].status


def test_an_address_where_something_else_listens_is_refused_within_the_probe_s_time(tmp_path, monkeypatch, capsys):
    # ray.init retries for ever there and ignores Ctrl-C: a child process tries, and is ended.
    pytest.importorskip("ray", reason="the cluster extra is not installed (pip install 'hugger[cluster]')")
    import socket

    monkeypatch.setattr(dataset, "RAY_PROBE_TIMEOUT", 15.0)
    with socket.create_server(("127.0.0.1", 0)) as server:
        address = f"127.0.0.1:{server.getsockname()[1]}"
        t0 = time.monotonic()
        assert main(["generate", "box", "--out", str(tmp_path / "r"), "--backend", "ray", "--address", address]) == 2
        assert time.monotonic() - t0 < 40
    err = capsys.readouterr().err
    assert f"no Ray cluster answers at {address}" in err and err.count("\n") == 1, err
    assert not (tmp_path / "r").exists()


def test_meshes_named_in_any_script_keep_their_names(tmp_path):
    # "苹果.obj" and "盒子.obj" had both become "object" (and were refused as sharing a name)
    apple, box = write_ball(tmp_path / "苹果.obj"), write_ball(tmp_path / "盒子.obj", radius=0.03)
    index = dataset.generate([str(apple), str(box)], str(tmp_path / "ds"), approaches=1, workers=1)
    assert sorted(o["name"] for o in index["objects"]) == ["盒子", "苹果"]
    assert sorted(p.name for p in (tmp_path / "ds" / "shards").iterdir()) == ["盒子__5x5.npz", "苹果__5x5.npz"]
    assert len(hugger.Dataset(tmp_path / "ds")) == 2
    shown = repr(hugger.Dataset(tmp_path / "ds")[0])  # one line of figures, not every array
    assert "object=" in shown and "epsilon=" in shown and "contact_points" not in shown and "\n" not in shown
    import unicodedata  # a decomposed accent stays with its letter

    assert dataset._safe(unicodedata.normalize("NFD", "Müsli")) == "Müsli" == unicodedata.normalize("NFC", "Müsli")


def test_a_shard_is_the_one_the_index_lists(reference, tmp_path):
    # a shard copied over another opened as the other object's, and re-planning it blamed the version
    import shutil

    ds_dir = tmp_path / "ds"
    shutil.copytree(reference, ds_dir)
    files = sorted((ds_dir / "shards").iterdir())
    shutil.copyfile(files[0], files[1])
    ds = hugger.Dataset(ds_dir)
    listed = [s["file"] for s in ds.shards]
    with pytest.raises(ValueError, match=f"{files[1].name} is not the shard the index lists: its SHA-256 differs"):
        ds.shard(listed.index(f"shards/{files[1].name}"))
    ds.shard(listed.index(f"shards/{files[0].name}"))  # the shard copied reads as before
    files[1].write_bytes(b"garbage")  # not a zip: said so (NumPy took it for a pickle, and said how to unpickle it)
    with pytest.raises(ValueError, match=f"{files[1].name} is not a whole shard \\(not a zip archive\\)"):
        hugger.Dataset(ds_dir)
    files[1].unlink()  # as the message says: removed, and made again by the same command
    assert main(["generate", *OBJECTS, "--approaches", "3", "--out", str(ds_dir), "--workers", "1"]) == 0
    assert files[1].read_bytes() == (reference / "shards" / files[1].name).read_bytes()
    hugger.Dataset(ds_dir).shard(listed.index(f"shards/{files[1].name}"))
    index = json.loads((ds_dir / "index.json").read_text())
    del index["shards"][0]["sha256"]
    (ds_dir / "index.json").write_text(json.dumps(index))
    with pytest.raises(ValueError, match="is not the index of a hugger dataset"):
        hugger.Dataset(ds_dir)


def _craft_shard(ds_dir: Path, extra: dict[str, Any] | None = None, raw: tuple[str, bytes] | None = None) -> str:
    """Rewrites the dataset's first shard with extra members (``extra`` as np.savez writes them,
    ``raw``: one member's bytes as given) and lists its new SHA-256 in the index, as a crafted
    dataset from elsewhere would: only the shard reader's own checks stand in the way."""
    import hashlib
    import zipfile

    index = json.loads((ds_dir / "index.json").read_text())
    path = ds_dir / index["shards"][0]["file"]
    with zipfile.ZipFile(path, "a", compression=zipfile.ZIP_DEFLATED) as zf:
        for key, value in (extra or {}).items():
            with zf.open(f"{key}.npy", "w", force_zip64=True) as fh:
                np.lib.format.write_array(fh, value, allow_pickle=True)
        if raw is not None:
            with zf.open(f"{raw[0]}.npy", "w", force_zip64=True) as fh:
                fh.write(raw[1])
    index["shards"][0]["sha256"] = hashlib.sha256(path.read_bytes()).hexdigest()
    (ds_dir / "index.json").write_text(json.dumps(index))
    return path.name


def test_crafted_shards_are_refused_as_trajectory_files_are(reference, tmp_path):
    # shards are read by the trajectory file's reader: no pickle is unpickled, no declared size
    # allocated, no decompression bomb unpacked, even where the index vouches for the file
    import shutil
    import tracemalloc

    ran: list[str] = []

    class Evil:
        def __reduce__(self):
            return (ran.append, ("unpickled!",))

    # (a member is read when the shard is; a bomb over all the members is refused on opening)
    cases = [
        ({"evil": np.array([Evil()], dtype=object)}, None, "evil holds pickled Python objects", True),
        (None, ("huge", _npy_header((10 ** 11, 3)) + bytes(24)), "huge: its header declares", True),
        (None, ("bomb", _npy_header((((96 << 20) // 8),)) + bytes(96 << 20)), "decompression bomb", False),
    ]
    for n, (extra, raw, message, opens) in enumerate(cases):
        ds_dir = tmp_path / f"ds{n}"
        shutil.copytree(reference, ds_dir)
        name = _craft_shard(ds_dir, extra, raw)
        tracemalloc.start()
        try:
            with pytest.raises(ValueError, match=f"{name} is not a whole shard .*{message}"):
                ds = hugger.Dataset(ds_dir)
                assert opens  # (else refused above)
                ds.shard(0)
            assert tracemalloc.get_traced_memory()[1] < 32 << 20
        finally:
            tracemalloc.stop()
    assert ran == []


def _npy_header(shape: tuple[int, ...]) -> bytes:
    import io

    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, {"descr": "<f8", "fortran_order": False, "shape": shape})
    return buf.getvalue()
