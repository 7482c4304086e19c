"""The package's process pools: spawned workers that end with the thread that made them."""
from __future__ import annotations

import contextlib
import os
import sys
from typing import Any, Iterator

from ._signals import held_back

#: prctl's option that sends the calling process a signal when its parent ends (Linux).
_PR_SET_PDEATHSIG = 1


def _end_with_parent(parent: int) -> None:
    """Worker initializer. A pool's owner killed outright (SIGKILL) cannot shut its pool down: on
    Linux the kernel then sends each worker SIGTERM, as asked here (when the thread that started
    the worker ends: the pools here live within one call of the thread that made them); a parent
    already gone when this runs ends the worker at once. Elsewhere, or without prctl, the pool's
    own shutdown only."""
    if not sys.platform.startswith("linux"):
        return
    try:
        import ctypes
        import signal

        prctl = ctypes.CDLL(None, use_errno=True).prctl
        prctl.argtypes = [ctypes.c_int, ctypes.c_ulong, ctypes.c_ulong, ctypes.c_ulong, ctypes.c_ulong]
        prctl.restype = ctypes.c_int
        if prctl(_PR_SET_PDEATHSIG, int(signal.SIGTERM), 0, 0, 0) != 0:
            return
    except (ImportError, OSError, AttributeError):
        return
    if os.getppid() != parent:
        os._exit(1)


def process_pool(workers: int, jobs: int) -> Any:
    """A ``ProcessPoolExecutor`` of min(workers, jobs) spawned processes (not forked: MuJoCo and
    the planner's threads do not survive a fork), which end with the thread that made them and
    take no SIGINT (their owner is interrupted, and stops them). A spawning pool starts its
    processes in ``submit``, as the jobs come, which is where SIGINT is held back."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    class Pool(ProcessPoolExecutor):
        def submit(self, fn: Any, /, *args: Any, **kwargs: Any) -> Any:
            with held_back():
                return super().submit(fn, *args, **kwargs)

    return Pool(max_workers=min(workers, jobs), mp_context=multiprocessing.get_context("spawn"),
                initializer=_end_with_parent, initargs=(os.getpid(),))


def stop_pool(pool: Any) -> None:
    """Stop ``pool`` without waiting: the jobs not started are cancelled and the workers still
    running one are ended (SIGTERM), so that an interrupted caller stops at once. Python 3.14's
    ``terminate_workers``; before it, the processes the executor keeps in ``_processes`` (an
    attribute every version since 3.2 has; without it, only the cancelling)."""
    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)  # first: quick, and nothing queued runs after it
    terminate = getattr(pool, "terminate_workers", None)
    if terminate is not None:
        with contextlib.suppress(Exception):
            terminate()
    for process in processes:
        with contextlib.suppress(OSError, ValueError, AttributeError):
            process.terminate()


@contextlib.contextmanager
def running_pool(workers: int, jobs: int) -> Iterator[Any]:
    """:func:`process_pool` for a ``with`` block: shut down waiting for its jobs when the block
    ends normally, stopped at once (:func:`stop_pool`) when it raises (Ctrl-C, say), so that an
    interrupted caller does not wait for work it will drop."""
    pool = process_pool(workers, jobs)
    try:
        yield pool
        pool.shutdown(wait=True)
    except BaseException:  # (a Ctrl-C during that wait too)
        stop_pool(pool)
        raise
