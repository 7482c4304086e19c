"""A minimal progress display for long work on a terminal (standard error only, never in pipes)."""
from __future__ import annotations

import sys
import threading
import time
from typing import TextIO


_MARKS = "|/-\\"  # the spinner

#: The progress displays drawing now, the innermost last: lines printed meanwhile go above them.
_ACTIVE: list[Progress] = []
#: Every write of a display, and of a line printed while one runs, is made under this lock: a line
#: from another thread is never glued to a bar.
_WRITE = threading.Lock()


def print_line(text: str, stream: TextIO | None = None) -> None:
    """``text`` on a line of its own on ``stream`` (standard error by default), above the bars of
    the progress displays drawing there (so that a warning is not glued to a bar)."""
    stream = stream if stream is not None else sys.stderr
    with _WRITE:
        for p in _ACTIVE:
            if p.stream is stream and p._drawn:  # (displays on one stream share its last line)
                stream.write("\r\x1b[K")
                p._drawn = False
        stream.write(text + "\n")
        stream.flush()


class Progress:
    """``with Progress("rendering", total=n) as p: p.update(i)``; a background thread redraws the
    bar (or, with ``total=None``, a spinner) with the elapsed time, so that it moves while the work
    runs (which may hold no GIL, as the planner does). ``p.note(line)`` prints a line above it.

    Nothing is drawn unless ``stream`` is a terminal, nor before ``delay`` seconds have passed,
    so quick work and scripted use print nothing extra (notes still print).
    """

    def __init__(self, label: str, total: int | None = None, stream: TextIO | None = None, delay: float = 1.0,
                 enabled: bool | None = None) -> None:
        self.label, self.total, self.delay = label, total, delay
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = enabled if enabled is not None else bool(getattr(self.stream, "isatty", lambda: False)())
        self._start = 0.0
        self._done = 0
        self._tick = 0
        self._drawn = False
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def __enter__(self) -> Progress:
        self._start = time.perf_counter()
        if self.enabled:
            with _WRITE:
                _ACTIVE.append(self)
            self._thread = threading.Thread(target=self._run, daemon=True)
            self._thread.start()
        return self

    def update(self, done: int, total: int | None = None) -> None:
        """``done`` of ``total`` (when given, it replaces the total): a ``progress(done, total)`` callback."""
        if total is not None:
            self.total = total
        self._done = done
        self._redraw()

    def note(self, line: str) -> None:
        """``line`` on a line of its own above the bar (a ``log(line)`` callback)."""
        print_line(line, self.stream)
        self._redraw()

    def _text(self, elapsed: float) -> str:
        if self.total:
            frac = min(1.0, self._done / self.total)
            bar = "#" * int(30 * frac) + "-" * (30 - int(30 * frac))
            return f"{self.label} [{bar}] {self._done}/{self.total} {elapsed:.1f}s"
        return f"{self.label} {_MARKS[self._tick % 4]} {elapsed:.1f}s"

    def _redraw(self) -> None:
        elapsed = time.perf_counter() - self._start
        if self.enabled and elapsed >= self.delay:
            with _WRITE:
                if self._stop.is_set():  # ended (a note from another thread may come late): nothing more
                    return
                self.stream.write("\r" + self._text(elapsed) + "\x1b[K")
                self.stream.flush()
                self._drawn = True

    def _run(self) -> None:
        while not self._stop.wait(0.1):
            self._tick += 1
            self._redraw()

    def __exit__(self, *exc: object) -> None:
        with _WRITE:
            self._stop.set()
            if self in _ACTIVE:
                _ACTIVE.remove(self)
        if self._thread is not None:
            self._thread.join()
        with _WRITE:
            if self._drawn:
                self.stream.write("\r\x1b[K")
                self.stream.flush()
                self._drawn = False
