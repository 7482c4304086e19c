"""hugger.search and 'hugger plan --approaches': directions, ranking, determinism, the CLI."""
from __future__ import annotations

import json
import pickle
from dataclasses import replace

import numpy as np
import pytest

import hugger
from hugger.search import Candidate, approach_directions, rank


def test_directions_are_unit_spread_and_start_at_the_pole():
    for k in (1, 2, 6, 26, 100):
        d = approach_directions(k, pole=(1.0, 2.0, 2.0))
        assert d.shape == (k, 3)
        assert np.allclose(np.linalg.norm(d, axis=1), 1.0)
        assert np.allclose(d[0], np.array([1.0, 2.0, 2.0]) / 3.0)
        if k >= 6:
            # evenly spread: the mean is near the centre, every direction has a near neighbour,
            # and no two coincide
            cos = d @ d.T - 2 * np.eye(k)
            assert np.linalg.norm(d.mean(axis=0)) < 0.15
            nearest = np.arccos(np.clip(cos.max(axis=1), -1, 1))
            assert nearest.max() < 3.0 * np.sqrt(4 * np.pi / k)
            assert nearest.min() > 0.3 * np.sqrt(4 * np.pi / k)
    assert np.array_equal(approach_directions(26), approach_directions(26))
    for bad in (0, -1, 2.5, True):
        with pytest.raises(ValueError, match="approaches"):
            approach_directions(bad)
    for pole in ((0, 1), "up", (1e300, 1e300, 0), (0, 0, 0), (np.nan, 0, 1)):  # one sentence, no warning
        with pytest.raises(ValueError, match="pole must be a finite non-zero 3-vector"):
            approach_directions(3, pole)


def _cand(i, hug, closure=None, eps=None, status="done"):
    return Candidate(index=i, direction=np.zeros(3), status=status, links_in_contact=hug)


def test_rank_finds_the_escape_only_where_it_decides():
    cands = [_cand(0, 5), _cand(1, 9), _cand(2, 9), _cand(3, 3), _cand(4, 12, status="error")]
    truth = {0: (True, 0.5), 1: (True, 0.1), 2: (True, 0.45), 3: (False, 0.9)}
    slides = {0: 0.05, 1: 0.0, 2: 0.002, 3: 0.0}
    judged, escaped = [], []

    def judge(c):
        judged.append(c.index)
        fc, eps = truth[c.index]
        return replace(c, force_closure=fc, epsilon=eps, contacts=4)

    def escape(c):
        escaped.append(c.index)
        return replace(c, escape=slides[c.index])

    best, out = rank(cands, judge, escape=escape)
    # firmness: 0.5 - 0.2 (slides the whole reach) < 0.45 - 0.008: candidate 2 cages the object
    assert best == 2 and out[2].firmness == pytest.approx(0.45 - 0.2 * 0.002 / 0.05)
    assert sorted(judged) == [0, 1, 2, 3]  # every plan's contacts and epsilon
    assert escaped == [0, 2]  # candidate 1's epsilon (0.1) cannot reach 0.442; 3 lacks closure
    assert out[1].escape is None and out[1].firmness is None and out[0].escape == 0.05
    # without an escape, epsilon alone ranks
    best, _ = rank(cands, judge)
    assert best == 0
    # without force closure anywhere, firmness ranks them all
    truth.update({0: (False, 0.5), 1: (False, 0.1), 2: (False, 0.45)})
    escaped.clear()
    best, _ = rank(cands, judge, escape=escape)
    assert best == 3 and escaped == [3]  # 0.9 - 0 beats every other epsilon
    # a custom score judges everything that planned
    judged.clear()
    escaped.clear()
    best, out = rank(cands, judge, score=lambda c: c.epsilon - c.escape, escape=escape)
    assert best == 3 and sorted(judged) == [0, 1, 2, 3] and sorted(escaped) == [0, 1, 2, 3]
    assert out[3].score == 0.9
    with pytest.raises(ValueError, match="no approach"):
        rank([_cand(0, 1, status="error")], judge)


def test_escape_distance_of_a_palm_resting_on_a_ball(hand):
    from hugger import analysis

    ball = hugger.objects.sphere(0.03)
    pose = hugger.look_at([0.0, 0.0, 0.03 + 1e-4], [0.0, 0.0, 0.0])  # the palm on top, facing down
    far = np.zeros((hand.fingers, hand.links + 1, 3)) + [1.0, 0.0, 0.0]
    far[:, :, 1] = np.arange(hand.links + 1) * 0.01  # fingers a metre away
    d = analysis.escape_distance(hand, ball, pose, far)
    dirs = hugger.approach_directions(26)
    # the ball is blocked (at once) where it moves up into the palm, and slides free downward
    up, down = dirs[:, 2] > 0.2, dirs[:, 2] < 0.0
    assert up.any() and down.any()
    assert np.all(d[up] <= 0.004) and np.all(np.isinf(d[down]))
    # the palm a metre away: free everywhere; a finer reach and step are honoured
    away = pose.copy()
    away[:3, 3] += [0.0, 1.0, 0.0]
    assert np.all(np.isinf(analysis.escape_distance(hand, ball, away, far, reach=0.01, step=0.005)))
    d2 = analysis.escape_distance(hand, ball, pose, far, step=0.001)
    assert np.all(d2[up] <= 0.002)
    with pytest.raises(ValueError, match="step"):
        analysis.escape_distance(hand, ball, pose, far, step=0.0)
    with pytest.raises(ValueError, match="samples"):
        analysis.escape_distance(hand, ball, pose, far, step=1e-9)
    with pytest.raises(ValueError, match="directions"):
        analysis.escape_distance(hand, ball, pose, far, directions=0)
    # the last sample is the reach itself, also when the reach is not a multiple of the step
    far_palm = pose.copy()
    far_palm[:3, 3] += [0.0, 0.0, 0.0095]  # 9.5 mm above the ball: blocked only by the reach's sample
    d3 = analysis.escape_distance(hand, ball, far_palm, far, reach=0.0097, step=0.004)
    assert d3[0] == 0.0097 and np.all(np.isinf(d3[down]))
    with pytest.raises(ValueError, match="joints"):
        analysis.escape_distance(hand, ball, pose, far[:2])


def test_escape_distance_with_links_of_radius_zero():
    """A link of radius 0 blocks the slide as soon as its axis crosses the surface."""
    from hugger import analysis

    thin = hugger.Hand(fingers=3, links=2, link_radius=0.0)
    ball = hugger.objects.sphere(0.03)
    pose = hugger.look_at([0.0, 0.5, 0.0], [0.0, 0.0, 0.0])  # the palm far away
    joints = np.zeros((3, 3, 3)) + [0.0, 0.5, 0.0]
    joints[0] = [[-0.03, 0.0, 0.0301], [0.0, 0.0, 0.0301], [0.03, 0.0, 0.0301]]  # a bar resting on top
    d = analysis.escape_distance(thin, ball, pose, joints)
    up = hugger.approach_directions(26)[:, 2] > 0.2
    assert np.all(d[up] <= 0.004) and np.isinf(d).any()
    assert analysis.escape(thin, ball, pose, joints) == analysis.ESCAPE_REACH


def test_a_hugging_grasp_cages_its_object(hand):
    from hugger import analysis

    case = hugger.scenarios.default_case("sphere", hand)
    traj = hugger.Planner(hand, case.obj, case.target, case.palm_pose).plan()
    d = analysis.escape_distance(hand, case.obj, traj.palm_pose[-1], traj.joints[-1])
    assert np.all(d <= 0.02)  # wrapped: no direction lets the ball out


def test_search_is_deterministic_and_single_approach_is_the_default_plan(hand):
    case = hugger.scenarios.default_case("box", hand)
    one = hugger.search(hand, case.obj, case.target, approaches=1)
    default = hugger.Planner(hand, case.obj, case.target, case.palm_pose).plan()
    assert np.array_equal(one.trajectory.joints, default.joints)
    a = hugger.search(hand, case.obj, case.target, approaches=8, threads=1, keep_all=True)
    b = hugger.search(hand, case.obj, case.target, approaches=8, threads=3)
    assert a.best == b.best
    assert np.array_equal(a.trajectory.joints, b.trajectory.joints)
    assert [c.to_dict() | {"plan_time_s": 0} for c in a.candidates] == \
           [c.to_dict() | {"plan_time_s": 0} for c in b.candidates]
    chosen = a.chosen
    assert chosen.force_closure is not None
    # the chosen one is best by the documented key: (force closure, firmness); firmness <= epsilon
    # bounds the candidates whose escape was not needed
    assert chosen.firmness is not None
    for c in a.candidates:
        if not c.ok:
            continue
        bound = c.firmness if c.firmness is not None else c.epsilon
        assert (bool(c.force_closure), bound) <= (bool(chosen.force_closure), chosen.firmness)
    assert len(a.trajectories) == 8 and a.trajectories[a.best] is a.trajectory
    assert a.directions.shape == (8, 3)


def test_search_passes_rules_only_when_given(hand, monkeypatch):
    seen = []
    import hugger.planner as P

    original = P.Planner.__init__

    def spy(self, *args, **kwargs):
        seen.append(kwargs.get("rules", "absent"))
        original(self, *args, **{k: v for k, v in kwargs.items() if k != "rules"})

    monkeypatch.setattr(P.Planner, "__init__", spy)
    case = hugger.scenarios.default_case("box", hand)
    hugger.search(hand, case.obj, case.target, approaches=2, threads=1)
    hugger.search(hand, case.obj, case.target, approaches=2, threads=1, rules="paper")
    assert seen == ["absent", "absent", "paper", "paper"]


def test_search_rejects_bad_input(hand):
    obj = hugger.objects.get("box")
    with pytest.raises(ValueError, match="inside"):
        hugger.search(hand, obj, target=[1.0, 0, 0], approaches=2)
    with pytest.raises(ValueError, match="parameters"):
        hugger.search(hand, obj, approaches=2, bogus=1)
    with pytest.raises(ValueError, match="threads"):
        hugger.search(hand, obj, approaches=2, threads=0)
    with pytest.raises(ValueError, match="hand"):
        hugger.search("hand", obj)
    with pytest.raises(ValueError, match="keep_all must be True or False"):
        hugger.search(hand, obj, approaches=2, keep_all="no")
    # The planner's settings and the callback are checked once, before any approach is planned.
    for kwargs, message in (({"step": -1.0}, "step must be a positive finite number"), ({"rules": "x"}, "rules must be"),
                            ({"skin": "x"}, "skin must be one of"), ({"progress": 5}, "progress must be callable"),
                            ({"step": 0.5}, r"step \(0.5 m\) must not exceed the shortest link"),  # (the hand's)
                            ({"workers": 2}, "workers runs the simulations of robust=True in parallel")):
        with pytest.raises(ValueError, match=message) as info:
            hugger.search(hand, obj, approaches=2, **kwargs)
        assert "no approach could be planned" not in str(info.value)
    for answer in ("x", None, float("nan")):  # the scorer's mistake, named as such
        with pytest.raises(ValueError, match="score must return a finite number"):
            hugger.search(hand, obj, approaches=2, score=lambda c, a=answer: a)


def test_cli_plan_approaches(tmp_path, capsys, checker):
    from hugger.cli import main

    from helpers import assert_checked

    out = tmp_path / "p.npz"
    assert main(["plan", "box", "--approaches", "6", "--threads", "2", "--out", str(out), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    s = report["search"]
    assert s["approaches"] == 6 and len(s["candidates"]) == 6 and 0 <= s["best"] < 6
    assert report["links_in_contact"] == s["candidates"][s["best"]]["links_in_contact"]
    assert_checked(checker, out)
    assert main(["plan", "box", "--approaches", "3", "--turn", "10", "--out", str(out)]) == 2
    assert "--approaches" in capsys.readouterr().err


def test_verify_chooses_the_first_ranked_grasp_that_holds(hand, monkeypatch):
    pytest.importorskip("mujoco")
    from hugger import physics

    case = hugger.scenarios.default_case("box", hand)
    plain = hugger.search(hand, case.obj, case.target, approaches=6, threads=1)
    verdicts = []

    def fake(traj, *args, **kwargs):  # the first two checked lose, the third holds
        verdicts.append(len(traj))
        return {"held": len(verdicts) == 3}

    monkeypatch.setattr(physics, "validate", fake)
    v = hugger.search(hand, case.obj, case.target, approaches=6, threads=1, verify=5)
    assert len(verdicts) == 3
    assert all(c.epsilon is not None for c in v.candidates if c.ok)  # every candidate judged
    checked = [c for c in v.candidates if c.held is not None]
    assert len(checked) == 3 and v.chosen.held is True and sum(c.held for c in checked) == 1
    assert plain.chosen.index in [c.index for c in checked]  # the ranking's best was checked first
    verdicts.clear()
    monkeypatch.setattr(physics, "validate", lambda traj, *a, **k: {"held": False})
    none = hugger.search(hand, case.obj, case.target, approaches=6, threads=1, verify=2)
    assert none.best == plain.best  # nothing held: the ranking's choice stands
    with pytest.raises(ValueError, match="verify"):
        hugger.search(hand, case.obj, case.target, approaches=2, verify=-1)


def _ranking_order(hand, case, monkeypatch, approaches=6):
    """The ranking's order of every working candidate: a verify run in which nothing holds checks them all."""
    from hugger import physics

    monkeypatch.setattr(physics, "validate", lambda traj, *a, **k: {"held": False})
    lost = hugger.search(hand, case.obj, case.target, approaches=approaches, threads=1, verify=approaches)
    return lost, list(lost.verified)


def test_robust_verify_keeps_the_first_robust_grasp_or_the_largest_held_fraction(hand, monkeypatch):
    pytest.importorskip("mujoco")
    from hugger import physics

    case = hugger.scenarios.default_case("box", hand)
    plain, order = _ranking_order(hand, case, monkeypatch)
    assert order[0] == plain.best and len(order) >= 4
    start = {c.index: c.start_pose for c in plain.candidates}

    def index_of(traj):
        return min(start, key=lambda i: np.abs(traj.palm_pose[0] - start[i]).max())

    # by ranking position: 0 lost at nominal settings, 1 loses one perturbation, 2 loses two, 3 robust
    losses = {order[0]: {"nominal"}, order[1]: {"mu=0.5"}, order[2]: {"mu=1.0", "kp-20%"}, order[3]: set()}
    calls = []

    def fake(traj, k=-1, **kwargs):
        i = index_of(traj)
        name = next((n for n, v in physics.PERTURBATIONS.items() if v and all(kwargs.get(a) == b for a, b in v.items())),
                    "nominal")
        calls.append((i, name))
        return {"held": name not in losses.get(i, set())}

    monkeypatch.setattr(physics, "validate", fake)
    seen = []
    r = hugger.search(hand, case.obj, case.target, approaches=6, threads=1, verify=5, robust=True, workers=1,
                      progress=lambda d, t: seen.append((d, t)))
    assert r.best == order[3] and r.verified == tuple(order[:4]) and r.chosen.robust is True
    assert [i for i, _ in calls].count(order[0]) == 1  # lost at nominal: no perturbation run
    assert len(calls) == 1 + 3 * 9 and not any(i == order[4] for i, _ in calls)  # stopped at the robust one
    got = {c.index: (c.held, c.robust, c.held_fraction) for c in r.candidates}
    assert got[order[0]] == (False, False, None)
    assert got[order[1]] == (True, False, pytest.approx(8 / 9))
    assert got[order[2]] == (True, False, pytest.approx(7 / 9))
    assert got[order[3]] == (True, True, 1.0)
    assert all(got[i] == (None, None, None) for i in order[4:])
    assert seen[-1][0] == seen[-1][1] == 6 + len(calls)  # plans, then every simulation run
    assert seen[6] == (6, 6 + 5 * len(physics.PERTURBATIONS))  # after the plans, at once: the simulations to come (at most)
    assert [d for d, _ in seen] == sorted(d for d, _ in seen)
    d = r.chosen.to_dict()
    assert d["robust"] is True and d["held_fraction"] == 1.0

    calls.clear()  # none robust among the three checked: the largest held fraction wins
    r3 = hugger.search(hand, case.obj, case.target, approaches=6, threads=1, verify=3, robust=True, workers=1)
    assert r3.best == order[1] and r3.verified == tuple(order[:3]) and r3.chosen.robust is False
    losses[order[1]] = {"nominal"}  # nothing held at all: the ranking's best stays
    r2 = hugger.search(hand, case.obj, case.target, approaches=6, threads=1, verify=2, robust=True, workers=1)
    assert r2.best == order[0] and all(not r2.candidates[i].held for i in r2.verified)
    with pytest.raises(ValueError, match="verify"):
        hugger.search(hand, case.obj, case.target, approaches=2, robust=True)
    with pytest.raises(ValueError, match="workers"):
        hugger.search(hand, case.obj, case.target, approaches=2, verify=1, robust=True, workers=0)


@pytest.mark.slow
def test_robust_verify_on_a_sphere_matches_validate_robust(hand):
    """27 simulations (about 30 s on a loaded machine): real physics, one process and two."""
    pytest.importorskip("mujoco")
    from hugger import physics

    case = hugger.scenarios.default_case("sphere", hand)
    r = hugger.search(hand, case.obj, case.target, approaches=2, threads=1, verify=1, robust=True, workers=1)
    assert r.verified == (r.best,)
    full = physics.validate_robust(r.trajectory, workers=2, bisect_steps=0, max_factor=10.0)
    assert (r.chosen.held, r.chosen.robust, r.chosen.held_fraction) == (full["held"], full["robust"],
                                                                        full["held_fraction"])
    assert r.chosen.robust  # the sphere's grasp is robustly held (docs/generation.md)
    pickle.dumps(r.trajectory)  # the check cached no compiled object on it: it can go to a process pool
    r2 = hugger.search(hand, case.obj, case.target, approaches=2, threads=2, verify=1, robust=True, workers=2)
    def figures(res):
        return [(c.status, c.hug, c.epsilon, c.held, c.robust, c.held_fraction) for c in res.candidates]

    assert r2.best == r.best and r2.verified == r.verified and figures(r2) == figures(r)


def test_cli_plan_robust_verify(tmp_path, capsys, monkeypatch):
    pytest.importorskip("mujoco")
    from hugger import physics
    from hugger.cli import main

    monkeypatch.setattr(physics, "validate", lambda traj, *a, **k: {"held": k.get("mu") != 0.5})
    out = tmp_path / "p.npz"
    assert main(["plan", "box", "--approaches", "3", "--threads", "1", "--verify", "2", "--robust-verify",
                 "--workers", "1", "--out", str(out), "--json"]) == 0
    s = json.loads(capsys.readouterr().out)["search"]
    checked = [s["candidates"][i] for i in s["verified"]]
    assert len(checked) == 2 and all(c["held"] and c["robust"] is False for c in checked)
    assert checked[0]["held_fraction"] == pytest.approx(8 / 9) and s["best"] == s["verified"][0]
    # the table says what the simulations made of the grasp chosen, and that none was robust
    assert main(["plan", "box", "--approaches", "3", "--threads", "1", "--verify", "2", "--robust-verify",
                 "--workers", "1", "--out", str(out)]) == 0
    out_text, err = capsys.readouterr()
    rows = dict(line.split(None, 1) for line in out_text.splitlines() if line.strip())
    assert rows["verified"] == "2" and rows["chosen_held"] == "True" and rows["chosen_robust"] == "False"
    assert "none of the 2 grasps verified was robustly held in simulation: kept the held one holding under the most " \
           "perturbations" in err
    monkeypatch.setattr(physics, "validate", lambda traj, *a, **k: {"held": True})
    assert main(["plan", "box", "--approaches", "3", "--threads", "1", "--verify", "2", "--out", str(out)]) == 0
    out_text, err = capsys.readouterr()
    assert "chosen_held            True" in out_text and "none of" not in err and "chosen_robust" not in out_text
    assert main(["plan", "box", "--approaches", "3", "--robust-verify", "--out", str(out)]) == 2
    assert "--verify" in capsys.readouterr().err
