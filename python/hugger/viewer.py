"""An interactive 3D view of plans in the browser (viser), and the grasp as a glTF scene (trimesh).

:func:`view` serves the object O (semi-transparent), the target T (a black dot), the palm (a
grey disc, front face at P_o) and every link capsule coloured by its finger's TipState at the
configuration shown (FROZEN blue, CONTACT orange, DONE green, as in :mod:`hugger.viz`), and the
contacts (red dots, gap at most ``CONTACT_DISTANCE``). A timeline slider picks the
configuration; *play* runs through the plan and pauses on the final grasp; toggles switch the
object's transparency and the contacts. Several plans are shown side by side, each in its own
place along the world x axis, on one timeline (a shorter plan rests on its final grasp).

:func:`export_scene` writes the same pieces as a glTF binary (``.glb``) any viewer opens: the
final configuration, or every configuration (``all_frames=True``), one node per piece.

Needs the ``view`` extra (``pip install 'hugger[view]'``: viser and trimesh), imported only
when a function is called. The meshes of the hand are built here with numpy alone
(:func:`capsule_mesh`, :func:`palm_mesh`).
"""
from __future__ import annotations

import contextlib
import io
import math
import os
import threading
import time
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from . import _palette, analysis
from ._palette import rgb255
from ._checks import shown, whole
from ._files import write_atomic
from ._rotation import quaternion_wxyz
from .trajectory import Trajectory

#: The slowest playback the page's control offers (frames per second); the fastest is render's
#: limit, hugger.viz.backend.MAX_FPS.
MIN_FPS = 1.0


def _max_fps() -> float:
    from .viz.backend import MAX_FPS  # (hugger.viz imports this module)

    return MAX_FPS


__all__ = ["Viewer", "capsule_mesh", "export_scene", "palm_mesh", "scene_nodes", "view"]

VIEW_EXTRA = "pip install 'hugger[view]'"
#: RGB (0..255) of the TipStates FROZEN, CONTACT, DONE, the object, the palm and the contacts: the
#: colours of the figures (:mod:`hugger._palette`).
STATE_RGB = tuple(rgb255(c) for c in _palette.STATE_COLORS)
OBJECT_RGB = rgb255(_palette.OBJECT_RGB)
PALM_RGB = rgb255(_palette.PALM_RGB)
CONTACT_RGB = rgb255(_palette.CONTACT_COLOR)
TARGET_RGB = (20, 20, 20)
#: Opacity of the object when "transparent object" is on.
OBJECT_OPACITY = 0.45


def _viser() -> Any:
    try:
        import viser
    except ImportError:
        raise ImportError(f"the 3D viewer needs viser: {VIEW_EXTRA}") from None
    return viser


def _trimesh() -> Any:
    try:
        import trimesh
    except ImportError:
        raise ImportError(f"exporting a scene needs trimesh: {VIEW_EXTRA}") from None
    return trimesh


def _check_traj(traj: Any) -> Trajectory:
    if not isinstance(traj, Trajectory):
        raise ValueError(f"expected a hugger.Trajectory, got {type(traj).__name__}")
    return traj


# --- meshes of the hand (numpy only) ------------------------------------------------------------

def _lathe(profile: Sequence[tuple[float, float]], sides: int) -> tuple[np.ndarray, np.ndarray]:
    """A closed, outward-oriented surface of revolution about z from a profile (rho, z) whose
    first and last points lie on the axis (rho = 0), ordered from the lower pole to the upper."""
    prof = np.asarray(profile, dtype=np.float64)
    inner = prof[1:-1]
    t = 2 * np.pi * np.arange(sides) / sides
    rings = np.stack([inner[:, :1] * np.cos(t), inner[:, :1] * np.sin(t),
                      np.broadcast_to(inner[:, 1:], (len(inner), sides))], axis=-1).reshape(-1, 3)
    verts = np.vstack([[0.0, 0.0, prof[0, 1]], rings, [0.0, 0.0, prof[-1, 1]]])
    top = len(verts) - 1
    j = np.arange(sides)
    jj = (j + 1) % sides
    faces = [np.stack([np.zeros(sides, dtype=np.int64), 1 + jj, 1 + j], axis=1)]
    for i in range(len(inner) - 1):
        a, b = 1 + i * sides + j, 1 + i * sides + jj
        c, d = b + sides, a + sides
        faces += [np.stack([a, b, c], axis=1), np.stack([a, c, d], axis=1)]
    last = 1 + (len(inner) - 1) * sides
    faces.append(np.stack([np.full(sides, top), last + j, last + jj], axis=1))
    return verts, np.vstack(faces).astype(np.int64)


def capsule_mesh(length: float, radius: float, sides: int = 16, rings: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """(V, 3) vertices and (F, 3) faces of a capsule from the origin to (0, 0, ``length``) of
    ``radius`` (m), closed and outward-oriented: a link's capsule in its own frame (tail joint at
    the origin, the link along +z)."""
    h = np.linspace(-np.pi / 2, 0.0, rings + 1)
    low = [(radius * math.cos(a), radius * math.sin(a)) for a in h]
    high = [(radius * math.cos(a), length + radius * math.sin(a)) for a in -h[::-1]]
    return _lathe(low + high, sides)


def palm_mesh(radius: float, thickness: float, sides: int = 48) -> tuple[np.ndarray, np.ndarray]:
    """(V, 3) vertices and (F, 3) faces of the palm disc in the palm frame: front face at z = 0
    (P_o at its centre), back face at z = -``thickness``."""
    return _lathe([(0.0, -thickness), (radius, -thickness), (radius, 0.0), (0.0, 0.0)], sides)


def _rotation_z_to(d: np.ndarray) -> np.ndarray:
    """A rotation (3, 3) whose z column is the unit vector d (a capsule is the same about its axis,
    so any such rotation will do; this one is exact to rounding for every d)."""
    hint = np.array([1.0, 0.0, 0.0]) if abs(d[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(hint, d)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(d, x), d])


@dataclass(frozen=True)
class _Plan:
    """What both the viewer and the exporter draw of one trajectory."""

    traj: Trajectory
    lengths: np.ndarray  #: (M, N) link lengths (m)
    radius: float  #: capsule radius drawn (m): the link radius, or 4% of the mean link length for 0

    @classmethod
    def of(cls, traj: Trajectory) -> _Plan:
        h = traj.hand
        lengths = np.asarray(h["link_lengths"], dtype=np.float64)
        r = float(h["link_radius"])
        return cls(traj, lengths, r if r > 0 else 0.04 * float(lengths.mean()))

    @property
    def fingers(self) -> int:
        return int(self.lengths.shape[0])

    @property
    def links(self) -> int:
        return int(self.lengths.shape[1])

    def link_frames(self, k: int) -> np.ndarray:
        """(M, N, 4, 4): each link's frame at configuration k (origin at its tail joint, z along it)."""
        j = self.traj.joints[k]
        out = np.tile(np.eye(4), (self.fingers, self.links, 1, 1))
        for m in range(self.fingers):
            for n in range(self.links):
                d = j[m, n + 1] - j[m, n]
                length = float(np.linalg.norm(d))
                out[m, n, :3, :3] = _rotation_z_to(d / length if length > 0 else np.array([0.0, 0.0, 1.0]))
                out[m, n, :3, 3] = j[m, n]
        return out

    def contacts(self, k: int) -> np.ndarray:
        """(C, 3) contact points at configuration k."""
        return analysis.contacts(self.traj, k, obj=self.traj.object()).points

    def extent(self, final_only: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """The (min, max) corners of everything the plan shows over all its configurations (or,
        with ``final_only``, of the object and the final configuration)."""
        ks = slice(-1, None) if final_only else slice(None)
        pts = np.vstack([self.traj.object_vertices, self.traj.joints[ks].reshape(-1, 3),
                         self.traj.palm_pose[ks, :3, 3]])
        pad = self.radius + float(self.traj.hand["palm_radius"])
        return pts.min(axis=0) - pad, pts.max(axis=0) + pad


def _plans(trajs: Any) -> list[_Plan]:
    """Plans from a trajectory, a trajectory file's path, or a list of either."""
    items = [trajs] if isinstance(trajs, (Trajectory, str, os.PathLike)) else list(trajs)
    if not items:
        raise ValueError("give at least one trajectory")
    plans = [_Plan.of(Trajectory.load(t) if isinstance(t, (str, os.PathLike)) else _check_traj(t)) for t in items]
    for plan in plans:
        plan.traj.object()  # its contacts are shown: an object-free plan is refused before the server starts
    return plans


def _offsets(plans: Sequence[_Plan]) -> np.ndarray:
    """(P, 3): where each plan's scene is put, side by side along x with a 20% gap."""
    out, edge = [], 0.0
    for i, p in enumerate(plans):
        lo, hi = p.extent()
        shift = 0.0 if i == 0 else edge - lo[0]
        out.append([shift, 0.0, 0.0])
        edge = shift + hi[0] + 0.2 * float(np.max(hi - lo))
    return np.asarray(out)


def scene_nodes(fingers: int, links: int, plan: int = 0) -> dict[str, list[str]]:
    """The viewer's scene node names for plan ``plan`` of a hand of ``fingers`` x ``links``: keys
    ``object``, ``target``, ``palm``, ``links`` (M x N names, finger-major), ``contacts``."""
    base = f"/plan{plan}"
    return {"object": [f"{base}/object"], "target": [f"{base}/target"], "palm": [f"{base}/palm"],
            "links": [f"{base}/links/f{m}_l{n}" for m in range(fingers) for n in range(links)],
            "contacts": [f"{base}/contacts"]}


# --- the viewer ---------------------------------------------------------------------------------------

def check_fps(fps: Any) -> float:
    """``fps`` as a float: from MIN_FPS to render's MAX_FPS, the range of the page's control;
    otherwise a ValueError."""
    from .viz.backend import check_fps as check  # (hugger.viz imports this module)

    x = check(fps)
    if x < MIN_FPS:
        raise ValueError(f"fps must be at least {MIN_FPS:g}, got {shown(fps)}")
    return x


def _check_host(host: Any) -> None:
    """``host`` names an address of this machine: a server can listen there. (viser tries port
    after port on an address it cannot bind, for ever.)"""
    import socket

    if not isinstance(host, str) or not host:
        raise ValueError(f"host must be a host name or an address of this machine, got {host!r}")
    try:
        family, kind, proto, _, address = socket.getaddrinfo(host, 0, type=socket.SOCK_STREAM)[0]
        with socket.socket(family, kind, proto) as probe:
            probe.bind(address)
    except (OSError, UnicodeError) as exc:
        raise ValueError(f"cannot serve on host {host!r}: {getattr(exc, 'strerror', None) or exc}") from None


class Viewer:
    """A viser server showing one or more plans (see the module's docstring). ``configuration``
    is the index shown (common to all plans; each plan shows min(k, its K-1)). Stop it with
    :meth:`close` (or use it as a context manager)."""

    def __init__(self, trajs: Any, *, host: str = "127.0.0.1", port: int = 8080, fps: float = 20.0,
                 labels: Sequence[str] | None = None) -> None:
        plans = _plans(trajs)
        port = whole("port", port, 0, 65535)
        fps = check_fps(fps)
        if labels is not None and len(labels) != len(plans):
            raise ValueError(f"labels must name each of the {len(plans)} plans, got {len(labels)}")
        _check_host(host)
        viser = _viser()
        self.plans = plans
        self.fps = float(fps)
        self._contact_cache: dict[tuple[int, int], np.ndarray] = {}
        self._lock = threading.Lock()
        with contextlib.redirect_stdout(io.StringIO()):  # viser's banner: our callers say where it serves
            self.server = viser.ViserServer(host=host, port=port, label="hugger", verbose=False)
        self.playing = False
        self._closed = threading.Event()
        try:
            self._build(labels)
        except BaseException:
            self.server.stop()
            raise
        self._player = threading.Thread(target=self._play_loop, name="hugger-viewer-play", daemon=True)
        self._player.start()

    # the scene
    def _build(self, labels: Sequence[str] | None) -> None:
        scene, gui = self.server.scene, self.server.gui
        scene.set_up_direction("+z")
        offsets = _offsets(self.plans)
        self.offsets = offsets
        self.objects, self.palms, self.links, self.contact_clouds = [], [], [], []
        # the camera frames the final grasps (what is shown first)
        finals = [p.extent(True) for p in self.plans]
        lo = np.min([e[0] + o for e, o in zip(finals, offsets)], axis=0)
        hi = np.max([e[1] + o for e, o in zip(finals, offsets)], axis=0)
        for i, (plan, off) in enumerate(zip(self.plans, offsets)):
            t = plan.traj
            names = scene_nodes(plan.fingers, plan.links, i)
            scene.add_frame(f"/plan{i}", show_axes=False, position=tuple(off))
            self.objects.append(scene.add_mesh_simple(names["object"][0], t.object_vertices, t.object_faces,
                                                      color=OBJECT_RGB, opacity=OBJECT_OPACITY, side="double",
                                                      cast_shadow=False, receive_shadow=False))
            scene.add_icosphere(names["target"][0], radius=max(0.5 * plan.radius, 1e-3), color=TARGET_RGB,
                                position=tuple(t.target))
            pv, pf = palm_mesh(float(t.hand["palm_radius"]), max(float(t.hand["palm_thickness"]), 1e-4))
            self.palms.append(scene.add_mesh_simple(names["palm"][0], pv, pf, color=PALM_RGB, flat_shading=True,
                                                    cast_shadow=False, receive_shadow=False))
            handles = []
            for m in range(plan.fingers):
                for n in range(plan.links):
                    cv, cf = capsule_mesh(float(plan.lengths[m, n]), plan.radius)
                    handles.append(scene.add_mesh_simple(names["links"][m * plan.links + n], cv, cf,
                                                         color=STATE_RGB[0], cast_shadow=False,
                                                         receive_shadow=False))
            self.links.append(handles)
            self.contact_clouds.append(scene.add_point_cloud(
                names["contacts"][0], np.zeros((1, 3)), colors=CONTACT_RGB, point_size=max(plan.radius, 2e-3),
                point_shape="circle", precision="float32"))
            label = labels[i] if labels is not None else f"plan {i}: {t.status}, {len(t)} configurations"
            top = finals[i][1][2]
            scene.add_label(f"/plan{i}/label", label, position=(float(t.target[0]), float(t.target[1]), float(top)))
        centre = 0.5 * (lo + hi)
        size = float(np.max(hi - lo))
        cam = self.server.initial_camera
        cam.look_at = tuple(centre)
        cam.position = tuple(centre + size * np.array([0.45, -0.9, 0.6]))
        cam.up = (0.0, 0.0, 1.0)

        self.count = max(len(p.traj) for p in self.plans)
        self.slider = gui.add_slider("configuration k", min=0, max=max(self.count - 1, 1), step=1,
                                     initial_value=self.count - 1)
        self.play_button = gui.add_button("play / pause")
        self.fps_number = gui.add_number("frames per second", initial_value=self.fps, min=MIN_FPS, max=_max_fps(),
                                         step=1.0)
        self.transparent = gui.add_checkbox("transparent object", initial_value=True)
        self.show_contacts = gui.add_checkbox("contacts", initial_value=True)
        self.status = gui.add_markdown("")
        self.slider.on_update(lambda _: self._on_slider())
        self.play_button.on_click(lambda _: self._toggle())
        self.fps_number.on_update(lambda _: setattr(self, "fps", float(self.fps_number.value)))
        self.transparent.on_update(lambda _: self._set_opacity())
        self.show_contacts.on_update(lambda _: self._show(self.configuration))
        self.configuration: int = self.count - 1
        self.show(self.count - 1)

    def _set_opacity(self) -> None:
        for h in self.objects:
            h.opacity = OBJECT_OPACITY if self.transparent.value else None

    def _contacts(self, i: int, k: int) -> np.ndarray:
        key = (i, k)
        if key not in self._contact_cache:
            self._contact_cache[key] = self.plans[i].contacts(k)
        return self._contact_cache[key]

    def show(self, k: int) -> None:
        """Show configuration k (clamped to each plan's length; negative counts from the end).
        ``ValueError`` after :meth:`close`."""
        if self._closed.is_set():
            raise ValueError("the viewer is closed: its server has stopped")
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)):
            raise ValueError(f"k must be a whole number, got {shown(k)}")
        k = int(k) if k >= 0 else self.count + int(k)
        if not 0 <= k < self.count:
            raise ValueError(f"k must be in 0..{self.count - 1} (or negative from the end), got {k}")
        self._show(k)

    def _show(self, k: int) -> None:
        """show(k) for a k in range, from the viewer's own threads (the player, the GUI's callbacks),
        which may still run while close() stops them."""
        lines = []
        with self._lock, self.server.atomic():
            self.configuration = k
            for i, plan in enumerate(self.plans):
                t = plan.traj
                kk = min(k, len(t) - 1)
                pose = t.palm_pose[kk]
                self.palms[i].position = pose[:3, 3]
                self.palms[i].wxyz = quaternion_wxyz(pose[:3, :3])
                frames = plan.link_frames(kk)
                states = t.tip_state[kk]
                for m in range(plan.fingers):
                    color = STATE_RGB[int(states[m])]
                    for n in range(plan.links):
                        h = self.links[i][m * plan.links + n]
                        h.position = frames[m, n, :3, 3]
                        h.wxyz = quaternion_wxyz(frames[m, n, :3, :3])
                        h.color = color
                cloud = self.contact_clouds[i]
                pts = self._contacts(i, kk) if self.show_contacts.value else np.zeros((0, 3))
                if len(pts):
                    cloud.points = pts.astype(np.float32)
                    cloud.visible = True
                else:
                    cloud.visible = False
                counts = np.bincount(states.astype(int), minlength=3)
                lines.append(f"**plan {i}**: k = {kk} / {len(t) - 1}, phase {int(t.phase[kk])}, "
                             f"FROZEN {counts[0]} CONTACT {counts[1]} DONE {counts[2]}, {len(pts)} contacts")
            self.status.content = "  \n".join(lines)
        if int(self.slider.value) != k:
            self.slider.value = k

    def _on_slider(self) -> None:
        k = int(self.slider.value)
        if k != self.configuration:  # not the echo of show() moving the slider
            self._show(k)

    def _toggle(self) -> None:
        if not self.playing and self.configuration >= self.count - 1:
            self._show(0)  # play again from C_init
        self.playing = not self.playing

    def _play_loop(self) -> None:
        while not self._closed.wait(1.0 / max(self.fps, 1.0)):
            if self.playing:
                k = self.configuration + 1
                if k >= self.count - 1:
                    self.playing = False  # pause on the final grasp
                    k = self.count - 1
                self._show(k)

    @property
    def url(self) -> str:
        host = self.server.get_host()
        return f"http://{'localhost' if host in ('0.0.0.0', '127.0.0.1') else host}:{self.server.get_port()}"

    def close(self) -> None:
        """Stop playing and the server."""
        self._closed.set()
        self._player.join(timeout=2.0)
        self.server.stop()

    def __enter__(self) -> Viewer:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def serve(self) -> None:
        """Serve until interrupted (Ctrl-C), then stop (:meth:`close`)."""
        try:
            _serve(self)
        except KeyboardInterrupt:
            pass
        finally:
            self.close()


def _serve(viewer: Viewer) -> None:
    """Wait while ``viewer`` serves (its server and player run in threads of their own)."""
    while True:
        time.sleep(0.5)


def view(trajs: Any, *, port: int = 8080, host: str = "127.0.0.1", open_browser: bool = True, block: bool = True,
         fps: float = 20.0, labels: Sequence[str] | None = None) -> Viewer:
    """Serve an interactive 3D view of one trajectory or a list of them (side by side; trajectory
    file paths are read) at ``http://host:port`` (``port=0``: any free port, see ``Viewer.url``).
    ``open_browser`` opens it in the default web browser. ``block``: serve until interrupted
    (Ctrl-C), then stop and return the stopped :class:`Viewer`; otherwise return the running
    viewer at once (stop it with ``close()``, or serve on with :meth:`Viewer.serve`)."""
    viewer = Viewer(trajs, host=host, port=port, fps=fps, labels=labels)
    if open_browser:
        import webbrowser

        webbrowser.open(viewer.url)
    if block:
        viewer.serve()
    return viewer


# --- glTF export ------------------------------------------------------------------------------------

def _colored(trimesh: Any, verts: np.ndarray, faces: np.ndarray, rgb: Sequence[int], alpha: int = 255) -> Any:
    """A mesh of one glTF material: its colour, and below alpha 255 blended (glTF's default mode is
    opaque: a vertex colour's alpha alone is ignored by viewers)."""
    mesh = trimesh.Trimesh(vertices=verts, faces=faces, process=False)
    material = trimesh.visual.material.PBRMaterial(
        baseColorFactor=[*rgb, alpha], alphaMode="BLEND" if alpha < 255 else "OPAQUE", metallicFactor=0.0,
        roughnessFactor=0.8, doubleSided=alpha < 255)
    mesh.visual = trimesh.visual.TextureVisuals(material=material)
    return mesh


def _spheres(centres: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """One mesh of small spheres (octahedra refined once would do; a lathe of 8 sides is enough)."""
    v, f = _lathe([(0.0, -radius)] + [(radius * math.cos(a), radius * math.sin(a))
                                       for a in np.linspace(-np.pi / 2, np.pi / 2, 5)[1:-1]] + [(0.0, radius)], 8)
    verts = (centres[:, None, :] + v[None]).reshape(-1, 3)
    faces = (f[None] + len(v) * np.arange(len(centres))[:, None, None]).reshape(-1, 3)
    return verts, faces


def _place(scene: Any, node: str, geom_name: str, mesh: Any, transform: np.ndarray | None = None) -> None:
    """Add node ``node`` showing ``mesh`` stored once under ``geom_name`` (later nodes instance it)."""
    if geom_name not in scene.geometry:
        scene.add_geometry(mesh, node_name=node, geom_name=geom_name, transform=transform)
    else:
        scene.graph.update(frame_to=node, frame_from=scene.graph.base_frame,
                           matrix=np.eye(4) if transform is None else transform, geometry=geom_name)


def export_scene(traj: Trajectory, path: Any = None, *, all_frames: bool = False) -> Any:
    """The plan as a ``trimesh.Scene``, written to ``path`` (``.glb``) atomically when given.

    Nodes: ``object`` (alpha 0.5), ``target``, and for the final configuration (or, with
    ``all_frames``, for each configuration k as ``k{k}/...``): ``palm``, the M x N links
    ``f{m}_l{n}`` coloured by TipState, and ``contacts`` (one mesh of small red spheres, only
    when there are contacts). Identical link meshes are stored once and instanced. Returns the scene."""
    trimesh = _trimesh()
    plan = _Plan.of(_check_traj(traj))
    t = plan.traj
    scene = trimesh.Scene()
    scene.add_geometry(_colored(trimesh, t.object_vertices, t.object_faces, OBJECT_RGB, 128), node_name="object",
                       geom_name="object")
    tv, tf = _spheres(t.target[None], max(0.5 * plan.radius, 1e-3))
    scene.add_geometry(_colored(trimesh, tv, tf, TARGET_RGB), node_name="target", geom_name="target")
    pv, pf = palm_mesh(float(t.hand["palm_radius"]), max(float(t.hand["palm_thickness"]), 1e-4))
    palm = _colored(trimesh, pv, pf, PALM_RGB)
    link_meshes: dict[tuple[float, int], tuple[str, Any]] = {}
    frames = range(len(t)) if all_frames else [len(t) - 1]
    for k in frames:
        prefix = f"k{k}/" if all_frames else ""
        _place(scene, f"{prefix}palm", "palm", palm, t.palm_pose[k])
        lf = plan.link_frames(k)
        for m in range(plan.fingers):
            state = int(t.tip_state[k, m])
            for n in range(plan.links):
                key = (float(plan.lengths[m, n]), state)
                if key not in link_meshes:
                    cv, cf = capsule_mesh(key[0], plan.radius, sides=12, rings=3)
                    link_meshes[key] = (f"link_{len(link_meshes)}", _colored(trimesh, cv, cf, STATE_RGB[state]))
                geom_name, mesh = link_meshes[key]
                _place(scene, f"{prefix}f{m}_l{n}", geom_name, mesh, lf[m, n])
        pts = plan.contacts(k)
        if len(pts):
            sv, sf = _spheres(pts, max(0.25 * plan.radius, 5e-4))
            scene.add_geometry(_colored(trimesh, sv, sf, CONTACT_RGB), node_name=f"{prefix}contacts",
                               geom_name=f"{prefix}contacts")
    if path is not None:
        write_atomic(path, scene.export(file_type="glb", include_normals=True))  # (smooth shading)
    return scene
