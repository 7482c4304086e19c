"""Ctrl-C on the command line (hugger._signals) and in the process pools' workers (hugger._pool)."""
from __future__ import annotations

import math
import os
import signal
import sys
import threading
import time
from pathlib import Path

import pytest

from hugger import _pool, _signals, dataset


@pytest.fixture
def handler(monkeypatch):
    """The command line's SIGINT handler installed, with no interrupt before this test's."""
    monkeypatch.setattr(_signals, "_last", -math.inf)
    with _signals.installed(program=False):
        assert signal.getsignal(signal.SIGINT) is _signals._handler
        yield
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def _interrupt() -> None:
    """SIGINT to this process, and the time for its handler to run."""
    os.kill(os.getpid(), signal.SIGINT)
    for _ in range(200):
        time.sleep(0.001)


def test_a_second_interrupt_at_once_does_not_cut_the_cleanup_short(handler, tmp_path, monkeypatch):
    # a terminal's Ctrl-C and timeout -s INT deliver two: the second cut short the dataset run's
    # cleanup, which left a folder holding only its lock file
    real_rmdir = Path.rmdir

    def rmdir(self: Path) -> None:
        _interrupt()  # the second, as the first is cleaned up after
        real_rmdir(self)

    monkeypatch.setattr(dataset, "_check_index", lambda root, tasks: _interrupt())
    monkeypatch.setattr(Path, "rmdir", rmdir)
    with pytest.raises(KeyboardInterrupt):
        dataset.generate(["sphere"], tmp_path / "made" / "ds", approaches=1, workers=1)
    assert not (tmp_path / "made").exists()
    monkeypatch.setattr(_signals, "_last", time.monotonic() - _signals.REPEAT_WINDOW)
    with pytest.raises(KeyboardInterrupt):  # a later one is an interrupt again
        _interrupt()


def test_an_interrupt_a_library_swallowed_is_raised_again(handler, monkeypatch):
    # trimesh catches BaseException around its optional imports: a Ctrl-C then was lost
    with pytest.raises(KeyboardInterrupt):
        with _signals.kept():
            try:
                _interrupt()
            except BaseException:  # noqa: BLE001 - as the library does
                pass
    monkeypatch.setattr(_signals, "_last", -math.inf)  # (the next is no repeat)
    with pytest.raises(KeyboardInterrupt):  # swallowed, and then another failure for it
        with _signals.kept():
            try:
                _interrupt()
            except BaseException:  # noqa: BLE001
                pass
            raise RuntimeError("the library failed, having lost the interrupt")
    with _signals.kept():  # nothing raised within: nothing raised after
        pass
    with pytest.raises(RuntimeError):
        with _signals.kept():
            raise RuntimeError("a failure of its own")


def test_an_interrupted_program_ignores_a_repeat_as_it_exits(monkeypatch):
    monkeypatch.setattr(_signals, "_last", -math.inf)
    try:
        with pytest.raises(KeyboardInterrupt):
            with _signals.installed(program=True):
                _interrupt()
        assert signal.getsignal(signal.SIGINT) is _signals._exiting
        _interrupt()  # a repeat: ignored (a later one would end the process at once)
    finally:
        signal.signal(signal.SIGINT, signal.default_int_handler)
    with _signals.installed(program=True):  # not interrupted: Python's handler again after
        pass
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_installed_leaves_another_handler_alone(monkeypatch):
    chosen = lambda signum, frame: None  # noqa: E731
    previous = signal.signal(signal.SIGINT, chosen)
    try:
        with _signals.installed(program=False):
            assert signal.getsignal(signal.SIGINT) is chosen
    finally:
        signal.signal(signal.SIGINT, previous)


def _blocked_signals() -> int:
    with open(f"/proc/{os.getpid()}/status") as status:
        return int(next(line for line in status if line.startswith("SigBlk:")).split()[1], 16)


def test_an_interrupt_while_a_pool_spawns_is_raised_after_the_spawn():
    # with another thread alive (a progress bar's) the kernel gave it the SIGINT, and Python raised
    # KeyboardInterrupt in the main thread midway through a spawn: a worker started unrecorded
    stop = threading.Event()
    helper = threading.Thread(target=stop.wait, daemon=True)
    helper.start()
    reached = False
    try:
        with pytest.raises(KeyboardInterrupt):
            with _signals.held_back():
                _interrupt()
                reached = True
    finally:
        stop.set()
    assert reached and signal.getsignal(signal.SIGINT) is signal.default_int_handler


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads the signal mask from /proc (Linux)")
def test_pool_workers_take_no_sigint_and_their_owner_still_does():
    # a terminal's Ctrl-C reaches the whole process group: a worker interrupted as it started
    # printed "Fatal Python error: init_import_site" and a traceback; its owner stops it instead
    pool = _pool.process_pool(2, 2)
    try:
        masks = [f.result(timeout=120) for f in [pool.submit(_blocked_signals) for _ in range(2)]]
    finally:
        pool.shutdown()
    assert all(m & (1 << (signal.SIGINT - 1)) for m in masks), masks
    assert not _blocked_signals() & (1 << (signal.SIGINT - 1))  # held back only while the pool spawned
