"""Figures and animations of a plan (matplotlib): the paper's Fig. 4 and Fig. 5, a TipState plot,
GIF/MP4 animations, and :func:`render`, which the command line calls. :func:`view` (an interactive
3D view in the browser) and :func:`export_scene` (a glTF scene) come from :mod:`hugger.viewer`.

Needs the ``viz`` extra (``pip install 'hugger[viz]'``: matplotlib and Pillow); MP4 also needs an
ffmpeg binary (the ``imageio-ffmpeg`` package, or ``ffmpeg`` on the ``PATH``). Nothing here is
imported by ``import hugger``; matplotlib is imported when a function is first called, and the
non-interactive Agg backend is selected then, only if no backend has been chosen yet.

What the pictures show
----------------------
The object O is a semi-transparent, light-shaded mesh (meshes over ``max_faces`` triangles are
simplified for drawing only); each link is a capsule of the link radius; the palm is a disc of
``palm_radius`` and ``palm_thickness`` whose front face is at the palm origin P_o; T is a black
cross; contacts are red dots, drawn on top of everything. Zero-radius links (the paper's) are
drawn as thin tubes (4% of the mean link length) with dark beads at the joints: a thick line
that is still depth-sorted with the object and the palm. Fingers are coloured by their TipState
at that configuration: FROZEN blue, CONTACT orange, DONE green.

Contacts are those of :func:`hugger.analysis.contacts` (gap at most ``CONTACT_DISTANCE``, 1 mm).

The camera is fixed to the *final* palm pose, not to the world: every 3D view is drawn in a
"display frame" centred on T, in which the final palm normal p-hat points down the screen (the
display -z axis) and finger 0 along the display x axis, so the grasp reads the same whichever
way the hand approached. Axes are hidden
(the figures are about shape, as in the paper); lengths in the titles are in millimetres.
Configuration indices ``k`` count from 0 (C_init) to K-1, as in the trajectory file.
"""
from __future__ import annotations

import math
import os
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from ._checks import positive
from .trajectory import CONTACT_DISTANCE, Trajectory
from .viewer import export_scene, view  # the 3D viewer and glTF export (extra: view), hugger.viz.view

__all__ = ["CONTACT_DISTANCE", "RENDER_SUFFIXES", "STATE_COLORS", "animate", "draw_configuration", "export_scene",
           "ffmpeg_path", "fig4", "fig5", "overview", "render", "require", "tipstate_plot", "view"]

#: Colours of the TipStates FROZEN, CONTACT, DONE.
STATE_COLORS = ("#3b6fb6", "#e8842c", "#2e9e4f")
_STATE_NAMES = ("FROZEN", "CONTACT", "DONE")
_OBJECT_RGB = np.array([0.82, 0.75, 0.66])
_OBJECT_ALPHA = 0.5
_PALM_RGB = np.array([0.50, 0.50, 0.55])
_CONTACT_COLOR = "#d62728"
_STILL_EXTENSIONS = (".png", ".pdf", ".svg")
_MOVIE_EXTENSIONS = (".gif", ".mp4")
#: The extensions :func:`render` writes.
RENDER_SUFFIXES = _STILL_EXTENSIONS + _MOVIE_EXTENSIONS
_VIZ_EXTRA = "pip install 'hugger[viz]'"


# --- optional dependencies ---------------------------------------------------------------------

def _backend_unset(matplotlib: Any) -> bool:
    """True while neither the user, MPLBACKEND nor matplotlibrc has chosen a backend."""
    get = getattr(matplotlib.rcParams, "_get_backend_or_none", None)  # matplotlib >= 3.8
    if get is not None:
        return get() is None
    from matplotlib import rcsetup

    return dict.__getitem__(matplotlib.rcParams, "backend") is rcsetup._auto_backend_sentinel


def _pyplot():
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
    if isinstance(max_faces, bool) or not isinstance(max_faces, (int, np.integer)) or max_faces < 100:
        raise ValueError(f"max_faces must be a whole number >= 100, got {max_faces!r}")
    return int(max_faces)


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
    """Save (creating the parent folder) and close."""
    plt = _pyplot()
    p = Path(os.fspath(path))
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(p, dpi=dpi)
    finally:
        plt.close(fig)


# --- geometry of the drawing --------------------------------------------------------------------

def _decimate(vertices: np.ndarray, faces: np.ndarray, max_faces: int) -> tuple[np.ndarray, np.ndarray]:
    """Vertex clustering on a grid until at most ``max_faces`` triangles remain (drawing only)."""
    if len(faces) <= max_faces:
        return vertices, faces
    lo = vertices.min(axis=0)
    extent = float(np.ptp(vertices, axis=0).max()) or 1.0
    res = max(4, int(math.sqrt(max_faces / 2.0)))
    while True:
        cell = extent / res
        keys = np.floor((vertices - lo) / cell).astype(np.int64)
        _, inverse, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
        inverse = inverse.reshape(-1)
        v = np.zeros((len(counts), 3))
        np.add.at(v, inverse, vertices)
        v /= counts[:, None]
        f = inverse[faces]
        f = f[(f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 2] != f[:, 0])]
        _, first = np.unique(np.sort(f, axis=1), axis=0, return_index=True)
        f = f[np.sort(first)]
        if len(f) <= max_faces or res <= 4:
            return v, f
        res = max(4, int(res * 0.8))


def _frame(normal: np.ndarray, hint: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors completing ``normal`` to an orthonormal frame, the first near ``hint``."""
    u = hint - normal * float(hint @ normal)
    if np.linalg.norm(u) < 1e-9:
        u = np.array([1.0, 0.0, 0.0]) if abs(normal[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        u = u - normal * float(u @ normal)
    u /= np.linalg.norm(u)
    return u, np.cross(normal, u)


def _ring(center: np.ndarray, axis: np.ndarray, radius: float, sides: int, phase: float = 0.0):
    u, v = _frame(axis, np.array([0.3, 0.5, 0.8]))
    t = phase + 2 * np.pi * np.arange(sides) / sides
    dirs = np.cos(t)[:, None] * u + np.sin(t)[:, None] * v
    return center + radius * dirs, dirs


def _tube(a: np.ndarray, b: np.ndarray, radius: float, sides: int = 10):
    """Quads (sides, 4, 3) and outward normals (sides, 3) of a cylinder from a to b."""
    axis = b - a
    length = float(np.linalg.norm(axis))
    axis = axis / length if length > 0 else np.array([0.0, 0.0, 1.0])
    ra, dirs = _ring(a, axis, radius, sides)
    rb = ra + (b - a)
    j = (np.arange(sides) + 1) % sides
    quads = np.stack([ra, ra[j], rb[j], rb], axis=1)
    normals = dirs + dirs[j]
    return quads, normals / np.linalg.norm(normals, axis=1, keepdims=True)


def _unit_sphere(lon: int = 8, lat: int = 4):
    th = np.linspace(0, np.pi, lat + 1)
    ph = 2 * np.pi * np.arange(lon) / lon
    p = np.stack([np.sin(th)[:, None] * np.cos(ph), np.sin(th)[:, None] * np.sin(ph),
                  np.cos(th)[:, None] * np.ones_like(ph)], axis=-1)  # (lat+1, lon, 3)
    quads = []
    for i in range(lat):
        for j in range(lon):
            jj = (j + 1) % lon
            quads.append([p[i, j], p[i + 1, j], p[i + 1, jj], p[i, jj]])
    q = np.array(quads)
    n = q.mean(axis=1)
    return q, n / np.linalg.norm(n, axis=1, keepdims=True)


_SPHERE_QUADS, _SPHERE_NORMALS = _unit_sphere()


def _palm_polys(pose: np.ndarray, radius: float, thickness: float, sides: int = 28):
    """Quads (P, 4, 3) and outward normals (P, 3) of the palm disc: front face at P_o, back face
    at -thickness along the normal (the faces are fans of triangles stored as quads)."""
    rot, origin = pose[:3, :3], pose[:3, 3]
    normal = rot[:, 2]
    t = 2 * np.pi * np.arange(sides) / sides
    dirs = np.cos(t)[:, None] * rot[:, 0] + np.sin(t)[:, None] * rot[:, 1]
    front = origin + radius * dirs
    back = front - thickness * normal
    j = (np.arange(sides) + 1) % sides
    side = np.stack([front, front[j], back[j], back], axis=1)
    sn = dirs + dirs[j]
    fc, bc = np.broadcast_to(origin, front.shape), np.broadcast_to(origin - thickness * normal, back.shape)
    front_fan = np.stack([fc, front, front[j], front[j]], axis=1)
    back_fan = np.stack([bc, back[j], back, back], axis=1)
    quads = np.concatenate([front_fan, back_fan, side])
    normals = np.vstack([np.tile(normal, (sides, 1)), np.tile(-normal, (sides, 1)),
                         sn / np.linalg.norm(sn, axis=1, keepdims=True)])
    return quads, normals


def _shade(rgb: np.ndarray, normals: np.ndarray, light: np.ndarray, ambient: float = 0.38) -> np.ndarray:
    """Lambert shading with a head light: (n, 3) colours from (3,) or (n, 3) base colours."""
    # "wrapped" diffuse term: faces at right angles to the light keep some light
    lam = np.clip((normals @ light + 0.4) / 1.4, 0.0, 1.0)
    return np.clip(np.asarray(rgb) * (ambient + (1.0 - ambient) * lam)[:, None], 0.0, 1.0)


def _rgb(color: str) -> np.ndarray:
    from matplotlib.colors import to_rgb

    return np.array(to_rgb(color))


# --- the scene: one trajectory, seen in the display frame ---------------------------------------

@dataclass(frozen=True)
class _View:
    """A camera in the display frame: elevation and azimuth (deg) as in ``Axes3D.view_init``."""

    elev: float
    azim: float

    @property
    def eye(self) -> np.ndarray:
        e, a = math.radians(self.elev), math.radians(self.azim)
        return np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])

    @property
    def light(self) -> np.ndarray:
        eye = self.eye
        right = np.cross(np.array([0.0, 0.0, 1.0]), eye)
        right = right / np.linalg.norm(right) if np.linalg.norm(right) > 1e-9 else np.array([1.0, 0.0, 0.0])
        up = np.cross(eye, right)
        d = 0.7 * eye + 0.65 * up - 0.45 * right  # a key light above and to the left of the camera
        return d / np.linalg.norm(d)


_SIDE = _View(elev=12.0, azim=-62.0)
_ALONG_NORMAL = _View(elev=-90.0, azim=-90.0)
_OBLIQUE = _View(elev=38.0, azim=-62.0)


_VIEWS = {"side": _SIDE, "normal": _ALONG_NORMAL, "oblique": _OBLIQUE}


def _camera(view: Any) -> _View:
    if not isinstance(view, str) or view not in _VIEWS:
        raise ValueError(f"view must be one of {sorted(_VIEWS)}, got {view!r}")
    return _VIEWS[view]


class _Scene:
    """A trajectory prepared for drawing: display frame, simplified object mesh, contact finder."""

    def __init__(self, traj: Trajectory, max_faces: int) -> None:
        self.traj = traj
        h = traj.hand
        self.radius = float(h["link_radius"])
        self.palm_radius = float(h["palm_radius"])
        self.palm_thickness = float(h["palm_thickness"])
        lengths = np.asarray(h["link_lengths"], dtype=float)
        # zero-thickness links (the paper's) are drawn as thin tubes: a thick line that still
        # hides, and is hidden by, the rest of the scene
        self.draw_radius = self.radius if self.radius > 0 else 0.04 * float(lengths.mean())
        final = traj.palm_pose[-1]
        z = -final[:3, 2]  # the final palm normal points down the screen
        x, y = _frame(z, final[:3, 0])
        self.rot = np.vstack([x, y, z])  # world -> display
        self.origin = np.asarray(traj.target, dtype=float)
        v, f = _decimate(np.asarray(traj.object_vertices, dtype=float), np.asarray(traj.object_faces), max_faces)
        tris = self.to_display(v)[f]
        n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
        self.tris = tris[:, [0, 1, 2, 2]]  # drawn as quads with a repeated corner: one array, no ragged rows
        norm = np.linalg.norm(n, axis=1, keepdims=True)
        self.tri_normals = n / np.where(norm > 0, norm, 1.0)
        self._object = None
        self._contacts: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def to_display(self, p: np.ndarray) -> np.ndarray:
        return (np.asarray(p, dtype=float) - self.origin) @ self.rot.T

    @property
    def object(self):
        if self._object is None:
            self._object = self.traj.object()
        return self._object

    def contacts(self, k: int) -> np.ndarray:
        """Contact points (C, 3) of configuration k, in the world frame."""
        return self._contact_set(k)[0]

    def _contact_set(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Contact points (C, 3) of configuration k and which of them are the palm's (C,) bool."""
        if k not in self._contacts:
            from . import analysis

            c = analysis.contacts(self.traj, k, obj=self.object)
            self._contacts[k] = (np.asarray(c.points, dtype=float).reshape(-1, 3), np.asarray(c.finger) < 0)
        return self._contacts[k]

    def visible_contacts(self, k: int, cam: _View) -> np.ndarray:
        """The contact points of configuration k that ``cam`` can see: the palm's contacts lie
        between the opaque palm and the object, so they are left out when the camera is behind
        the palm (on the side of its back face); the links' always show."""
        points, palm = self._contact_set(k)
        normal = self.rot @ self.traj.palm_pose[k][:3, 2]  # the palm normal in the display frame
        if palm.any() and float(cam.eye @ normal) <= 0.0:
            return points[~palm]
        return points

    def pose_display(self, k: int) -> np.ndarray:
        pose = np.eye(4)
        pose[:3, :3] = self.rot @ self.traj.palm_pose[k][:3, :3]
        pose[:3, 3] = self.to_display(self.traj.palm_pose[k][:3, 3])
        return pose

    def points(self, k: int) -> np.ndarray:
        """Every point of the hand's drawing at configuration k (display frame), for axis limits."""
        joints = self.to_display(self.traj.joints[k].reshape(-1, 3))
        pose = self.pose_display(k)
        rim, _ = _palm_polys(pose, self.palm_radius, self.palm_thickness, sides=12)
        return np.vstack([joints, rim.reshape(-1, 3)])

    def limits(self, ks: Sequence[int]) -> _Box:
        """The box (display frame) holding the object and the hand at configurations ks."""
        pts = np.vstack([self.tris.reshape(-1, 3)] + [self.points(k) for k in ks])
        pad = max(self.draw_radius, 0.002)
        return _Box(pts.min(axis=0) - pad, pts.max(axis=0) + pad, pts, 1.6 * self.draw_radius)


@dataclass(frozen=True)
class _Box:
    """Axis limits (display frame): corners ``lo``, ``hi`` (3,), the points (P, 3) they hold and
    how far (m) the drawing reaches beyond those points (the link radius)."""

    lo: np.ndarray
    hi: np.ndarray
    points: np.ndarray
    reach: float = 0.0

    def zoom(self, cam: _View) -> float:
        """The ``zoom`` of ``Axes3D.set_box_aspect`` that makes the points fill the axes.

        matplotlib draws a 3D axes in a square and scales the box so that its diagonal is about
        1.03 times the square's side at zoom 1, whatever the view (measured, matplotlib 3.9+);
        the box's centre sits at the square's centre, and the drawing is clipped to the square.
        So the points fit, with a small margin, when zoom = 0.9 * diagonal / (largest projected
        extent about the centre)."""
        a = math.radians(cam.azim)
        right = np.array([-math.sin(a), math.cos(a), 0.0])
        up = np.cross(cam.eye, right)
        rel = self.points - (self.lo + self.hi) / 2.0
        extent = 2.0 * (max(float(np.abs(rel @ right).max()), float(np.abs(rel @ up).max())) + self.reach)
        if extent <= 0:
            return 1.0
        return float(np.clip(0.9 * np.linalg.norm(self.hi - self.lo) / extent, 0.5, 4.0))


def _contact_points(traj: Trajectory, k: int, obj) -> np.ndarray:
    """Contact points (C, 3) at configuration k, from :func:`hugger.analysis.contacts`."""
    from . import analysis

    return np.asarray(analysis.contacts(traj, k, obj=obj).points, dtype=float).reshape(-1, 3)


def _hand_polys(scene: _Scene, k: int, light: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Quads (P, 4, 3) in the display frame and their RGBA colours (P, 4) for the hand at k."""
    traj = scene.traj
    polys: list[np.ndarray] = []
    colors: list[np.ndarray] = []
    joints = scene.to_display(traj.joints[k].reshape(-1, 3)).reshape(traj.joints[k].shape)
    r = scene.draw_radius
    for m in range(joints.shape[0]):
        base = _rgb(STATE_COLORS[int(traj.tip_state[k, m]) % 3])
        for n in range(joints.shape[1] - 1):
            quads, normals = _tube(joints[m, n], joints[m, n + 1], r, sides=10 if scene.radius > 0 else 6)
            polys.append(quads)
            colors.append(_shade(base, normals, light))
        # joints: spheres of the link radius (capsule ends), or dark beads on zero-radius links
        joint_r, joint_rgb = (r, base * 0.82) if scene.radius > 0 else (1.6 * r, np.full(3, 0.15))
        for p in joints[m]:
            polys.append(_SPHERE_QUADS * joint_r + p)
            colors.append(_shade(joint_rgb, _SPHERE_NORMALS, light))
    palm, pn = _palm_polys(scene.pose_display(k), scene.palm_radius, scene.palm_thickness)
    polys.append(palm)
    colors.append(_shade(_PALM_RGB, pn, light))
    rgb = np.vstack(colors)
    return np.concatenate(polys), np.hstack([rgb, np.ones((len(rgb), 1))])


def draw_configuration(ax: Any, traj: Trajectory, k: int = -1, *, view: str = "side",
                       limits: Any = None, contacts: bool = True,
                       max_faces: int = 20000, _scene: _Scene | None = None) -> list:
    """Draw configuration ``k`` of ``traj`` into a 3D axes ``ax``; returns the artists added.

    ``view`` is ``"side"`` (perpendicular to the final palm normal, 12 degrees from the palm's
    side), ``"normal"`` (along the final palm normal, seen from beyond the object, looking back
    at the palm) or ``"oblique"`` (38 degrees from the palm's side).
    ``limits`` = (lower, upper) corners (3,) of the box shown, in the display frame (see the
    module doc); default: the object and this configuration. ``contacts`` marks contacts as red dots
    (the palm's only when the camera sees the palm's front face: behind the palm they are hidden by it).
    """
    _pyplot()
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    traj = _check_traj(traj)
    k = range(len(traj))[k]
    cam = _camera(view)
    scene = _scene if _scene is not None else _Scene(traj, _check_faces(max_faces))
    light = cam.light
    if limits is None:
        limits = scene.limits([k])
    elif not isinstance(limits, _Box):
        lo, hi = (np.asarray(x, dtype=float).reshape(3) for x in limits)
        if not np.all(np.isfinite(lo)) or not np.all(np.isfinite(hi)) or np.any(hi <= lo):
            raise ValueError("limits must be (lower, upper) corners with lower < upper")
        limits = _Box(lo, hi, np.vstack([lo, hi]))

    obj_rgb = _shade(_OBJECT_RGB, scene.tri_normals, light, ambient=0.3)
    obj_rgba = np.hstack([obj_rgb, np.full((len(obj_rgb), 1), _OBJECT_ALPHA)])
    polys, rgba = _hand_polys(scene, k, light)
    all_polys = np.concatenate([scene.tris, polys])
    all_rgba = np.vstack([obj_rgba, rgba])
    artists = []
    # the hand's opaque faces get edges of their own colour, which hides antialiasing seams
    edges = all_rgba.copy()
    edges[: len(obj_rgba), 3] = 0.0
    coll = Poly3DCollection(all_polys, facecolors=all_rgba, edgecolors=edges, linewidths=0.3, zorder=1)
    # thousands of shaded faces: an image in PDF and SVG output (text, legend and dots stay vector),
    # which keeps a sheet under a megabyte or two instead of tens of megabytes
    coll.set_rasterized(True)
    ax.add_collection3d(coll)
    artists.append(coll)
    t = scene.to_display(np.asarray(traj.target, dtype=float)[None])[0]
    artists.append(ax.scatter([t[0]], [t[1]], [t[2]], marker="x", s=40, c="k", linewidths=1.5,
                              depthshade=False, zorder=4))
    if contacts:
        cp = scene.visible_contacts(k, cam)
        if len(cp):
            d = scene.to_display(cp)
            artists.append(ax.scatter(d[:, 0], d[:, 1], d[:, 2], s=14, c=_CONTACT_COLOR, edgecolors="k",
                                      linewidths=0.4, depthshade=False, zorder=3))
    _setup_axes(ax, cam, limits)
    return artists


def _setup_axes(ax: Any, cam: _View, box: _Box) -> None:
    ax.computed_zorder = False
    lo, hi = box.lo, box.hi
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(tuple(hi - lo), zoom=box.zoom(cam))  # equal scale on the three axes
    ax.set_proj_type("ortho")
    ax.view_init(elev=cam.elev, azim=cam.azim)
    ax.set_axis_off()


def _legend(fig: Any, loc: str = "lower center", ncol: int = 5, **kw) -> None:
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    handles = [Patch(color=c, label=s) for c, s in zip(STATE_COLORS, _STATE_NAMES)]
    handles.append(Line2D([], [], ls="", marker="o", ms=5, mfc=_CONTACT_COLOR, mec="k", mew=0.4, label="contact"))
    handles.append(Line2D([], [], ls="", marker="x", ms=6, mec="k", mew=1.5, label="target T"))
    fig.legend(handles=handles, loc=loc, ncol=ncol, frameon=False, fontsize=8, **kw)


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


def _phase_name(traj: Trajectory, k: int) -> str:
    p = int(traj.phase[k])
    return "C_init" if p == 0 else f"Phase {p}"


# --- the figures ----------------------------------------------------------------------------------

FIG4_SIZE = (10.0, 9.0)
FIG5_SIZE = (10.0, 5.2)
TIPSTATE_SIZE = (9.0, 5.5)
OVERVIEW_SIZE = (13.0, 9.0)
MOVIE_SIZE = (6.4, 4.8)


def _fig4_axes(fig, traj: Trajectory, scene: _Scene, grid, cells: Sequence[tuple[int, int]]) -> list:
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


def _still(traj: Any, path: Any, dpi: Any, max_faces: Any):
    """Checked arguments of a still figure: (pyplot, trajectory, dpi, scene)."""
    plt = _pyplot()
    traj = _check_traj(traj)
    _check_still(path)
    return plt, traj, positive("dpi", dpi), _Scene(traj, _check_faces(max_faces))


def fig4(traj: Trajectory, path: str | os.PathLike | None = None, *, dpi: float = 120,
         max_faces: int = 20000):
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
    ll = np.asarray(h["link_lengths"], dtype=float)
    return (f"{h['fingers']} fingers x {h['links']} links ({ll.mean() * 1000:.0f} mm, radius "
            f"{float(h['link_radius']) * 1000:.1f} mm), {len(traj.object_faces)} triangles, "
            f"{len(traj)} configurations, status {traj.status}")


def _fig5_axes(fig, traj: Trajectory, scene: _Scene, cells) -> list:
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


def fig5(traj: Trajectory, path: str | os.PathLike | None = None, *, dpi: float = 120, max_faces: int = 20000):
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


def overview(traj: Trajectory, path: str | os.PathLike | None = None, *, dpi: float = 100,
             max_faces: int = 20000):
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


def _subsample(count: int, limit: int) -> np.ndarray:
    """min(count, limit) distinct indices 0..count-1, evenly spread, first and last included."""
    n = min(count, limit)
    return np.unique(np.round(np.linspace(0, count - 1, n)).astype(int))


def tipstate_plot(traj: Trajectory, path: str | os.PathLike | None = None, *, dpi: float = 120,
                  max_samples: int = 400):
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
    dpi = positive("dpi", dpi)
    if isinstance(max_samples, bool) or not isinstance(max_samples, (int, np.integer)) or max_samples < 1:
        raise ValueError(f"max_samples must be a positive whole number, got {max_samples!r}")
    count, fingers = traj.tip_state.shape
    obj = traj.object()
    ks = _subsample(count, int(max_samples))
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
    handles = [Patch(color=c, label=s) for c, s in zip(STATE_COLORS, _STATE_NAMES)]
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


# --- animation --------------------------------------------------------------------------------------

def animate(traj: Trajectory, path: str | os.PathLike, fps: float = 30, max_frames: int = 300, *,
            dpi: float = 100, view: str = "oblique", max_faces: int = 6000,
            progress: Callable[[int, int], Any] | None = None, hold: float = 0.0) -> int:
    """Write the whole plan as a ``.gif`` (Pillow) or ``.mp4`` (ffmpeg, H.264), subsampled evenly to at
    most ``max_frames`` frames (first and last included) at ``fps`` frames per second, with fixed
    axis limits over the plan. ``progress(i, n)`` is called after frame i of n (1-based) is
    written. The object is simplified to ``max_faces`` triangles for speed. ``hold`` (s) shows the
    final grasp that much longer (repeated frames, not counted). Returns the number of
    configurations drawn. ``ValueError`` for another extension or bad numbers; ``ImportError`` (naming
    what to install) when an MP4 is asked for and no ffmpeg is found (see :func:`ffmpeg_path`)."""
    plt = _pyplot()
    from matplotlib import animation, rc_context

    traj = _check_traj(traj)
    ext = _suffix(path)
    if ext not in _MOVIE_EXTENSIONS:
        raise ValueError(f"cannot animate to {Path(os.fspath(path)).name!r}: use .gif or .mp4")
    fps = positive("fps", fps)
    hold = positive("hold", hold, allow_zero=True)
    if isinstance(max_frames, bool) or not isinstance(max_frames, (int, np.integer)) or max_frames < 1:
        raise ValueError(f"max_frames must be a positive whole number, got {max_frames!r}")
    if progress is not None and not callable(progress):
        raise ValueError("progress must be callable as progress(i, n)")
    dpi = positive("dpi", dpi)
    max_faces = _check_faces(max_faces)
    _camera(view)
    rc = {}
    if ext == ".mp4":
        rc["animation.ffmpeg_path"] = _ffmpeg()
        writer = animation.FFMpegWriter(fps=fps, codec="h264", bitrate=-1)
    else:
        writer = animation.PillowWriter(fps=fps)
    frames = _subsample(len(traj), int(max_frames))
    scene = _Scene(traj, max_faces)
    limits = scene.limits(range(len(traj)))
    out = Path(os.fspath(path))
    out.parent.mkdir(parents=True, exist_ok=True)
    fig = plt.figure(figsize=MOVIE_SIZE)
    try:
        ax = fig.add_axes((0.0, 0.08, 1.0, 0.84), projection="3d")
        _legend(fig)
        with rc_context(rc), writer.saving(fig, str(out), dpi):
            artists: list = []
            for i, k in enumerate(frames, start=1):
                for a in artists:
                    a.remove()
                artists = draw_configuration(ax, traj, int(k), view=view, limits=limits, _scene=scene)
                states = np.bincount(traj.tip_state[k].astype(int), minlength=3)
                ax.set_title(f"k = {int(k)} / {len(traj) - 1}, {_phase_name(traj, int(k))}   "
                             f"FROZEN {states[0]}  CONTACT {states[1]}  DONE {states[2]}", fontsize=9)
                writer.grab_frame()
                if progress is not None:
                    progress(i, len(frames))
            for _ in range(int(round(hold * fps))):  # a pause on the final grasp
                writer.grab_frame()
    finally:
        plt.close(fig)
    return len(frames)


# --- dispatch ------------------------------------------------------------------------------------------

def render(traj: Trajectory, path: str | os.PathLike, *, progress: Callable[[int, int], Any] | None = None,
           **kwargs: Any) -> Path:
    """Write a picture of the plan, chosen by the extension of ``path`` (case-insensitive):

    * ``.png``, ``.pdf``, ``.svg``: :func:`overview`, one sheet with Fig. 4's panels and Fig. 5's
      two views of the final grasp;
    * ``.gif``, ``.mp4``: :func:`animate`, the whole plan.

    ``progress(i, n)`` is passed to :func:`animate` (called once, (1, 1), for a still picture).
    Extra keyword arguments go to that function. Returns the path written. ``ValueError`` for
    any other extension (:data:`RENDER_SUFFIXES` lists those accepted)."""
    traj = _check_traj(traj)
    ext = _suffix(path)
    if progress is not None and not callable(progress):
        raise ValueError("progress must be callable as progress(i, n)")
    if ext in _STILL_EXTENSIONS:
        overview(traj, path, **kwargs)
        if progress is not None:
            progress(1, 1)
    elif ext in _MOVIE_EXTENSIONS:
        animate(traj, path, progress=progress, **kwargs)
    else:
        raise ValueError(f"cannot render to {Path(os.fspath(path)).name!r}: use one of {', '.join(RENDER_SUFFIXES)}")
    return Path(os.fspath(path))
