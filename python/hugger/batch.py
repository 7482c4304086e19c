"""Many independent plans on a thread pool: :func:`plan_many`.

The engine releases the GIL while it plans, so plans of different cases run in parallel on
separate cores. Results come back in input order; a case that fails does not stop the others,
and its exception is reported with the case's index, never lost.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Iterable, Mapping

from . import _checks
from .hand import Hand
from .planner import PARAMS, Planner, _Batch, _timeout, check_case, check_params
from .trajectory import Trajectory
from .world import Object


@dataclass(frozen=True)
class CaseError:
    """What went wrong with one case of :func:`plan_many` (``errors="return"``)."""

    index: int  #: position of the case in the input
    exception: BaseException  #: the exception the case raised

    def __str__(self) -> str:
        return f"case {self.index}: {type(self.exception).__name__}: {self.exception}"


class PlanManyError(RuntimeError):
    """One or more cases of :func:`plan_many` failed (``errors="raise"``, the default).

    ``errors`` maps each failed case's index to its exception; ``results`` holds every case's
    outcome in input order (a :class:`Trajectory`, or None where the case failed).
    """

    def __init__(self, errors: dict[int, BaseException], results: list[Trajectory | None]) -> None:
        self.errors = errors
        self.results = results
        lines = [str(CaseError(i, e)) for i, e in sorted(errors.items())]
        shown = lines[:10] + ([f"... and {len(lines) - 10} more"] if len(lines) > 10 else [])
        super().__init__(f"{len(errors)} of {len(results)} cases failed:\n  " + "\n  ".join(shown))


@dataclass(frozen=True)
class _Job:
    hand: Hand
    obj: Object
    target: Any
    palm_pose: Any
    params: dict[str, Any]
    timeout: float | None


def _job(index: int, case: Any, hand: Hand | None, params: dict[str, Any], timeout: float | None) -> _Job:
    """Normalise one case: a mapping, a (hand, obj, target, palm_pose[, params]) tuple, or an
    object with ``obj``, ``target`` and ``palm_pose`` attributes (like ``hugger.scenarios.Case``)."""
    own: dict[str, Any] = {}
    if isinstance(case, Mapping):
        unknown = set(case) - {"hand", "obj", "target", "palm_pose", "timeout", "record_object", *PARAMS}
        if unknown:
            hint = " (the object's key is 'obj')" if "object" in unknown else ""
            raise ValueError(f"case {index}: unknown keys {sorted(unknown)}{hint}")
        c_hand, obj = case.get("hand", hand), case.get("obj")
        target, pose = case.get("target"), case.get("palm_pose")
        own = {k: case[k] for k in (*PARAMS, "record_object") if k in case}
        if "timeout" in case:
            timeout = _timeout(case["timeout"])
    elif isinstance(case, tuple):
        if len(case) == 5:
            if not isinstance(case[4], Mapping):
                raise ValueError(f"case {index}: a tuple case's fifth item must be a mapping of planner parameters, "
                                 f"got {type(case[4]).__name__}")
            c_hand, obj, target, pose = case[:4]
            own = dict(case[4])
        elif len(case) == 4:
            c_hand, obj, target, pose = case
        else:
            raise ValueError(f"case {index}: a tuple case must be (hand, obj, target, palm_pose[, params]), "
                             f"got {len(case)} items")
    elif all(hasattr(case, a) for a in ("obj", "target", "palm_pose")):
        own_hand = getattr(case, "hand", None)  # a Case may carry hand=None: plan_many's hand then
        c_hand, obj, target, pose = own_hand if own_hand is not None else hand, case.obj, case.target, case.palm_pose
    else:
        raise ValueError(f"case {index}: expected a mapping, a (hand, obj, target, palm_pose) tuple or an object "
                         f"with obj, target and palm_pose; got {type(case).__name__}")
    if c_hand is None:
        raise ValueError(f"case {index}: no hand (give one in the case or plan_many(..., hand=...))")
    if obj is None or target is None or pose is None:
        raise ValueError(f"case {index}: obj, target and palm_pose are all required")
    merged = {**params, **own}
    try:  # as the planner would refuse them, before anything is planned
        check_params(merged, "parameters", also=("record_object",), hand=c_hand if isinstance(c_hand, Hand) else None)
        check_case(c_hand, obj, target, pose, merged.get("record_object"))
    except (TypeError, ValueError) as exc:
        raise ValueError(f"case {index}: {exc}") from None
    return _Job(c_hand, obj, target, pose, merged, timeout)


def _run(job: _Job, batch: _Batch) -> Trajectory:
    return batch.plan(Planner(job.hand, job.obj, job.target, job.palm_pose, **job.params), job.timeout)


def _run_all(jobs: list[_Job], batch: _Batch) -> list[Trajectory | BaseException]:
    """Plan ``jobs`` one after another; each outcome a trajectory or the case's exception."""
    out: list[Trajectory | BaseException] = []
    for job in jobs:
        try:
            out.append(_run(job, batch))
        except Exception as exc:  # reported per case
            out.append(exc)
    return out


def _stateful(skin: Any) -> list[int]:
    """The ids of the skins that keep state (``keeps_state``) among ``skin`` and the skins it wraps
    (a wrapper's ``skin``, as a SensorModel's)."""
    out: list[int] = []
    seen: set[int] = set()
    while skin is not None and id(skin) not in seen:
        seen.add(id(skin))
        if getattr(skin, "keeps_state", False):
            out.append(id(skin))
        skin = getattr(skin, "skin", None)
    return out


def _groups(jobs: list[_Job]) -> list[list[int]]:
    """The cases, in groups planned one after another in one thread: the cases that share a skin
    which keeps state (``keeps_state``: a SensorModel's noise stream), given or wrapped by the
    skins given, in input order, so that each reads the skin as a serial run would; every other
    case alone (stateless skins, compiled or not, are shared by threads in parallel)."""
    group_of: dict[int, int] = {}  # a stateful skin's id -> its group (the first case that reads it)
    parent = list(range(len(jobs)))

    def root(i: int) -> int:
        while parent[i] != i:
            i = parent[i]
        return i

    for i, job in enumerate(jobs):
        for key in _stateful(job.obj):
            j = group_of.setdefault(key, i)
            a, b = root(i), root(j)
            parent[max(a, b)] = min(a, b)  # a group is known by its first case
    groups: dict[int, list[int]] = {}
    for i in range(len(jobs)):
        groups.setdefault(root(i), []).append(i)
    return list(groups.values())


def plan_many(cases: Iterable[Any], threads: int | None = None, hand: Hand | None = None,
              progress: Callable[[int, int], Any] | None = None, timeout: float | None = None,
              errors: str = "raise", **params: Any) -> list[Trajectory] | list[Trajectory | CaseError]:
    """Plan many independent cases on ``threads`` threads; trajectories in input order.

    Each case is a mapping with ``hand`` (or the ``hand`` argument), ``obj``,
    ``target``, ``palm_pose`` and optionally ``step``, ``epsilon``, ``contact_tolerance``,
    ``max_iterations``, ``rules``, ``skin``, ``timeout`` and ``record_object`` (the mesh a plan
    through a skin without one records, as :class:`Planner` takes it); or a tuple ``(hand, obj, target, palm_pose[, params])``;
    or an object with ``obj``, ``target`` and ``palm_pose`` attributes such as
    ``hugger.scenarios.Case``. ``**params`` and ``timeout`` (seconds per plan's Phase 2, see
    :meth:`Planner.plan`) apply to every case unless the case gives its own.

    ``threads``: worker threads (default: the CPUs this process may use; 1 plans in the calling
    thread). The engine plans with the GIL released, so threads run in parallel; cases may share
    a :class:`Hand`, an :class:`Object` and a skin. Cases that share a skin which keeps state
    (``keeps_state = True``: a SensorModel's noise stream), given or wrapped (a wrapper's ``skin``),
    are planned one after another in input order, in one thread, so that the results are those of ``threads=1``; ``progress`` then
    reports them when the last of them ends.

    ``progress(done, total)`` is called in the calling thread after each case finishes.

    ``errors``: ``"raise"`` (default) plans every case, then raises :class:`PlanManyError`
    naming each failed case (its index, exception type and message; ``.errors`` and
    ``.results`` hold the details) if any failed; ``"return"`` puts a :class:`CaseError` in
    place of each failed case's trajectory. Malformed cases and bad arguments (parameters a case's
    hand cannot plan with among them) raise ``ValueError`` before anything is planned.
    """
    if errors not in ("raise", "return"):
        raise ValueError(f"errors must be 'raise' or 'return', got {errors!r}")
    threads = _checks.workers("threads", threads)
    _checks.callback("progress", progress, "progress(done, total)")
    if hand is not None and not isinstance(hand, Hand):
        raise ValueError(f"hand must be a hugger.Hand, got {type(hand).__name__}")
    check_params(params, also=("record_object",))
    if isinstance(cases, (str, bytes)) or not isinstance(cases, Iterable):
        raise ValueError(f"cases must be an iterable of cases, got {type(cases).__name__}")
    limit = _timeout(timeout)
    jobs = [_job(i, c, hand, params, limit) for i, c in enumerate(cases)]
    total = len(jobs)
    results: list[Trajectory | None] = [None] * total
    failed: dict[int, BaseException] = {}

    def finish(i: int, outcome: Trajectory | BaseException, done: int) -> None:
        if isinstance(outcome, BaseException):
            failed[i] = outcome
        else:
            results[i] = outcome
        if progress is not None:
            progress(done, total)

    batch = _Batch()  # (the serial path plans through it too: one _run for both)
    if threads == 1 or total <= 1:
        for i, job in enumerate(jobs):
            try:
                outcome: Trajectory | BaseException = _run(job, batch)
            except Exception as exc:  # reported per case below
                outcome = exc
            finish(i, outcome, i + 1)
    else:
        from concurrent.futures import FIRST_COMPLETED, Future, ThreadPoolExecutor, wait

        groups = _groups(jobs)
        with ThreadPoolExecutor(max_workers=min(int(threads), len(groups)), thread_name_prefix="hugger") as pool:
            group_of: dict[Future[Any], list[int]] = {pool.submit(_run_all, [jobs[i] for i in g], batch): g
                                                      for g in groups}
            pending = set(group_of)
            done = 0
            try:
                while pending:
                    finished, pending = wait(pending, return_when=FIRST_COMPLETED)
                    for fut in sorted(finished, key=lambda f: group_of[f][0]):
                        error = fut.exception()
                        outcomes = [error] * len(group_of[fut]) if error is not None else fut.result()
                        for i, outcome in zip(group_of[fut], outcomes):
                            done += 1
                            finish(i, outcome, done)
            except BaseException:  # Ctrl-C, or the progress callback raised: the workers stop too
                batch.stop(pool)
                raise
    if failed and errors == "raise":
        err = PlanManyError(failed, results)
        raise err from failed[min(failed)]
    out: list[Trajectory | CaseError] = [r if r is not None else CaseError(i, failed[i]) for i, r in enumerate(results)]
    return out


__all__ = ["CaseError", "PlanManyError", "plan_many"]
