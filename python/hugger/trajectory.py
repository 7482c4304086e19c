"""The trajectory file (format 1, docs/file-format.md): a NumPy .npz without pickles."""
from __future__ import annotations

import hashlib
import json
import os
import warnings
from dataclasses import dataclass, field, fields, replace
from typing import Any, cast

import numpy as np

from . import _core
from ._checks import positive, shown
from ._files import atomic_path
from ._npz import READ_ERRORS, Archive, ArchiveError
from ._types import CONTACT_DISTANCE, MAX_FINGERS, MAX_LINKS, VERSION, Configuration
from .hand import Hand
from .world import MAX_COORDINATE, Object

FORMAT_VERSION = 1

# key: (number of dimensions, dtype kind(s))
_ARRAYS = {
    "object_vertices": (2, "f"),
    "object_faces": (2, "iu"),
    "target": (1, "f"),
    "palm_pose": (3, "f"),
    "joints": (4, "f"),
    "angles": (3, "f"),
    "tip_state": (2, "iu"),
    "phase": (1, "iu"),
}
_STRINGS = ("hand_json", "params_json", "status")
#: Why a trajectory of no configuration is refused: by load(), save() and summary().
EMPTY = "the trajectory holds no configuration (a plan starts with C_init)"


def configuration_index(count: int, k: Any) -> int:
    """Index ``k`` (negative counts from the end) of a trajectory of ``count`` configurations:
    ``ValueError`` for what is no whole number, ``IndexError`` naming the range otherwise."""
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)):
        raise ValueError(f"k must be a whole configuration index, got {shown(k)}")
    if not -count <= k < count:
        raise IndexError(f"configuration k={k} is out of range for a trajectory of {count} configurations")
    return int(range(count)[k])


@dataclass(frozen=True)
class Trajectory:
    """A plan: K configurations of a hand with M fingers of N links, and what it grasped.

    Arrays as in docs/file-format.md: ``palm_pose`` (K, 4, 4), ``joints`` (K, M, N+1, 3),
    ``angles`` (K, M, N), ``tip_state`` (K, M) int8 (0 FROZEN, 1 CONTACT, 2 DONE),
    ``phase`` (K,) int8; ``status`` says which rule ended the plan.
    """

    hand_json: str
    params_json: str
    object_vertices: np.ndarray
    object_faces: np.ndarray
    target: np.ndarray
    palm_pose: np.ndarray
    joints: np.ndarray
    angles: np.ndarray
    tip_state: np.ndarray
    phase: np.ndarray
    status: str
    stats_json: str = "{}"
    #: JSON object: what made the plan (see :attr:`provenance`); ``"{}"`` in files written before it existed
    provenance_json: str = "{}"
    #: the Object built from object_vertices/object_faces by object(), kept for later calls
    _object: Any = field(default=None, init=False, repr=False, compare=False)

    def __len__(self) -> int:
        return int(self.palm_pose.shape[0])

    def __repr__(self) -> str:
        # One line: the arrays' contents would fill a terminal (every field is still an attribute).
        k, m, n = (self.angles.shape + (0, 0, 0))[:3]
        return (f"Trajectory(status={self.status!r}, configurations={len(self)}, fingers={m}, links={n}, "
                f"object={len(self.object_vertices)} vertices/{len(self.object_faces)} faces)")

    def __getstate__(self) -> dict[str, Any]:
        # Pickled (to a worker process, say) without object()'s cached C++ Object, which cannot be
        # pickled: the receiver builds its own from the arrays when it needs one.
        state = dict(self.__dict__)
        state["_object"] = None
        return state

    @property
    def hand(self) -> dict[str, Any]:
        return cast(dict[str, Any], json.loads(self.hand_json))

    @property
    def params(self) -> dict[str, Any]:
        return cast(dict[str, Any], json.loads(self.params_json))

    @property
    def stats(self) -> dict[str, Any]:
        return cast(dict[str, Any], json.loads(self.stats_json))

    @property
    def provenance(self) -> dict[str, Any]:
        """What made the plan: ``hugger_version`` and ``object_sha256`` (filled in by :meth:`save`
        when missing), and, when the ``hugger`` command or the caller recorded them, ``object``
        (a built-in name or a mesh file's absolute path), ``object_source`` (``builtin`` or
        ``file``), ``command`` (the command line as a list) and ``arguments`` (its parsed options)."""
        return cast(dict[str, Any], json.loads(self.provenance_json))

    def with_provenance(self, **fields: Any) -> Trajectory:
        """A copy whose provenance holds ``fields`` (JSON-serialisable) over the present ones."""
        merged = {**self.provenance, **fields}
        try:
            text = json.dumps(merged, sort_keys=True, allow_nan=False)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"provenance must be JSON-serialisable: {exc}") from None
        return replace(self, provenance_json=text)

    def object_sha256(self) -> str:
        """SHA-256 (hex) of the object as stored: the little-endian float64 vertices, then the
        int64 faces, C order (what ``object_vertices`` and ``object_faces`` hold in the file)."""
        h = hashlib.sha256()
        h.update(np.ascontiguousarray(self.object_vertices, dtype="<f8").tobytes())
        h.update(np.ascontiguousarray(self.object_faces, dtype="<i8").tobytes())
        return h.hexdigest()

    def save(self, path: str | os.PathLike[str]) -> None:
        """Write the .npz (loads with ``allow_pickle=False``) atomically: under a temporary name in
        the same directory (which must exist), then renamed, so that an interrupted save never
        leaves a partial file under ``path``. The provenance gets ``hugger_version`` and
        ``object_sha256`` when it lacks them. ``ValueError`` for a trajectory of no configuration
        (``Planner.trajectory()`` before the first ``step()``), or whose angles and joints disagree
        (as :meth:`load` checks them), which no file may hold."""
        if len(self) == 0:
            raise ValueError(f"{EMPTY}: nothing to save")
        prov = dict(self.provenance)
        prov.setdefault("hugger_version", VERSION)
        if "object_sha256" not in prov:  # hashing the mesh only when the provenance lacks it
            prov["object_sha256"] = self.object_sha256()
        arrays: dict[str, Any] = {
            "format_version": np.int64(FORMAT_VERSION),
            "hand_json": np.array(self.hand_json),
            "params_json": np.array(self.params_json),
            "stats_json": np.array(self.stats_json),
            "provenance_json": np.array(json.dumps(prov, sort_keys=True)),
            "status": np.array(self.status),
            "object_vertices": np.asarray(self.object_vertices, dtype=np.float64),
            "object_faces": np.asarray(self.object_faces, dtype=np.int64),
            "target": np.asarray(self.target, dtype=np.float64),
            "palm_pose": np.asarray(self.palm_pose, dtype=np.float64),
            "joints": np.asarray(self.joints, dtype=np.float64),
            "angles": np.asarray(self.angles, dtype=np.float64),
            "tip_state": np.asarray(self.tip_state, dtype=np.int8),
            "phase": np.asarray(self.phase, dtype=np.int8),
        }
        _check_angles(_quiet_hand(self.hand), arrays["palm_pose"], arrays["angles"], arrays["joints"], "the trajectory")
        with atomic_path(path) as tmp, open(tmp, "wb") as fh:
            np.savez_compressed(fh, **arrays)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> Trajectory:
        """Read and check a trajectory file (format 1, docs/file-format.md).

        ``ValueError`` if it is not a valid format-1 file: not a zip, truncated or corrupt,
        an array holding pickled Python objects (never unpickled), a declared array size the
        file does not hold, a member unpacking to over 64 MiB and 100 times its packed size (a
        decompression bomb, refused unread), missing keys, wrong shapes, dtypes or values. Extra
        keys are ignored.
        ``FileNotFoundError`` if there is no such file.
        """
        source = os.fspath(path)
        try:
            with open(path, "rb") as fh:
                if fh.read(6) == b"\x93NUMPY":
                    raise ValueError(f"{source!r} holds a single array (.npy), not a trajectory file (.npz)")
                fh.seek(0)
                with Archive(fh) as archive:
                    data = archive.read_all()
        except FileNotFoundError:
            raise
        except ArchiveError as exc:
            raise ValueError(f"cannot read trajectory file {source!r}: {exc}") from None
        except READ_ERRORS as exc:
            raise ValueError(f"cannot read trajectory file {source!r}: {type(exc).__name__}: {exc}") from None
        return cls.from_arrays(data, source=source)

    @classmethod
    def from_arrays(cls, data: dict[str, Any], source: str = "trajectory") -> Trajectory:
        """A trajectory from the arrays of a format-1 file; ``ValueError`` naming what is wrong."""
        missing = [k for k in ("format_version", *_STRINGS, *_ARRAYS) if k not in data]
        if missing:
            shard = "task_sha256" in data and "contact_offsets" in data  # (docs/generation.md, "Format")
            hint = "; it is a shard of a dataset: read it with hugger.Dataset (its folder)" if shard else ""
            raise ValueError(f"{source}: missing keys {missing}{hint}")
        version = np.asarray(data["format_version"])
        if version.shape != () or version.dtype.kind not in "iu" or int(version) != FORMAT_VERSION:
            got = f"{version.item()!r} ({version.dtype})" if version.shape == () else f"an array of shape {version.shape}"
            raise ValueError(f"{source}: format_version must be {FORMAT_VERSION}, got {got}")
        strings: dict[str, str] = {}
        for key in (*_STRINGS, "stats_json", "provenance_json"):
            if key not in data:
                strings[key] = "{}"
                continue
            a = np.asarray(data[key])
            if a.shape != () or a.dtype.kind != "U":
                raise ValueError(f"{source}: {key} must be a string")
            strings[key] = str(a)
        arrays: dict[str, Any] = {}
        for key, (ndim, kinds) in _ARRAYS.items():
            a = np.asarray(data[key])
            if a.ndim != ndim or a.dtype.kind not in kinds:
                raise ValueError(f"{source}: {key} has shape {a.shape} and dtype {a.dtype}, expected {ndim} dimensions of kind {kinds!r}")
            if a.dtype.kind == "f" and not np.all(np.isfinite(a)):
                raise ValueError(f"{source}: {key} holds non-finite numbers")
            # Where a plan's numbers lie: an object's coordinates, T and the palm's within
            # MAX_COORDINATE (the engine's bound; the poses' is check_pose's, below), the joints
            # within a hand's reach of the palm (twice that bound holds them), the angles far within.
            bound = 2.0 * MAX_COORDINATE if key == "joints" else MAX_COORDINATE
            if a.dtype.kind == "f" and a.size and key != "palm_pose" and float(np.abs(a).max()) > bound:
                raise ValueError(f"{source}: {key} holds numbers beyond +-{bound:g}")
            arrays[key] = a
        parsed = {}
        for key in ("hand_json", "params_json", "stats_json", "provenance_json"):  # each named when not JSON
            try:
                parsed[key] = json.loads(strings[key])
            except (ValueError, RecursionError) as exc:
                raise ValueError(f"{source}: {key} is not valid JSON: {type(exc).__name__}: {exc}") from None
        hand, params, stats, provenance = (parsed[k] for k in ("hand_json", "params_json", "stats_json",
                                                               "provenance_json"))
        if not isinstance(hand, dict):
            raise ValueError(f"{source}: hand_json must be a JSON object (a hand description)")
        lacks = [k for k in ("fingers", "links") if k not in hand]
        if lacks:
            raise ValueError(f"{source}: hand_json lacks {lacks} (a hand description: docs/file-format.md)")
        m, n = hand["fingers"], hand["links"]
        if not isinstance(params, dict) or not isinstance(stats, dict) or not isinstance(provenance, dict):
            raise ValueError(f"{source}: params_json, stats_json and provenance_json must be JSON objects")
        if isinstance(m, float) and m.is_integer():
            m = int(m)
        if isinstance(n, float) and n.is_integer():
            n = int(n)
        for name, count, limit in (("fingers", m, MAX_FINGERS), ("links", n, MAX_LINKS)):
            if isinstance(count, bool) or not isinstance(count, int) or not 1 <= count <= limit:
                raise ValueError(f"{source}: hand_json {name} must be a whole number in 1..{limit}, got {count!r}")
        model = _check_hand(hand, m, n, source)
        k = arrays["palm_pose"].shape[0]
        if k < 1:
            raise ValueError(f"{source}: {EMPTY}")
        expect = {"palm_pose": (k, 4, 4), "joints": (k, m, n + 1, 3), "angles": (k, m, n), "tip_state": (k, m),
                  "phase": (k,), "target": (3,)}
        for key, shape in expect.items():
            if arrays[key].shape != shape:
                raise ValueError(f"{source}: {key} has shape {arrays[key].shape}, expected {shape}")
        verts, faces = arrays["object_vertices"], arrays["object_faces"]
        object_free = verts.shape == (0, 3) and faces.shape == (0, 3)  # planned with a skin, no mesh recorded
        if not object_free and (verts.shape[1:] != (3,) or faces.shape[1:] != (3,) or len(verts) == 0 or len(faces) == 0):
            raise ValueError(f"{source}: object_vertices and object_faces must be non-empty (V, 3) and (F, 3), "
                             f"or both empty (0, 3) for an object-free plan, got {verts.shape} and {faces.shape}")
        if not object_free and (faces.min() < 0 or faces.max() >= len(verts)):
            raise ValueError(f"{source}: object_faces index vertices outside 0..{len(verts) - 1}")
        for key, allowed in (("tip_state", "0 FROZEN, 1 CONTACT, 2 DONE"), ("phase", "0, 1 or 2")):
            a = arrays[key]
            if a.min() < 0 or a.max() > 2:
                raise ValueError(f"{source}: {key} holds {a.max() if a.max() > 2 else a.min()}; allowed are {allowed}")
        # The rounding of the file's own precision (float32 and float16 files are read too).
        eps = max(float(np.finfo(arrays[key].dtype).eps) for key in ("palm_pose", "joints", "angles"))
        for key in ("object_vertices", "target", "palm_pose", "joints", "angles"):
            arrays[key] = arrays[key].astype(np.float64)
        for i, pose in enumerate(arrays["palm_pose"]):  # rigid, as the engine requires (its rule)
            try:
                _core.check_pose(pose, f"palm_pose[{i}]")
            except ValueError as exc:
                raise ValueError(f"{source}: {exc}") from None
        _check_angles(model, arrays["palm_pose"], arrays["angles"], arrays["joints"], source, eps)
        arrays["tip_state"] = arrays["tip_state"].astype(np.int8)
        arrays["phase"] = arrays["phase"].astype(np.int8)
        arrays["object_faces"] = arrays["object_faces"].astype(np.int64)
        names = {f.name for f in fields(cls) if f.init}
        return cls(**{k: v for k, v in {**strings, **arrays}.items() if k in names})

    def configuration(self, k: int) -> Configuration:
        """Configuration k (negative counts from the end)."""
        k = configuration_index(len(self), k)
        return Configuration(palm_pose=self.palm_pose[k], joints=self.joints[k], angles=self.angles[k],
                             tip_state=self.tip_state[k], phase=int(self.phase[k]), iteration=k)

    @property
    def has_object(self) -> bool:
        """False for an object-free plan (made with a skin that has no mesh, none given for the
        record): it holds the hand's motion only, and nothing can judge its contacts."""
        return len(self.object_vertices) > 0

    def object(self) -> Object:
        """The grasped object as a :class:`hugger.Object` (``ValueError`` for an object-free plan): built (validation and BVH) on the first
        call from ``object_vertices``/``object_faces`` as they are then, and kept for later calls,
        so that reports, figures and checks of one trajectory share it. The arrays are the plan's
        record; edit a copy (``dataclasses.replace``), not the arrays in place."""
        if self._object is None:
            if not self.has_object:
                raise ValueError("this plan is object-free (made with a skin that has no mesh): plan it again "
                                 "with record_object= to judge, simulate or export it")
            obj = Object(self.object_vertices, self.object_faces, warn_size=False)  # warned when it was made
            object.__setattr__(self, "_object", obj)  # a cache on a frozen dataclass
        return cast(Object, self._object)

    def link_gaps(self, k: int = -1, obj: Object | None = None) -> np.ndarray:
        """(M, N) gap (m) between each link capsule and the object at configuration k."""
        obj = obj if obj is not None else self.object()
        j = self.joints[k]
        a, b = j[:, :-1].reshape(-1, 3), j[:, 1:].reshape(-1, 3)
        return (obj.segment_distance(a, b) - float(self.hand["link_radius"])).reshape(j.shape[0], j.shape[1] - 1)

    def palm_gap(self, k: int = -1, obj: Object | None = None) -> float:
        """Gap (m) between the palm and the object at configuration k."""
        obj = obj if obj is not None else self.object()
        h = self.hand
        return float(obj._core.palm_gap(np.asarray(self.palm_pose[k], dtype=np.float64), float(h["palm_radius"]),
                                        float(h["palm_thickness"])))

    def summary(self, contact_distance: float = CONTACT_DISTANCE, obj: Object | None = None) -> dict[str, Any]:
        """Figures of the final grasp: status, sizes, palm contact, links within ``contact_distance``.
        ``phase2_iterations`` and ``first_contact_iteration`` are the planner's own counts (None
        where the trajectory's stats lack them)."""
        contact_distance = positive("contact_distance", contact_distance, allow_zero=True)
        if len(self) == 0:
            raise ValueError(f"{EMPTY}: no grasp to sum up")
        obj = obj if obj is not None else self.object()
        gaps = self.link_gaps(-1, obj)
        palm = self.palm_gap(-1, obj)
        stats = self.stats
        return {
            "status": self.status,
            "configurations": len(self),
            "phase1_configurations": int(np.sum(self.phase == 1)),
            "phase2_configurations": int(np.sum(self.phase == 2)),
            # (an iteration that approaches free space emits several configurations)
            "phase2_iterations": stats.get("phase2_iterations"),
            "palm_contact": bool(palm <= contact_distance),
            "palm_gap_m": palm,
            "links_in_contact": int(np.sum(gaps <= contact_distance)),
            "links": int(gaps.size),
            "fingers_done": int(np.sum(self.tip_state[-1] == 2)),
            "first_contact_iteration": stats.get("first_contact_iteration"),
        }


def _check_hand(hand: dict[str, Any], m: int, n: int, source: str) -> Hand:
    """``hand_json`` holds its link lengths as the format says (an M x N list, which tools read as
    such) and describes a hand :meth:`hugger.Hand.from_dict` takes (the hand's rules), of the
    arrays' M fingers and N links. The hand's size is not warned of again (it was when made)."""
    try:
        shape = np.shape(cast(Any, hand.get("link_lengths")))
    except ValueError:  # ragged
        shape = ()
    if shape != (m, n):
        raise ValueError(f"{source}: hand_json link_lengths must be a ({m}, {n}) list of lengths (m)")
    try:  # (M and N are its own fingers and links: the hand it describes has them)
        return _quiet_hand(hand)
    except (ValueError, TypeError, OverflowError, RecursionError) as exc:
        raise ValueError(f"{source}: hand_json is not a valid hand: {exc}") from None


def _quiet_hand(hand: dict[str, Any]) -> Hand:
    """:meth:`Hand.from_dict` of a trajectory's hand, whose size is not warned of again (it was
    when the hand was made)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return Hand.from_dict(hand)


#: How many configurations, evenly spread from the first to the last, Trajectory.load checks
#: the angles of against the joints (every one would cost a forward kinematics each: 8 us).
ANGLE_SAMPLES = 64


def _check_angles(hand: Hand, poses: np.ndarray, angles: np.ndarray, joints: np.ndarray, source: str,
                  eps: float = 0.0) -> None:
    """The joint positions of the file's angles (the hand's forward kinematics) are its joints, at
    ANGLE_SAMPLES configurations, to a micrometre and the rounding of the arrays' precision
    (``eps``, of the least precise: 0 for float64): tools read one or the other (the analysis the
    joints, the physics test and the MJCF export the angles), and files that disagree (angles in
    degrees, joints of another hand) were judged one way by one and another by the other."""
    k = len(poses)
    relative, reach = max(1e-9, 16.0 * eps), hand.reach
    for i in np.unique(np.linspace(0, k - 1, min(k, ANGLE_SAMPLES)).round().astype(int)):
        error = float(np.abs(hand.forward(poses[i], angles[i]) - joints[i]).max())
        if not error <= 1e-6 + relative * (float(np.abs(joints[i]).max()) + reach):
            raise ValueError(f"{source}: angles and joints disagree at configuration {i}: the joints the angles "
                             f"give are {error:.3g} m from those stored (angles in degrees, or joints of another hand?)")
