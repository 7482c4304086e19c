"""The `hugger` command: every sub-command, bad arguments, missing extras, progress display."""
from __future__ import annotations

import io
import json
import re
import os
import subprocess
import sys

import numpy as np
import pytest

import hugger
from hugger import cli, objects
from hugger._progress import Progress

from helpers import OBJECTS_DIR, SHARED_MISSING, assert_checked, assert_names_the_extra, write_ball, ycb_paths
from helpers import run_cli as run

RUN = [sys.executable, "-m", "hugger"]


@pytest.fixture(scope="module")
def sphere_file(tmp_path_factory):
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
                "contacts", "ferrari_canny_epsilon", "wrench_space_volume"):
        assert key in report, key
    assert report["status"] == "done"
    traj = hugger.Trajectory.load(out)
    assert len(traj) == report["configurations"]
    assert_checked(checker, out, samples=40)


@pytest.mark.skipif(not OBJECTS_DIR.is_dir(), reason=SHARED_MISSING)
@pytest.mark.parametrize("path", ycb_paths(), ids=lambda p: p.stem)
def test_plan_every_shared_mesh_with_defaults(path, tmp_path, capsys, checker):
    out = tmp_path / "plan.npz"
    code, text, err = run(["plan", path, "--out", out, "--json"], capsys)
    assert code == 0, err
    report = json.loads(text)
    assert report["status"] == "done", report
    assert_checked(checker, out, samples=25)


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
    mesh = write_ball(tmp_path / "ball_mm.stl", 40.0, subdivisions=3)  # a 4 cm ball in millimetres
    code, _, err = run(["plan", mesh, "--out", tmp_path / "a.npz"], capsys)
    # an implausible size (millimetres read as metres) is refused before planning, unless --force
    assert code == 2 and err.startswith("hugger: error: ") and "millimetres" in err and "--force" in err
    assert len(err.strip().splitlines()) == 1 and not (tmp_path / "a.npz").exists()
    code, text, err = run(["plan", mesh, "--scale", "0.001", "--out", tmp_path / "b.npz", "--json"], capsys)
    assert code == 0, err
    assert json.loads(text)["status"] == "done"
    assert "repaired" not in err and "merged" not in err  # reading an STL merges vertices: not a repair


def test_plan_implausible_size_with_force(tmp_path, capsys):
    mesh = write_ball(tmp_path / "speck.stl", 4e-4)  # a 0.8 mm speck: too small for a hand
    code, _, err = run(["plan", mesh, "--out", tmp_path / "a.npz"], capsys)
    assert code == 2 and "implausibly small" in err
    code, text, err = run(["plan", mesh, "--out", tmp_path / "a.npz", "--force", "--json",
                           "--max-iterations", "50"], capsys)
    assert code == 0, err
    assert "hugger: warning: " in err and "--force" in err and (tmp_path / "a.npz").is_file()


def test_a_hand_in_millimetres_is_refused_unless_forced(tmp_path, capsys):
    # a mesh of implausible size was refused, a hand only warned of (and planned: epsilon 0.004)
    code, _, err = run(["plan", "sphere", "--link-length", "20", "--out", tmp_path / "a.npz"], capsys)
    assert code == 2 and err.startswith("hugger: error: the hand is 100 m across, implausibly large")
    assert "--force" in err and not (tmp_path / "a.npz").exists()
    code, _, err = run(["plan", "sphere", "--link-length", "20", "--out", tmp_path / "a.npz", "--force",
                        "--max-iterations", "5"], capsys)
    assert code == 0 and "hugger: warning: the hand is 100 m across" in err
    # every size of the hand counts: a palm 15 m thick planned without a word
    code, _, err = run(["plan", "sphere", "--palm-thickness", "15", "--out", tmp_path / "b.npz"], capsys)
    assert code == 2 and err.startswith("hugger: error: the hand is 15 m across, implausibly large")


@pytest.mark.parametrize("command", ["plan", "baseline"])
def test_a_hand_file_in_millimetres_is_refused_unless_forced(tmp_path, capsys, command):
    # --hand FILE in millimetres was only warned of; then the analysis sampled its 30 m palm every
    # millimetre, and plan and baseline hung
    if command == "baseline":
        pytest.importorskip("mujoco")
    with pytest.warns(UserWarning, match="implausibly large"):
        hand = hugger.Hand(link_length=20, link_radius=4, palm_radius=30, palm_thickness=10)
    path = tmp_path / "hand_mm.json"
    path.write_text(hand.to_json())
    code, _, err = run([command, "sphere", "--hand", path, "--out", tmp_path / "a.npz"], capsys)
    assert code == 2 and err.startswith("hugger: error: the hand is 100 m across, implausibly large")
    assert "--force" in err and len(err.strip().splitlines()) == 1 and not (tmp_path / "a.npz").exists()
    if command == "plan":
        code, out, err = run([command, "sphere", "--hand", path, "--out", tmp_path / "a.npz", "--force"], capsys)
        assert code == 0 and "hugger: warning: the hand is 100 m across" in err and "links_in_contact" in out


def test_the_palm_samples_are_bounded_for_any_palm():
    from hugger import analysis

    for radius, thickness in ((0.03, 0.01), (30.0, 10.0), (0.03, 1e-7), (1e-4, 1.0)):
        local, _ = analysis._palm_points(np.eye(4), radius, thickness)
        assert 7 <= len(local) <= 120_000, (radius, thickness, len(local))
        assert np.abs(local[:, :2]).max() <= radius * (1 + 1e-12) and local[:, 2].min() >= -thickness * (1 + 1e-12)
    assert len(analysis._palm_points(np.eye(4), 0.03, 0.01)[0]) == len(analysis._palm_samples(0.03, 0.01, 1e-3))


def test_scale_is_refused_for_a_builtin(tmp_path, capsys):
    code, _, err = run(["plan", "sphere", "--scale", "0.001", "--out", tmp_path / "a.npz"], capsys)
    assert code == 2 and "--scale applies to mesh files only" in err and not (tmp_path / "a.npz").exists()
    code, _, err = run(["plan", "sphere", "--scale", "1", "--out", tmp_path / "a.npz"], capsys)
    assert code == 2  # even a scale of 1: the option is for mesh files
    with pytest.raises(ValueError, match="mesh files only"):
        hugger.scenarios.default_case("sphere", scale=0.001)


@pytest.mark.parametrize("argv, message", [
    (["--verify", "2"], "--approaches K > 1"),
    (["--verify", "-1"], "--approaches K > 1"),
    (["--robust-verify"], "--approaches K > 1"),
    (["--workers", "2"], "--approaches K > 1"),
    (["--turn", "inf"], "must be within [-180, 180]"),
    (["--turn", "400"], "must be within [-180, 180]"),  # refused, not taken as 40 degrees
    (["--finger", "3"], "unrecognized arguments: --finger"),  # an option's prefix is not the option
])
def test_plan_refuses_options_it_would_ignore_or_cannot_use(argv, tmp_path, capsys, message):
    code, _, err = run(["plan", "sphere", "--out", tmp_path / "a.npz", *argv], capsys)
    assert code == 2 and err.startswith("hugger: error: ") and message in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "a.npz").exists()


def test_plan_of_a_directory_says_so(tmp_path, capsys):
    code, _, err = run(["plan", str(tmp_path), "--out", tmp_path / "a.npz"], capsys)
    assert code == 2 and "is a directory, not a mesh file" in err


def test_stl_load_reports_no_merged_vertices(tmp_path):
    mesh = write_ball(tmp_path / "ball.stl")  # STL: three vertices of its own per face
    obj, repairs = objects.load_mesh(mesh)
    assert repairs == [] and len(obj.vertices) == len(objects.icosphere(2)[0])  # merged, and not called a repair


def test_mesh_files_are_read_once_per_process(tmp_path, monkeypatch):
    mesh = write_ball(tmp_path / "ball.stl")
    reads = []
    real = objects.load_mesh
    monkeypatch.setattr(objects, "load_mesh", lambda *a, **k: (reads.append(a), real(*a, **k))[1])
    cases = [hugger.scenarios.default_case(mesh, turn_deg=t) for t in (0.0, 10.0, 20.0)]
    assert len(reads) == 1 and cases[0].obj is cases[2].obj
    os.utime(mesh, ns=(0, 0))  # a changed file is read again
    hugger.scenarios.default_case(mesh)
    assert len(reads) == 2

@pytest.mark.parametrize("args, message", [
    (["plan", "banana", "--out", "x.npz"], "neither a built-in object"),
    (["plan", "sphere"], "required: --out"),
    (["plan", "sphere", "--out", "x.npz", "--fingers", "0"], "fingers"),
    (["plan", "sphere", "--out", "x.npz", "--link-length", "-0.02"], "link_length"),
    (["plan", "sphere", "--out", "x.npz", "--step", "-1"], "step"),
    (["plan", "sphere", "--out", "x.npz", "--epsilon", "0"], "epsilon"),
    (["plan", "sphere", "--out", "x.npz", "--target", "1", "0", "0"], "not inside"),
    (["plan", "sphere", "--out", "x.npz", "--start", "0", "0", "0.01"], "link 0 of finger 0's axis enters it"),  # no -inf
    (["view", "p.npz", "--fps", "inf"], "--fps must be a positive finite number"),  # as render says it
    (["view", "p.npz", "--fps", "500"], "--fps must be at most 120"),  # the page's control: 1 to 120
    (["view", "p.npz", "--fps", "0.5"], "--fps must be at least 1"),
    (["plan", "x.stl", "--out", "x.npz", "--scale", "0"], "scale"),
    (["plan", "sphere", "--out", "no/such/dir/x.npz"], "no such directory 'no/such/dir'"),
    (["plan", "sphere", "--out", "x.txt"], "--out must end in .npz, got 'x.txt'"),
    (["plan", "sphere", "--out", "."], "--out '.' is a directory"),
    (["plan", "sphere", "--out", ""], "--out is empty"),
    (["plan", "sphere", "--out", "x.npz", "--hand", "barrett_bh8", "--fingers", "3"],
     "--fingers cannot be combined with it"),
    (["plan", "sphere", "--out", "x.npz", "--hand", "barrett_bh8", "--links", "4", "--palm-radius", "0.04"],
     "--links, --palm-radius cannot be combined"),
    (["render", "p.npz", "--out", "no/such/dir/x.png"], "no such directory"),
    (["render", "p.npz", "--out", "x.png", "--figure", "animation"], "--figure animation writes .gif or .mp4"),
    (["render", "p.npz", "--out", "x.gif", "--figure", "fig4"], "--figure fig4 writes .png, .pdf or .svg"),
    (["render", "p.npz", "--out", "x.png", "--fps", "10"], "--fps applies to animations only"),
    (["render", "p.npz", "--out", "x.gif", "--fps", "0"], "--fps must be a positive finite number"),
    (["render", "p.npz", "--out", "x.gif", "--fps", "1e9"], "--fps must be at most 120"),
    (["render", "p.npz", "--out", "x.png", "--dpi", "100000"], "--dpi must be at most 1200"),
    (["render", "p.npz", "--out", "x.png", "--dpi", "1e9"], "--dpi must be at most 1200"),
    (["render", "p.npz", "--out", "x.png", "--dpi", "inf"], "--dpi must be a positive finite number"),
    (["render", "p.npz", "--out", "x.gif", "--frames", "0"], "--frames must be at least 1"),
    (["render", "p.npz", "--out", "x.png", "--figure", "fig6"], "invalid choice"),
    (["export-mjcf", "p.npz", "--out", "hand.urdf"], "--out must end in .xml or .mjcf"),
    (["render", "p.npz", "--out", "x.png", "--dpi", "2"], "--dpi must be at least 10"),
    (["export-scene", "p.npz", "--out", "grasp.gltf"], "--out must end in .glb"),
    (["export-scene", "p.npz", "--out", "no/dir/grasp.glb"], "no such directory"),
    (["export-scene", "no/such/plan.npz", "--out", "grasp.glb"], "no such trajectory file"),
    (["view", "no/such/plan.npz", "--no-browser"], "no such trajectory file"),
    (["view", "p.npz", "--port", "70000"], "--port must be in 0..65535"),
    (["view"], "required: FILE"),
    (["demo", "--out", "no/such/dir/demo"], "no such directory"),
    (["validate", "no/such/plan.npz"], "no such trajectory file"),
    (["validate", "p.npz", "--workers", "2"], "--workers runs the perturbations of --robust in parallel"),
    (["plan", "sphere", "--out", "x.npz", "--threads", "2"], "--threads plans the approaches of --approaches K > 1"),
    (["plan", "sphere", "--out", "x.npz", "--approaches", "4", "--verify", "2", "--workers", "2"],
     "--workers runs the simulations of --robust-verify in parallel"),
    (["plan", "sphere", "--out", "x.npz", "--fingers", "two"], "invalid int value"),
    (["plan", "no/such/file.stl", "--out", "x.npz"], "no such mesh file"),
    (["info", "no/such/plan.npz"], "no such trajectory file"),
    (["render", "no/such/plan.npz", "--out", "x.png"], "no such trajectory file"),
    (["frobnicate"], "invalid choice"),
    ([], "required"),
    (["plan", "sphere", "--out", "x.npz", "--step", "nan"], "argument --step: expected a finite number, got 'nan'"),
    (["plan", "sphere", "--out", "x.npz", "--contact-tolerance", "inf"], "expected a finite number"),
    (["objects", "extra"], "unrecognized arguments: extra (see 'hugger objects --help')"),
    (["hands", "--bogus"], "see 'hugger hands --help'"),
    (["generate", "sphere", "--out", "no/such/dir/gen"], "no such directory 'no/such/dir'"),
    (["info", "."], ". is a folder, not a trajectory file"),
    (["info", os.devnull], f"{os.devnull} is not a regular file, not a trajectory file"),
    *([(["plan", "sphere", "--out", "/proc/x.npz"], "--out: cannot write in '/proc'")]  # before planning
      if os.path.isdir("/proc/self") else []),
])
def test_bad_arguments_exit_2_with_one_line(args, message, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, out, err = run(args, capsys)
    assert code == 2
    assert err.startswith("hugger: error: ") and message in err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err


@pytest.mark.parametrize("command, out", [("export-mjcf", "h.xml"), ("export-urdf", "h.urdf")])
def test_exports_name_the_configuration_out_of_range(command, out, sphere_file, tmp_path, capsys):
    n = len(hugger.Trajectory.load(sphere_file))
    for k in (n, -n - 1):
        code, _, err = run([command, sphere_file, "--out", tmp_path / out, "--configuration", str(k)], capsys)
        assert code == 2 and err.strip() == (f"hugger: error: --configuration {k} is out of range for {n} "
                                             "configurations"), err
        assert not (tmp_path / out).exists()


def test_info_shows_a_file_s_control_characters_as_escapes(sphere_file, tmp_path, capsys):
    # a name that would retitle the terminal and clear its screen is printed, not obeyed
    odd = tmp_path / "odd.npz"
    hugger.Trajectory.load(sphere_file).with_provenance(object="\x1b]0;title\x07\x1b[2Jball").save(odd)
    code, out, _ = run(["info", odd], capsys)
    assert code == 0 and "\x1b" not in out and "\x07" not in out
    assert "\\x1b]0;title\\x07\\x1b[2Jball: " in out


def test_info_warns_of_a_hand_sunk_into_a_rescaled_object(sphere_file, tmp_path, capsys):
    # the object of a file scaled by 1000 (millimetres read as metres): every link lies 40 m inside
    # it, and the counts alone called it a perfect grasp
    import dataclasses

    traj = hugger.Trajectory.load(sphere_file)
    code, out, err = run(["info", sphere_file, "--json"], capsys)
    assert code == 0 and err == "" and json.loads(out)["penetration_m"] <= 5e-5
    mm = tmp_path / "mm.npz"
    dataclasses.replace(traj, object_vertices=traj.object_vertices * 1000).save(mm)
    code, out, err = run(["info", mm, "--json"], capsys)
    assert code == 0 and json.loads(out)["penetration_m"] > 30
    assert "the object is 80 m across, implausibly large" in err
    assert re.search(r"warning: the hand lies [\d.e+]+ mm inside the object at the final configuration", err)


def test_info_reports_the_file(sphere_file, capsys):
    code, out, _ = run(["info", sphere_file, "--json"], capsys)
    assert code == 0
    info = json.loads(out)
    assert info["status"] == "done" and info["palm_contact"] is True and info["links_in_contact"] >= 15
    traj = hugger.Trajectory.load(sphere_file)
    h = info["hand"]  # structured, not prose
    assert h["fingers"] == 5 and h["links"] == 5 and h["link_radius"] == 0.004 and h["palm_radius"] == 0.03
    assert np.array_equal(h["link_lengths"], traj.hand["link_lengths"])
    o = info["object"]
    assert o["name"] == "sphere" and o["source"] == "builtin" and o["triangles"] == len(traj.object_faces)
    assert o["vertices"] == len(traj.object_vertices) and len(o["sha256"]) == 64
    assert np.allclose(o["extent_m"], np.ptp(traj.object_vertices, axis=0))
    assert o["volume_m3"] == pytest.approx(4 / 3 * np.pi * 0.04 ** 3, rel=0.02)
    assert info["params"] == traj.params and info["planner_epsilon_m"] == traj.params["epsilon"]
    assert "ferrari_canny_epsilon" in info and "epsilon" not in info  # the two epsilons, named apart
    assert info["provenance"]["hugger_version"] == hugger.__version__
    code, out, _ = run(["info", sphere_file], capsys)
    assert code == 0 and "links_in_contact" in out and "ferrari_canny_epsilon" in out


def test_plan_records_provenance(tmp_path, capsys):
    out = tmp_path / "p.npz"
    args = ["plan", "ellipsoid", "--out", str(out), "--fingers", "3", "--step", "0.002"]
    assert run(args, capsys)[0] == 0
    traj = hugger.Trajectory.load(out)
    prov = traj.provenance
    assert prov["command"] == ["hugger", *args]
    assert prov["object"] == "ellipsoid" and prov["object_source"] == "builtin"
    assert prov["arguments"]["fingers"] == 3 and prov["arguments"]["step"] == 0.002
    assert prov["arguments"]["links"] == 5 and prov["arguments"]["palm_radius"] == 0.03  # defaults included
    assert prov["hugger_version"] == hugger.__version__
    assert prov["object_sha256"] == traj.object_sha256() and len(prov["object_sha256"]) == 64
    # a mesh file is recorded by its absolute path
    write_ball(tmp_path / "ball.stl")
    assert run(["plan", tmp_path / "ball.stl", "--out", out], capsys)[0] == 0
    prov = hugger.Trajectory.load(out).provenance
    assert prov["object"] == str(tmp_path / "ball.stl") and prov["object_source"] == "file"


def test_plan_report_names_the_two_epsilons_apart(sphere_file, capsys):
    with pytest.raises(SystemExit):
        cli.main(["plan", "--help"])
    out = " ".join(capsys.readouterr().out.split())
    assert "overextension threshold" in out and "tip-to-surface" not in out
    code, out, _ = run(["plan", "sphere", "--out", sphere_file.parent / "again.npz", "--json"], capsys)
    report = json.loads(out)
    assert "epsilon" not in report and report["ferrari_canny_epsilon"] > 0


def test_every_output_is_written_atomically(sphere_file, tmp_path, capsys, monkeypatch):
    # a writer that fails half way leaves no file under the final name, and no temporary file
    pytest.importorskip("matplotlib")
    from matplotlib.figure import Figure

    def half_written(fig, path, **kwargs):
        with open(path, "wb") as fh:
            fh.write(b"\x89PNG half")
        raise KeyboardInterrupt

    with monkeypatch.context() as m:
        m.setattr(Figure, "savefig", half_written)  # what render's writer calls
        code, _, err = run(["render", sphere_file, "--out", tmp_path / "grasp.png"], capsys)
    assert code == 130 and "interrupted" in err
    assert list(tmp_path.iterdir()) == []
    # the trajectory file too
    traj = hugger.Trajectory.load(sphere_file)

    def broken(*a, **k):
        raise OSError("disk full")

    monkeypatch.setattr(np, "savez_compressed", broken)
    with pytest.raises(OSError, match="disk full"):
        traj.save(tmp_path / "p.npz")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs named pipes")
def test_out_replaces_only_a_regular_file_and_writes_through_a_link(sphere_file, tmp_path, capsys):
    pipe = tmp_path / "pipe.npz"
    os.mkfifo(pipe)
    code, _, err = run(["plan", "sphere", "--out", pipe], capsys)
    assert code == 2 and "exists and is not a regular file" in err and not pipe.is_file()  # still the pipe
    assert sorted(p.name for p in tmp_path.iterdir()) == ["pipe.npz"]
    with pytest.raises(ValueError, match="the output path is empty"):
        hugger.Trajectory.load(sphere_file).save("")
    target, link = tmp_path / "target.dat", tmp_path / "link.npz"  # the link's name gives the format
    link.symlink_to(target)
    code, _, err = run(["plan", "sphere", "--out", link], capsys)
    assert code == 0, err
    assert link.is_symlink() and target.is_file() and hugger.Trajectory.load(link).status == "done"
    (tmp_path / "dev.npz").symlink_to("/dev/null")  # refused before planning, as the pipe
    code, _, err = run(["plan", "curvy", "--out", tmp_path / "dev.npz"], capsys)
    assert code == 2 and "'/dev/null' exists and is not a regular file" in err


def test_what_the_system_refuses_is_a_one_line_error(sphere_file, tmp_path):
    if not os.path.exists("/dev/full"):
        pytest.skip("needs /dev/full")
    with open("/dev/full", "w") as full:
        r = subprocess.run([sys.executable, "-m", "hugger", "info", str(sphere_file)], stdout=full,
                           stderr=subprocess.PIPE, text=True)
    assert r.returncode == 2 and r.stderr.strip() == "hugger: error: [Errno 28] No space left on device", r.stderr


@pytest.mark.parametrize("command", [["generate", "sphere", "--approaches", "2"], ["demo"], ["simulate", "sphere"],
                                     ["plan", "sphere"]])
def test_an_empty_out_is_refused_and_nothing_is_written(command, tmp_path, monkeypatch, capsys):
    if command[0] == "simulate":
        pytest.importorskip("mujoco")
    monkeypatch.chdir(tmp_path)  # where an empty path would have written
    code, _, err = run([*command, "--out", ""], capsys)
    assert code == 2 and "--out is empty" in err and len(err.strip().splitlines()) == 1, err
    assert list(tmp_path.iterdir()) == []


def test_out_refuses_a_missing_directory_and_creates_nothing(tmp_path, capsys):
    out = tmp_path / "missing" / "x.npz"
    code, _, err = run(["plan", "sphere", "--out", out], capsys)
    assert code == 2 and "no such directory" in err and not (tmp_path / "missing").exists()


def test_corrupt_trajectory_file_exit_2(tmp_path, capsys):
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"PK\x03\x04 truncated")
    code, _, err = run(["info", bad], capsys)
    assert code == 2 and "cannot read trajectory file" in err


def test_render_png_and_bad_extension(sphere_file, tmp_path, capsys):
    pytest.importorskip("matplotlib")
    png = tmp_path / "grasp.png"
    code, out, err = run(["render", sphere_file, "--out", png], capsys)
    assert code == 0, err
    assert png.stat().st_size > 10_000
    code, _, err = run(["render", sphere_file, "--out", tmp_path / "grasp.txt"], capsys)
    assert code == 2 and ".png" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["grasp.png"]  # no temporary file left


def test_render_options(sphere_file, tmp_path, capsys):
    pytest.importorskip("matplotlib")
    from PIL import Image

    sizes = {}
    for figure in ("fig4", "fig5", "tipstate", "sheet"):
        out = tmp_path / f"{figure}.png"
        code, _, err = run(["render", sphere_file, "--out", out, "--figure", figure, "--dpi", "50"], capsys)
        assert code == 0, err
        with Image.open(out) as im:
            sizes[figure] = im.size
    from hugger import viz

    # each figure at its own size, at 50 dpi
    assert sizes["fig4"] == (round(viz.FIG4_SIZE[0] * 50), round(viz.FIG4_SIZE[1] * 50))
    assert sizes["fig5"] == (round(viz.FIG5_SIZE[0] * 50), round(viz.FIG5_SIZE[1] * 50))
    assert sizes["tipstate"] == (round(viz.TIPSTATE_SIZE[0] * 50), round(viz.TIPSTATE_SIZE[1] * 50))
    assert sizes["sheet"] == (round(viz.OVERVIEW_SIZE[0] * 50), round(viz.OVERVIEW_SIZE[1] * 50))
    gif = tmp_path / "a.gif"
    code, _, err = run(["render", sphere_file, "--out", gif, "--frames", "7", "--fps", "5", "--view", "side",
                        "--dpi", "40"], capsys)
    assert code == 0, err
    with Image.open(gif) as im:
        assert im.size == (round(viz.MOVIE_SIZE[0] * 40), round(viz.MOVIE_SIZE[1] * 40))
        assert im.n_frames >= 7 and im.info["duration"] == pytest.approx(200, abs=10)
        im.seek(im.n_frames - 1)  # the final grasp is held about a second (5 repeated frames, merged or not)
        held = im.info["duration"] if im.n_frames == 7 else 200 * (im.n_frames - 6)
        assert held >= 1000 - 10


def test_vector_output_stays_small(sphere_file, tmp_path, capsys):
    pytest.importorskip("matplotlib")
    for suffix in (".pdf", ".svg"):
        out = tmp_path / f"sheet{suffix}"
        code, _, err = run(["render", sphere_file, "--out", out], capsys)
        assert code == 0, err
        assert out.stat().st_size < 1_500_000, (suffix, out.stat().st_size)  # the object surface is rasterised

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
    ("yourdfpy", ["export-urdf", "{plan}", "--out", "{tmp}/h.urdf"], "writing a URDF needs yourdfpy: pip install 'hugger[hands]'"),
    ("mujoco", ["generate", "sphere", "--validate", "--approaches", "2", "--out", "{tmp}/ds"], "validate needs MuJoCo"),
])
def test_missing_optional_dependency_names_the_extra(module, command, extra, sphere_file, tmp_path):
    (tmp_path / "ball.stl").write_bytes(b"")
    assert_names_the_extra(module, [a.format(plan=sphere_file, tmp=tmp_path) for a in command], extra)
    assert not (tmp_path / "ds").exists()  # refused before anything is made


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


def test_progress_update_is_a_done_total_callback():
    tty = _Tty()
    with Progress("frames", total=1, stream=tty, delay=0.0) as p:
        for i in range(1, 8):
            p.update(i, 7)  # as progress(done, total) callbacks call it
    assert p.total == 7 and "7/7" in tty.getvalue()


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
    assert sorted(summary["files"]) == sorted(p.name for p in out.iterdir())  # every file, itself included
    assert summary["status"] == "done" and summary["phase1_configurations"] > 0
    assert summary["palm_contact"] and summary["links_in_contact"] >= 12
    assert "written to" in text
    assert os.path.basename(str(out)) in text


def test_export_mjcf_and_validate(sphere_file, tmp_path, capsys):
    mujoco = pytest.importorskip("mujoco", reason="needs the physics extra")
    xml = tmp_path / "hand.xml"
    code, out, err = run(["export-mjcf", sphere_file, "--out", xml], capsys)
    assert code == 0, err
    model = mujoco.MjModel.from_xml_path(str(xml))
    assert model.njnt == 25 + 1  # 5 x 5 hinges and the object's free joint
    code, out, err = run(["validate", sphere_file, "--json"], capsys)
    assert code == 0, err  # held: exit 0
    result = json.loads(out)
    assert result["held"] is True and set(result["directions"]) == {"+x", "-x", "+y", "-y", "+z", "-z"}
    assert "settings" in result
    code, out, _ = run(["validate", sphere_file], capsys)
    assert code == 0 and "verdict: held" in out


def test_validate_reports_a_diverged_direction(sphere_file, capsys, monkeypatch):
    # physics.validate reports None figures for a direction whose simulation diverged; the text
    # report must say so rather than fail on them
    from hugger import physics

    held = {"displacement_m": 0.001, "rotation_deg": 0.5, "held": True}
    lost = {"displacement_m": None, "rotation_deg": None, "held": False, "diverged": True}
    monkeypatch.setattr(physics, "validate", lambda traj: {"held": False, "directions": {"+x": held, "-x": lost}})
    code, out, err = run(["validate", sphere_file], capsys)
    assert code == 1, err  # not held: exit 1
    assert "-x  the simulation diverged: LOST" in out and "+x  moved" in out and "verdict: not held" in out


def test_validate_exit_status_and_lost_objects(sphere_file, capsys, monkeypatch):
    from hugger import physics

    held = {"displacement_m": 0.001, "rotation_deg": 0.5, "held": True}
    slipped = {"displacement_m": 0.07, "rotation_deg": 3.0, "held": False}
    flew = {"displacement_m": 186.89144, "rotation_deg": 170.0, "held": False}
    results = {"held": {"held": True, "directions": {"+x": held}},
               "not held": {"held": False, "directions": {"+x": held, "-x": slipped, "+z": flew}}}
    for verdict, result in results.items():
        monkeypatch.setattr(physics, "validate", lambda traj, r=result: r)
        code, out, err = run(["validate", sphere_file], capsys)
        assert code == (0 if verdict == "held" else 1), err
        assert f"verdict: {verdict}" in out
        code, out, _ = run(["validate", sphere_file, "--json"], capsys)
        assert code == (0 if verdict == "held" else 1) and json.loads(out)["held"] is (verdict == "held")
    code, out, _ = run(["validate", sphere_file], capsys)
    assert "-x  moved   70.00 mm" in out and "LOST" in out
    assert "+z  lost (moved more than 200 mm)" in out and "186891" not in out
    with pytest.raises(SystemExit):
        cli.main(["validate", "--help"])
    assert "Exit status: 0 held, 1 not held, 2 bad input." in " ".join(capsys.readouterr().out.split())


def test_plan_timeout_gives_a_partial_plan(tmp_path, capsys, checker):
    out = tmp_path / "t.npz"
    code, text, err = run(["plan", "curvy", "--out", out, "--json", "--timeout", "1e-6"], capsys)
    assert code == 0 and json.loads(text)["status"] == "timeout"
    assert "status 'timeout'" in err
    assert_checked(checker, out)
    code, _, err = run(["plan", "curvy", "--out", out, "--timeout", "-1"], capsys)
    assert code == 2 and "timeout" in err


def test_validate_says_when_the_plan_did_not_finish(tmp_path, sphere_file, capsys, monkeypatch):
    # a timed-out (or running) plan's last configuration is judged as any: said so, not silently
    from hugger import physics

    monkeypatch.setattr(physics, "validate", lambda traj: {"held": False, "directions": {}})
    out = tmp_path / "t.npz"
    assert run(["plan", "curvy", "--out", out, "--timeout", "1e-6"], capsys)[0] == 0
    code, _, err = run(["validate", out], capsys)
    assert code == 1 and "hugger: note: the plan did not finish (status timeout); its last configuration is judged" in err
    code, _, err = run(["validate", sphere_file], capsys)
    assert "did not finish" not in err


def test_render_draws_palm_contacts_only_where_the_palm_does_not_hide_them(sphere_file):
    pytest.importorskip("matplotlib")
    import matplotlib.pyplot as plt

    from hugger import analysis, viz

    traj = hugger.Trajectory.load(sphere_file)
    c = analysis.contacts(traj, -1)
    palm, links = int(np.sum(c.finger < 0)), int(np.sum(c.finger >= 0))
    assert palm > 0 and links > 0
    shown = {}
    for view in ("oblique", "normal"):  # from behind the palm; from beyond the object, facing it
        fig = plt.figure()
        ax = fig.add_subplot(projection="3d")
        artists = viz.draw_configuration(ax, traj, -1, view=view, max_faces=500)
        dots = [a for a in artists if hasattr(a, "_offsets3d") and len(a._offsets3d[0]) > 1]
        shown[view] = len(dots[0]._offsets3d[0]) if dots else 0
        plt.close(fig)
    assert shown == {"oblique": links, "normal": palm + links}


def test_fig4_keeps_one_scale_across_panels(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    import matplotlib.pyplot as plt

    from hugger import viz

    out = tmp_path / "turned.npz"
    assert run(["plan", "ellipsoid", "--turn", "40", "--out", out], capsys)[0] == 0
    traj = hugger.Trajectory.load(out)
    for draw in (viz.fig4, viz.overview):
        fig = draw(traj, max_faces=500)
        panels = [ax for ax in fig.axes if ax.name == "3d"][:6]  # Fig. 4's panels (a)-(f)
        assert len(panels) == 6
        limits = {(ax.get_xlim(), ax.get_ylim(), ax.get_zlim(), tuple(ax.get_box_aspect())) for ax in panels}
        assert len(limits) == 1  # one box, one scale: the hand far away in (a) is as large as in (f)
        plt.close(fig)


def test_files_without_provenance_still_load(sphere_file, tmp_path, capsys):
    with np.load(sphere_file, allow_pickle=False) as data:
        arrays = {k: data[k] for k in data.files if k != "provenance_json"}  # as written before it existed
    old = tmp_path / "old.npz"
    np.savez_compressed(old, **arrays)
    traj = hugger.Trajectory.load(old)
    assert traj.provenance == {}
    code, out, _ = run(["info", old, "--json"], capsys)
    info = json.loads(out)
    assert code == 0 and info["provenance"] == {} and info["object"]["name"] is None
    assert info["object"]["sha256"] == hugger.Trajectory.load(sphere_file).object_sha256()
    code, out, _ = run(["info", old], capsys)
    assert code == 0 and "(not recorded)" in out
    # an API user adds their own fields; saving fills in the version and the object's hash
    again = tmp_path / "again.npz"
    traj.with_provenance(experiment="grid 3", seed=7).save(again)
    prov = hugger.Trajectory.load(again).provenance
    assert prov["experiment"] == "grid 3" and prov["seed"] == 7 and prov["hugger_version"] == hugger.__version__
    with pytest.raises(ValueError, match="JSON-serialisable"):
        traj.with_provenance(when=object())
    bad = dict(arrays, provenance_json=np.array("[1, 2]"))
    np.savez_compressed(tmp_path / "bad.npz", **bad)
    with pytest.raises(ValueError, match="must be JSON objects"):
        hugger.Trajectory.load(tmp_path / "bad.npz")


def test_progress_bar_moves_with_the_time_and_notes_print_above_it():
    import time

    tty = _Tty()
    with Progress("shards", total=2, stream=tty, delay=0.0) as p:
        p.update(0)
        p.note("hugger: 0 of 2 shards already done; making 2")
        time.sleep(0.35)  # no update meanwhile: the bar is redrawn all the same
    text = tty.getvalue()
    assert "hugger: 0 of 2 shards already done; making 2\n" in text
    assert text.count("0/2") >= 3  # drawn again as the time went by
    pipe = io.StringIO()
    with Progress("shards", total=2, stream=pipe, delay=0.0) as p:
        p.note("a line")
    assert pipe.getvalue() == "a line\n"  # a note prints in a pipe too; no bar there


def test_a_warning_while_a_bar_is_drawn_prints_above_it(monkeypatch):
    from hugger import _progress

    tty = _Tty()
    monkeypatch.setattr(sys, "stderr", tty)
    with Progress("shards", total=2, delay=0.0) as p:
        p.update(0)
        cli._show_warning(UserWarning("repaired ball"), UserWarning, "x.py", 1)
    text = tty.getvalue()
    assert "\r\x1b[Khugger: warning: repaired ball\n" in text  # the bar's line cleared first
    assert not _progress._ACTIVE


def test_a_line_goes_above_the_bar_that_is_drawn_when_displays_nest(monkeypatch):
    from hugger import _progress

    tty = _Tty()
    monkeypatch.setattr(sys, "stderr", tty)
    with Progress("outer", total=2, delay=0.0) as outer:
        outer.update(1)
        with Progress("inner", total=2, delay=60.0):  # not drawn yet
            _progress.print_line("hugger: warning: x")
    text = tty.getvalue()
    assert "\r\x1b[Khugger: warning: x\n" in text and "0.0s\x1b[Khugger" not in text
    tail = text.rsplit("\n", 1)[-1]  # after the last line: no bar left on the screen
    assert (tail == "" or tail.endswith("\r\x1b[K")) and not _progress._ACTIVE


def test_lines_from_threads_are_never_glued_to_a_bar(monkeypatch):
    import threading

    from hugger import _progress

    tty = _Tty()
    monkeypatch.setattr(sys, "stderr", tty)
    with Progress("bar", total=2, delay=0.0) as p:
        p.update(1)

        def lines() -> None:
            for i in range(3000):
                _progress.print_line(f"L{i}")

        threads = [threading.Thread(target=lines) for _ in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    text = tty.getvalue()
    assert text.count("\x1b[KL") + text.count("\nL") == 12000  # each line starts on a cleared or new line
    assert "s\x1b[KL" not in text.replace("\r\x1b[KL", "")  # never right after a bar
