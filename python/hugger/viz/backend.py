"""matplotlib (with the Agg backend) and ffmpeg, loaded on first use, and the checks of arguments and
paths shared by the figures and the animation."""
from __future__ import annotations

import os
import shutil
from pathlib import Path
from typing import Any

from .._checks import positive, whole
from .._files import atomic_path
from ..trajectory import Trajectory

_STILL_EXTENSIONS = (".png", ".pdf", ".svg")
_MOVIE_EXTENSIONS = (".gif", ".mp4")
#: The extensions :func:`render` writes.
RENDER_SUFFIXES = _STILL_EXTENSIONS + _MOVIE_EXTENSIONS
_VIZ_EXTRA = "pip install 'hugger[viz]'"
#: The largest resolution a figure or animation is drawn at (dots per inch): print needs 300-600,
#: and a page-wide figure at this resolution is already about 20,000 pixels wide.
MAX_DPI = 1200.0
#: The smallest: below it the titles' fonts cannot be drawn (FreeType refuses a size under one pixel).
MIN_DPI = 10.0
#: The highest frame rate of an animation (an MP4's; a GIF's frame delays are whole hundredths of a
#: second, so it shows at most 100 frames a second).
MAX_FPS = 120.0
#: The longest pause on an animation's final grasp (s): its frames are written out one by one.
MAX_HOLD = 10.0


# --- optional dependencies ---------------------------------------------------------------------

def _backend_unset(matplotlib: Any) -> bool:
    """True while neither the user, MPLBACKEND nor matplotlibrc has chosen a backend."""
    get = getattr(matplotlib.rcParams, "_get_backend_or_none", None)  # matplotlib >= 3.8
    if get is not None:
        return get() is None
    from matplotlib import rcsetup

    return dict.__getitem__(matplotlib.rcParams, "backend") is rcsetup._auto_backend_sentinel


def _pyplot() -> Any:
    """matplotlib.pyplot, with the Agg backend selected if no backend was chosen yet."""
    try:
        import matplotlib
    except ImportError as exc:
        raise ImportError(f"hugger.viz needs matplotlib and Pillow: {_VIZ_EXTRA}") from exc
    if _backend_unset(matplotlib):
        matplotlib.use("Agg")
    try:
        import matplotlib.pyplot as plt
        from mpl_toolkits.mplot3d import Axes3D  # noqa: F401  (registers the 3d projection)
    except ImportError as exc:
        raise ImportError(f"hugger.viz needs matplotlib and Pillow: {_VIZ_EXTRA}") from exc
    return plt


def require() -> None:
    """Raise ``ImportError`` naming the ``viz`` extra unless matplotlib can be imported; a cheap
    check for callers (the CLI) that want to fail before long work rather than after it."""
    _pyplot()


def ffmpeg_path() -> str | None:
    """Path of an ffmpeg binary for MP4 output: imageio-ffmpeg's when that package is installed
    (and has one), else ``ffmpeg`` on the PATH, else None."""
    try:
        import imageio_ffmpeg
    except ImportError:
        imageio_ffmpeg = None
    if imageio_ffmpeg is not None:
        try:
            return str(imageio_ffmpeg.get_ffmpeg_exe())
        except RuntimeError:  # the package is there but has no binary for this platform
            pass
    return shutil.which("ffmpeg")


def _ffmpeg() -> str:
    exe = ffmpeg_path()
    if exe is None:
        raise ImportError("MP4 output needs ffmpeg: pip install imageio-ffmpeg (part of 'hugger[viz]'), or put "
                          "an ffmpeg binary on the PATH (e.g. apt-get install ffmpeg); a .gif needs no ffmpeg")
    return exe


# --- argument checks ----------------------------------------------------------------------------

def _check_traj(traj: Any) -> Trajectory:
    if not isinstance(traj, Trajectory):
        raise ValueError(f"traj must be a hugger.Trajectory, got {type(traj).__name__}")
    if len(traj) == 0:
        raise ValueError("the trajectory holds no configurations")
    return traj


def _check_faces(max_faces: Any) -> int:
    return whole("max_faces", max_faces, 100)


def check_dpi(dpi: Any) -> float:
    """``dpi`` as a float: from :data:`MIN_DPI` to :data:`MAX_DPI`; otherwise a ValueError."""
    return positive("dpi", dpi, most=MAX_DPI, least=MIN_DPI)


def check_fps(fps: Any) -> float:
    """``fps`` as a float: positive and at most :data:`MAX_FPS`; otherwise a ValueError."""
    return positive("fps", fps, most=MAX_FPS)


def _suffix(path: Any) -> str:
    try:
        return Path(os.fspath(path)).suffix.lower()
    except TypeError:
        raise ValueError(f"path must be a file path, got {path!r}") from None


def _check_still(path: Any) -> None:
    """``ValueError`` unless ``path`` is None or names a PNG, PDF or SVG file."""
    if path is not None and _suffix(path) not in _STILL_EXTENSIONS:
        raise ValueError(f"cannot write a figure to {Path(os.fspath(path)).name!r}: "
                         f"use one of {', '.join(_STILL_EXTENSIONS)}")


def _save(fig: Any, path: Any, dpi: float) -> None:
    """Save (creating the parent folder; atomically: complete under its name, or not there) and close."""
    plt = _pyplot()
    p = Path(os.fspath(path))
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(p) as tmp:
            fig.savefig(tmp, dpi=dpi)
    finally:
        plt.close(fig)
