"""The MuJoCo skin and closed-loop hugging (hugger simulate)."""
from __future__ import annotations

import json
import os

import numpy as np
import pytest

import hugger
from hugger import skins

mujoco = pytest.importorskip("mujoco", reason="the physics extra is not installed (pip install 'hugger[physics]')")

from hugger import mujoco_skin  # noqa: E402

#: Long runs (minutes): with HUGGER_SLOW=1 (bench/closed_loop.py prints the same figures).
LONG = pytest.mark.skipif(not os.environ.get("HUGGER_SLOW"), reason="long run: set HUGGER_SLOW=1")


def test_mujoco_skin_gaps_match_the_mesh_world(hand):
    obj = hugger.objects.sphere(0.04)
    pose = hugger.look_at([0.2, 0, 0], [0, 0, 0])
    sim = mujoco_skin.Simulation(hand, obj, pose)
    skin, ref = hugger.physics.MujocoSkin(sim), skins.MeshSkin(obj)
    rng = np.random.default_rng(0)
    compared = 0
    for _ in range(100):
        a = rng.uniform(-0.07, 0.07, 3)
        b = a + rng.normal(scale=0.01, size=3)
        r = float(rng.uniform(0.0, 0.005))
        t, u = skin.capsule(a, b, r, np.inf), ref.capsule(a, b, r, np.inf)
        assert np.sign(t.gap) == np.sign(u.gap)
        if u.gap > 0:
            compared += 1
            assert t.gap == pytest.approx(u.gap, abs=1e-6)
            np.testing.assert_allclose(t.normal, u.normal, atol=1e-3)
    assert compared > 30
    assert skin.palm(pose, 0.03, 0.01, np.inf) == pytest.approx(ref.palm(pose, 0.03, 0.01, np.inf), abs=1e-6)
    # a capped query may stop early, but never reports less than the cap for a farther part
    far = skin.capsule(np.array([0.1, 0, 0]), np.array([0.1, 0.01, 0]), 0.004, 0.01)
    assert far.gap >= 0.01


def test_the_skin_reads_the_simulated_state(hand):
    obj = hugger.objects.sphere(0.04)
    sim = mujoco_skin.Simulation(hand, obj, hugger.look_at([0.2, 0, 0], [0, 0, 0]), latency=2)
    skin = mujoco_skin.MujocoSkin(sim)
    a = np.array([0.0, 0.0, 0.06])
    before = skin.capsule(a, a, 0.0, np.inf).gap
    for k in range(3):
        sim.advance(0.05, force=np.array([0.0, 0.0, 1.0]))  # pushed up, toward the probe
        if k < 1:  # two control periods of latency: still the old pose
            assert skin.capsule(a, a, 0.0, np.inf).gap == pytest.approx(before, abs=1e-9)
    assert skin.capsule(a, a, 0.0, np.inf).gap < before - 1e-3


def test_hugger_simulate_closed_loop_holds_with_t_off(tmp_path, capsys):
    from hugger.cli import main

    out = tmp_path / "closed.npz"
    assert main(["simulate", "sphere", "--offset", "0", "0.005", "0", "--out", str(out), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    closed = report["closed"]
    assert closed["status"] == "done" and closed["held"], report
    assert closed["links_in_contact"] >= 10
    traj = hugger.Trajectory.load(out)
    assert traj.has_object and len(traj) == closed["configurations"]
    assert traj.provenance["object"] == "sphere" and traj.provenance["command"][:2] == ["hugger", "simulate"]


def test_hugger_simulate_bad_input(capsys):
    from hugger.cli import main

    assert main(["simulate", "sphere", "--push", "-1"]) == 2
    assert "hugger: error:" in capsys.readouterr().err
    assert main(["simulate", "sphere", "--latency", "-1"]) == 2
    capsys.readouterr()
    # A skin chooses how the open loop's plan senses the static mesh; the closed loop's is MuJoCo.
    assert main(["simulate", "sphere", "--skin", "mesh"]) == 2
    err = capsys.readouterr().err
    assert "--skin chooses the sensing of the --open-loop plan" in err and err.count("\n") == 1


def test_hugger_simulate_skin_applies_to_the_open_loop_plan(monkeypatch, capsys):
    from hugger.cli import main

    asked = {}
    replay, simulate = mujoco_skin.replay, mujoco_skin.simulate

    def seen(mode, run):
        def call(*args, **kwargs):
            asked[mode] = kwargs.get("skin")
            return run(*args, **kwargs)
        return call

    monkeypatch.setattr(mujoco_skin, "replay", seen("open", replay))
    monkeypatch.setattr(mujoco_skin, "simulate", seen("closed", simulate))
    assert main(["simulate", "sphere", "--open-loop", "--skin", "mesh", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert asked == {"open": "mesh", "closed": None}  # the closed loop senses through MuJoCo
    assert report["open"]["status"] == "done" and report["closed"]["status"] == "done", report


@pytest.mark.slow
@LONG
@pytest.mark.parametrize("name", ["sphere", "ellipsoid", "cylinder", "curvy"])
@pytest.mark.parametrize("offset_mm", [0.0, 5.0])
def test_closed_loop_holds_in_the_six_direction_test(hand, name, offset_mm):
    case = hugger.scenarios.default_case(name, hand)
    r = mujoco_skin.simulate(hand, case.obj, case.target, case.palm_pose,
                             offset=offset_mm * 1e-3 * case.palm_pose[:3, 0])
    assert r.status == "done" and r.hold["held"], r.as_dict()


def test_a_simulation_that_goes_unstable_is_no_hold(hand):
    # A push of 10^12 N blows the accelerations up; MuJoCo then resets the state, where the object
    # sits untouched in a grasp that looks held. The counter of that warning says it happened.
    case = hugger.scenarios.default_case("sphere", hand)
    r = mujoco_skin.simulate(hand, case.obj, case.target, case.palm_pose, push=1e12)
    assert r.hold == {"held": False, "diverged": True}
    assert r.as_dict()["held"] is False
    assert r.object_moved_m is None and r.links_in_contact is None  # the reset state's figures say nothing


def test_the_command_gives_no_figures_of_a_simulation_that_went_unstable(capsys):
    from hugger.cli import main

    assert main(["simulate", "sphere", "--push", "1e12"]) == 0
    out = capsys.readouterr().out
    assert "went unstable (MuJoCo reset it): no figures, NOT held" in out and "object moved" not in out

