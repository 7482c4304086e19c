"""Approach search: plan from many directions around T and keep the firmest grasp.

``hugger.search(hand, obj)`` spreads ``approaches`` directions evenly over the sphere around the
target T (:func:`approach_directions`, deterministic), starts the hand on each at the safe
distance facing T (:func:`hugger.scenarios.start_pose`), plans them all in parallel threads (the
engine releases the GIL) and ranks the final grasps (:func:`rank`). The result holds the best
trajectory and every candidate's figures.

The ranking (the default score) is lexicographic:

1. the plan ended without an error (``done``, ``stalled``, ``max_iterations``, ``timeout`` all count);
2. force closure of the grasp over all its contacts (:func:`hugger.analysis.grasp_quality`);
3. *firmness* = epsilon - ``ESCAPE_WEIGHT`` x escape / ``ESCAPE_REACH``: the Ferrari-Canny epsilon
   (mu = 0.5) less a penalty for the largest distance *escape* the object can slide away from the
   fixed hand in any of 26 directions (:func:`hugger.analysis.escape_distance`, up to 5 cm, the
   hold test's limit): a grasp that cages the object holds when friction or squeeze falls short;
4. the lowest candidate index.

Contacts, force closure and epsilon (about 20 ms together) are computed for every candidate that
planned, in the planning threads; the escape (a few ms to a few tens of ms) only where it can decide: candidates are
visited by decreasing (force closure, epsilon), and as firmness is at most epsilon, once the best
so far beats the next one's epsilon the rest cannot win (their ``escape`` stays ``None``).

A custom ``score(candidate) -> float`` (larger is better) judges every candidate fully and ranks
by it (ties: lowest index).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from typing import Any, Callable, Sequence, cast

import numpy as np

from . import _checks, _stable
from ._types import CONTACT_DISTANCE
from .analysis import ESCAPE_REACH
from .hand import Hand
from .trajectory import Trajectory
from .world import Object

__all__ = ["Candidate", "SearchResult", "approach_directions", "rank", "search"]

#: Friction coefficient of the epsilon used for ranking (as :func:`hugger.analysis.analyze`).
RANK_MU = 0.5
#: Firmness = epsilon - ESCAPE_WEIGHT x escape / ESCAPE_REACH (docs/generation.md#the-score).
ESCAPE_WEIGHT = 0.2
_GOLDEN_ANGLE = math.pi * (3.0 - math.sqrt(5.0))
_FAILED = ("error",)


@dataclass(frozen=True)
class Candidate:
    """One approach: where the hand started and the grasp it ended in."""

    index: int  #: position in the search's direction list
    direction: np.ndarray  #: (3,) unit vector from T toward the start palm centre
    status: str  #: the plan's status, or ``error`` when planning raised
    start_pose: np.ndarray | None = None  #: (4, 4) the palm pose the plan was started from
    configurations: int = 0  #: length of the plan
    plan_time_s: float = 0.0  #: wall time of this plan (s), setup included
    links_in_contact: int = 0  #: links within 1 mm of the object at the end
    palm_contact: bool = False  #: the palm within 1 mm of the object at the end
    contacts: int | None = None  #: contact points (None: not judged, see the module docstring)
    force_closure: bool | None = None  #: force closure over all contacts (None: not judged)
    epsilon: float | None = None  #: Ferrari-Canny epsilon, mu = 0.5 (None: not judged)
    #: the largest distance (m) the object slides freely from the fixed hand, at most ESCAPE_REACH
    #: (None: not judged, see the module docstring)
    escape: float | None = None
    score: float | None = None  #: the custom score, when one was given
    held: bool | None = None  #: the six-direction physics verdict, when ``verify`` checked it
    robust: bool | None = None  #: held under every perturbation, when ``verify`` with ``robust`` checked it
    held_fraction: float | None = None  #: fraction of the perturbations held (None: not measured)
    error: str | None = None  #: the exception message when planning failed

    @property
    def hug(self) -> int:
        """Links in contact + 2 for the palm: how much of the hand touches (not ranked on)."""
        return int(self.links_in_contact) + (2 if self.palm_contact else 0)

    @property
    def ok(self) -> bool:
        return self.status not in _FAILED

    @property
    def firmness(self) -> float | None:
        """epsilon - ESCAPE_WEIGHT x escape / ESCAPE_REACH: the ranking's figure (None: not judged)."""
        if self.epsilon is None or self.escape is None:
            return None
        return firmness(self.epsilon, self.escape)

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON types."""
        return {"index": self.index, "direction": [float(x) for x in self.direction], "status": self.status,
                "configurations": self.configurations, "plan_time_s": self.plan_time_s,
                "links_in_contact": self.links_in_contact, "palm_contact": self.palm_contact, "hug": self.hug,
                "contacts": self.contacts, "force_closure": self.force_closure, "epsilon": self.epsilon,
                "escape": self.escape, "firmness": self.firmness, "score": self.score, "held": self.held, "robust": self.robust,
                "held_fraction": self.held_fraction, "error": self.error}


@dataclass(frozen=True, eq=False)
class SearchResult:
    """The outcome of :func:`search`."""

    best: int  #: index of the chosen candidate
    trajectory: Trajectory  #: its plan
    candidates: tuple[Candidate, ...]  #: every approach, in direction order
    target: np.ndarray  #: T (3,)
    time_s: float  #: wall time of the whole search (s): planning and ranking
    trajectories: tuple[Trajectory | None, ...] | None = field(default=None, repr=False)
    #: every candidate's plan (None where planning failed) when ``keep_all``; else None
    contacts: tuple[Any, ...] | None = field(default=None, repr=False)
    #: every candidate's final contacts (:class:`hugger.analysis.Contacts`, those its force
    #: closure and epsilon were computed from; None where planning failed) when ``keep_all``
    verified: tuple[int, ...] = ()  #: the candidates ``verify`` checked, in the order checked

    @property
    def chosen(self) -> Candidate:
        return self.candidates[self.best]

    @property
    def directions(self) -> np.ndarray:
        """(K, 3) the approach directions."""
        return np.stack([c.direction for c in self.candidates])


def _direction_count(name: str, count: Any) -> int:
    """``count`` as a number of directions, 1 to 10000; otherwise a ValueError naming ``name``."""
    return _checks.whole(name, count, 1, 10000)


def approach_directions(count: int, pole: Any = (0.0, 0.0, 1.0)) -> np.ndarray:
    """``count`` unit vectors (count, 3) spread evenly over the sphere, the first one ``pole``.

    A spherical Fibonacci lattice from the pole to its antipode: direction i has height
    z_i = 1 - 2 i / (count - 1) along the pole and turns by the golden angle (pi (3 - sqrt 5))
    about it from one to the next; the frame about the pole is that of :func:`hugger.look_at`
    (deterministic). ``count`` = 1 gives the pole alone (the default single approach).
    """
    n = _direction_count("approaches", count)
    try:
        p = _checks.real_array("pole", pole).reshape(3)
    except ValueError:
        raise ValueError(f"pole must be a finite non-zero 3-vector, got {pole!r}") from None
    with np.errstate(over="ignore"):  # a length beyond ~1e154 overflows: refused below
        length = float(_stable.norm(p))
    if not np.all(np.isfinite(p)) or not 0 < length < math.inf:
        raise ValueError(f"pole must be a finite non-zero 3-vector, got {pole!r}")
    p = p / length
    if n == 1:
        return p[None].copy()
    from .planner import look_at

    frame = look_at(np.zeros(3), p)[:3, :3]  # columns x, y, z = p
    i = np.arange(n)
    z = 1.0 - 2.0 * i / (n - 1)
    r = np.sqrt(np.clip(1.0 - z * z, 0.0, None))
    phi = _GOLDEN_ANGLE * i
    local = np.column_stack([r * _stable.cos(phi), r * _stable.sin(phi), z])
    out: np.ndarray = _stable.matmul(local, frame.T)
    out /= _stable.norm(out)[:, None]
    out[0] = p  # exactly the pole
    return out


def torque_scale(obj: Object, target: np.ndarray) -> float:
    """The torque scale of the ranking's grasp quality: the object's largest distance from T (m)."""
    return _stable.farthest(obj.vertices, target)


def final_grasp_quality(traj: Trajectory, hand: Hand, obj: Object, target: np.ndarray,
                        scale: float) -> tuple[Any, Any]:
    """The contacts of a plan's final configuration and their force closure and epsilon (the
    ranking's definition: mu = RANK_MU, torques divided by ``scale``, no volume)."""
    from . import analysis

    found = analysis.contacts_of(hand, obj, traj.palm_pose[-1], traj.joints[-1], CONTACT_DISTANCE)
    return found, analysis.grasp_quality(found, target, mu=RANK_MU, torque_scale=scale, volume=False)


def _judge(cand: Candidate, traj: Trajectory, hand: Hand, obj: Object, target: np.ndarray,
           scale: float) -> tuple[Candidate, Any]:
    """The candidate with its contacts, force closure and epsilon filled in, and its contacts
    (a :class:`hugger.analysis.Contacts`)."""
    found, q = final_grasp_quality(traj, hand, obj, target, scale)
    return replace(cand, contacts=len(found), force_closure=bool(q.force_closure), epsilon=float(q.epsilon)), found


def _escape(cand: Candidate, traj: Trajectory, hand: Hand, obj: Object) -> Candidate:
    """The candidate with its escape filled in."""
    from .analysis import escape

    return replace(cand, escape=escape(hand, obj, traj.palm_pose[-1], traj.joints[-1]))


def firmness(epsilon: float, escape: float) -> float:
    """The ranking's figure: epsilon - ESCAPE_WEIGHT x escape / ESCAPE_REACH."""
    return float(epsilon) - ESCAPE_WEIGHT * float(escape) / ESCAPE_REACH


def _default_key(c: Candidate) -> tuple[Any, ...]:
    # firmness, or epsilon where no escape is measured (rank without an escape function)
    firm = c.firmness if c.firmness is not None else c.epsilon
    return (c.ok, bool(c.force_closure), firm if firm is not None else -math.inf, -c.index)


def _upper_key(c: Candidate) -> tuple[Any, ...]:
    """A bound on _default_key(c) before its escape is known: firmness <= epsilon."""
    return (c.ok, bool(c.force_closure), c.epsilon if c.epsilon is not None else -math.inf, -c.index)


def rank(candidates: Sequence[Candidate], judge: Callable[[Candidate], Candidate],
         score: Callable[[Candidate], float] | None = None,
         escape: Callable[[Candidate], Candidate] | None = None) -> tuple[int, list[Candidate]]:
    """The index of the best candidate and the candidates, judged where it decides.

    ``judge(c)`` returns c with ``contacts``, ``force_closure`` and ``epsilon`` filled in;
    ``escape(c)`` returns c with ``escape`` filled in (None: no escape is measured, and epsilon
    ranks in firmness's place). Default ranking: see the module docstring; with ``score``, every working
    candidate is judged fully and the largest ``score(c)`` wins (ties: lowest index).
    """
    out = list(candidates)
    working = [c for c in out if c.ok]
    if not working:
        raise ValueError("no approach could be planned: " + "; ".join(f"{c.index}: {c.error}" for c in out))
    caged = escape if escape is not None else (lambda c: c)  # no escape: epsilon ranks
    for c in working:  # search judges as its plans end; judge the others
        out[c.index] = judge(c) if c.epsilon is None else c
    if score is not None:
        for c in working:
            j = caged(out[c.index])
            answer = score(j)
            try:
                s = float(answer)
            except (TypeError, ValueError):
                s = math.nan  # not a number at all: refused below, as NaN is
            if not math.isfinite(s):
                raise ValueError(f"score must return a finite number, got {_checks.shown(answer)} for candidate {c.index}")
            out[c.index] = replace(j, score=s)
        chosen = max((c for c in out if c.ok), key=lambda c: (c.score, -c.index))
        return chosen.index, out
    best: Candidate | None = None
    for c in sorted((out[c.index] for c in working), key=_upper_key, reverse=True):
        if best is not None and _upper_key(c) < _default_key(best):
            break  # its firmness cannot reach the best's
        j = caged(c)
        out[c.index] = j
        if best is None or _default_key(j) > _default_key(best):
            best = j
    assert best is not None
    return best.index, out


def _verify(order: Sequence[Candidate], trajs: Sequence[Trajectory | None], count: int, robust: bool,
            workers: int, progress: Callable[[int, int], Any] | None, planned: int) -> tuple[int, list[Candidate]]:
    """The physics check of ``search(verify=count, robust=robust)``: the chosen index and the
    checked candidates (in the order checked), each with ``held`` (and ``robust``,
    ``held_fraction`` when ``robust``) filled in."""
    from . import physics
    import contextlib

    from ._pool import running_pool
    from .physics.hold import NOMINAL_FORCE as force
    from .physics.hold import PERTURBATIONS, _validate_job

    physics._mujoco()  # fail early when MuJoCo is missing
    others = [n for n in PERTURBATIONS if n != "nominal"]
    total = planned + len(order[:count]) * (1 + (len(others) if robust else 0))
    done = planned
    if progress is not None:  # the simulations to come, before the first (a bar would sit at full)
        progress(done, total)
    checked: list[Candidate] = []
    pool: Any = None
    with contextlib.ExitStack() as pools:  # the pool, once made, stopped at once if interrupted
        for c in order[:count]:
            traj = trajs[c.index]
            assert traj is not None
            if not robust:
                held = bool(physics.validate(replace(traj))["held"])
                checked.append(replace(c, held=held))
            else:
                # nominal first, the cheapest; on a copy, so that the plan caches no compiled object
                # (which would not pickle for a process pool, here or in physics.validate_robust)
                held = bool(physics.validate(replace(traj), force=force)["held"])
                verdicts = [held]
                if held:  # then the other perturbations, in a process pool when workers > 1
                    jobs: list[tuple[Trajectory, int, dict[str, Any]]] = [
                        (traj, -1, {**PERTURBATIONS[n], "force": force}) for n in others]
                    if workers > 1 and pool is None:  # one pool for every candidate checked
                        pool = pools.enter_context(running_pool(workers, len(jobs)))
                    found = (pool.map(_validate_job, jobs) if pool is not None
                             else (physics.validate(replace(j[0]), j[1], **j[2]) for j in jobs))
                    for r in found:
                        verdicts.append(bool(r["held"]))
                        done += 1
                        if progress is not None:
                            progress(done, total)
                else:  # lost at nominal settings: not robust, the perturbations are not run
                    total -= len(others)
                fraction = sum(verdicts) / len(PERTURBATIONS) if held else None
                checked.append(replace(c, held=held, robust=all(verdicts) and held, held_fraction=fraction))
            done += 1
            if progress is not None:
                progress(done, total)
            last = checked[-1]
            if (last.robust if robust else last.held):
                break
    if progress is not None and done != total:  # stopped early: the work is complete
        progress(done, done)
    last = checked[-1]
    if (last.robust if robust else last.held):
        return last.index, checked
    held_ones = [c for c in checked if c.held]
    if robust and held_ones:  # none robust: the largest held fraction, then the ranking's order
        return max(held_ones, key=lambda c: c.held_fraction or 0.0).index, checked
    return order[0].index, checked


def search(hand: Hand, obj: Object, target: Any = None, approaches: int = 26, rules: str | None = None,
           threads: int | None = None, score: Callable[[Candidate], float] | None = None,
           pole: Any = (0.0, 0.0, 1.0), timeout: float | None = None, keep_all: bool = False,
           progress: Callable[[int, int], Any] | None = None, verify: int = 0, robust: bool = False,
           workers: int | None = None, **params: Any) -> SearchResult:
    """The firmest of ``approaches`` grasps of ``obj``, approached evenly from all around T.

    ``target``: T (default :func:`hugger.scenarios.interior_target`). Direction 0 is ``pole``
    (default +z). The command line passes its default approach (``default_case``'s palm position
    less T, +x for the built-in cylinder and torus), so there ``approaches=1`` is the single
    default plan. ``rules`` is passed to :class:`hugger.Planner` when given (the Phase 2 rule set), as are
    ``params`` (``step``, ``epsilon``, ``contact_tolerance``, ``max_iterations``) and ``timeout``
    (seconds per plan). ``threads``: worker threads (default: the CPUs this process may use).
    ``score``: see :func:`rank`. ``keep_all`` keeps every candidate's trajectory and final contacts in the result.
    ``progress(done, total)`` is called as plans finish. Deterministic: the same input gives the
    same result on any number of threads.

    ``verify`` = V > 0 checks the ranking in physics (needs ``hugger[physics]``): every candidate
    is judged, and the V best by the ranking are put through the six-direction test of
    :func:`hugger.physics.validate` in ranking order; the first that holds is chosen (``held`` in
    its figures), or the ranking's best when none of them does.

    With ``robust=True`` the V best are checked with the robust verdict of
    :func:`hugger.physics.validate_robust` instead (without its largest-push search), cheapest first:
    the six-direction test at nominal settings, and only for a candidate that holds there the other
    eight perturbations (on ``workers`` processes, default: the CPUs available; ``workers`` is for
    ``robust=True`` only, a ValueError without it). The first robustly
    held one is chosen; when none is, the held one with the largest ``held_fraction`` (ties: the
    ranking's order), or the ranking's best when none holds. Checked candidates carry ``held``,
    ``robust`` and ``held_fraction`` (None where the nominal test was lost: the perturbations are
    not run); ``SearchResult.verified`` lists them in the order checked. With ``verify``,
    ``progress(done, total)`` goes on counting the simulations after the plans (``total`` grows
    then, and shrinks when perturbations are skipped). The choice does not depend on ``threads``
    or ``workers``.
    """
    from .planner import Planner, _Batch, _timeout, check_params
    from .scenarios import interior_target, safe_distance, start_pose

    t0 = time.perf_counter()
    if not isinstance(hand, Hand):
        raise ValueError(f"hand must be a hugger.Hand, got {type(hand).__name__}")
    if not isinstance(obj, Object):
        raise ValueError(f"obj must be a hugger.Object, got {type(obj).__name__}")
    if rules is not None:
        params = {**params, "rules": rules}
    check_params(params, hand=hand)  # before any planning (against the hand: a step longer than a link, say)
    _checks.callback("progress", progress, "progress(done, total)")
    _checks.whole("verify", verify, 0)
    robust, keep_all = _checks.flag("robust", robust), _checks.flag("keep_all", keep_all)
    if robust and not verify:
        raise ValueError("robust=True checks the verify=V best-ranked candidates: give verify >= 1")
    if workers is not None and not robust:  # (as hugger plan --workers without --robust-verify)
        raise ValueError("workers runs the simulations of robust=True in parallel: give robust=True, or no workers")
    procs = _checks.workers("workers", workers)
    _checks.callback("score", score, "score(candidate) -> float")
    limit = _timeout(timeout)
    workers = _checks.workers("threads", threads)
    t = interior_target(obj) if target is None else _checks.real_array("target", target).reshape(3)
    if not np.all(np.isfinite(t)) or not bool(obj.inside(t[None])[0]):
        raise ValueError(f"target T {t.tolist()} is not inside the object")
    dirs = approach_directions(approaches, pole)
    distance = safe_distance(obj, hand, t)
    scale = torque_scale(obj, t)

    def run(i: int) -> tuple[Candidate, Trajectory | None, Any]:
        d = dirs[i]
        pose = start_pose(obj, hand, t, d, distance=distance)
        t1 = time.perf_counter()
        try:
            traj = batch.plan(Planner(hand, obj, t, pose, **params), limit)
        except (ValueError, RuntimeError) as exc:
            return Candidate(index=i, direction=d, status="error", start_pose=pose,
                             error=f"{type(exc).__name__}: {exc}"), None, None
        elapsed = time.perf_counter() - t1
        s = traj.summary(obj=obj)
        cand = Candidate(index=i, direction=d, status=traj.status, start_pose=pose, configurations=len(traj),
                         plan_time_s=elapsed,
                         links_in_contact=int(s["links_in_contact"]), palm_contact=bool(s["palm_contact"]))
        judged, found = _judge(cand, traj, hand, obj, t, scale)  # in this thread: the queries release the GIL
        return judged, traj, found

    k = len(dirs)
    batch = _Batch()  # (the serial path plans through it too: one run() for both)
    slots: list[tuple[Candidate, Trajectory | None, Any] | None] = [None] * k
    if workers == 1 or k == 1:
        for i in range(k):
            slots[i] = run(i)
            if progress is not None:
                progress(i + 1, k)
    else:
        from concurrent.futures import ThreadPoolExecutor, as_completed

        with ThreadPoolExecutor(max_workers=min(workers, k), thread_name_prefix="hugger-search") as pool:
            futures = {pool.submit(run, i): i for i in range(k)}
            try:
                for done, fut in enumerate(as_completed(futures), 1):
                    slots[futures[fut]] = fut.result()
                    if progress is not None:
                        progress(done, k)
            except BaseException:  # Ctrl-C, or the progress callback raised: the workers stop too
                batch.stop(pool)
                raise
    results = [r for r in slots if r is not None]  # every slot is filled (a failed run raised)
    trajs = [r[1] for r in results]

    def judge(c: Candidate) -> Candidate:
        return _judge(c, cast(Trajectory, trajs[c.index]), hand, obj, t, scale)[0]

    def caged(c: Candidate) -> Candidate:
        return _escape(c, cast(Trajectory, trajs[c.index]), hand, obj)

    best, ranked = rank([r[0] for r in results], judge, score, caged)
    verified: tuple[int, ...] = ()
    if verify:
        ranked = [caged(c) if c.ok and c.escape is None else c for c in ranked]
        key = (lambda c: (c.score, -c.index)) if score is not None else _default_key
        order = sorted((c for c in ranked if c.ok), key=key, reverse=True)
        best, checked = _verify(order, trajs, int(verify), robust, procs, progress, k)
        for c in checked:
            ranked[c.index] = c
        verified = tuple(c.index for c in checked)
    # rank() chooses a candidate that was planned (it raises when none was): its plan is there
    return SearchResult(best=best, trajectory=cast(Trajectory, trajs[best]), candidates=tuple(ranked), target=t,
                        time_s=time.perf_counter() - t0, trajectories=tuple(trajs) if keep_all else None,
                        contacts=tuple(r[2] for r in results) if keep_all else None, verified=verified)
