"""Real hands: general layouts, joint limits, rest angles, presets, URDF/MJCF import and export."""
from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import hugger
from hugger import hands

from helpers import check_file

REST_RULE = "is FROZEN but not extended"  # the checker's rule for rest = 0; see docs/hands.md


def full_check(checker, traj: hugger.Trajectory, path: Path, rest_nonzero: bool) -> tuple[list[str], dict]:
    """Save ``traj`` to ``path`` and run every check of the independent checker on it: structure,
    kinematics (limits included), algorithm, collision and motion (DONE angles, Phase 2 joint moves
    of at most 4 steps, swept collision on every step), as its command line runs them by default.
    Returns the failures that count: the checker does not read rest_angles yet, so for a hand with
    non-zero rest angles its "FROZEN but not extended" rule is set aside (our own
    assert_plan_properties asserts that FROZEN fingers stay at rest)."""
    traj.save(path)
    _, failures, figures = check_file(checker, path, motion=True)
    assert not any(f.startswith("structure:") for f in failures), failures
    return [f for f in failures if not (rest_nonzero and REST_RULE in f)], figures


def random_layout(rng: np.random.Generator) -> hugger.Hand:
    """A random general layout that the hand model accepts: roots anywhere on the palm, random
    directions, unequal links, limits, rest angles including fingers lying along the palm."""
    while True:
        m, n = int(rng.integers(2, 5)), int(rng.integers(2, 5))
        palm = rng.uniform(0.03, 0.045)
        rho = palm * np.sqrt(rng.uniform(0.1, 1.0, m))
        phi = rng.uniform(0, 2 * np.pi, m)
        roots = np.stack([rho * np.cos(phi), rho * np.sin(phi), np.zeros(m)], axis=1)
        psi = phi + rng.normal(0.0, 0.6, m) if rng.random() < 0.7 else rng.uniform(0, 2 * np.pi, m)
        dirs = np.stack([np.cos(psi), np.sin(psi), np.zeros(m)], axis=1)
        lengths = rng.uniform(0.012, 0.025, (m, n))
        radius = float(rng.choice([0.0, rng.uniform(0.002, 0.004)]))
        lo = -rng.uniform(0.0, 0.8, (m, n))
        hi = rng.uniform(0.5, 1.9, (m, n))
        rest = np.zeros((m, n))
        for f in range(m):
            r = rng.random()
            if r < 0.2:  # sideways: link 0 along the palm (outward), the next link straight up
                rest[f, 0], lo[f, 0], hi[f, 0] = -np.pi / 2, -np.pi / 2, -np.pi / 2 + rng.uniform(0, 0.5)
                if n > 1:
                    rest[f, 1], lo[f, 1], hi[f, 1] = np.pi / 2, np.pi / 2 - 0.2, np.pi / 2 + 1.2
            elif r < 0.3:  # lying along the palm toward its centre (an Allegro-like finger laid flat)
                rest[f, 0], lo[f, 0], hi[f, 0] = np.pi / 2, np.pi / 2 - rng.uniform(0, 0.5), np.pi / 2
            elif r < 0.5:
                rest[f] = rng.uniform(lo, hi)[f] * 0.3
        if limits_off := rng.random() >= 0.85:
            rest[:] = 0.0
        limits = None if limits_off else np.stack([lo, hi], axis=-1)
        try:
            return hugger.Hand.from_layout(roots, dirs, lengths, rest=rest, limits=limits, link_radius=radius,
                                           palm_radius=palm)
        except ValueError:
            continue


def plan_random(seed: int):
    rng = np.random.default_rng(seed)
    hand = random_layout(rng)
    kind = ["sphere", "apple", "box", "cylinder", "ellipsoid"][seed % 5]
    obj = {"sphere": lambda: hugger.objects.sphere(0.035, subdivisions=3),
           "apple": lambda: hugger.objects.apple(),
           "box": lambda: hugger.objects.box([0.05, 0.04, 0.035], divisions=3),
           "cylinder": lambda: hugger.objects.cylinder(0.03, 0.08, sections=32, rings=4),
           "ellipsoid": lambda: hugger.objects.ellipsoid([0.04, 0.03, 0.025], subdivisions=3)}[kind]()
    target = np.zeros(3)
    d = rng.normal(size=3)
    d /= np.linalg.norm(d)
    pose = hugger.scenarios.start_pose(obj, hand, target, direction=d, turn_deg=float(rng.uniform(0, 40)))
    traj = hugger.Planner(hand, obj, target, pose).plan()
    return hand, traj


def assert_plan_properties(hand: hugger.Hand, traj) -> None:
    assert traj.status in ("done", "stalled"), traj.status
    lim = hand.joint_limits
    a = traj.angles
    assert np.all(a >= lim[..., 0] - 1e-9) and np.all(a <= lim[..., 1] + 1e-9)
    frozen = traj.tip_state == hugger.FROZEN
    rest = np.broadcast_to(hand.rest_angles, a.shape)
    assert np.array_equal(a[frozen], rest[frozen])  # FROZEN = at rest, bit for bit while it translates
    # roots stay where the layout puts them
    for k in (0, len(traj) // 2, len(traj) - 1):
        assert np.allclose(traj.joints[k, :, 0], hand.roots(traj.palm_pose[k]), atol=1e-9)


def _run(seeds, checker, tmp_path):
    statuses = {}
    for seed in seeds:
        hand, traj = plan_random(seed)
        assert_plan_properties(hand, traj)
        statuses[traj.status] = statuses.get(traj.status, 0) + 1
        if checker is not None:
            fails, _ = full_check(checker, traj, tmp_path / f"p{seed}.npz", bool(np.any(hand.rest_angles != 0)))
            assert not fails, (seed, fails)
    return statuses


def test_random_layouts_plan_within_limits_and_pass_the_checker(checker, tmp_path):
    _run(range(20), checker, tmp_path)


@pytest.mark.slow
@pytest.mark.skipif(os.environ.get("HUGGER_FUZZ_PROFILE") != "long",
                    reason="200 random layouts, about 3 minutes: run by make fuzz (HUGGER_FUZZ_PROFILE=long)")
def test_random_layouts_many(checker, tmp_path):
    """The property over 200 random layouts and objects."""
    _run(range(1000, 1200), checker, tmp_path)


def test_plans_are_deterministic():
    _, a = plan_random(5)
    _, b = plan_random(5)
    assert np.array_equal(a.joints, b.joints) and np.array_equal(a.angles, b.angles)


def test_rim_layout_keeps_its_old_file_form():
    h = hugger.Hand(fingers=3, links=2)
    d = h.to_dict()
    assert not h.general and "finger_roots" not in d
    again = hugger.Hand.from_dict(d)
    assert not again.general and again.same_as(h)
    # a general hand round-trips through hand_json
    g = hands.preset("robotiq_3f")
    assert hugger.Hand.from_dict(json.loads(g.to_json())).same_as(g, 0.0)


@pytest.mark.parametrize("kwargs, message", [
    (dict(roots=[[0.05, 0, 0], [-0.01, 0, 0]]), "off the palm"),
    (dict(roots=[[0.01, 0, 0.002], [-0.01, 0, 0]]), "front face"),
    (dict(directions=[[1, 0, 0.3], [-1, 0, 0]]), "palm plane"),
    (dict(limits=[[[0.1, 1.0]] * 2] * 2), "outside its limits"),
    (dict(limits=[[[1.0, 0.1]] * 2] * 2), "lower <= upper"),
    (dict(rest=[[1.8, 0.0], [0.0, 0.0]]), "behind the palm"),
    (dict(rest=[[np.pi / 2, 0], [np.pi / 2, 0]]), "intersect"),
])
def test_layouts_the_planner_cannot_handle_are_refused(kwargs, message):
    base = dict(roots=[[0.01, 0, 0], [-0.01, 0, 0]], directions=[[1, 0, 0], [-1, 0, 0]],
                link_lengths=[[0.02, 0.02]] * 2, link_radius=0.003, palm_radius=0.03)
    base.update(kwargs)
    with pytest.raises(ValueError, match=message):
        hugger.Hand.from_layout(**base)


@pytest.mark.parametrize("name", list(hands.PRESETS))
def test_presets_plan_and_round_trip(name, checker, tmp_path):
    hand = hands.preset(name)
    case = hugger.scenarios.default_case("sphere", hand)
    traj = hugger.Planner(hand, case.obj, case.target, case.palm_pose).plan()
    assert traj.status == "done"
    assert_plan_properties(hand, traj)
    if name != "paper_5x5":  # the rim hand's plan is checked by the planner's own tests
        fails, _ = full_check(checker, traj, tmp_path / "p.npz", bool(np.any(hand.rest_angles != 0)))
        assert not fails
    for ext, write, read in ((".urdf", hands.to_urdf, hands.from_urdf), (".xml", hands.to_mjcf, hands.from_mjcf)):
        f = tmp_path / f"hand{ext}"
        f.write_text(write(hand, traj.angles[-1]))
        back = read(f)
        assert back.same_as(hand, 1e-9)
        again = hugger.Planner(back, case.obj, case.target, case.palm_pose).plan()
        assert np.array_equal(again.joints, traj.joints)  # bit-identical
        # without the embedded exact description, the geometry alone gives the same hand
        text = f.read_text()
        start = text.find("<!-- hugger-hand")
        (tmp_path / f"bare{ext}").write_text(text[:start] + text[text.find("-->", start) + 3:])
        assert read(tmp_path / f"bare{ext}").same_as(hand, 1e-9)


THUMB_URDF = """<?xml version="1.0"?>
<robot name="thumb_hand">
  <link name="palm">
    <collision><origin xyz="0 0 -0.006"/><geometry><cylinder radius="0.045" length="0.012"/></geometry></collision>
  </link>
  {fingers}
</robot>
"""

FINGER = """
  <joint name="{p}_spread" type="revolute"><parent link="palm"/><child link="{p}_base"/>
    <origin xyz="{x} {y} 0" rpy="0 0 {yaw}"/><axis xyz="0 0 1"/><limit lower="-0.3" upper="0.3" effort="1" velocity="1"/></joint>
  <link name="{p}_base"/>
  <joint name="{p}_j0" type="revolute"><parent link="{p}_base"/><child link="{p}_l0"/>
    <origin xyz="0 0 0"/><axis xyz="0 -1 0"/><limit lower="-0.2" upper="1.4" effort="1" velocity="1"/></joint>
  <link name="{p}_l0"><collision><origin xyz="0 0 0.011"/><geometry><cylinder radius="0.005" length="0.022"/></geometry></collision></link>
  <joint name="{p}_j1" type="revolute"><parent link="{p}_l0"/><child link="{p}_l1"/>
    <origin xyz="0 0 0.022"/><axis xyz="0 -1 0"/><limit lower="0" upper="1.5" effort="1" velocity="1"/></joint>
  <link name="{p}_l1"><collision><origin xyz="0 0 0.009"/><geometry><cylinder radius="0.005" length="0.018"/></geometry></collision></link>
  <joint name="{p}_j2" type="revolute"><parent link="{p}_l1"/><child link="{p}_l2"/>
    <origin xyz="0 0 0.018"/><axis xyz="0 -1 0"/><limit lower="0" upper="1.5" effort="1" velocity="1"/></joint>
  <link name="{p}_l2"><collision><origin xyz="0 0 0.008"/><geometry><cylinder radius="0.005" length="0.016"/></geometry></collision></link>
  <joint name="{p}_tip" type="fixed"><parent link="{p}_l2"/><child link="{p}_tip"/><origin xyz="0 0 0.016"/></joint>
  <link name="{p}_tip"/>
"""


def thumb_urdf(path: Path, tilt_thumb: bool = False) -> Path:
    """Three parallel fingers along +x and an opposed thumb: each finger has a spread joint about
    the palm normal (its axis z breaks planarity unless held) and three flexion joints."""
    fingers = [FINGER.format(p=f"f{i}", x=0.025, y=y, yaw=0.0) for i, y in enumerate((-0.022, 0.0, 0.022))]
    fingers.append(FINGER.format(p="thumb", x=-0.03, y=0.0, yaw=math.pi))
    path.write_text(THUMB_URDF.format(fingers="".join(fingers)))
    return path


def test_urdf_with_a_non_planar_finger_names_the_joint(tmp_path):
    pytest.importorskip("yourdfpy")
    f = thumb_urdf(tmp_path / "thumb.urdf")
    with pytest.raises(ValueError, match=r"joint 'f0_spread'.*(palm normal|planarity)") as info:
        hugger.Hand.from_urdf(f)
    assert "\n" not in str(info.value)
    r = subprocess.run([sys.executable, "-m", "hugger", "plan", "sphere", "--hand", str(f), "--out",
                        str(tmp_path / "x.npz")], capture_output=True, text=True)
    assert r.returncode == 2 and r.stderr.startswith("hugger: error:") and "f0_spread" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1


def test_urdf_with_fixed_spread_joints_imports_and_plans(tmp_path, checker):
    pytest.importorskip("yourdfpy")
    f = thumb_urdf(tmp_path / "thumb.urdf")
    fixed = {f"{p}_spread": 0.0 for p in ("f0", "f1", "f2", "thumb")}
    hand = hugger.Hand.from_urdf(f, fixed_joints=fixed)
    assert (hand.fingers, hand.links) == (4, 3)
    assert hand.link_radius == 0.005 and hand.palm_radius == 0.045
    assert np.allclose(hand.link_lengths, [[0.022, 0.018, 0.016]] * 4, atol=1e-12)
    assert np.allclose(hand.finger_directions[3], [-1, 0, 0], atol=1e-12)  # the opposed thumb
    assert np.allclose(hand.joint_limits[0, 0], [-0.2, 1.4])
    for name in ("sphere", "apple", "cylinder"):
        case = hugger.scenarios.default_case(name, hand)
        traj = hugger.Planner(hand, case.obj, case.target, case.palm_pose).plan()
        assert_plan_properties(hand, traj)
        fails, _ = full_check(checker, traj, tmp_path / f"{name}.npz", False)
        assert not fails, fails
    # a spread held away from 0 turns the finger's plane about the palm normal
    turned = hugger.Hand.from_urdf(f, fixed_joints={**fixed, "f0_spread": 0.2})
    assert np.allclose(turned.finger_directions[0], [math.cos(0.2), math.sin(0.2), 0], atol=1e-12)
    for bad, message in (({**fixed, "f0_spread": math.inf}, r"fixed_joints\['f0_spread'\] must be a finite angle"),
                         ({**fixed, "f0_spread": "x"}, r"fixed_joints\['f0_spread'\] must be an angle"),
                         (list(fixed), "fixed_joints must map joint names to angles"),
                         ({**fixed, "f0_spread": 5.0},
                          r"joint 'f0_spread' held at 5 rad is outside its limits \[-0.3, 0.3\] rad")):
        with pytest.raises(ValueError, match=message):
            hugger.Hand.from_urdf(f, fixed_joints=bad)
    # On the command line: a joint held twice, or beyond its limits, in one line.
    holds = [a for p in ("f1", "f2", "thumb") for a in ("--fixed-joint", f"{p}_spread=0")]
    for extra, message in ((["--fixed-joint", "f0_spread=0", "--fixed-joint", "f0_spread=0.1"],
                            "--fixed-joint holds 'f0_spread' more than once"),
                           (["--fixed-joint", "f0_spread=5"], "joint 'f0_spread' held at 5 rad is outside its limits")):
        r = subprocess.run([sys.executable, "-m", "hugger", "plan", "sphere", "--hand", str(f), *holds, *extra,
                            "--out", str(tmp_path / "x.npz")], capture_output=True, text=True)
        assert r.returncode == 2 and message in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
    with pytest.raises(ValueError, match=r"fixed_joints \(--fixed-joint\): for a URDF or MJCF file only; the preset"):
        hugger.hands.load("barrett_bh8", fixed_joints={"f0_spread": 0.0})


def test_a_preset_or_json_hand_refuses_joints_and_a_palm_to_choose(tmp_path):
    f = tmp_path / "hand.json"
    f.write_text(hugger.Hand(fingers=3, links=2).to_json())
    for spec in ("barrett_bh8", str(f)):
        for kwargs, what in (({"fixed_joints": {"x": 0.0}}, r"fixed_joints \(--fixed-joint\)"),
                             ({"palm": "base"}, r"palm \(--palm-link\)"), ({"palm_link": "base"}, "palm_link")):
            with pytest.raises(ValueError, match=f"^{what}: for a URDF or MJCF file only"):
                hands.load(spec, **kwargs)
        for option in (["--fixed-joint", "x=0"], ["--palm-link", "base"]):
            r = subprocess.run([sys.executable, "-m", "hugger", "plan", "sphere", "--hand", spec, *option, "--out",
                                str(tmp_path / "x.npz")], capture_output=True, text=True)
            assert r.returncode == 2 and "for a URDF or MJCF file only" in r.stderr, r.stderr
            assert len(r.stderr.strip().splitlines()) == 1 and not (tmp_path / "x.npz").exists()
    r = subprocess.run([sys.executable, "-m", "hugger", "plan", "sphere", "--palm-link", "base", "--out",
                        str(tmp_path / "x.npz")], capture_output=True, text=True)
    assert r.returncode == 2 and "--palm-link needs --hand FILE" in r.stderr


def test_unknown_keys_are_refused_in_a_hand_file_and_ignored_in_a_trajectory_file(tmp_path):
    d = {**hugger.Hand(fingers=3, links=2).to_dict(), "maker": "another tool"}
    assert hugger.Hand.from_dict(d).same_as(hugger.Hand(fingers=3, links=2))  # a newer writer's key
    with pytest.raises(ValueError, match="unknown key 'maker'"):
        hugger.Hand.from_dict(d, strict=True)
    c = hugger.scenarios.default_case("sphere", hugger.Hand(fingers=3, links=2))
    path = tmp_path / "plan.npz"
    hugger.plan(c.hand, c.obj, c.target, c.palm_pose).save(path)
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    arrays["hand_json"] = np.array(json.dumps({**json.loads(str(arrays["hand_json"])), "maker": "another tool"}))
    np.savez(path, **arrays)
    assert hugger.Trajectory.load(path).hand["maker"] == "another tool"


def test_a_hand_mounted_below_a_world_link_takes_its_palm_by_name(tmp_path):
    pytest.importorskip("yourdfpy")
    hand = hands.preset("parallel_3link")
    path = _edited_urdf(tmp_path, '<link name="palm">',
                        '<link name="world"/><joint name="mount" type="fixed"><parent link="world"/>'
                        '<child link="palm"/><origin xyz="0 0 1"/></joint><link name="palm">')
    # the root link is the palm by default: the error says which, and how to name another
    with pytest.raises(ValueError, match=r"\(the palm is link 'world'; name another with palm_link= or --palm-link\)"):
        hands.load(path)
    assert hands.load(path, palm="palm").same_as(hand) and hands.from_urdf(path, palm_link="palm").same_as(hand)
    with pytest.raises(ValueError, match="palm and palm_link both name the palm"):
        hands.load(path, palm="palm", palm_link="palm")
    out = tmp_path / "x.npz"
    r = subprocess.run([sys.executable, "-m", "hugger", "plan", "sphere", "--hand", str(path), "--out", str(out)],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "--palm-link" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    r = subprocess.run([sys.executable, "-m", "hugger", "plan", "sphere", "--hand", str(path), "--palm-link", "palm",
                        "--out", str(out)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert hugger.Hand.from_dict(hugger.Trajectory.load(out).hand).same_as(hand)


def test_urdf_limits_in_degrees_and_mimic_joints_are_warned_of(tmp_path):
    pytest.importorskip("yourdfpy")
    path = _edited_urdf(tmp_path, 'lower="-0.3490658503988659" upper="1.7453292519943295"',
                        'lower="-20" upper="100"')
    with pytest.warns(UserWarning, match=r"joint 'f0_j0' has limits \[-20.0, 100.0\], beyond \+-2 pi as if in degrees"):
        assert not np.isfinite(hands.load(path).joint_limits[0, 0]).any()  # taken as no bound, as documented
    path = _edited_urdf(tmp_path, '<joint name="f1_j1" type="revolute">',
                        '<joint name="f1_j1" type="revolute"><mimic joint="f0_j1"/>')
    with pytest.warns(UserWarning, match="joint 'f1_j1' mimics 'f0_j1' in the file; the hand moves each joint on its own"):
        hands.load(path)


def test_cli_hands_export_urdf_and_plan_with_it(tmp_path):
    pytest.importorskip("yourdfpy")
    run = lambda *a: subprocess.run([sys.executable, "-m", "hugger", *a], capture_output=True, text=True)  # noqa: E731
    r = run("hands", "--json")
    assert r.returncode == 0
    names = [h["name"] for h in json.loads(r.stdout)]
    assert {"barrett_bh8", "robotiq_3f", "parallel_3link"} <= set(names)
    plan = tmp_path / "p.npz"
    assert run("plan", "sphere", "--hand", "parallel_3link", "--out", str(plan)).returncode == 0
    out = tmp_path / "hand.urdf"
    r = run("export-urdf", str(plan), "--out", str(out), "--json")
    assert r.returncode == 0, r.stderr
    values = json.loads(r.stdout)["joint_values"]
    traj = hugger.Trajectory.load(plan)
    assert np.allclose(list(values.values()), traj.angles[-1].ravel() - hands.preset("parallel_3link").rest_angles.ravel())
    plan2 = tmp_path / "p2.npz"
    assert run("plan", "sphere", "--hand", str(out), "--out", str(plan2)).returncode == 0
    assert np.array_equal(hugger.Trajectory.load(plan2).joints, traj.joints)
    r = run("plan", "sphere", "--hand", "nonesuch", "--out", str(plan2))
    assert r.returncode == 2 and "barrett_bh8" in r.stderr


def test_export_mjcf_of_a_general_layout_puts_every_joint_where_the_plan_has_it():
    mujoco = pytest.importorskip("mujoco")
    from hugger import physics

    hand = hands.preset("barrett_bh8")  # a root on the palm axis, links along the palm
    case = hugger.scenarios.default_case("sphere", hand)
    traj = hugger.Planner(hand, case.obj, case.target, case.palm_pose).plan()
    model = mujoco.MjModel.from_xml_string(physics.export_mjcf(traj, decompose=False))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    mujoco.mj_kinematics(model, data)
    for f in range(hand.fingers):
        for n in range(hand.links):
            body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f"f{f}_l{n}")
            assert np.allclose(data.xpos[body], traj.joints[-1, f, n], atol=1e-9)


def test_mjcf_with_a_non_planar_finger_names_the_joint(tmp_path):
    pytest.importorskip("mujoco")
    text = hands.to_mjcf(hands.preset("parallel_3link"))
    start = text.index('name="f0_j1"')
    axis = text.index('axis="', start)
    bad = text[:axis] + 'axis="0.0 0.3 1.0"' + text[text.index('"', axis + 6) + 1:]
    bad = bad[bad.index("-->") + 3:]  # without the embedded description: read from geometry
    f = tmp_path / "bad.xml"
    f.write_text(bad)
    with pytest.raises(ValueError, match="joint 'f0_j1' breaks planarity"):
        hugger.Hand.from_mjcf(f)


def test_mjcf_joint_held_beyond_its_range_is_refused(tmp_path):
    pytest.importorskip("mujoco")
    f = tmp_path / "hand.xml"
    f.write_text(hands.to_mjcf(hands.preset("parallel_3link")))
    with pytest.raises(ValueError, match=r"joint 'f0_j1' held at 10 rad is outside its limits"):
        hugger.Hand.from_mjcf(f, fixed_joints={"f0_j1": 10.0})


@pytest.mark.parametrize("bad", ["1 -1", "nan 1"])
def test_an_mjcf_range_lower_above_upper_is_warned_of_and_one_of_nans_refused(tmp_path, bad):
    # MuJoCo (autolimits) takes an inverted range for no limit at all, as limited="false" would
    pytest.importorskip("mujoco")
    import re

    text = re.sub(r"<!-- hugger-hand .*? -->", "", hands.to_mjcf(hands.preset("parallel_3link")), flags=re.S)
    old = 'range="-0.3490658503988659 1.7453292519943295" limited="true"'
    assert old in text
    f = tmp_path / "hand.xml"
    f.write_text(text.replace(old, f'range="{bad}"', 1))
    if bad == "1 -1":
        with pytest.warns(UserWarning, match=r"joint 'f0_j0' has range \[1, -1\] rad, lower above upper: MuJoCo takes "
                                             r"it for no limit, and so does the hand"):
            hand = hugger.Hand.from_mjcf(f)
        assert np.all(np.isinf(hand.joint_limits[0, 0])) and np.all(np.isfinite(hand.joint_limits[0, 1]))
    else:
        with pytest.raises(ValueError, match=r"joint 'f0_j0' has range \[nan, 1\]: not numbers"):
            hugger.Hand.from_mjcf(f)


def test_urdf_grasp_comment_gives_plain_joint_values():
    pytest.importorskip("yourdfpy")
    hand = hands.preset("barrett_bh8")
    angles = np.clip(hand.rest_angles + 0.05, hand.joint_limits[..., 0], hand.joint_limits[..., 1])
    text = hands.to_urdf(hand, angles)
    line = next(x for x in text.splitlines() if "grasp joint values" in x)
    pairs = dict(item.split("=") for item in line.split(":", 1)[1].replace("-->", "").split())
    assert {k: float(v) for k, v in pairs.items()} == hands.grasp_joint_values(hand, angles)
    for write in (hands.to_urdf, hands.to_mjcf):  # a grasp the hand cannot take is refused
        with pytest.raises(ValueError, match="angles must be finite"):
            write(hand, np.full(angles.shape, np.nan))
        with pytest.raises(ValueError, match=r"angles\[0, 0\] = 10 rad is outside that joint's limits"):
            write(hand, np.full(angles.shape, 10.0))


def test_robot_files_are_told_apart_by_their_root_element(tmp_path, capfd):
    """A URDF read as MJCF and the reverse, a file of neither kind or one that declares XML
    entities are refused in one line; so is a URDF that yourdfpy reads only with its lenient
    parser and then reads wrong (with the strict parser's complaint, not the part found missing),
    and nothing else is printed (yourdfpy logs that complaint). hands.load, and so ``--hand``,
    reads either kind by its root element, whatever the file's name; files the readers took
    before (a URDF with text after its root, an undeclared prefix, a truncated end tag) still load."""
    pytest.importorskip("yourdfpy")
    pytest.importorskip("mujoco")
    hand = hands.preset("barrett_bh8")
    urdf, mjcf = tmp_path / "hand.urdf", tmp_path / "hand.xml"
    urdf.write_text(hands.to_urdf(hand))
    mjcf.write_text(hands.to_mjcf(hand))

    def file(name: str, text: str) -> Path:
        f = tmp_path / name
        f.write_text(text)
        return f

    bad = file("bad.urdf", '<robot name="x"><link name="a"></robot')
    other = file("other.xml", "<sdf/>")
    entity = file("entity.urdf", '<?xml version="1.0"?><!DOCTYPE r [<!ENTITY a "aa">]><robot name="x">&a;</robot>')
    for read, f, match in ((hugger.Hand.from_urdf, bad, r"not well-formed XML \(expected '>'"),
                           (hugger.Hand.from_mjcf, file("bad.xml", "<mujoco><worldbody></mujoco"), "cannot read the MJCF"),
                           (hugger.Hand.from_mjcf, urdf, r"a URDF file \(<robot> at its root\), not MJCF"),
                           (hugger.Hand.from_urdf, mjcf, r"an MJCF file \(<mujoco> at its root\), not URDF"),
                           (hugger.Hand.from_urdf, other, "its root element is <sdf>, not <robot>"),
                           (hands.load, other, "neither URDF nor MJCF: its root element is <sdf>"),
                           (hands.load, entity, "declares the XML entity 'a'")):
        with pytest.raises(ValueError, match=match) as info:
            read(f)
        assert "\n" not in str(info.value)
    with pytest.raises(ValueError, match="is URDF, whose palm is chosen by palm_link, not palm_body"):
        hands.load(urdf, palm_body="palm")
    captured = capfd.readouterr()
    assert captured.out == "" and captured.err == ""
    text = urdf.read_text()
    for name, variant in (("urdf_named.xml", text), ("tail.urdf", text + "tail"),
                          ("prefix.urdf", text.replace("</robot>", '<xacro:property name="a" value="1"/></robot>')),
                          ("truncated.urdf", text.rstrip()[:-1])):
        assert hands.load(file(name, variant)).same_as(hand), name
    assert hands.load(mjcf).same_as(hand) and hands.load(file("hand.mjcf", mjcf.read_text())).same_as(hand)
    assert capfd.readouterr().err == ""
    r = subprocess.run([sys.executable, "-m", "hugger", "plan", "sphere", "--hand", str(bad), "--out",
                        str(tmp_path / "x.npz")], capture_output=True, text=True)
    assert r.returncode == 2 and r.stderr.startswith("hugger: error:") and "not well-formed XML" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1


def _edited_urdf(tmp_path: Path, old: str, new: str, count: int = 1) -> Path:
    """The parallel gripper's URDF without its embedded hand (so the file is read as written), with
    `old` replaced by `new` (`count` times)."""
    import re

    text = re.sub(r"<!-- hugger-hand .*? -->", "", hands.to_urdf(hands.preset("parallel_3link")), flags=re.S)
    assert text.count(old) >= count, old
    path = tmp_path / "edited.urdf"
    path.write_text(text.replace(old, new, count))
    return path


@pytest.mark.parametrize("old, new, message", [
    ('<link name="f0_l1">', '<link name="f0_l0">', "two links are called 'f0_l0'"),
    ('<parent link="palm"/><child link="f0_l0"/>', '<parent link="f0_l2"/><child link="f0_l0"/>',
     "the joints form a cycle through link"),
    ('<parent link="palm"/><child link="f0_l0"/>', '<parent link="ghost"/><child link="f0_l0"/>',
     "joint 'f0_j0' names parent link 'ghost', which the file does not have"),
    ('lower="-0.3490658503988659" upper="1.7453292519943295"', 'lower="1.0" upper="-1.0"',
     "joint 'f0_j0' has limits lower = 1.0 > upper = -1.0"),
    ('<axis xyz="0.0 -1.0 0.0"/>', '<axis xyz="0 0 0"/>', r"joint 'f0_j0' has axis \[0.0, 0.0, 0.0\]: not a direction"),
])
def test_a_urdf_that_is_no_tree_or_has_inverted_limits_is_refused(tmp_path, old, new, message):
    path = _edited_urdf(tmp_path, old, new)
    with pytest.raises(ValueError, match=message):
        hands.load(path)


LIMITS = 'lower="-0.3490658503988659" upper="1.7453292519943295"'


@pytest.mark.parametrize("old, new, message", [
    # these were taken for a joint without limits, silently; URDF requires both (0 by default)
    ('<limit effort="10.0" velocity="2.0" ' + LIMITS + '/>', "", "revolute joint 'f0_j0' has no <limit>, which URDF"),
    (LIMITS, "", "revolute joint 'f0_j0' has a <limit> with neither lower nor upper: by URDF's defaults"),
    (LIMITS, 'lower="nan" upper="1.6"', r"joint 'f0_j0' has limits \[nan, 1.6\]: not numbers"),
    # these overflowed, or named the wrong joint or none
    ('<origin xyz="0.0 0.0 0.03"', '<origin xyz="0.0 0.0 1e300"', r"joint 'f0_j1' has origin xyz .*: not a finite"),
    ('<origin xyz="0.0 0.0 0.03"', '<origin xyz="nan 0.0 0.03"', r"joint 'f0_j1' has origin xyz \[nan"),
    ('<origin xyz="0.0 0.0 0.03" rpy="0.0 -0.0 0.0"', '<origin xyz="0.0 0.0 0.03" rpy="nan 0 0"',
     "joint 'f0_j1' has an origin rpy that is not finite"),
])
def test_a_urdf_joint_without_limits_or_at_no_finite_place_is_named(tmp_path, old, new, message):
    path = _edited_urdf(tmp_path, old, new)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # and no numpy overflow on the way
        with pytest.raises(ValueError, match=message) as info:
            hands.load(path)
    assert "\n" not in str(info.value)


def test_a_urdf_limit_side_left_out_is_zero_as_urdf_says(tmp_path):
    with_upper = hands.load(_edited_urdf(tmp_path, LIMITS, 'upper="1.5"'))
    assert with_upper.joint_limits[0, 0].tolist() == [0.0, 1.5]
    with_lower = hands.load(_edited_urdf(tmp_path, LIMITS, 'lower="-0.2"'))
    assert with_lower.joint_limits[0, 0].tolist() == [-0.2, 0.0]


def test_a_prismatic_joint_held_by_fixed_joints_moves_what_it_carries(tmp_path):
    # it was placed as if at 0, whatever value it was held at
    slide = ('<link name="slider"/><joint name="slide" type="prismatic"><parent link="palm"/><child link="slider"/>'
             '<axis xyz="1 0 0"/><limit effort="1" velocity="1" lower="0" upper="0.01"/></joint></robot>')
    text = _edited_urdf(tmp_path, "</robot>", slide).read_text()
    path = tmp_path / "slide.urdf"
    path.write_text(text.replace('<parent link="palm"/><child link="f0_l0"/>', '<parent link="slider"/><child link="f0_l0"/>'))
    at = {x: hands.load(path, fixed_joints={"slide": x}) for x in (0.0, 0.004)}
    moved = at[0.004].finger_roots - at[0.0].finger_roots  # (f0 comes after the palm's own fingers)
    assert sorted(np.round(moved[:, 0], 12).tolist()) == [0.0] * (len(moved) - 1) + [0.004]
    assert np.allclose(moved[:, 1:], 0.0, atol=1e-12)


def test_infinite_urdf_limits_are_no_bound_without_a_warning(tmp_path):
    path = _edited_urdf(tmp_path, LIMITS, 'lower="-inf" upper="inf"')
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # not "beyond +-2 pi as if in degrees"
        assert not np.isfinite(hands.load(path).joint_limits[0, 0]).any()


@pytest.mark.parametrize("angle", ["0.1", True, None, [0.1]])
def test_fixed_joints_take_numbers_only(tmp_path, angle):
    f = thumb_urdf(tmp_path / "thumb.urdf")
    with pytest.raises(ValueError, match=r"fixed_joints\['f0_spread'\] must be an angle"):
        hugger.Hand.from_urdf(f, fixed_joints={"f0_spread": angle})


def test_a_urdf_without_finger_cylinders_warns_and_takes_a_given_radius(tmp_path):
    import re

    # every finger link's collision a box instead of a cylinder (the palm keeps its own)
    path = _edited_urdf(tmp_path, "<robot", "<robot")
    path.write_text(re.sub(r'<cylinder radius="0.006" length="[0-9.e-]+"/>', '<box size="0.01 0.01 0.01"/>',
                           path.read_text()))
    with pytest.warns(UserWarning, match="no collision cylinder or capsule on the finger links"):
        assert hands.load(path).link_radius == 0.0
    assert hands.load(path, link_radius=0.005).link_radius == 0.005
    r = subprocess.run([sys.executable, "-m", "hugger", "plan", "sphere", "--hand", str(path), "--link-radius", "0.005",
                        "--out", str(tmp_path / "x.npz"), "--json"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert hugger.Trajectory.load(tmp_path / "x.npz").hand["link_radius"] == 0.005
    r = subprocess.run([sys.executable, "-m", "hugger", "plan", "sphere", "--hand", "barrett_bh8", "--link-radius",
                        "0.005", "--out", str(tmp_path / "y.npz")], capture_output=True, text=True)
    assert r.returncode == 2 and "cannot be combined" in r.stderr


@pytest.mark.parametrize("export", [hands.to_urdf, hands.to_mjcf])
def test_the_exporters_take_a_hand_only(export):
    with pytest.raises(ValueError, match="hand must be a hugger.Hand, got str"):
        export("x")


@pytest.mark.parametrize("text, match", [("[" * 100000 + "]" * 100000, "not readable JSON"),
                                         ("{not json", "not readable JSON"),
                                         ("[1, 2]", "a hand description must be a dict"),
                                         ('{"fingers": 3, "links": 2, "link_lengths": 0.02, "link_radius": 0.004, '
                                          '"palm_radius": 0.03, "palm_thickness": 0.01, "rest_angle": 0.1}',
                                          "unknown key 'rest_angle' \\(did you mean 'rest_angles'\\?\\)"),
                                         ('{"fingers": 3, "links": 2, "link_lengths": NaN, "link_radius": 0.004, '
                                          '"palm_radius": 0.03, "palm_thickness": 0.01}', r"hand\.json'?: link_length")])
def test_a_hand_file_that_is_no_hand_json_is_a_one_line_error(tmp_path, text, match):
    f = tmp_path / "hand.json"
    f.write_text(text)
    with pytest.raises(ValueError, match=match):
        hands.load(str(f))
    r = subprocess.run([sys.executable, "-m", "hugger", "plan", "sphere", "--hand", str(f), "--out",
                        str(tmp_path / "x.npz")], capture_output=True, text=True)
    assert r.returncode == 2 and r.stderr.startswith("hugger: error:") and len(r.stderr.strip().splitlines()) == 1



def test_exported_joint_values_lie_within_the_exported_limits_exactly():
    # an angle the planner left 1e-13 beyond a limit (its slack) was exported as q = -1.1e-16
    # below a lower limit of 0, which a strict controller may refuse
    import re

    pytest.importorskip("yourdfpy")
    hand = hands.preset("barrett_bh8")
    angles = np.clip(np.zeros((hand.fingers, hand.links)), hand.joint_limits[..., 0], hand.joint_limits[..., 1])
    angles[0, 1] = hand.joint_limits[0, 1, 0] - 1e-13
    angles[1, 0] = hand.joint_limits[1, 0, 1] + 1e-13
    q = hands.grasp_joint_values(hand, angles)
    text = hands.to_urdf(hand, angles)
    for name in ("f0_j1", "f1_j0"):
        lo, hi = (float(x) for x in re.search(rf'<joint name="{name}".*?lower="([^"]+)" upper="([^"]+)"', text,
                                               re.S).groups())
        assert lo <= q[name] <= hi, (name, lo, q[name], hi)
    assert q["f0_j1"] == hand.joint_limits[0, 1, 0] - hand.rest_angles[0, 1]


def test_exported_joint_values_of_a_joint_limited_on_one_side_lie_within_its_exported_range():
    # a side without a limit is written at +-pi (where joint angles end); an angle beyond it was
    # exported outside the range the same file gives the joint
    import re

    pytest.importorskip("yourdfpy")
    hand = hugger.Hand.from_layout(roots=[[0.02, 0, 0], [-0.02, 0, 0]], directions=[[1, 0, 0], [-1, 0, 0]],
                                   link_lengths=[[0.03, 0.03], [0.03, 0.03]],
                                   limits=[[[-np.inf, 1.0], [0.0, 1.5]], [[-0.5, 0.5], [0.0, 1.5]]])
    angles = np.zeros((2, 2))
    angles[0, 0] = -3.5  # beyond -pi, on the side without a limit
    with pytest.raises(ValueError, match=r"angles\[0, 0\] = -3\.5 rad is outside \[-3\.14159, 1\].*\[-pi, pi\]"):
        hands.grasp_joint_values(hand, angles)
    with pytest.raises(ValueError, match=r"outside \[-3\.14159, 1\]"):
        hands.to_mjcf(hand, angles)
    angles[0, 0] = -np.pi
    q = hands.grasp_joint_values(hand, angles)
    lo, hi = (float(x) for x in re.search(r'<joint name="f0_j0".*?lower="([^"]+)" upper="([^"]+)"',
                                           hands.to_urdf(hand, angles), re.S).groups())
    assert lo <= q["f0_j0"] <= hi and lo == -np.pi
    # a joint without limits (written continuous): the same [-pi, pi], said so
    free = hugger.Hand.from_layout(roots=[[0.02, 0, 0]], directions=[[1, 0, 0]], link_lengths=[[0.03]])
    with pytest.raises(ValueError, match=r"outside \[-pi, pi\], where joint angles lie \(that joint has no limits\)"):
        hands.grasp_joint_values(free, [[4.0]])
