"""One configuration drawn in 3D: the geometry of hand and object, the camera and display frame
(:class:`_Scene`), the axis box (:class:`_Box`) and :func:`draw_configuration`."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence, cast

import numpy as np

from .. import _palette, analysis
from ..trajectory import Trajectory
from ..world import Object
from .backend import _check_faces, _check_traj, _pyplot

#: Colours of the TipStates FROZEN, CONTACT, DONE.
STATE_COLORS = _palette.STATE_COLORS
_STATE_NAMES = ("FROZEN", "CONTACT", "DONE")
_OBJECT_RGB = np.array(_palette.OBJECT_RGB)
_OBJECT_ALPHA = 0.5
_PALM_RGB = np.array(_palette.PALM_RGB)
_CONTACT_COLOR = _palette.CONTACT_COLOR


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


def _ring(center: np.ndarray, axis: np.ndarray, radius: float, sides: int,
          phase: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    u, v = _frame(axis, np.array([0.3, 0.5, 0.8]))
    t = phase + 2 * np.pi * np.arange(sides) / sides
    dirs = np.cos(t)[:, None] * u + np.sin(t)[:, None] * v
    return center + radius * dirs, dirs


def _tube(a: np.ndarray, b: np.ndarray, radius: float, sides: int = 10) -> tuple[np.ndarray, np.ndarray]:
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


def _unit_sphere(lon: int = 8, lat: int = 4) -> tuple[np.ndarray, np.ndarray]:
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


def _palm_polys(pose: np.ndarray, radius: float, thickness: float, sides: int = 28) -> tuple[np.ndarray, np.ndarray]:
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
    return cast(np.ndarray, np.clip(np.asarray(rgb) * (ambient + (1.0 - ambient) * lam)[:, None], 0.0, 1.0))


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
        return cast(np.ndarray, d / np.linalg.norm(d))


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
        self._contacts: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def to_display(self, p: np.ndarray) -> np.ndarray:
        return cast(np.ndarray, (np.asarray(p, dtype=float) - self.origin) @ self.rot.T)

    @property
    def object(self) -> Object:
        return self.traj.object()  # built once and kept by the trajectory

    def _contact_set(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Contact points (C, 3) of configuration k and which of them are the palm's (C,) bool."""
        if k not in self._contacts:
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
            return cast(np.ndarray, points[~palm])
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


def _contact_points(traj: Trajectory, k: int, obj: Object | None) -> np.ndarray:
    """Contact points (C, 3) at configuration k, from :func:`hugger.analysis.contacts`."""
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
                       max_faces: int = 20000, _scene: _Scene | None = None) -> list[Any]:
    """Draw configuration ``k`` of ``traj`` into a 3D axes ``ax``; returns the artists added.

    ``view`` is ``"side"`` (perpendicular to the final palm normal, 12 degrees from the palm's
    side), ``"normal"`` (along the final palm normal, seen from beyond the object, looking back
    at the palm) or ``"oblique"`` (38 degrees from the palm's side).
    ``limits`` = (lower, upper) corners (3,) of the box shown, in the display frame (see
    :mod:`hugger.viz`); default: the object and this configuration. ``contacts`` marks contacts as red dots
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


def _legend(fig: Any, loc: str = "lower center", ncol: int = 5, **kw: Any) -> None:
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    handles: list[Any] = [Patch(color=c, label=s) for c, s in zip(STATE_COLORS, _STATE_NAMES)]
    handles.append(Line2D([], [], ls="", marker="o", ms=5, mfc=_CONTACT_COLOR, mec="k", mew=0.4, label="contact"))
    handles.append(Line2D([], [], ls="", marker="x", ms=6, mec="k", mew=1.5, label="target T"))
    fig.legend(handles=handles, loc=loc, ncol=ncol, frameon=False, fontsize=8, **kw)


# --- shared by the figures and the animation -----------------------------------------------------

def _phase_name(traj: Trajectory, k: int) -> str:
    p = int(traj.phase[k])
    return "C_init" if p == 0 else f"Phase {p}"


def _subsample(count: int, limit: int) -> np.ndarray:
    """min(count, limit) distinct indices 0..count-1, evenly spread, first and last included."""
    n = min(count, limit)
    return np.unique(np.round(np.linspace(0, count - 1, n)).astype(int))
