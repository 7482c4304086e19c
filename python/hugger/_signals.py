"""Ctrl-C for the command line (:func:`hugger.cli.main`).

The first SIGINT raises ``KeyboardInterrupt`` as Python's own handler does. Another that comes
within :data:`REPEAT_WINDOW` of it is ignored: a terminal's Ctrl-C reaches the process and
``timeout -s INT`` sends a second, and a second ``KeyboardInterrupt`` would cut short the cleanup
the first started (a dataset folder left holding only its lock file, tracebacks from the
interpreter's exit). A later one raises again: the user insists.

An interrupt that a library swallowed is raised again where it returns (:func:`kept`): trimesh
catches ``BaseException`` around its optional imports, so a Ctrl-C while it loads was lost and the
command ran on to the end.
"""
from __future__ import annotations

import contextlib
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


@contextlib.contextmanager
def installed(program: bool) -> Iterator[None]:
    """The handler above for SIGINT meanwhile, where Python's own is installed (in the main
    thread; elsewhere, or under another handler a caller chose, nothing changes). Python's is
    installed again after, except in a ``program`` (the process ends after the block) that was
    interrupted: SIGINT is then ignored while the interpreter exits."""
    if threading.current_thread() is not threading.main_thread() or \
            signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        yield
        return
    before = _raised
    signal.signal(signal.SIGINT, _handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, signal.SIG_IGN if program and _raised != before else signal.default_int_handler)


@contextlib.contextmanager
def kept() -> Iterator[None]:
    """Raise ``KeyboardInterrupt`` when the block ends normally although the handler raised one
    within it: a library swallowed it."""
    before = _raised
    yield
    if _raised != before:
        raise KeyboardInterrupt
