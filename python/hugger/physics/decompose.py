"""Convex pieces of a mesh for MuJoCo: the CoACD decomposition and its on-disk cache."""
from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from .._files import atomic_path
from .._npz import READ_ERRORS, Archive
from ._common import _coacd
from .mass import hull_volume, mass_properties

#: Hull volume / mesh volume below which a mesh is treated as convex (one piece, no CoACD).
CONVEX_RATIO = 1.02
#: CoACD settings: coarse on purpose (see :func:`convex_pieces`).
COACD_SETTINGS = {"threshold": 0.1, "max_convex_hull": 16, "preprocess_mode": "off", "resolution": 1000,
                  "mcts_nodes": 10, "mcts_iterations": 60, "mcts_max_depth": 3, "seed": 0}


#: The answers of this process, newest last (at most _MEMO_SIZE): the hull test compiles a MuJoCo
#: model (~0.2 s at 20k triangles) and every MJCF build of the same mesh asks again.
_MEMO: dict[tuple[str, str, float], list[tuple[np.ndarray, np.ndarray]]] = {}
_MEMO_SIZE = 16


def default_cache_dir() -> Path:
    """Where convex decompositions are cached: ``$HUGGER_CACHE_DIR/coacd``, else
    ``$XDG_CACHE_HOME/hugger/coacd``, else ``~/.cache/hugger/coacd``."""
    if os.environ.get("HUGGER_CACHE_DIR"):
        return Path(os.environ["HUGGER_CACHE_DIR"]) / "coacd"
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "hugger" / "coacd"


def convex_pieces(vertices: Any, faces: Any, decompose: bool = True, cache_dir: str | os.PathLike[str] | None = None,
                  convex_ratio: float = CONVEX_RATIO) -> list[tuple[np.ndarray, np.ndarray]]:
    """Convex pieces (list of (vertices, faces)) standing in for a closed mesh in MuJoCo.

    A nearly convex mesh (hull volume / mesh volume < ``convex_ratio``) and any mesh when
    ``decompose`` is False come back whole: MuJoCo then collides its convex hull. Otherwise
    CoACD splits it with :data:`COACD_SETTINGS`: a coarse concavity threshold (0.1 instead of
    CoACD's 0.05), at most 16 pieces and a short tree search, so that a 16k-triangle scan takes
    seconds, not minutes. The trade-off: concavities shallower than about a tenth of the object's
    size stay filled in, so the simulated object is slightly fuller there than the planned one
    (conservative: the hand never sinks into it). The convexity rule has a similar blind spot: a
    concavity small in volume but deep where the hand touches it (the recessed lid of a can, a
    few millimetres) is filled by the hull. Results are cached as .npz files named by a hash
    of the mesh and the settings under ``cache_dir`` (default :func:`default_cache_dir`).
    """
    v = np.ascontiguousarray(vertices, dtype=np.float64)
    f = np.ascontiguousarray(faces, dtype=np.int64)
    if not decompose:
        return [(v, f)]
    key = hashlib.sha256(v.tobytes() + f.tobytes() + json.dumps(COACD_SETTINGS, sort_keys=True).encode()).hexdigest()
    folder = Path(cache_dir) if cache_dir is not None else default_cache_dir()
    memo = (str(folder), key, float(convex_ratio))
    if memo not in _MEMO:
        if len(_MEMO) >= _MEMO_SIZE:
            del _MEMO[next(iter(_MEMO))]
        _MEMO[memo] = _decompose(v.copy(), f.copy(), folder / f"{key[:32]}.npz", convex_ratio)
        for pv, pf in _MEMO[memo]:
            pv.setflags(write=False)
            pf.setflags(write=False)
    return list(_MEMO[memo])


def _decompose(v: np.ndarray, f: np.ndarray, path: Path, convex_ratio: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """convex_pieces without the memo: the hull test, then the cache file at ``path`` or CoACD."""
    volume = mass_properties(v, f)[0]
    if hull_volume(v) / volume < convex_ratio:
        return [(v, f)]
    folder = path.parent
    if path.is_file():
        try:
            with open(path, "rb") as fh, Archive(fh) as z:
                n = int(z["count"])
                return [(z[f"v{i}"], z[f"f{i}"]) for i in range(n)]
        except READ_ERRORS:
            pass  # a damaged cache entry is recomputed below
    coacd = _coacd()
    coacd.set_log_level("error")
    parts = coacd.run_coacd(coacd.Mesh(v, f), **COACD_SETTINGS)
    pieces = [(np.asarray(pv, dtype=np.float64), np.asarray(pf, dtype=np.int64)) for pv, pf in parts]
    if not pieces:
        return [(v, f)]
    try:
        folder.mkdir(parents=True, exist_ok=True)
        arrays: dict[str, Any] = {"count": np.int64(len(pieces))}
        for i, (pv, pf) in enumerate(pieces):
            arrays[f"v{i}"], arrays[f"f{i}"] = pv, pf
        with atomic_path(path) as tmp:
            np.savez(tmp, **arrays)
    except OSError:
        pass  # an unwritable cache only costs time
    return pieces
