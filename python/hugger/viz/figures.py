"""The still figures: the paper's Fig. 4 and Fig. 5, the overview sheet, the TipState plot, and
:func:`render`, which draws one of them or the animation (:data:`FIGURES`), by name or by the file's
extension."""
from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from .._checks import callback, whole
from .._types import CONTACT_DISTANCE
from ..trajectory import Trajectory
from .animation import animate
from .backend import (_MOVIE_EXTENSIONS, RENDER_SUFFIXES, _check_faces, _check_still, _check_traj, check_dpi,
                      _pyplot, _save, _suffix)
from .scene import STATE_COLORS, _STATE_NAMES, _Scene, _legend, _phase_name, _subsample, draw_configuration


# --- picking the configurations of Fig. 4 --------------------------------------------------------

def _first_contact(traj: Trajectory) -> tuple[int | None, str]:
    """The first configuration in which some finger is no longer FROZEN, else the first Phase 2
    configuration (a plan that ended before any contact), with its caption."""
    touched = np.flatnonzero(np.any(traj.tip_state != 0, axis=1))
    if len(touched):
        return int(touched[0]), "first contact"
    p2 = np.flatnonzero(traj.phase == 2)
    return (int(p2[0]), "Phase 2 starts") if len(p2) else (None, "")


def _fig4_panels(traj: Trajectory) -> list[tuple[int, str]]:
    """(k, caption) of the panels: C_init, end of Phase 1, first contact, two intermediate
    Phase 2 configurations, the final one. Indices are distinct; panels that would repeat one
    (no Phase 1, a short plan) are left out."""
    last = len(traj) - 1
    cands: list[tuple[int | None, str]] = [(0, "initial")]
    p1 = np.flatnonzero(traj.phase == 1)
    cands.append((int(p1[-1]) if len(p1) else None, "after Phase 1"))
    fc, caption = _first_contact(traj)
    cands.append((fc, caption))
    if fc is not None:
        for frac in (1 / 3, 2 / 3):
            cands.append((int(round(fc + frac * (last - fc))), "intermediate"))
    cands.append((last, "final"))
    out: list[tuple[int, str]] = []
    seen: set[int] = set()
    for k, caption in cands:
        if k is None or k in seen:
            continue
        if caption == "intermediate" and k in (fc, last):
            continue
        seen.add(k)
        out.append((k, caption))
    out.sort(key=lambda kc: kc[0])
    return out


# --- the figures ----------------------------------------------------------------------------------

FIG4_SIZE = (10.0, 9.0)
FIG5_SIZE = (10.0, 5.2)
TIPSTATE_SIZE = (9.0, 5.5)
OVERVIEW_SIZE = (13.0, 9.0)


def _fig4_axes(fig: Any, traj: Trajectory, scene: _Scene, grid: Any, cells: Sequence[tuple[int, int]]) -> list[Any]:
    panels = _fig4_panels(traj)
    rows = sorted({r for r, _ in cells})
    # one box for every panel: one scale (and one camera) across the figure, as in the paper
    common = scene.limits([k for k, _ in panels])
    limits = {r: common for r in rows}
    axes = []
    for (k, caption), (r, c), letter in zip(panels, cells, "abcdefgh"):
        ax = fig.add_subplot(grid[r, c], projection="3d")
        draw_configuration(ax, traj, k, view="side", limits=limits[r], _scene=scene)
        ax.set_title(f"({letter}) {caption}\nk = {k}, {_phase_name(traj, k)}", fontsize=9, pad=-4)
        axes.append(ax)
    return axes


def _still(traj: Any, path: Any, dpi: Any, max_faces: Any) -> tuple[Any, Trajectory, float, _Scene]:
    """Checked arguments of a still figure: (pyplot, trajectory, dpi, scene)."""
    plt = _pyplot()
    traj = _check_traj(traj)
    _check_still(path)
    return plt, traj, check_dpi(dpi), _Scene(traj, _check_faces(max_faces))


def fig4(traj: Trajectory, path: str | os.PathLike[str] | None = None, *, dpi: float = 120,
         max_faces: int = 20000) -> Any:
    """The paper's Fig. 4: the plan in six panels, (a) C_init, (b) after Phase 1 (reorientation),
    (c) first contact (the first configuration in which a finger leaves FROZEN; the first Phase 2
    configuration if none does), (d), (e) two intermediate Phase 2 configurations (a third and two
    thirds of the way from (c) to the end), (f) the final one. All panels share one camera (fixed
    to the final palm pose) and one scale. A panel that would repeat
    another's configuration (no Phase 1, a very short plan) is left out, so there may be fewer
    than six. Each panel's title gives its letter, what it shows, the configuration index k and
    the phase. Saves to ``path`` (PNG, PDF or SVG) and closes the figure when ``path`` is given;
    returns the Figure."""
    plt, traj, dpi, scene = _still(traj, path, dpi, max_faces)
    fig = plt.figure(figsize=FIG4_SIZE)
    grid = fig.add_gridspec(2, 3, left=0.0, right=1.0, top=0.9, bottom=0.06, wspace=0.0, hspace=0.12)
    _fig4_axes(fig, traj, scene, grid, [(0, 0), (0, 1), (0, 2), (1, 0), (1, 1), (1, 2)])
    fig.suptitle(_headline(traj), fontsize=10)
    _legend(fig)
    if path is not None:
        _save(fig, path, dpi)
    return fig


def _headline(traj: Trajectory) -> str:
    h = traj.hand
    ll = np.asarray(h["link_lengths"], dtype=float) * 1000
    lo, hi = round(float(ll.min())), round(float(ll.max()))  # a range for unequal links, not their mean
    lengths = f"{lo} mm" if lo == hi else f"{lo}-{hi} mm"
    return (f"{h['fingers']} fingers x {h['links']} links ({lengths}, radius "
            f"{float(h['link_radius']) * 1000:.1f} mm), {len(traj.object_faces)} triangles, "
            f"{len(traj)} configurations, status {traj.status}")


def _fig5_axes(fig: Any, traj: Trajectory, scene: _Scene, cells: Sequence[Any]) -> list[Any]:
    k = len(traj) - 1
    limits = scene.limits([k])
    axes = []
    views = (("side", "side view"), ("normal", "along the palm normal,\nseen from beyond O"))
    for cell, (camera, caption) in zip(cells, views):
        ax = fig.add_subplot(cell, projection="3d")
        draw_configuration(ax, traj, k, view=camera, limits=limits, _scene=scene)
        ax.set_title(f"final grasp, {caption}", fontsize=9, pad=-4)
        axes.append(ax)
    return axes


def fig5(traj: Trajectory, path: str | os.PathLike[str] | None = None, *, dpi: float = 120,
         max_faces: int = 20000) -> Any:
    """The paper's Fig. 5: two views of the final grasp, from the side (perpendicular to the palm
    normal) and along the palm normal, seen from beyond the object looking back at the palm, so
    the fingers are seen closing round O. The title counts the links and palm within 1 mm of O.
    Saves to ``path`` (PNG, PDF or SVG) and closes the figure when given; returns the Figure."""
    plt, traj, dpi, scene = _still(traj, path, dpi, max_faces)
    fig = plt.figure(figsize=FIG5_SIZE)
    grid = fig.add_gridspec(1, 2, left=0.0, right=1.0, top=0.86, bottom=0.08, wspace=0.0)
    _fig5_axes(fig, traj, scene, [grid[0, 0], grid[0, 1]])
    fig.suptitle(_contact_caption(traj, scene), fontsize=10)
    _legend(fig)
    if path is not None:
        _save(fig, path, dpi)
    return fig


def _contact_caption(traj: Trajectory, scene: _Scene) -> str:
    s = traj.summary(CONTACT_DISTANCE, obj=scene.object)
    return (f"final configuration k = {len(traj) - 1}: {s['links_in_contact']} of {s['links']} "
            f"links and {'the' if s['palm_contact'] else 'not the'} palm within "
            f"{CONTACT_DISTANCE * 1000:g} mm of O, status {traj.status}")


def overview(traj: Trajectory, path: str | os.PathLike[str] | None = None, *, dpi: float = 100,
             max_faces: int = 20000) -> Any:
    """One sheet: Fig. 4's panels (2 x 3, left) and Fig. 5's two views of the final grasp (right
    column). This is what :func:`render` writes for PNG, PDF and SVG."""
    plt, traj, dpi, scene = _still(traj, path, dpi, max_faces)
    fig = plt.figure(figsize=OVERVIEW_SIZE)
    grid = fig.add_gridspec(2, 4, left=0.0, right=1.0, top=0.92, bottom=0.06, wspace=0.0, hspace=0.1)
    _fig4_axes(fig, traj, scene, grid, [(0, 0), (0, 1), (0, 2), (1, 0), (1, 1), (1, 2)])
    _fig5_axes(fig, traj, scene, [grid[0, 3], grid[1, 3]])
    fig.suptitle(_headline(traj) + "\n" + _contact_caption(traj, scene), fontsize=10)
    _legend(fig)
    if path is not None:
        _save(fig, path, dpi)
    return fig


def tipstate_plot(traj: Trajectory, path: str | os.PathLike[str] | None = None, *, dpi: float = 120,
                  max_samples: int = 400) -> Any:
    """TipState of every finger over the configurations (an image: rows are fingers 0..M-1,
    columns configurations k), with the start of Phase 2 and the first contact marked; below, the
    number of links within 1 mm of O and whether the palm is (shaded), over the configurations,
    computed on at most ``max_samples`` evenly spread configurations. Saves to ``path`` and
    closes the figure when given; returns the Figure."""
    plt = _pyplot()
    from matplotlib.colors import ListedColormap
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    traj = _check_traj(traj)
    _check_still(path)
    dpi = check_dpi(dpi)
    max_samples = whole("max_samples", max_samples, 1)
    count, fingers = traj.tip_state.shape
    obj = traj.object()
    ks = _subsample(count, max_samples)
    touching = np.array([int(np.sum(traj.link_gaps(k, obj) <= CONTACT_DISTANCE)) for k in ks])
    palm = np.array([traj.palm_gap(k, obj) <= CONTACT_DISTANCE for k in ks])

    fig, (top, bottom) = plt.subplots(2, 1, figsize=TIPSTATE_SIZE, sharex=True,
                                      gridspec_kw={"height_ratios": [1.3, 1.0], "hspace": 0.08})
    fig.subplots_adjust(left=0.1, right=0.98, top=0.86, bottom=0.1)
    top.imshow(traj.tip_state.T.astype(float), aspect="auto", interpolation="nearest",
               cmap=ListedColormap(STATE_COLORS), vmin=-0.5, vmax=2.5,
               extent=(-0.5, count - 0.5, fingers - 0.5, -0.5))
    top.set_yticks(range(fingers))
    top.set_yticklabels([f"finger {m}" for m in range(fingers)], fontsize=8)
    top.set_ylabel("TipState", fontsize=9)
    for m in range(fingers - 1):
        top.axhline(m + 0.5, color="white", lw=1.0)
    marks = []
    p2 = np.flatnonzero(traj.phase == 2)
    if len(p2):
        marks.append((int(p2[0]) - 0.5, "k", "--", f"Phase 2 starts (k = {int(p2[0])})"))
    touched = np.flatnonzero(np.any(traj.tip_state != 0, axis=1))
    if len(touched):
        marks.append((int(touched[0]) - 0.5, "0.3", ":", f"first contact (k = {int(touched[0])})"))
    for ax in (top, bottom):
        for x, color, style, _ in marks:
            ax.axvline(x, color=color, ls=style, lw=1.3)
    for p in (1, 2):
        idx = np.flatnonzero(traj.phase == p)
        if len(idx):
            bottom.text((idx[0] + idx[-1]) / 2.0, 0.97, f"Phase {p}", transform=bottom.get_xaxis_transform(),
                        ha="center", va="top", fontsize=8, color="0.3")
    handles: list[Any] = [Patch(color=c, label=s) for c, s in zip(STATE_COLORS, _STATE_NAMES)]
    handles += [Line2D([], [], color=c, ls=s, label=label) for _, c, s, label in marks]
    fig.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.54, 0.945), ncol=len(handles), fontsize=8,
               frameon=False)

    bottom.plot(ks, touching, drawstyle="steps-post", color="#333333", lw=1.4,
                label=f"links within {CONTACT_DISTANCE * 1000:g} mm of O")
    if palm.any():
        bottom.fill_between(ks, 0, 1, where=palm, step="post", color="#9467bd", alpha=0.25,
                            transform=bottom.get_xaxis_transform(),
                            label=f"palm within {CONTACT_DISTANCE * 1000:g} mm of O")
    links = traj.joints.shape[1] * (traj.joints.shape[2] - 1)
    bottom.set_ylim(-0.05 * links, links * 1.05)
    bottom.set_xlim(-0.5, count - 0.5)
    bottom.set_ylabel("links in contact", fontsize=9)
    bottom.set_xlabel("configuration k", fontsize=9)
    bottom.legend(loc="center left", fontsize=8, frameon=False)
    bottom.grid(alpha=0.3)
    sampled = "" if len(ks) == count else f" (contacts on {len(ks)} sampled configurations)"
    fig.suptitle(f"{len(traj)} configurations, status {traj.status}{sampled}", fontsize=10, y=0.985)
    if path is not None:
        _save(fig, path, dpi)
    return fig


# --- dispatch ------------------------------------------------------------------------------------------

#: What :func:`render` draws, by name (``hugger render --figure``): the drawing function, and what it shows.
FIGURES: dict[str, tuple[Callable[..., Any], str]] = {
    "sheet": (overview, "Fig. 4's panels and Fig. 5's two views on one sheet"),
    "fig4": (fig4, "the paper's Fig. 4"),
    "fig5": (fig5, "the paper's Fig. 5"),
    "tipstate": (tipstate_plot, "TipState and links in contact over the plan"),
    "animation": (animate, "the whole plan as a GIF or MP4"),
}


def pick_figure(path: Any, figure: str | None = None) -> str:
    """The name in :data:`FIGURES` that :func:`render` draws into ``path``: ``figure``, or by default
    ``sheet`` for a still (.png, .pdf, .svg) and ``animation`` for a movie (.gif, .mp4).
    ``ValueError`` for an extension not in :data:`RENDER_SUFFIXES`, an unknown figure, or a figure
    that does not write that extension (the animation is a movie, every other figure a still)."""
    ext = _suffix(path)
    if ext not in RENDER_SUFFIXES:
        raise ValueError(f"cannot render to {Path(os.fspath(path)).name!r}: use one of {', '.join(RENDER_SUFFIXES)}")
    movie = ext in _MOVIE_EXTENSIONS
    name = figure if figure is not None else "animation" if movie else "sheet"
    if name not in FIGURES:
        raise ValueError(f"figure must be one of {', '.join(FIGURES)}, got {figure!r}")
    if (name == "animation") != movie:
        want = ".gif or .mp4" if name == "animation" else ".png, .pdf or .svg"
        raise ValueError(f"figure {name} writes {want}, got {Path(os.fspath(path)).name!r}")
    return name


def render(traj: Trajectory, path: str | os.PathLike[str], *, figure: str | None = None,
           progress: Callable[[int, int], Any] | None = None, **kwargs: Any) -> Path:
    """Write a picture of the plan: ``figure``, a name in :data:`FIGURES`, or by default one chosen
    by the extension of ``path`` (case-insensitive):

    * ``.png``, ``.pdf``, ``.svg``: :func:`overview`, one sheet with Fig. 4's panels and Fig. 5's
      two views of the final grasp;
    * ``.gif``, ``.mp4``: :func:`animate`, the whole plan.

    ``progress(i, n)`` is passed to :func:`animate` (called once, (1, 1), for a still picture).
    Extra keyword arguments go to that function. Returns the path written. ``ValueError`` for
    any other extension (:data:`RENDER_SUFFIXES` lists those accepted) or a figure that does not
    write it (see :func:`pick_figure`)."""
    traj = _check_traj(traj)
    callback("progress", progress, "progress(i, n)")
    name = pick_figure(path, figure)
    draw = FIGURES[name][0]
    if name == "animation":
        draw(traj, path, progress=progress, **kwargs)
    else:
        draw(traj, path, **kwargs)
        if progress is not None:
            progress(1, 1)
    return Path(os.fspath(path))
