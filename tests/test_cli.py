"""The `hugger` command: every sub-command, bad arguments, missing extras, progress display."""
from __future__ import annotations

import io
import json
import os
import subprocess
import sys

import numpy as np
import pytest

import hugger
from hugger import cli, objects
from hugger._progress import Progress

from helpers import OBJECTS_DIR, SHARED_MISSING, check_file, ycb_paths

RUN = [sys.executable, "-m", "hugger"]


def run(args, capsys):
    code = cli.main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(scope="module")
def sphere_plan(tmp_path_factory):
    path = tmp_path_factory.mktemp("cli") / "sphere.npz"
    assert cli.main(["plan", "sphere", "--out", str(path)]) == 0
    return path


def test_objects_lists_every_builtin_name_first(capsys):
    code, out, _ = run(["objects"], capsys)
    lines = out.strip().splitlines()
    assert code == 0 and [ln.split()[0] for ln in lines] == objects.names()
    assert all(len(ln.split()) > 3 for ln in lines)  # a size and a description follow


@pytest.mark.parametrize("name", objects.names())
def test_plan_every_builtin_with_defaults(name, tmp_path, capsys, checker):
    out = tmp_path / f"{name}.npz"
    code, text, err = run(["plan", name, "--out", out, "--json"], capsys)
    assert code == 0, err
    report = json.loads(text)
    for key in ("status", "configurations", "plan_time_s", "configurations_per_s", "palm_contact", "links_in_contact",
                "contacts", "epsilon", "volume"):
        assert key in report, key
    assert report["status"] == "done"
    traj = hugger.Trajectory.load(out)
    assert len(traj) == report["configurations"]
    ok, failures, _ = check_file(checker, out, every=max(1, len(traj) // 40))
    assert ok, failures


@pytest.mark.skipif(not OBJECTS_DIR.is_dir(), reason=SHARED_MISSING)
@pytest.mark.parametrize("path", ycb_paths(), ids=lambda p: p.stem)
def test_plan_every_shared_mesh_with_defaults(path, tmp_path, capsys, checker):
    out = tmp_path / "plan.npz"
    code, text, err = run(["plan", path, "--out", out, "--json"], capsys)
    assert code == 0, err
    report = json.loads(text)
    assert report["status"] == "done", report
    ok, failures, _ = check_file(checker, out, every=max(1, report["configurations"] // 25))
    assert ok, failures


def test_plan_prints_a_table_and_honours_options(tmp_path, capsys):
    out = tmp_path / "p.npz"
    code, text, _ = run(["plan", "ellipsoid", "--out", out, "--fingers", "3", "--links", "4", "--link-length", "0.025",
                         "--step", "0.002", "--turn", "30", "--target", "0.01", "0", "0"], capsys)
    assert code == 0
    assert "status" in text and "links_in_contact" in text
    traj = hugger.Trajectory.load(out)
    assert traj.hand["fingers"] == 3 and traj.hand["links"] == 4
    assert traj.params["step"] == pytest.approx(0.002)
    assert np.allclose(traj.target, [0.01, 0, 0])
    assert np.any(traj.phase == 1)  # turned away from T: Phase 1 ran


def test_plan_mesh_file_with_scale(tmp_path, capsys):
    trimesh = pytest.importorskip("trimesh")
    v, f = objects.icosphere(3)
    mesh = tmp_path / "ball_mm.stl"
    trimesh.Trimesh(40.0 * v, f, process=False).export(mesh)  # a 4 cm ball in millimetres
    code, _, err = run(["plan", mesh, "--out", tmp_path / "a.npz"], capsys)
    assert "hugger: warning: " in err and "millimetres" in err  # warned about the implausible size
    code, text, err = run(["plan", mesh, "--scale", "0.001", "--out", tmp_path / "b.npz", "--json"], capsys)
    assert code == 0, err
    assert json.loads(text)["status"] == "done"


@pytest.mark.parametrize("args, message", [
    (["plan", "banana", "--out", "x.npz"], "neither a built-in object"),
    (["plan", "sphere"], "required: --out"),
    (["plan", "sphere", "--out", "x.npz", "--fingers", "0"], "fingers"),
    (["plan", "sphere", "--out", "x.npz", "--link-length", "-0.02"], "link_length"),
    (["plan", "sphere", "--out", "x.npz", "--step", "-1"], "step"),
    (["plan", "sphere", "--out", "x.npz", "--epsilon", "0"], "epsilon"),
    (["plan", "sphere", "--out", "x.npz", "--target", "1", "0", "0"], "not inside"),
    (["plan", "sphere", "--out", "x.npz", "--start", "0", "0", "0.01"], ""),
    (["plan", "sphere", "--out", "x.npz", "--scale", "0"], "scale"),
    (["plan", "sphere", "--out", "x.npz", "--fingers", "two"], "invalid int value"),
    (["plan", "no/such/file.stl", "--out", "x.npz"], "no such mesh file"),
    (["info", "no/such/plan.npz"], "no such trajectory file"),
    (["render", "no/such/plan.npz", "--out", "x.png"], "no such trajectory file"),
    (["frobnicate"], "invalid choice"),
    ([], "required"),
])
def test_bad_arguments_exit_2_with_one_line(args, message, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, out, err = run(args, capsys)
    assert code == 2
    assert err.startswith("hugger: error: ") and message in err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_info_reports_the_file(sphere_plan, capsys):
    code, out, _ = run(["info", sphere_plan, "--json"], capsys)
    assert code == 0
    info = json.loads(out)
    assert info["status"] == "done" and info["palm_contact"] is True and info["links_in_contact"] >= 15
    assert "5 fingers x 5 links" in info["hand"]
    code, out, _ = run(["info", sphere_plan], capsys)
    assert code == 0 and "links_in_contact" in out


def test_corrupt_trajectory_file_exit_2(tmp_path, capsys):
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"PK\x03\x04 truncated")
    code, _, err = run(["info", bad], capsys)
    assert code == 2 and "cannot read trajectory file" in err


def test_render_png_and_bad_extension(sphere_plan, tmp_path, capsys):
    pytest.importorskip("matplotlib")
    png = tmp_path / "grasp.png"
    code, out, err = run(["render", sphere_plan, "--out", png], capsys)
    assert code == 0, err
    assert png.stat().st_size > 10_000
    code, _, err = run(["render", sphere_plan, "--out", tmp_path / "grasp.txt"], capsys)
    assert code == 2 and ".png" in err


def test_internal_error_exits_1_with_a_report(monkeypatch, capsys):
    def boom(args):
        raise RuntimeError("unexpected state")

    monkeypatch.setattr(cli, "cmd_objects", boom)
    code, _, err = run(["objects"], capsys)
    assert code == 1 and "internal error: RuntimeError: unexpected state" in err


@pytest.mark.parametrize("module, command, extra", [
    ("matplotlib", ["render", "{plan}", "--out", "{tmp}/x.png"], "hugger[viz]"),
    ("trimesh", ["plan", "{tmp}/ball.stl", "--out", "{tmp}/x.npz"], "hugger[mesh]"),
    ("mujoco", ["validate", "{plan}"], "hugger[physics]"),
])
def test_missing_optional_dependency_names_the_extra(module, command, extra, sphere_plan, tmp_path):
    (tmp_path / "ball.stl").write_bytes(b"")
    args = [a.format(plan=sphere_plan, tmp=tmp_path) for a in command]
    code = (f"import sys; sys.modules[{module!r}] = None\n"
            f"from hugger.cli import main; sys.exit(main({args!r}))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert r.returncode == 2, r.stderr
    assert extra in r.stderr and "Traceback" not in r.stderr


def test_entry_point_runs_as_a_module(tmp_path):
    r = subprocess.run(RUN + ["objects"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and r.stdout.startswith("sphere")
    r = subprocess.run(RUN + ["plan", "banana", "--out", str(tmp_path / "x.npz")], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 2 and r.stderr.count("\n") == 1


class _Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_progress_draws_on_a_terminal_only():
    tty = _Tty()
    with Progress("work", total=4, stream=tty, delay=0.0) as p:
        for i in range(1, 5):
            p.update(i)
    assert "work [" in tty.getvalue() and "4/4" in tty.getvalue()
    pipe = io.StringIO()
    with Progress("work", total=4, stream=pipe, delay=0.0) as p:
        p.update(4)
    assert pipe.getvalue() == ""


def test_progress_spinner_runs_while_the_main_thread_works():
    import time

    tty = _Tty()
    with Progress("planning", stream=tty, delay=0.0):
        time.sleep(0.35)
    assert "planning" in tty.getvalue() and "s" in tty.getvalue()


def test_demo_writes_figures_animation_and_summary(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    out = tmp_path / "demo"
    code, text, err = run(["demo", "--out", out], capsys)
    assert code == 0, err
    for name in ("plan.npz", "fig4.png", "fig5.png", "tipstate.png", "animation.gif", "summary.json"):
        assert (out / name).stat().st_size > 0, name
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "done" and summary["phase1_configurations"] > 0
    assert summary["palm_contact"] and summary["links_in_contact"] >= 12
    assert "written to" in text
    assert os.path.basename(str(out)) in text


def test_export_mjcf_and_validate(sphere_plan, tmp_path, capsys):
    mujoco = pytest.importorskip("mujoco", reason="needs the physics extra")
    xml = tmp_path / "hand.xml"
    code, out, err = run(["export-mjcf", sphere_plan, "--out", xml], capsys)
    assert code == 0, err
    model = mujoco.MjModel.from_xml_path(str(xml))
    assert model.njnt == 25 + 1  # 5 x 5 hinges and the object's free joint
    code, out, err = run(["validate", sphere_plan, "--json"], capsys)
    assert code == 0, err
    result = json.loads(out)
    assert result["held"] is True and set(result["directions"]) == {"+x", "-x", "+y", "-y", "+z", "-z"}
    assert "settings" in result
    code, out, _ = run(["validate", sphere_plan], capsys)
    assert code == 0 and "verdict: held" in out


def test_validate_reports_a_diverged_direction(sphere_plan, capsys, monkeypatch):
    # physics.validate reports None figures for a direction whose simulation diverged; the text
    # report must say so rather than fail on them
    from hugger import physics

    held = {"displacement_m": 0.001, "rotation_deg": 0.5, "held": True}
    lost = {"displacement_m": None, "rotation_deg": None, "held": False, "diverged": True}
    monkeypatch.setattr(physics, "validate", lambda traj: {"held": False, "directions": {"+x": held, "-x": lost}})
    code, out, err = run(["validate", sphere_plan], capsys)
    assert code == 0, err
    assert "-x  the simulation diverged: LOST" in out and "+x  moved" in out and "verdict: not held" in out


def test_plan_timeout_gives_a_partial_plan(tmp_path, capsys, checker):
    out = tmp_path / "t.npz"
    code, text, err = run(["plan", "curvy", "--out", out, "--json", "--timeout", "1e-6"], capsys)
    assert code == 0 and json.loads(text)["status"] == "timeout"
    assert "status 'timeout'" in err
    ok, failures, _ = check_file(checker, out)
    assert ok, failures
    code, _, err = run(["plan", "curvy", "--out", out, "--timeout", "-1"], capsys)
    assert code == 2 and "timeout" in err
