"""GIF and MP4 animations of a whole plan (Pillow; ffmpeg for MP4)."""
from __future__ import annotations

import contextlib
import logging
import os
import signal
import subprocess
from pathlib import Path
from typing import Any, Callable, Iterator

import numpy as np

from .._checks import callback, positive, whole
from .._files import atomic_path
from ..trajectory import Trajectory
from .backend import MAX_HOLD, _MOVIE_EXTENSIONS, _check_faces, _check_traj, _ffmpeg, _pyplot, _suffix, check_dpi
from .backend import check_fps
from .scene import _Scene, _camera, _legend, _phase_name, _subsample, draw_configuration

MOVIE_SIZE = (6.4, 4.8)


# --- animation --------------------------------------------------------------------------------------

class _HeldOutput(logging.Filter):
    """Holds back the movie writer's log of ffmpeg's output (matplotlib logs it as a warning when
    ffmpeg fails), for _ffmpeg_interrupted to let through or drop."""

    def __init__(self) -> None:
        super().__init__()
        self.records: list[logging.LogRecord] = []

    def filter(self, record: logging.LogRecord) -> bool:
        if record.getMessage().startswith("MovieWriter std"):
            self.records.append(record)
            return False
        return True


@contextlib.contextmanager
def _ffmpeg_interrupted() -> Iterator[None]:
    """Ctrl-C at a terminal reaches ffmpeg too, which ends first (status 255, or killed by the
    signal) while Python takes its KeyboardInterrupt: the writer's CalledProcessError, raised with
    that interrupt as its context, is then the interrupt it is, and ffmpeg's complaint of the
    frame it was cut off in is not shown. (ffmpeg's own failures end it with 255 too, as an error
    of -1: without the interrupt they stay what they are, and its output is shown.)"""
    log = logging.getLogger("matplotlib.animation")
    held = _HeldOutput()
    log.addFilter(held)
    interrupted = False
    try:
        yield
    except subprocess.CalledProcessError as exc:
        cause: BaseException | None = exc.__context__
        while cause is not None and not isinstance(cause, KeyboardInterrupt):
            cause = cause.__context__
        interrupted = cause is not None and exc.returncode in (255, -signal.SIGINT)
        if interrupted:
            raise KeyboardInterrupt from None
        raise
    finally:
        log.removeFilter(held)
        if not interrupted:
            for record in held.records:
                log.handle(record)


def animate(traj: Trajectory, path: str | os.PathLike[str], fps: float = 30, max_frames: int = 300, *,
            dpi: float = 100, view: str = "oblique", max_faces: int = 6000,
            progress: Callable[[int, int], Any] | None = None, hold: float = 0.0) -> int:
    """Write the whole plan as a ``.gif`` (Pillow) or ``.mp4`` (ffmpeg, H.264), subsampled evenly to at
    most ``max_frames`` frames (first and last included) at ``fps`` frames per second, with fixed
    axis limits over the plan. ``progress(i, n)`` is called after frame i of n (1-based) is
    written. The object is simplified to ``max_faces`` triangles for speed. ``hold`` (s) shows the
    final grasp that much longer (repeated frames, not counted). Returns the number of
    configurations drawn. ``ValueError`` for another extension or bad numbers (``fps`` at most
    :data:`MAX_FPS`, ``dpi`` from :data:`MIN_DPI` to :data:`MAX_DPI`, ``hold`` at most :data:`MAX_HOLD`); ``ImportError`` (naming
    what to install) when an MP4 is asked for and no ffmpeg is found (see :func:`ffmpeg_path`)."""
    plt = _pyplot()
    from matplotlib import animation, rc_context

    traj = _check_traj(traj)
    ext = _suffix(path)
    if ext not in _MOVIE_EXTENSIONS:
        raise ValueError(f"cannot animate to {Path(os.fspath(path)).name!r}: use .gif or .mp4")
    fps = check_fps(fps)
    hold = positive("hold", hold, allow_zero=True, most=MAX_HOLD)
    max_frames = whole("max_frames", max_frames, 1)
    callback("progress", progress, "progress(i, n)")
    dpi = check_dpi(dpi)
    max_faces = _check_faces(max_faces)
    _camera(view)
    rc: dict[Any, Any] = {}
    if ext == ".mp4":
        rc["animation.ffmpeg_path"] = _ffmpeg()
        writer: animation.AbstractMovieWriter = animation.FFMpegWriter(
            fps=fps, codec="h264", bitrate=-1)  # type: ignore[arg-type]  # a float rate works; the stubs say int
    else:
        writer = animation.PillowWriter(fps=fps)  # type: ignore[arg-type]  # a float rate works; the stubs say int
    frames = _subsample(len(traj), int(max_frames))
    scene = _Scene(traj, max_faces)
    limits = scene.limits(range(len(traj)))
    out = Path(os.fspath(path))
    out.parent.mkdir(parents=True, exist_ok=True)
    fig = plt.figure(figsize=MOVIE_SIZE)
    try:
        ax = fig.add_axes((0.0, 0.08, 1.0, 0.84), projection="3d")
        _legend(fig)

        def draw(k: int) -> list[Any]:
            artists = draw_configuration(ax, traj, k, view=view, limits=limits, _scene=scene)
            states = np.bincount(traj.tip_state[k].astype(int), minlength=3)
            ax.set_title(f"k = {k} / {len(traj) - 1}, {_phase_name(traj, k)}   "
                         f"FROZEN {states[0]}  CONTACT {states[1]}  DONE {states[2]}", fontsize=9)
            return artists

        # The first frame is drawn before the writer starts: what cannot be drawn (an object-free
        # plan) raises as itself, not as the writer's complaint of a movie without frames.
        artists = draw(int(frames[0]))
        with atomic_path(out) as tmp, rc_context(rc), _ffmpeg_interrupted(), writer.saving(fig, str(tmp), dpi):
            for i, k in enumerate(frames, start=1):
                if i > 1:
                    for a in artists:
                        a.remove()
                    artists = draw(int(k))
                writer.grab_frame()
                if progress is not None:
                    progress(i, len(frames))
            for _ in range(int(round(hold * fps))):  # a pause on the final grasp
                writer.grab_frame()
    finally:
        plt.close(fig)
    return len(frames)
