"""A minimal progress display for long work on a terminal (standard error only, never in pipes)."""
from __future__ import annotations

import sys
import threading
import time
from typing import TextIO


class Progress:
    """``with Progress("rendering", total=n) as p: p.update(i)``; with ``total=None`` a spinner with
    the elapsed time runs on a background thread (the work may hold no GIL, as the planner does).

    Nothing is drawn unless ``stream`` is a terminal, nor before ``delay`` seconds have passed,
    so quick work and scripted use print nothing extra.
    """

    def __init__(self, label: str, total: int | None = None, stream: TextIO | None = None, delay: float = 1.0,
                 enabled: bool | None = None) -> None:
        self.label, self.total, self.delay = label, total, delay
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = enabled if enabled is not None else bool(getattr(self.stream, "isatty", lambda: False)())
        self._start = 0.0
        self._done = 0
        self._drawn = False
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def __enter__(self) -> Progress:
        self._start = time.perf_counter()
        if self.enabled and self.total is None:
            self._thread = threading.Thread(target=self._spin, daemon=True)
            self._thread.start()
        return self

    def update(self, done: int, total: int | None = None) -> None:
        """``done`` of ``total`` (when given, it replaces the total): a ``progress(done, total)`` callback."""
        if total is not None:
            self.total = total
        self._done = done
        if self.enabled and self.total and time.perf_counter() - self._start >= self.delay:
            frac = min(1.0, done / self.total)
            bar = "#" * int(30 * frac) + "-" * (30 - int(30 * frac))
            self._draw(f"{self.label} [{bar}] {done}/{self.total} {time.perf_counter() - self._start:.1f}s")

    def _spin(self) -> None:
        marks = "|/-\\"
        i = 0
        while not self._stop.wait(0.1):
            elapsed = time.perf_counter() - self._start
            if elapsed >= self.delay:
                self._draw(f"{self.label} {marks[i % 4]} {elapsed:.1f}s")
                i += 1

    def _draw(self, text: str) -> None:
        self.stream.write("\r" + text + "\x1b[K")
        self.stream.flush()
        self._drawn = True

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        if self._drawn:
            self.stream.write("\r\x1b[K")
            self.stream.flush()
