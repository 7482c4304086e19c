"""The package's process pools: spawned workers that end with the process that made them."""
from __future__ import annotations

import os
import sys
from typing import Any

#: prctl's option that sends the calling process a signal when its parent ends (Linux).
_PR_SET_PDEATHSIG = 1


def _end_with_parent(parent: int) -> None:
    """Worker initializer. A pool's owner killed outright (SIGKILL) cannot shut its pool down: on
    Linux the kernel then sends each worker SIGTERM, as asked here; a parent already gone when
    this runs ends the worker at once."""
    if not sys.platform.startswith("linux"):
        return
    import ctypes
    import signal

    try:
        ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, int(signal.SIGTERM), 0, 0, 0)
    except (OSError, AttributeError):  # no prctl in this C library: the pool's own shutdown only
        return
    if os.getppid() != parent:
        os._exit(1)


def process_pool(workers: int, jobs: int) -> Any:
    """A ``ProcessPoolExecutor`` of min(workers, jobs) spawned processes (not forked: MuJoCo and
    the planner's threads do not survive a fork), which end with this process."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    return ProcessPoolExecutor(max_workers=min(workers, jobs), mp_context=multiprocessing.get_context("spawn"),
                               initializer=_end_with_parent, initargs=(os.getpid(),))
