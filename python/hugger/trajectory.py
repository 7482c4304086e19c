"""The trajectory file (format 1, DESIGN.md section 5): a NumPy .npz without pickles."""
from __future__ import annotations

import json
import os
import zipfile
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

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


@dataclass(frozen=True)
class Trajectory:
    """A plan: K configurations of a hand with M fingers of N links, and what it grasped.

    Arrays as in DESIGN.md section 5: ``palm_pose`` (K, 4, 4), ``joints`` (K, M, N+1, 3),
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

    def __len__(self) -> int:
        return int(self.palm_pose.shape[0])

    @property
    def hand(self) -> dict:
        return json.loads(self.hand_json)

    @property
    def params(self) -> dict:
        return json.loads(self.params_json)

    @property
    def stats(self) -> dict:
        return json.loads(self.stats_json)

    def save(self, path: str | os.PathLike) -> None:
        """Write the .npz (loads with ``allow_pickle=False``)."""
        arrays = {
            "format_version": np.int64(FORMAT_VERSION),
            "hand_json": np.array(self.hand_json),
            "params_json": np.array(self.params_json),
            "stats_json": np.array(self.stats_json),
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
        with open(path, "wb") as fh:
            np.savez_compressed(fh, **arrays)

    @classmethod
    def load(cls, path: str | os.PathLike) -> Trajectory:
        """Read and check a trajectory file; ``ValueError`` if it is not a valid format-1 file."""
        try:
            with open(path, "rb") as fh, np.load(fh, allow_pickle=False) as z:
                data = {k: z[k] for k in z.files}
        except FileNotFoundError:
            raise
        except AttributeError:  # a plain .npy array has no .files
            raise ValueError(f"{os.fspath(path)!r} holds a single array, not a trajectory file") from None
        except (OSError, ValueError, EOFError, zipfile.BadZipFile, KeyError) as exc:
            raise ValueError(f"cannot read trajectory file {os.fspath(path)!r}: {exc}") from None
        return cls.from_arrays(data, source=os.fspath(path))

    @classmethod
    def from_arrays(cls, data: dict[str, Any], source: str = "trajectory") -> Trajectory:
        missing = [k for k in ("format_version", *_STRINGS, *_ARRAYS) if k not in data]
        if missing:
            raise ValueError(f"{source}: missing keys {missing}")
        version = np.asarray(data["format_version"])
        if version.shape != () or version.dtype.kind not in "iu" or int(version) != FORMAT_VERSION:
            raise ValueError(f"{source}: format_version must be {FORMAT_VERSION}, got {version!r}")
        strings = {}
        for key in (*_STRINGS, "stats_json"):
            if key not in data:
                strings[key] = "{}"
                continue
            a = np.asarray(data[key])
            if a.shape != () or a.dtype.kind != "U":
                raise ValueError(f"{source}: {key} must be a string")
            strings[key] = str(a)
        arrays = {}
        for key, (ndim, kinds) in _ARRAYS.items():
            a = np.asarray(data[key])
            if a.ndim != ndim or a.dtype.kind not in kinds:
                raise ValueError(f"{source}: {key} has shape {a.shape} and dtype {a.dtype}, expected {ndim} dimensions of kind {kinds!r}")
            if a.dtype.kind == "f" and not np.all(np.isfinite(a)):
                raise ValueError(f"{source}: {key} holds non-finite numbers")
            arrays[key] = a
        try:
            hand = json.loads(strings["hand_json"])
            json.loads(strings["params_json"])
            m, n = int(hand["fingers"]), int(hand["links"])
        except (ValueError, KeyError, TypeError) as exc:
            raise ValueError(f"{source}: hand_json/params_json are not valid: {exc}") from None
        k = arrays["palm_pose"].shape[0]
        expect = {"palm_pose": (k, 4, 4), "joints": (k, m, n + 1, 3), "angles": (k, m, n), "tip_state": (k, m),
                  "phase": (k,), "target": (3,)}
        for key, shape in expect.items():
            if arrays[key].shape != shape:
                raise ValueError(f"{source}: {key} has shape {arrays[key].shape}, expected {shape}")
        if arrays["object_vertices"].shape[1:] != (3,) or arrays["object_faces"].shape[1:] != (3,):
            raise ValueError(f"{source}: object_vertices and object_faces must be (V, 3) and (F, 3)")
        arrays["tip_state"] = arrays["tip_state"].astype(np.int8)
        arrays["phase"] = arrays["phase"].astype(np.int8)
        arrays["object_faces"] = arrays["object_faces"].astype(np.int64)
        names = {f.name for f in fields(cls)}
        return cls(**{k: v for k, v in {**strings, **arrays}.items() if k in names})

    def configuration(self, k: int):
        """Configuration k (negative counts from the end)."""
        from .planner import Configuration

        k = range(len(self))[k]
        return Configuration(palm_pose=self.palm_pose[k], joints=self.joints[k], angles=self.angles[k],
                             tip_state=self.tip_state[k], phase=int(self.phase[k]), iteration=k)

    def object(self):
        """The grasped object as a :class:`hugger.Object`."""
        from .world import Object

        return Object(self.object_vertices, self.object_faces)

    def link_gaps(self, k: int = -1, obj=None) -> np.ndarray:
        """(M, N) gap (m) between each link capsule and the object at configuration k."""
        obj = obj if obj is not None else self.object()
        j = self.joints[k]
        a, b = j[:, :-1].reshape(-1, 3), j[:, 1:].reshape(-1, 3)
        return (obj.segment_distance(a, b) - float(self.hand["link_radius"])).reshape(j.shape[0], j.shape[1] - 1)

    def palm_gap(self, k: int = -1, obj=None) -> float:
        """Gap (m) between the palm and the object at configuration k."""
        obj = obj if obj is not None else self.object()
        h = self.hand
        return float(obj._core.palm_gap(np.asarray(self.palm_pose[k], dtype=np.float64), float(h["palm_radius"]),
                                        float(h["palm_thickness"])))

    def summary(self, contact_distance: float = 1e-3) -> dict:
        """Figures of the final grasp: status, sizes, palm contact, links within ``contact_distance``."""
        obj = self.object()
        gaps = self.link_gaps(-1, obj)
        palm = self.palm_gap(-1, obj)
        stats = self.stats
        return {
            "status": self.status,
            "configurations": len(self),
            "phase1_configurations": int(np.sum(self.phase == 1)),
            "phase2_iterations": int(np.sum(self.phase == 2)),
            "palm_contact": bool(palm <= contact_distance),
            "palm_gap_m": palm,
            "links_in_contact": int(np.sum(gaps <= contact_distance)),
            "links": int(gaps.size),
            "fingers_done": int(np.sum(self.tip_state[-1] == 2)),
            "first_contact_iteration": stats.get("first_contact_iteration"),
        }
