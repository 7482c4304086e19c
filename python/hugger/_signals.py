"""Ctrl-C for the command line (:func:`hugger.cli.main`).

The first SIGINT raises ``KeyboardInterrupt`` as Python's own handler does. Another that comes
within :data:`REPEAT_WINDOW` of it is ignored: a terminal's Ctrl-C reaches the process and
``timeout -s INT`` sends a second, and a second ``KeyboardInterrupt`` would cut short the cleanup
the first started (a dataset folder left holding only its lock file, tracebacks from the
interpreter's exit). A later one raises again: the user insists (once the command has ended,
interrupted, it ends the process at once, exit status 130).

An interrupt that a library swallowed is raised again where it returns (:func:`kept`): trimesh
catches ``BaseException`` around its optional imports, so a Ctrl-C while it loads was lost and the
command ran on to the end.

The package's process pools spawn their workers with SIGINT held back (:func:`held_back`), from
the command line or not.
"""
from __future__ import annotations

import contextlib
import os
import signal
import threading
import time
from types import FrameType
from typing import Iterator

#: Seconds after an interrupt during which another SIGINT is ignored.
REPEAT_WINDOW = 1.0

_raised = 0  # interrupts raised by the handler
_last = -float("inf")  # when the last was raised (time.monotonic)


def _handler(signum: int, frame: FrameType | None) -> None:
    global _raised, _last
    now = time.monotonic()
    if now - _last < REPEAT_WINDOW:
        return
    _raised += 1
    _last = now
    raise KeyboardInterrupt


def _exiting(signum: int, frame: FrameType | None) -> None:
    """After an interrupted command, while the interpreter exits (joining the pools' threads, say):
    a repeat is ignored, a later SIGINT ends the process at once."""
    if time.monotonic() - _last >= REPEAT_WINDOW:
        os._exit(130)


@contextlib.contextmanager
def installed(program: bool) -> Iterator[None]:
    """The handler above for SIGINT meanwhile, where Python's own is installed (in the main
    thread; elsewhere, or under another handler a caller chose, nothing changes). Python's is
    installed again after, except in a ``program`` (the process ends after the block) that was
    interrupted: a repeat is then ignored while the interpreter exits, and a later SIGINT ends the
    process at once."""
    global _last
    if threading.current_thread() is not threading.main_thread() or \
            signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        yield
        return
    before = _raised
    _last = -float("inf")  # (an interrupt of an earlier call in this process is no repeat)
    signal.signal(signal.SIGINT, _handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, _exiting if program and _raised != before else signal.default_int_handler)


@contextlib.contextmanager
def kept() -> Iterator[None]:
    """Raise ``KeyboardInterrupt`` when the block ends although the handler raised one within it:
    a library swallowed it (and went on, or failed another way for it)."""
    before = _raised
    try:
        yield
    except Exception as exc:
        if _raised != before:
            raise KeyboardInterrupt from exc
        raise
    if _raised != before:
        raise KeyboardInterrupt


@contextlib.contextmanager
def held_back() -> Iterator[None]:
    """SIGINT held back from this thread meanwhile, and from the processes it spawns meanwhile,
    which keep the mask for good (it survives fork and exec, and Python leaves it): a terminal's
    Ctrl-C, sent to the whole process group, then reaches the pool's owner alone, which stops the
    workers (stop_pool). A worker interrupted as it started printed a fatal error and a traceback.

    A SIGINT that comes meanwhile is raised as the block ends, not within it: another thread (a
    progress bar's) may take it, and Python would run its handler in the main thread at once,
    midway through a spawn (a worker started and not recorded, which stop_pool misses). In the
    main thread the handler only notes it meanwhile, and it is raised again after. (Where there
    is no pthread_sigmask: nothing held back.)"""
    block = getattr(signal, "pthread_sigmask", None)
    if block is None:
        yield
        return
    noted: list[int] = []
    # (a handler installed from C, which getsignal gives as None, could not be put back: kept)
    handler = signal.getsignal(signal.SIGINT) if threading.current_thread() is threading.main_thread() else None
    if handler is not None:
        signal.signal(signal.SIGINT, lambda signum, frame: noted.append(signum))
    old = block(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        block(signal.SIG_SETMASK, old)  # (one pending for this thread is noted now)
        if handler is not None:
            signal.signal(signal.SIGINT, handler)
            if noted:
                signal.raise_signal(signal.SIGINT)  # to the handler in force: KeyboardInterrupt
