"""MuJoCo physics check (hugger.physics) and the close-until-contact baseline (hugger.baselines)."""
from __future__ import annotations

import dataclasses
import json
import sys
from pathlib import Path

import numpy as np
import pytest

import hugger

mujoco = pytest.importorskip("mujoco", reason="the physics extra is not installed (pip install 'hugger[physics]')")

from hugger import baselines, physics  # noqa: E402
from hugger._rotation import quaternion_wxyz  # noqa: E402
from helpers import bench_module  # noqa: E402


@pytest.fixture(scope="module")
def cache(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("coacd-cache")


def _far_away(traj: hugger.Trajectory, distance: float = 0.5) -> hugger.Trajectory:
    """The same trajectory with the whole hand moved ``distance`` back along the final palm normal."""
    shift = -distance * traj.palm_pose[-1, :3, 2]
    pose = traj.palm_pose.copy()
    pose[:, :3, 3] += shift
    return dataclasses.replace(traj, palm_pose=pose, joints=traj.joints + shift)


# ------------------------------------------------------------------------------------------
# mesh helpers


def test_mass_properties_match_closed_forms():
    box = hugger.objects.box((0.06, 0.04, 0.02), center=(0.1, -0.2, 0.3), divisions=2)
    vol, centre, inertia = physics.mass_properties(box.vertices, box.faces)
    assert vol == pytest.approx(0.06 * 0.04 * 0.02, rel=1e-12)
    np.testing.assert_allclose(centre, [0.1, -0.2, 0.3], atol=1e-12)
    a, b, c = 0.06, 0.04, 0.02
    expect = vol / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    np.testing.assert_allclose(inertia, expect, rtol=1e-9, atol=1e-20)

    ball = hugger.objects.sphere(0.05, subdivisions=4)
    vol, centre, inertia = physics.mass_properties(ball.vertices, ball.faces)
    assert vol == pytest.approx(ball.volume, rel=1e-9)
    np.testing.assert_allclose(inertia, 0.4 * vol * 0.05 ** 2 * np.eye(3), rtol=0.01, atol=1e-12)


def test_mass_properties_rejects_inside_out():
    box = hugger.objects.box()
    with pytest.raises(ValueError, match="positive volume"):
        physics.mass_properties(box.vertices, box.faces[:, ::-1])


def test_convex_object_is_one_piece_without_coacd(monkeypatch, cache):
    ball = hugger.objects.sphere(0.04, subdivisions=3)
    monkeypatch.setitem(sys.modules, "coacd", None)  # would raise if CoACD were called
    pieces = physics.convex_pieces(ball.vertices, ball.faces, cache_dir=cache)
    assert len(pieces) == 1
    np.testing.assert_array_equal(pieces[0][0], ball.vertices)


@pytest.mark.parametrize("make", [lambda: hugger.objects.sphere(0.0006, subdivisions=3),
                                  lambda: hugger.objects.sphere(0.004, subdivisions=3),
                                  lambda: hugger.objects.sphere(1.5, subdivisions=3),
                                  lambda: hugger.objects.cylinder(0.0001, 0.012),  # a needle
                                  lambda: hugger.objects.cylinder(0.00005, 0.011)])
def test_a_hulls_volume_at_any_size_and_shape_the_planner_takes(make):
    # (a hull whose mass or inertia at unit density is below what MuJoCo takes is weighed denser)
    obj = make()
    volume, _, _ = physics.mass_properties(obj.vertices, obj.faces)
    assert physics.hull_volume(obj.vertices) == pytest.approx(volume, rel=1e-6)


def test_a_grasp_of_a_one_millimetre_object_is_judged(tmp_path):
    # 1.2 mm across: above the smallest size the planner takes (1 mm); the hold test runs
    ball = hugger.objects.sphere(0.0006, subdivisions=3)
    hand = hugger.Hand(fingers=3, links=3, link_length=0.002, link_radius=0.0002, palm_radius=0.002,
                       palm_thickness=0.001)
    traj = hugger.plan(hand, ball, [0, 0, 0], hugger.look_at([0, 0, 0.01], [0, 0, 0]), contact_tolerance=2e-5)
    verdict = physics.validate(traj, cache_dir=tmp_path)
    assert set(verdict["directions"]) == set(physics.DIRECTIONS)


def test_nonconvex_object_is_decomposed_and_cached(monkeypatch, cache):
    blob = hugger.objects.blob(0.04, amplitude=0.6, seed=1, subdivisions=2)
    assert physics.hull_volume(blob.vertices) / blob.volume > physics.CONVEX_RATIO
    pytest.importorskip("coacd", reason="CoACD is not installed (pip install 'hugger[physics]')")
    first = physics.convex_pieces(blob.vertices, blob.faces, cache_dir=cache)
    assert len(first) > 1
    assert len(list(cache.glob("*.npz"))) == 1
    total = sum(physics.mass_properties(v, f)[0] for v, f in first)
    assert 0.9 * blob.volume < total < 1.5 * blob.volume
    monkeypatch.setitem(sys.modules, "coacd", None)  # the second call must come from the cache
    second = physics.convex_pieces(blob.vertices, blob.faces, cache_dir=cache)
    assert len(second) == len(first)
    for (v1, f1), (v2, f2) in zip(first, second):
        np.testing.assert_array_equal(v1, v2)
        np.testing.assert_array_equal(f1, f2)
    assert len(physics.convex_pieces(blob.vertices, blob.faces, decompose=False)) == 1


def test_pieces_are_remembered_per_mesh_and_cache(monkeypatch, tmp_path):
    """The hull test (a MuJoCo compile) runs once per mesh and cache folder in a process."""
    from hugger.physics import decompose

    ball = hugger.objects.sphere(0.04, subdivisions=3)
    first = physics.convex_pieces(ball.vertices, ball.faces, cache_dir=tmp_path)
    monkeypatch.setattr(decompose, "hull_volume", lambda v: pytest.fail("asked again"))
    again = physics.convex_pieces(ball.vertices.copy(), ball.faces, cache_dir=tmp_path)
    assert len(again) == 1 and np.array_equal(again[0][0], first[0][0]) and not again[0][0].flags.writeable
    with pytest.raises(pytest.fail.Exception, match="asked again"):  # another folder is another cache
        physics.convex_pieces(ball.vertices, ball.faces, cache_dir=tmp_path / "other")


def test_missing_coacd_raises_import_error_naming_the_extra(monkeypatch, tmp_path):
    blob = hugger.objects.blob(0.04, amplitude=0.6, seed=1, subdivisions=2)
    assert physics.hull_volume(blob.vertices) / blob.volume > physics.CONVEX_RATIO
    monkeypatch.setitem(sys.modules, "coacd", None)  # and an empty cache: CoACD would be needed
    with pytest.raises(ImportError, match=r"hugger\[physics\]"):
        physics.convex_pieces(blob.vertices, blob.faces, cache_dir=tmp_path)


def test_missing_mujoco_raises_import_error_naming_the_extra(monkeypatch, sphere_plan):
    monkeypatch.setitem(sys.modules, "mujoco", None)
    with pytest.raises(ImportError, match=r"hugger\[physics\]"):
        physics.export_mjcf(sphere_plan)
    with pytest.raises(ImportError, match=r"hugger\[physics\]"):
        physics.validate(sphere_plan)


# ------------------------------------------------------------------------------------------
# MJCF export


@pytest.mark.parametrize("k", [0, -1])
def test_export_round_trip_reproduces_configuration(sphere_plan, tmp_path, k):
    traj = sphere_plan
    path = tmp_path / "hand.xml"
    xml = physics.export_mjcf(traj, path, k=k)
    assert path.read_text() == xml
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    m_count, n_count = traj.angles.shape[1:]
    assert model.nu == m_count * n_count
    # qpos of the hinges set from the trajectory, everything else from the model's defaults
    data.mocap_pos[0] = traj.palm_pose[k, :3, 3]
    data.mocap_quat[0] = quaternion_wxyz(traj.palm_pose[k, :3, :3])
    for m in range(m_count):
        for n in range(n_count):
            j = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, f"f{m}_j{n}")
            data.qpos[model.jnt_qposadr[j]] = traj.angles[k, m, n]
    mujoco.mj_forward(model, data)
    joints = traj.joints[k]
    worst = 0.0
    for m in range(m_count):
        for n in range(n_count):
            b = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f"f{m}_l{n}")
            g = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, f"f{m}_l{n}")
            j = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, f"f{m}_j{n}")
            tail = data.xpos[b]
            half = model.geom_size[g, 1]
            tip = data.geom_xpos[g] + data.geom_xmat[g].reshape(3, 3)[:, 2] * half
            worst = max(worst, np.abs(tail - joints[m, n]).max(), np.abs(tip - joints[m, n + 1]).max())
            # the hinge is at j_mn, its axis normal to the finger plane
            np.testing.assert_allclose(data.xanchor[j], joints[m, n], atol=1e-9)
            assert abs(float(data.xaxis[j] @ (joints[m, n + 1] - joints[m, n]))) < 1e-9
            assert abs(float(data.xaxis[j] @ traj.palm_pose[k, :3, 2])) < 1e-9
            lo, hi = model.jnt_range[j]
            assert lo <= traj.angles[k, m, n] <= hi
    assert worst < 1e-6
    # the palm: a cylinder behind the front face, radius and thickness of the hand
    g = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "palm")
    hand = traj.hand
    np.testing.assert_allclose(model.geom_size[g, :2], [hand["palm_radius"], hand["palm_thickness"] / 2])
    centre = traj.palm_pose[k, :3, 3] - traj.palm_pose[k, :3, 2] * hand["palm_thickness"] / 2
    np.testing.assert_allclose(data.geom_xpos[g], centre, atol=1e-12)
    # the object: a free body of 0.1 kg at the mesh's centre of volume
    obj = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "object")
    assert model.body_mass[obj] == pytest.approx(0.1)
    np.testing.assert_allclose(data.xipos[obj], traj.object().centroid, atol=1e-9)


def test_export_keyframe_holds_the_configuration(sphere_plan):
    model, data = physics.load_model(sphere_plan)
    angles = []
    for m in range(5):
        for n in range(5):
            j = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, f"f{m}_j{n}")
            angles.append(data.qpos[model.jnt_qposadr[j]])
    np.testing.assert_allclose(np.reshape(angles, (5, 5)), sphere_plan.angles[-1], atol=1e-12)
    np.testing.assert_allclose(data.ctrl, sphere_plan.angles[-1].ravel(), atol=1e-12)
    assert model.opt.gravity[2] < 0  # the file keeps gravity for the object...
    assert np.all(model.body_gravcomp[2:-1] == 1)  # ...and compensates it on the finger links (body 1: the palm)


def test_export_zero_radius_links_and_nonconvex_object(cache):
    thin = hugger.Hand(fingers=3, links=3, link_length=0.03, link_radius=0.0, palm_radius=0.03, palm_thickness=0.01)
    blob = hugger.objects.blob(0.04, amplitude=0.6, seed=1, subdivisions=2)  # decomposition cached above
    traj = hugger.plan(thin, blob, [0, 0, 0], hugger.look_at([0, 0, 0.25], [0, 0, 0]))
    xml = physics.export_mjcf(traj, cache_dir=cache)
    model = mujoco.MjModel.from_xml_string(xml)
    g = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "f0_l0")
    assert model.geom_size[g, 0] == pytest.approx(physics.ZERO_RADIUS_SUBSTITUTE)
    obj = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "object")
    assert int(np.sum(model.geom_bodyid == obj)) > 1
    single = mujoco.MjModel.from_xml_string(physics.export_mjcf(traj, decompose=False))
    assert int(np.sum(single.geom_bodyid == obj)) == 1


def test_export_rejects_bad_input(sphere_plan):
    with pytest.raises(ValueError, match="out of range"):
        physics.export_mjcf(sphere_plan, k=len(sphere_plan))
    with pytest.raises(ValueError, match="object_mass"):
        physics.export_mjcf(sphere_plan, object_mass=-1)
    with pytest.raises(ValueError, match="friction"):
        physics.export_mjcf(sphere_plan, friction=float("nan"))
    with pytest.raises(ValueError, match="Trajectory"):
        physics.export_mjcf({"not": "a trajectory"})


# ------------------------------------------------------------------------------------------
# validate


def test_caged_sphere_is_held_in_all_six_directions(sphere_plan):
    res = physics.validate(sphere_plan)
    json.dumps(res, allow_nan=False)  # plain JSON
    assert set(res["directions"]) == {"+x", "-x", "+y", "-y", "+z", "-z"}
    for name, d in res["directions"].items():
        assert d["held"], (name, d)
        assert d["displacement_m"] < 0.05 and d["rotation_deg"] < 15.0
    assert res["held"] is True
    assert all(res["touching_fingers"])
    s = res["settings"]
    assert s["mass_kg"] == 0.1 and s["mu"] == 0.6 and s["force_N"] == pytest.approx(10 * 0.1 * 9.81)
    for key in ("timestep_s", "integrator", "condim", "solref", "solimp", "kp_Nm_per_rad", "squeeze_rad", "duration_s",
                "gravity", "impratio", "contact_distance_m"):
        assert key in s


def test_hand_moved_away_holds_nothing(sphere_plan):
    res = physics.validate(_far_away(sphere_plan), duration=0.5)
    assert res["held"] is False
    assert not any(res["touching_fingers"])
    toward_hand = -sphere_plan.palm_pose[-1, :3, 2]  # the hand was moved back along this
    for name, d in res["directions"].items():
        assert not d["held"], name
        assert d["displacement_m"] > 0.3
        if abs(float(np.dot(physics.DIRECTIONS[name], toward_hand))) < 1e-9:
            # free flight under 10 x 9.81 m/s^2 for 0.5 s (toward the hand it hits the hand 0.5 m away)
            assert d["displacement_m"] == pytest.approx(0.5 * 98.1 * 0.5 ** 2, rel=0.01)


def test_validate_is_deterministic(sphere_plan):
    a = physics.validate(sphere_plan, duration=0.3)
    b = physics.validate(sphere_plan, duration=0.3)
    assert json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)


def test_validate_rejects_bad_input(sphere_plan):
    for kwargs, word in (({"mass": 0}, "mass"), ({"mu": -0.1}, "mu"), ({"duration": 0}, "duration"),
                         ({"squeeze": -0.01}, "squeeze"), ({"force_factor": float("inf")}, "force_factor"),
                         ({"k": 1.5}, "k"), ({"duration": 1e9}, "duration must be at most 60")):
        with pytest.raises(ValueError, match=word):
            physics.validate(sphere_plan, **kwargs)
    for kwargs, word in (({"max_factor": float("nan")}, "max_factor"), ({"max_factor": 0}, "max_factor"),
                         ({"bisect_steps": -1}, "bisect_steps"), ({"bisect_steps": 2.5}, "bisect_steps")):
        with pytest.raises(ValueError, match=word):
            physics.validate_robust(sphere_plan, **kwargs)


def test_validate_reads_trajectory_files(sphere_plan, tmp_path):
    path = tmp_path / "plan.npz"
    sphere_plan.save(path)
    assert physics.export_mjcf(path) == physics.export_mjcf(sphere_plan)


# ------------------------------------------------------------------------------------------
# the close-until-contact baseline


@pytest.fixture(scope="module")
def baseline_sphere(hand):
    obj = hugger.objects.sphere(0.04, subdivisions=3)
    return baselines.plan_baseline(hand, obj, [0, 0, 0], hugger.look_at([0, 0, 0.2], [0, 0, 0]))


def test_baseline_is_a_valid_trajectory(baseline_sphere, checker, tmp_path):
    import helpers

    traj = baseline_sphere
    assert traj.status == "done"
    assert np.all(traj.tip_state[-1] == hugger.DONE)
    assert traj.phase[0] == 0 and np.all(traj.phase[1:] == 2)
    helpers.save_and_check(checker, traj, tmp_path / "baseline.npz", every=4)
    # it stopped on a touch: every finger ends within the contact tolerance of the object
    gaps = traj.link_gaps(-1)
    assert np.all(gaps.min(axis=1) <= traj.params["contact_tolerance"] + 1e-6)


def test_baseline_plans_the_same_bytes_twice_and_times_apart(hand, tmp_path):
    # its wall-clock times lived in its stats: two saves of one plan from Python differed
    obj = hugger.objects.sphere(0.04, subdivisions=2)
    start = hugger.look_at([0, 0, 0.2], [0, 0, 0])
    runs = [baselines.run_baseline(hand, obj, [0, 0, 0], start) for _ in range(2)]
    for i, run in enumerate(runs):
        assert run.setup_time_s > 0 and run.plan_time_s > 0
        assert not any(k.endswith("_time_s") for k in run.trajectory.stats)
        run.trajectory.save(tmp_path / f"{i}.npz")
    assert (tmp_path / "0.npz").read_bytes() == (tmp_path / "1.npz").read_bytes()
    plain = baselines.plan_baseline(hand, obj, [0, 0, 0], start)
    plain.save(tmp_path / "plain.npz")
    assert (tmp_path / "plain.npz").read_bytes() == (tmp_path / "0.npz").read_bytes()


def test_baseline_touches_less_than_hugger(baseline_sphere, sphere_plan):
    base, hug = baseline_sphere.summary(), sphere_plan.summary()
    assert base["links_in_contact"] < hug["links_in_contact"]
    assert hug["palm_contact"] and not base["palm_contact"]
    res = physics.validate(baseline_sphere, duration=0.5)  # validate applies to it unchanged
    assert set(res["directions"]) == set(physics.DIRECTIONS)


def test_baseline_turns_to_face_the_target_first(hand, checker, tmp_path):
    import helpers

    obj = hugger.objects.sphere(0.03, subdivisions=2)
    start = hugger.look_at([0.0, 0.0, 0.2], [0.05, 0.0, 0.0])  # not facing T
    traj = baselines.plan_baseline(hand, obj, [0, 0, 0], start, step=0.002)
    assert np.sum(traj.phase == 1) > 0
    helpers.save_and_check(checker, traj, tmp_path / "turn.npz", every=8)


def test_baseline_rejects_bad_starts(hand):
    obj = hugger.objects.sphere(0.03, subdivisions=2)
    with pytest.raises(ValueError, match="inside the object"):
        baselines.plan_baseline(hand, obj, [0.1, 0, 0], hugger.look_at([0, 0, 0.2], [0.1, 0, 0]))
    with pytest.raises(ValueError, match="at the start"):
        baselines.plan_baseline(hand, obj, [0, 0, 0], hugger.look_at([0, 0, 0.05], [0, 0, 0]))


def test_hugger_baseline_writes_the_same_file_twice_and_refuses_bad_input(tmp_path, capsys):
    # python -m hugger.baselines printed tracebacks for bad input and wrote its wall-clock times into
    # the file (two runs differed); it is now hugger baseline, with the CLI's errors and outputs
    from hugger.cli import main

    out = tmp_path / "base.npz"
    assert main(["baseline", "sphere", "--out", str(out), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["status"] == "done" and report["plan_time_s"] > 0 and report["penetration_m"] <= 5e-5
    first = out.read_bytes()
    assert baselines.main(["--object=sphere", "--out", str(out), "--json"]) == 0
    capsys.readouterr()
    traj = hugger.Trajectory.load(out)
    assert out.read_bytes() == first  # the same command, the same bytes (the provenance names the command)
    assert "plan_time_s" not in traj.stats and traj.stats["collision_queries"] > 0
    assert traj.provenance["object"] == "sphere" and traj.provenance["command"][:3] == ["hugger", "baseline", "sphere"]
    for argv, message in ((["--object", "nope"], "'nope' is neither a built-in object"),
                          (["--object", "sphere", "--out", str(tmp_path / "no" / "x.npz")], "no such directory"),
                          (["--object", "sphere", "--out", str(tmp_path / "x.txt")], "--out must end in .npz"),
                          (["--object"], "--object needs"), (["--object="], "--object needs")):
        assert baselines.main(argv) == 2
        err = capsys.readouterr().err
        assert err.startswith("hugger: error: ") and message in err and len(err.strip().splitlines()) == 1


def test_hugger_baseline_plans_with_the_hand_options(checker, tmp_path, capsys):
    # a preset (or a URDF) hand compared from the command line, as hugger plan takes it
    import helpers
    from hugger.cli import main

    out = tmp_path / "robotiq.npz"
    assert main(["baseline", "sphere", "--hand", "robotiq_3f", "--out", str(out), "--json"]) == 0
    preset = hugger.hands.load("robotiq_3f")
    assert json.loads(capsys.readouterr().out)["links"] == preset.fingers * preset.links
    traj = hugger.Trajectory.load(out)
    assert traj.hand["name"] == "robotiq_3f" and traj.status == "done"
    helpers.assert_checked(checker, out)
    assert main(["baseline", "sphere", "--link-length", "20"]) == 2
    assert "implausibly large" in capsys.readouterr().err


def test_compare_script_writes_a_table(tmp_path, capsys):
    pytest.importorskip("scipy", reason="the comparison's grasp quality needs scipy (pip install 'hugger[analysis]')")
    mod = bench_module("compare_baseline")
    out = tmp_path / "table.md"
    assert mod.main(["--objects", "sphere", "--out", str(out), "--no-validate"]) == 0
    text = out.read_text()
    assert "| sphere | hug | done |" in text and "| sphere | paper | done |" in text and "| sphere | baseline | done |" in text
    assert "sphere" in capsys.readouterr().out


def test_a_direction_whose_simulation_resets_is_not_held(sphere_plan):
    # A push of 10^12 N blows the accelerations up; MuJoCo then resets the state, with finite
    # figures of an object at rest. Its warning counter says so: no direction holds.
    report = physics.validate(sphere_plan, force=1e12)
    assert not report["held"]
    assert all(d["diverged"] and not d["held"] for d in report["directions"].values()), report["directions"]
