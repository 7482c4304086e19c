"""Grasp datasets: ``hugger generate`` writes them, :class:`Dataset` reads them.

A dataset is a folder (the format is described in ``docs/generation.md``)::

    DIR/index.json                     what was made, from what, by which command
    DIR/shards/<object>__<hand>.npz    one shard per (object, hand): every approach's grasp

Each shard holds the ``approaches`` grasps of :func:`hugger.search` for one object and one hand:
start and final palm poses, joint angles and positions, every contact (points, normals, finger,
link), quality figures (links and palm in contact, force closure, epsilon) and, with
``validate``, the six-direction physics verdict of every grasp. Shards are written to a
temporary name and renamed, so a shard under its final name is always whole: a run killed at
any moment and started again makes only the missing shards. Shards are byte-identical for the
same command, whatever the number of workers and the backend (``local`` process pool or ``ray``).
"""
from __future__ import annotations

import contextlib
import hashlib
import io
import json
import os
import re
import unicodedata
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Iterator, Mapping, Sequence, cast

import numpy as np

from . import _checks
from ._files import remove_temporaries, write_atomic
from ._npz import READ_ERRORS, Archive, ArchiveError
from ._types import VERSION

if TYPE_CHECKING:
    from .hand import Hand
    from .trajectory import Trajectory
    from .world import Object

__all__ = ["Dataset", "Grasp", "generate", "parse_hand", "DATASET_FORMAT", "SHARD_FORMAT"]

DATASET_FORMAT = "hugger-dataset"
DATASET_VERSION = 1
SHARD_FORMAT = 2  # 2: the escape figure of the ranking
_ZIP_DATE = (1980, 1, 1, 0, 0, 0)  # fixed member timestamps: byte-identical shards
_HAND_KEYS = {"link_length": float, "link_radius": float, "palm_radius": float, "palm_thickness": float}


# --------------------------------------------------------------------------------------------
# hands and tasks


def parse_hand(spec: str, force: bool = False) -> tuple[str, dict[str, Any]]:
    """A hand spec ``MxN`` or ``MxN:key=value,...`` (keys ``link_length``, ``link_radius``,
    ``palm_radius``, ``palm_thickness``, in m) -> (label for file names, Hand keyword arguments).
    ``5x5`` is the default hand of ``hugger.Hand()``. A hand of implausible size (millimetres read
    as metres: :attr:`hugger.Hand.size_warning`) is refused unless ``force``."""
    label, kwargs, _ = _parse_hand(spec, force)
    return label, kwargs


def _parse_hand(spec: str, force: bool) -> tuple[str, dict[str, Any], Hand]:
    """:func:`parse_hand`, and the hand it made."""
    m = re.fullmatch(r"\s*(\d+)x(\d+)\s*(?::(.*))?", str(spec))
    if not m:
        raise ValueError(f"hand spec must be MxN or MxN:key=value,... (e.g. 5x5, 4x3:link_length=0.025), got {spec!r}")
    kwargs: dict[str, Any] = {"fingers": int(m.group(1)), "links": int(m.group(2))}
    label = f"{kwargs['fingers']}x{kwargs['links']}"
    for item in filter(None, (m.group(3) or "").split(",")):
        key, _, value = item.partition("=")
        key = key.strip()
        if key not in _HAND_KEYS or not value:
            raise ValueError(f"hand spec {spec!r}: unknown or empty setting {item!r}; expected some of "
                             f"{sorted(_HAND_KEYS)}")
        if key in kwargs:
            raise ValueError(f"hand spec {spec!r}: {key} is given twice")
        try:
            kwargs[key] = _HAND_KEYS[key](value)
        except ValueError:
            raise ValueError(f"hand spec {spec!r}: {key} must be a number, got {value!r}") from None
        label += f"_{key}{kwargs[key]:g}"
    from .hand import Hand, plausible_hand

    try:  # the sizes checked now, not in a worker
        hand = plausible_hand(force, "force=True, --force, to make its shards anyway", lambda: Hand(**kwargs))
    except ValueError as exc:
        raise ValueError(f"hand spec {spec!r}: {exc}") from None
    return label, kwargs, hand


def _safe(name: str) -> str:
    """``name`` as part of a file name: letters and digits of any script (composed: a decomposed
    accent is kept with its letter), '.', '-' and '_'."""
    return re.sub(r"[^\w.-]+", "_", unicodedata.normalize("NFC", name)).strip("_") or "object"


def _sha256_file(path: str) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _object_entry(spec: str, scale: float, force: bool = False) -> dict[str, Any]:
    """Index entry of one object: name, path (as given, or the built-in name) and content hash.
    A mesh file of an implausible size for a hand is refused unless ``force``; its repairs are
    told (as warnings)."""
    import warnings

    from . import objects
    from .scenarios import judged_case, load_object

    if spec in objects.BUILTINS:
        _, obj, _ = load_object(spec, scale)
        digest = hashlib.sha256(np.ascontiguousarray(obj.vertices).tobytes() +
                                np.ascontiguousarray(obj.faces).tobytes()).hexdigest()
        return {"name": spec, "path": spec, "builtin": True, "sha256": digest, "scale": scale}
    if not os.path.isfile(spec):  # refused as the plan command refuses it (no such file: a ValueError)
        try:
            load_object(spec, scale)  # raises, saying what the path is
        except FileNotFoundError as exc:
            raise ValueError(str(exc)) from None
    # Refuses what a worker would, before any shard is made: a mesh the planner cannot take, or
    # one whose natural target T is not inside it (the start pose depends on the hand; T does not).
    case, message = judged_case(spec, scale=scale, force=force)
    if message:
        warnings.warn(f"{message} (making its shards anyway: force)", UserWarning, stacklevel=3)
    for r in case.repairs:
        warnings.warn(f"repaired {case.name}: {r}", UserWarning, stacklevel=3)
    return {"name": Path(spec).stem, "path": spec, "builtin": False, "sha256": _sha256_file(spec), "scale": scale}


def _task_key(task: dict[str, Any], spelled: bool = False) -> str:
    """Hash of everything a shard depends on: not the worker count, backend or output folder, nor
    how its mesh file's path is spelled (its content hash stands for the file). ``spelled``: the
    key earlier versions gave, which hashed the path as given too (their shards are resumed)."""
    keep = {k: task[k] for k in ("object", "hand", "approaches", "params", "rules", "validate", "format")}
    if not spelled:
        keep["object"] = {k: v for k, v in keep["object"].items() if k != "path"}
    return hashlib.sha256(json.dumps(keep, sort_keys=True).encode()).hexdigest()


# --------------------------------------------------------------------------------------------
# one shard


def _npz_bytes(arrays: dict[str, np.ndarray]) -> bytes:
    """An .npz (loads with allow_pickle=False) whose bytes depend only on the arrays."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for key in sorted(arrays):
            info = zipfile.ZipInfo(key + ".npy", date_time=_ZIP_DATE)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            member = io.BytesIO()
            arr = np.asarray(arrays[key])  # (np.ascontiguousarray would turn scalars into (1,) arrays)
            np.lib.format.write_array(member, arr if arr.flags.c_contiguous else arr.copy(), allow_pickle=False)
            zf.writestr(info, member.getvalue(), compresslevel=6)
    return buf.getvalue()


def make_shard(task: dict[str, Any]) -> bytes:
    """The shard of one (object, hand) task, as the bytes of its .npz file. Pure: the same task
    gives the same bytes in any process."""
    import warnings

    from .hand import Hand
    from .scenarios import judged_case
    from .analysis import escape
    from .search import search

    ob = task["object"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # a hand's size: warned of (or refused) by generate
        hand = Hand(**task["hand"]["kwargs"])
    case, _ = judged_case(ob["path"], hand, scale=ob["scale"], force=True)  # judged by generate
    if ob["builtin"] is False and _sha256_file(ob["path"]) != ob["sha256"]:
        raise ValueError(f"{ob['path']} changed since the dataset was started (content hash differs)")
    pole = case.palm_pose[:3, 3] - case.target
    params = {k: v for k, v in task["params"].items() if v is not None}
    result = search(hand, case.obj, case.target, approaches=task["approaches"], rules=task["rules"], threads=1,
                    pole=pole, keep_all=True, **params)
    k = len(result.candidates)
    m, n = hand.fingers, hand.links
    nan = np.nan
    a: dict[str, Any] = {
        "format_version": np.int64(SHARD_FORMAT), "task_sha256": np.str_(_task_key(task)),
        "object_name": np.str_(ob["name"]), "object_sha256": np.str_(ob["sha256"]),
        # the rule set is the task's own (its key keeps None among the parameters): recorded here too,
        # so that a shard read on its own says how it was planned
        "hand_json": np.str_(hand.to_json()),
        "params_json": np.str_(json.dumps({**task["params"], "rules": task["rules"]}, sort_keys=True)),
        "target": np.asarray(case.target, dtype=np.float64), "best": np.int64(result.best),
        "direction": np.stack([c.direction for c in result.candidates]).astype(np.float64),
        "status": np.array([c.status for c in result.candidates], dtype=np.str_),
        "configurations": np.array([c.configurations for c in result.candidates], dtype=np.int64),
        "start_pose": np.full((k, 4, 4), nan), "palm_pose": np.full((k, 4, 4), nan),
        "joints": np.full((k, m, n + 1, 3), nan), "angles": np.full((k, m, n), nan),
        "tip_state": np.full((k, m), -1, dtype=np.int8),
        "links_in_contact": np.zeros(k, dtype=np.int64), "palm_contact": np.zeros(k, dtype=bool),
        "force_closure": np.zeros(k, dtype=bool), "epsilon": np.zeros(k), "escape": np.full(k, nan),
    }
    points, normals, finger, link, offsets = [], [], [], [], [0]
    verdicts: list[dict[str, Any] | None] = []
    for i, (cand, traj, found) in enumerate(zip(result.candidates, result.trajectories or (), result.contacts or ())):
        if traj is None:
            offsets.append(offsets[-1])
            verdicts.append(None)
            continue
        a["start_pose"][i], a["palm_pose"][i] = cand.start_pose, traj.palm_pose[-1]  # the pose given, exactly
        a["joints"][i], a["angles"][i], a["tip_state"][i] = traj.joints[-1], traj.angles[-1], traj.tip_state[-1]
        a["links_in_contact"][i], a["palm_contact"][i] = cand.links_in_contact, cand.palm_contact
        a["force_closure"][i], a["epsilon"][i] = cand.force_closure, cand.epsilon  # judged on `found`
        a["escape"][i] = cand.escape if cand.escape is not None else escape(hand, case.obj, traj.palm_pose[-1],
                                                                          traj.joints[-1])
        points.append(found.points)
        normals.append(found.normals)
        finger.append(found.finger)
        link.append(found.link)
        offsets.append(offsets[-1] + len(found))
        verdicts.append(None)
        if task["validate"]:
            from . import physics

            verdicts[-1] = physics.validate(traj, cache_dir=task.get("cache_dir"))
    a["contact_offsets"] = np.asarray(offsets, dtype=np.int64)
    a["contact_points"] = np.concatenate(points) if points else np.zeros((0, 3))
    a["contact_normals"] = np.concatenate(normals) if normals else np.zeros((0, 3))
    a["contact_finger"] = np.concatenate(finger).astype(np.int64) if finger else np.zeros(0, np.int64)
    a["contact_link"] = np.concatenate(link).astype(np.int64) if link else np.zeros(0, np.int64)
    if task["validate"]:
        from .physics import DIRECTIONS

        names = list(DIRECTIONS)
        a["held"] = np.array([bool(v and v["held"]) for v in verdicts])
        a["held_directions"] = np.array([[bool(v and v["directions"][d]["held"]) for d in names] for v in verdicts],
                                        dtype=bool).reshape(k, len(names))
        a["displacement_m"] = np.array([[(v["directions"][d]["displacement_m"] if v else None) or nan for d in names]
                                        for v in verdicts], dtype=np.float64).reshape(k, len(names))
        a["validate_directions"] = np.array(names, dtype=np.str_)
    return _npz_bytes(a)


def _not_whole(path: Path, why: object) -> ValueError:
    """The error of a shard file that is not whole (damaged, or not of the format), naming it."""
    return ValueError(f"{path} is not a whole shard ({why}); 'hugger generate' with the command in index.json "
                      f"makes it again")


@contextlib.contextmanager
def _open_shard(path: Path, data: bytes | None = None) -> Iterator[Archive]:
    """The arrays of a shard file, read as trajectory files are (hugger._npz: no pickles, no
    declared size the file lacks, no decompression bomb), the file closed whatever happens;
    ``ValueError`` naming the file when it is not a whole .npz (on opening, or on reading an
    array of it). ``data``: the file's bytes, read already (not read again)."""
    if data is None and not path.is_file():
        raise ValueError(f"{path} is missing; 'hugger generate' with the command in index.json makes it again")
    with open(path, "rb") if data is None else io.BytesIO(data) as fh:
        if not zipfile.is_zipfile(fh):
            raise _not_whole(path, "not a zip archive")
        fh.seek(0)
        try:
            z = Archive(fh)
        except READ_ERRORS as exc:
            raise _not_whole(path, exc) from None
        with z:
            try:
                yield z
            except ArchiveError as exc:
                raise _not_whole(path, exc) from None


def _read_index(path: Path) -> dict[str, Any]:
    """A dataset's index.json; ``ValueError`` unless it is one of this format and version."""
    try:
        index = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError) as exc:  # (nested too deep for the reader)
        raise ValueError(f"{path} is not the index of a hugger dataset ({exc})") from None
    if not isinstance(index, dict) or index.get("format") != DATASET_FORMAT or \
            index.get("format_version") != DATASET_VERSION or not isinstance(index.get("shards"), list):
        raise ValueError(f"{path} is not the index of a hugger dataset of version {DATASET_VERSION}")
    # what the loader reads of it, of the types it reads (docs/generation.md, "Format")
    def listed(key: str, fields: dict[str, type | tuple[type, ...]]) -> bool:
        entries = index.get(key)
        return isinstance(entries, list) and all(
            isinstance(e, dict) and all(isinstance(e.get(f), t) and not (t is not bool and isinstance(e.get(f), bool))
                                        for f, t in fields.items()) for e in entries)

    if not (listed("shards", {"file": str, "object": str, "hand": str, "task_sha256": str, "sha256": str})
            and listed("objects", {"name": str, "path": str, "builtin": bool, "sha256": str, "scale": (int, float)})
            and listed("hands", {"label": str, "kwargs": dict}) and isinstance(index.get("parameters"), dict)):
        raise ValueError(f"{path} is not the index of a hugger dataset: its shards, objects, hands or parameters "
                         f"are not the entries docs/generation.md describes")
    return index


def _shard_done(path: Path, keys: tuple[str, ...]) -> str | None:
    """The key of the shard under its final name when it exists and was made for this task (one of
    the task's ``keys``), else None."""
    if not path.is_file():
        return None
    try:
        with _open_shard(path) as z:
            stored = str(z["task_sha256"])
    except (OSError, ValueError, KeyError):
        return None  # not ours or damaged: made again
    if stored not in keys:
        raise ValueError(f"{path} was made with other settings (objects, hand, approaches, planner parameters or "
                         f"--validate); remove it and repeat the command to make it again, or write this dataset "
                         f"to a new --out folder")
    return stored


def _check_index(root: Path, tasks: list[dict[str, Any]]) -> None:
    """Refuses a folder whose index lists a shard this run would not make (other objects, hands or
    settings): the run would write an index without it. The same command, or one that adds
    objects or hands with the same settings, finishes or grows the dataset."""
    path = root / "index.json"
    if not path.exists():
        return
    try:
        old = _read_index(path)
    except ValueError as exc:
        raise ValueError(f"{exc}; write this dataset to a new folder") from None
    listed = [(e["file"], e["task_sha256"]) for e in old["shards"]]  # (entries _read_index checked)
    ours = {(f"shards/{t['file']}", key) for t in tasks for key in t["keys"]}
    left_out = [f for f, key in listed if (f, key) not in ours]
    if left_out:
        made_by = old.get("hugger_version")
        why = f" (made by hugger {made_by}; this is {VERSION})" if made_by != VERSION else ""
        raise ValueError(f"{root} holds a dataset made with other settings or objects{why}: {len(left_out)} of its "
                         f"{len(listed)} shards (e.g. {left_out[0]}) are not part of this run; write this dataset to "
                         f"a new folder, or repeat the command that made it (it may add objects or hands), or "
                         f"remove {path.name} to make an index of this run's shards alone")


# --------------------------------------------------------------------------------------------
# the run


#: How long a Ray address is given to accept a connection before it is refused (s).
RAY_CONNECT_TIMEOUT = 10.0


def _check_ray_address(address: Any) -> str:
    """``address`` for ``ray.init``: 'auto', 'local', HOST:PORT or ray://HOST:PORT (HOST a name or
    an address, IPv6 in brackets), where something accepts a connection within
    :data:`RAY_CONNECT_TIMEOUT` once the name is resolved (``ray.init`` would retry for minutes);
    otherwise a ValueError. Ray's other address schemes are not taken."""
    import socket

    if not isinstance(address, str):
        raise ValueError(f"address must be a string, got {address!r}")
    if address in ("auto", "local"):
        return address
    rest = address[len("ray://"):] if address.startswith("ray://") else address
    host, sep, port = rest.rpartition(":")
    if host.startswith("[") and host.endswith("]"):  # an IPv6 address, bracketed
        host = host[1:-1]
    elif ":" in host:
        host = ""
    if (not sep or not host or "/" in host or any(c.isspace() for c in host) or not port.isdigit()
            or not 0 < int(port) < 65536):
        raise ValueError(f"address must be 'auto', 'local', HOST:PORT or ray://HOST:PORT, got {address!r}")
    try:
        with socket.create_connection((host, int(port)), timeout=RAY_CONNECT_TIMEOUT):
            pass
    except OSError as exc:
        raise ValueError(f"no Ray cluster answers at {address}: {exc.strerror or exc}") from None
    return address


#: How long a Ray client is given to join the cluster at an address before it is refused (s).
RAY_PROBE_TIMEOUT = 60.0


def _probe_ray(address: str) -> None:
    """Join the cluster at ``address`` from a child process, which is ended after
    :data:`RAY_PROBE_TIMEOUT`: where something other than Ray listens, ``ray.init`` retries for ever
    and ignores Ctrl-C, which must not happen to this process."""
    import subprocess
    import sys

    if address in ("auto", "local"):  # (a cluster found, or started, on this machine: no address to try)
        return
    code = "import sys, ray; ray.init(address=sys.argv[1], log_to_driver=False, logging_level='ERROR')"
    try:
        done = subprocess.run([sys.executable, "-c", code, address], capture_output=True, text=True,
                              timeout=RAY_PROBE_TIMEOUT)
    except subprocess.TimeoutExpired:
        raise ValueError(f"no Ray cluster answers at {address} within {RAY_PROBE_TIMEOUT:g} s (something else "
                         f"listens there?)") from None
    if done.returncode != 0:
        lines = [line for line in done.stderr.splitlines() if line.strip()]
        raise ValueError(f"no Ray cluster answers at {address}: {lines[-1] if lines else 'ray.init failed'}")


@contextlib.contextmanager
def _ray_session(ray: Any, address: str | None, workers: int) -> Iterator[None]:
    """Ray for the block (``ray`` None: no Ray needed): started here unless it runs already, on
    ``address`` (tried first: _probe_ray) or locally with ``workers`` CPUs, and shut down when the
    block ends if it was started here."""
    if ray is None or ray.is_initialized():
        yield
        return
    if address is None:
        ray.init(num_cpus=workers, include_dashboard=False, log_to_driver=False, logging_level="WARNING")
    else:
        _probe_ray(address)
        try:
            ray.init(address=address, log_to_driver=False, logging_level="WARNING")
        except ConnectionError as exc:  # something answered the address check, but no Ray
            raise ValueError(f"no Ray cluster answers at {address}: {exc}") from None
    try:
        yield
    finally:
        ray.shutdown()


def _ray() -> Any:
    try:
        import ray
    except ImportError:
        raise ImportError("--backend ray needs Ray: pip install 'hugger[cluster]'") from None
    return ray


def _names(name: str, value: Any, what: str = "names") -> list[Any]:
    """``value`` (a list, or any iterable, read here once) as a list; a ValueError naming ``name``
    for a single string (one name, not a list of them) or for what is no iterable."""
    if isinstance(value, (str, bytes, os.PathLike)):
        hint = f" (write [{value!r}])" if what == "names" else ""
        raise ValueError(f"{name} must be a list of {what}, got the single {value!r}{hint}")
    try:
        return list(value)
    except TypeError:
        raise ValueError(f"{name} must be a list of {what}, got {value!r}") from None


#: The file a run of generate holds locked in its dataset's folder while it writes there.
LOCK_FILE = ".hugger-lock"


def _lock(path: Path) -> int | None:
    """An open descriptor of ``path`` (made if missing) holding its exclusive lock; None where the
    filesystem takes no lock (NFS without its lock service, Lustre without ``flock``: the run goes
    on unguarded, and says so) or the system has no ``flock`` (not POSIX); ``ValueError`` when
    another run holds it."""
    import errno
    import warnings

    try:
        import fcntl
    except ImportError:
        return None

    for _ in range(8):
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(fd)
            raise ValueError(f"{path.parent} is being written by another hugger generate: wait for it to end, or "
                             f"write to another folder") from None
        except OSError as exc:
            os.close(fd)
            if exc.errno not in (errno.EBADF, errno.ENOLCK, errno.ENOSYS, errno.EOPNOTSUPP, errno.EINVAL):
                raise
            warnings.warn(f"{path.parent}: this filesystem takes no lock ({exc.strerror}); two runs writing this "
                          f"dataset at once would not be told apart", stacklevel=4)
            return None
        # A run that failed may have removed the file between our open and our lock: the lock
        # then holds a file no other run finds. Locked the file under the name, or try again.
        try:
            if os.stat(path).st_ino == os.fstat(fd).st_ino:
                return fd
        except FileNotFoundError:
            pass
        os.close(fd)
    raise ValueError(f"{path}: could not be locked (removed again and again)")


@contextlib.contextmanager
def _exclusive(root: Path) -> Iterator[None]:
    """Holds the dataset folder ``root`` (made here, with its parents) for this run: a second run
    writing the same folder meanwhile is refused (the two would mix their shards, and each write
    its own index). A run that ends in an exception leaves none of the folders it made that are
    still empty but for its lock file and an empty ``shards``."""
    made = [p for p in (root, *root.parents) if not p.exists()]  # the deepest first
    root.mkdir(parents=True, exist_ok=True)
    fd: int | None = None
    try:
        fd = _lock(root / LOCK_FILE)
        yield
    except BaseException:
        if made:  # this run made the folder: what it holds of this run alone goes with it
            with contextlib.suppress(OSError):
                (root / "shards").rmdir()  # only if empty
            if {p.name for p in root.iterdir()} <= {LOCK_FILE}:
                with contextlib.suppress(OSError):
                    (root / LOCK_FILE).unlink()
            for p in made:
                with contextlib.suppress(OSError):
                    p.rmdir()  # only if empty
        raise
    finally:
        if fd is not None:
            os.close(fd)  # (the lock goes with it)


def generate(objects: Sequence[str], out: str | os.PathLike[str], approaches: int = 26, hands: Sequence[str] = ("5x5",),
             validate: bool = False, workers: int | None = None, backend: str = "local", address: str | None = None,
             scale: float = 1.0, rules: str | None = None, params: dict[str, Any] | None = None,
             command: Sequence[str] | None = None, log: Callable[[str], Any] | None = None,
             progress: Callable[[int, int], Any] | None = None, force: bool = False) -> dict[str, Any]:
    """Make (or finish) the dataset in ``out``: one shard per (object, hand); returns the index.

    ``objects``: built-in names or mesh files; ``hands``: specs of :func:`parse_hand`;
    ``approaches``: K of :func:`hugger.search`; ``validate``: run :func:`hugger.physics.validate` on
    every grasp. ``workers``: processes (``local``, default the CPUs available) or the Ray tasks
    in flight (``ray``). ``backend="ray"`` runs one Ray task per shard on ``ray.init(address)``
    (a local Ray when ``address`` is None; an address where nothing answers within
    :data:`RAY_CONNECT_TIMEOUT` is refused, and so is one where a Ray client tried in a child
    process joins no cluster within :data:`RAY_PROBE_TIMEOUT`, before the first shard). Shards
    already present are kept; the index is written last. ``command``: the command line recorded
    in the index. A mesh file whose size is implausible for a hand (millimetres read as metres:
    :data:`hugger.hand.PLAUSIBLE_SIZE`), or a hand of implausible size, is refused (``ValueError``)
    unless ``force``.
    """
    from .search import approach_directions

    approach_directions(approaches)  # checks K
    if backend not in ("local", "ray"):
        raise ValueError(f"backend must be 'local' or 'ray', got {backend!r}")
    objects, hands = _names("objects", objects), _names("hands", hands)
    command = None if command is None else _names("command", command, "strings (the command line's words)")
    if not objects:
        raise ValueError("give at least one object")
    if not hands:
        raise ValueError("give at least one hand")
    for o in objects:
        if not isinstance(o, (str, os.PathLike)):
            raise ValueError(f"each object must be a built-in name or a mesh file's path, got {o!r}")
    if not isinstance(out, (str, os.PathLike)) or not os.fspath(out):
        raise ValueError(f"out must be a folder's path, got {out!r}")
    scale = _checks.positive("scale", scale)
    if params is not None and not isinstance(params, Mapping):
        raise ValueError(f"params must be a mapping of planner parameters, got {type(params).__name__}")
    if command is not None and not all(isinstance(c, str) for c in command):
        raise ValueError(f"command must be a list of strings (the command line's words), got {command!r}")
    validate = _checks.flag("validate", validate)
    force = _checks.flag("force", force)
    _checks.callback("log", log, "log(line)")
    _checks.callback("progress", progress, "progress(done, total)")
    blocking = next((p for p in (Path(out), *Path(out).parents) if p.exists() and not p.is_dir()), None)
    if blocking is not None:  # (mkdir would raise NotADirectoryError or FileExistsError)
        raise ValueError(f"{blocking} is a file; a dataset is a folder (give a new folder, or the folder of a "
                         f"dataset to finish)")
    workers = _checks.workers("workers", workers)
    if address is not None and backend != "ray":
        raise ValueError("an address applies to the Ray backend only")
    ray: Any = _ray() if backend == "ray" else None  # the extra named first
    if validate and backend == "local":  # MuJoCo, before any folder is made (Ray's workers have their own)
        from .physics._common import _mujoco

        _mujoco("validate")
    if address is not None:
        _check_ray_address(address)
    from .planner import PARAMS, check_params

    params = dict(params or {})
    check_params(params)
    if params.get("rules") is not None:  # the rule set given among the planner parameters
        if rules is not None and rules != params["rules"]:
            raise ValueError(f"the rule set is given twice: rules={rules!r} and params['rules']={params['rules']!r}")
        rules = params["rules"]
    from .planner import RULES

    if rules is not None and rules not in RULES:
        raise ValueError(f"rules must be one of {list(RULES)}, got {rules!r}")
    params = {k: params.get(k) for k in PARAMS}
    params["rules"] = None  # the rule set is the task's own "rules" (as in the keys of earlier datasets)
    built = [_parse_hand(h, force) for h in hands]
    if len({label for label, _, _ in built}) != len(built):
        raise ValueError("the same hand is given twice")
    obj_list = [_object_entry(os.fspath(o), float(scale), force) for o in objects]
    names = [_safe(o["name"]) for o in obj_list]
    if len(set(names)) != len(names):
        raise ValueError(f"two objects share a name: {sorted(x for x in names if names.count(x) > 1)}")
    root = Path(out)
    shard_dir = root / "shards"
    tasks: list[dict[str, Any]] = []
    hand_entries = [{"label": label, "kwargs": kwargs, "json": hand.to_json()} for label, kwargs, hand in built]
    for label, _, hand in built:  # the parameters against each hand, before any shard is made
        try:
            check_params(params, hand=hand)
        except ValueError as exc:
            raise ValueError(f"hand {label!r}: {exc}") from None
    # The same hand under two specs (5x5, 5x5:link_length=0.02) would make the same grasps twice;
    # a dataset made so before this check (shards of both in its folder) is still finished by its
    # own command.
    shard_names = [p.name for p in shard_dir.glob("*.npz")]  # (none where the folder is not yet)
    for i, entry in enumerate(hand_entries):
        same = next((e["label"] for e in hand_entries[:i] if e["json"] == entry["json"]), None)
        made = [any(n.endswith(f"__{label}.npz") for n in shard_names) for label in (same, entry["label"])]
        if same is not None and not all(made):
            raise ValueError(f"the hands {same!r} and {entry['label']!r} are the same hand")
    for ob, safe_name in zip(obj_list, names):
        for entry in hand_entries:
            task: dict[str, Any] = {"format": SHARD_FORMAT, "object": ob, "hand": entry, "approaches": int(approaches),
                                    "params": params, "rules": rules, "validate": bool(validate)}
            task["file"] = f"{safe_name}__{entry['label']}.npz"
            task["keys"] = (_task_key(task), _task_key(task, spelled=True))  # this version's first
            tasks.append(task)
    with _exclusive(root):  # this run alone writes the folder, from its check of the index to its index
        _check_index(root, tasks)
        held = {t["file"]: _shard_done(shard_dir / t["file"], t["keys"]) for t in tasks}  # their keys
        todo = [t for t in tasks if held[t["file"]] is None]
        # Ray first: a cluster that cannot be reached is refused before anything is written (and a Ray
        # started here is shut down however the block ends).
        with _ray_session(ray if todo else None, address, workers):
            shard_dir.mkdir(parents=True, exist_ok=True)
            remove_temporaries(shard_dir)  # left by a killed run
            say = log or (lambda s: None)
            say(f"{len(tasks) - len(todo)} of {len(tasks)} shards already done; making {len(todo)}")
            done = len(tasks) - len(todo)
            if progress is not None:
                progress(done, len(tasks))

            digests: dict[str, str] = {}  # of the shards written now (kept ones are hashed from disk)

            def finished(task: dict[str, Any], data: bytes) -> None:
                nonlocal done
                write_atomic(shard_dir / task["file"], data)
                digests[task["file"]] = hashlib.sha256(data).hexdigest()
                done += 1
                say(f"shard {done}/{len(tasks)} written: {task['file']}")
                if progress is not None:
                    progress(done, len(tasks))

            if todo and backend == "local":
                if workers == 1 or len(todo) == 1:
                    for t in todo:
                        finished(t, make_shard(t))
                else:
                    from concurrent.futures import FIRST_COMPLETED, wait

                    from ._pool import running_pool

                    # Interrupted (Ctrl-C, or SIGINT to this process alone), the pool is stopped at once
                    # rather than waited for (running_pool), and the shards made meanwhile are kept.
                    with running_pool(workers, len(todo)) as pool:
                        pending: dict[Any, dict[str, Any]] = {}
                        try:
                            for t in todo:
                                pending[pool.submit(make_shard, t)] = t
                            while pending:
                                ready, _ = wait(pending, return_when=FIRST_COMPLETED)
                                for fut in sorted(ready, key=lambda f: pending[f]["file"]):
                                    finished(pending.pop(fut), fut.result())
                        except BaseException:
                            with contextlib.suppress(Exception):
                                for fut in sorted(pending, key=lambda f: pending[f]["file"]):
                                    if fut.done() and not fut.cancelled() and fut.exception() is None:
                                        finished(pending[fut], fut.result())
                            raise
            elif todo:
                remote = ray.remote(num_cpus=1, max_retries=2)(make_shard)
                waiting: dict[Any, dict[str, Any]] = {}
                queue = list(todo)
                while queue or waiting:
                    while queue and len(waiting) < max(1, workers):
                        t = queue.pop(0)
                        waiting[remote.remote(t)] = t
                    ready, _ = ray.wait(list(waiting), num_returns=1)
                    for ref in ready:
                        finished(waiting.pop(ref), ray.get(ref))

        index = {
            "format": DATASET_FORMAT, "format_version": DATASET_VERSION, "hugger_version": VERSION,
            "command": list(command) if command is not None else None,
            "parameters": {"approaches": int(approaches), "validate": bool(validate), "rules": rules, "scale": float(scale),
                           "planner": params},
            # a mesh file's absolute path beside the path as given (this run's): the dataset is then
            # read from any folder
            "objects": [o if o["builtin"] else {**o, "abspath": os.path.abspath(o["path"])} for o in obj_list],
            "hands": hand_entries,
            "shards": [{"file": f"shards/{t['file']}", "object": t["object"]["name"], "hand": t["hand"]["label"],
                        "task_sha256": held[t["file"]] or t["keys"][0],
                        "sha256": digests.get(t["file"]) or _sha256_file(str(shard_dir / t["file"]))} for t in tasks],
        }
        write_atomic(root / "index.json", json.dumps(index, indent=1, sort_keys=True) + "\n")
        return index


# --------------------------------------------------------------------------------------------
# reading


@dataclass(frozen=True, eq=False)
class Grasp:
    """One grasp of a dataset (arrays in the world frame, m, rad; its repr leaves the arrays out)."""

    object: str  #: object name
    hand: str  #: hand label
    shard: int  #: shard index in the dataset
    index: int  #: approach index within the shard
    best: bool  #: the one :func:`hugger.search` chose for this (object, hand)
    status: str  #: the plan's status (``error`` when it failed)
    direction: np.ndarray = field(repr=False)  #: (3,) approach direction from T
    start_pose: np.ndarray = field(repr=False)  #: (4, 4) palm pose the plan started from
    palm_pose: np.ndarray = field(repr=False)  #: (4, 4) final palm pose T_WP
    joints: np.ndarray = field(repr=False)  #: (M, N+1, 3) final joint positions
    angles: np.ndarray = field(repr=False)  #: (M, N) final joint angles
    links_in_contact: int
    palm_contact: bool
    force_closure: bool
    epsilon: float  #: Ferrari-Canny epsilon (mu = 0.5) over all contacts
    escape: float | None  #: the largest free slide of the object (m, at most 0.05; None: a shard of format 1)
    contact_points: np.ndarray = field(repr=False)  #: (C, 3) contact points on the object
    contact_normals: np.ndarray = field(repr=False)  #: (C, 3) outward normals there
    contact_finger: np.ndarray = field(repr=False)  #: (C,) finger of each contact, -1 the palm
    contact_link: np.ndarray = field(repr=False)  #: (C,) link of each contact, -1 the palm
    held: bool | None  #: six-direction physics verdict (None: not validated)


#: K, the approaches of a shard, and K + 1, in the shapes below.
_K, _K1 = -1, -2
#: A shard's members the loader reads, and their shapes (None: any length). Its ``status``, one per
#: approach, is read when the dataset is opened (Dataset's constructor) and gives K.
_SHARD_MEMBERS: dict[str, tuple[int | None, ...]] = {
    "best": (), "direction": (_K, 3), "start_pose": (_K, 4, 4), "palm_pose": (_K, 4, 4),
    "joints": (_K, None, None, 3), "angles": (_K, None, None), "links_in_contact": (_K,), "palm_contact": (_K,),
    "force_closure": (_K,), "epsilon": (_K,), "contact_offsets": (_K1,), "contact_points": (None, 3),
    "contact_normals": (None, 3), "contact_finger": (None,), "contact_link": (None,), "target": (3,),
    "params_json": ()}
#: ... and those it reads when a shard holds them (format 1 has no escape; held comes with --validate).
_SHARD_OPTIONAL: dict[str, tuple[int | None, ...]] = {"escape": (_K,), "held": (_K,)}


def _check_shard(z: dict[str, np.ndarray], k: int, path: Path) -> None:
    """``ValueError`` unless the shard's members the loader reads are there, of its K approaches,
    and its contact offsets split its contacts (docs/generation.md, "Format")."""
    sizes = {_K: k, _K1: k + 1}
    for key, shape in {**_SHARD_MEMBERS, **_SHARD_OPTIONAL}.items():
        if key not in z:
            if key in _SHARD_OPTIONAL:
                continue
            raise _not_whole(path, f"no {key}")
        got = z[key].shape
        if len(got) != len(shape) or any(want is not None and n != sizes.get(want, want) for n, want in zip(got, shape)):
            raise _not_whole(path, f"{key} has shape {got}")
    c = len(z["contact_points"])
    off = z["contact_offsets"]
    if (off.dtype.kind not in "iu" or off[0] != 0 or off[-1] != c or np.any(np.diff(off) < 0)
            or any(len(z[key]) != c for key in ("contact_normals", "contact_finger", "contact_link"))):
        raise _not_whole(path, "its contact offsets do not split its contacts")
    if z["best"].dtype.kind not in "iu" or not 0 <= int(z["best"]) < max(k, 1):
        raise _not_whole(path, f"best is {_checks.shown(z['best'])}")


def _item_index(i: Any, count: int, what: str) -> int:
    """Index ``i`` (negative counts from the end) of a dataset's ``count`` shards or grasps
    (``what``): ``TypeError`` for what is no integer, ``IndexError`` naming the range."""
    if isinstance(i, bool) or not isinstance(i, (int, np.integer)):
        raise TypeError(f"a {what} index must be an integer, got {type(i).__name__}")
    if not -count <= i < count:
        raise IndexError(f"{what} {_checks.shown(i)} is out of range for a dataset of {count} {what}s")
    return int(i) % count


class Dataset:
    """A dataset written by :func:`generate` / ``hugger generate``: ``len(ds)`` grasps over
    ``ds.shards``; ``ds[i]`` is a :class:`Grasp`; ``ds.trajectory(i)`` re-plans grasp i
    (deterministic, checked against the stored grasp); ``ds.export_mjcf(i, path)`` writes it as
    MJCF with the ``grasp`` keyframe (as ``hugger export-mjcf``)."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.root = Path(path)
        index_path = self.root / "index.json"
        # A path that is not there, or no folder, is refused as objects.load and Trajectory.load
        # refuse theirs (an OSError); a folder that holds no dataset is a ValueError (below).
        if not self.root.exists():
            raise FileNotFoundError(f"no such dataset folder: {self.root}")
        if not self.root.is_dir():
            raise NotADirectoryError(f"{self.root} is not a folder (a dataset is a folder, made by 'hugger generate')")
        if not index_path.is_file():
            raise ValueError(f"{self.root} holds no dataset index (index.json); make one with 'hugger generate'")
        self.index = _read_index(index_path)
        self.shards: list[dict[str, Any]] = list(self.index["shards"])
        self._cache: dict[int, dict[str, np.ndarray]] = {}
        self._objects: dict[str, Object] = {}
        self._sizes = []
        for s in self.shards:  # the grasp counts only: whole shards load on first use (shard())
            with _open_shard(self.root / s["file"]) as z:
                status = z["status"] if "status" in z.files else None
                if status is None or status.ndim != 1:
                    raise _not_whole(self.root / s["file"], "no status per approach")
                self._sizes.append(int(status.shape[0]))
        self._starts = np.concatenate([[0], np.cumsum(self._sizes)]).astype(int)

    def __len__(self) -> int:
        return int(self._starts[-1])

    def shard(self, i: int) -> dict[str, np.ndarray]:
        """Every array of shard i (see docs/generation.md), loaded without pickles."""
        i = _item_index(i, len(self.shards), "shard")
        if i not in self._cache:
            path = self.root / self.shards[i]["file"]
            data = path.read_bytes() if path.is_file() else None  # once: loaded and hashed (None: missing)
            with _open_shard(path, data) as z:
                arrays = z.read_all()
            _check_shard(arrays, self._sizes[i], path)
            # the shard the index lists, not another one copied or renamed there, nor one changed
            if hashlib.sha256(cast(bytes, data)).hexdigest() != self.shards[i]["sha256"]:  # (None: refused above)
                raise ValueError(f"{path} is not the shard the index lists: its SHA-256 differs (replaced or changed "
                                 f"since it was made); remove it and repeat the command that made the dataset, which makes it again")
            self._cache[i] = arrays
        return self._cache[i]

    def _locate(self, i: int) -> tuple[int, int]:
        i = _item_index(i, len(self), "grasp")
        s = int(np.searchsorted(self._starts, i, side="right") - 1)
        return s, i - int(self._starts[s])

    def __getitem__(self, i: int) -> Grasp:
        s, j = self._locate(i)
        z = self.shard(s)
        lo, hi = int(z["contact_offsets"][j]), int(z["contact_offsets"][j + 1])
        return Grasp(object=self.shards[s]["object"], hand=self.shards[s]["hand"], shard=s, index=j,
                     best=j == int(z["best"]), status=str(z["status"][j]), direction=z["direction"][j],
                     start_pose=z["start_pose"][j], palm_pose=z["palm_pose"][j], joints=z["joints"][j],
                     angles=z["angles"][j], links_in_contact=int(z["links_in_contact"][j]),
                     palm_contact=bool(z["palm_contact"][j]), force_closure=bool(z["force_closure"][j]),
                     epsilon=float(z["epsilon"][j]),
                     escape=float(z["escape"][j]) if "escape" in z else None, contact_points=z["contact_points"][lo:hi],
                     contact_normals=z["contact_normals"][lo:hi], contact_finger=z["contact_finger"][lo:hi],
                     contact_link=z["contact_link"][lo:hi], held=bool(z["held"][j]) if "held" in z else None)

    def __iter__(self) -> Iterator[Grasp]:
        for i in range(len(self)):
            yield self[i]

    def object(self, name: str) -> Object:
        """The object ``name`` as a :class:`hugger.Object`, checked against its recorded hash (once)."""
        if name not in self._objects:
            self._objects[name] = self._load_object(name)
        return self._objects[name]

    def _load_object(self, name: str) -> Object:
        from .scenarios import load_object

        entry = next((o for o in self.index["objects"] if o["name"] == name), None)
        if entry is None:
            raise ValueError(f"no object {name!r} in this dataset")
        if not entry["builtin"]:
            # as given, else where it was when the dataset was made, else beside the dataset: the
            # first of these that is the mesh it was made from
            # (beside it: under its path within the dataset's folder, or by its name in that folder)
            given = entry["path"]
            tried = list(dict.fromkeys(p for p in (given, entry.get("abspath"), str(self.root / given),
                                                   str(self.root / Path(given).name)) if p is not None))
            found = [p for p in tried if os.path.isfile(p)]
            path = next((p for p in found if _sha256_file(p) == entry["sha256"]), None)
            if path is None:
                raise ValueError(f"the mesh file {entry['path']!r} of object {name!r} is not found (tried "
                                 f"{', '.join(repr(p) for p in tried)})" if not found else
                                 f"{found[0]} is not the mesh this dataset was made from (content hash differs)")
            entry = {**entry, "path": path}
        return load_object(entry["path"], entry["scale"])[1]

    def trajectory(self, i: int) -> Trajectory:
        """Grasp i's whole plan, made again from its stored start pose with the recorded hand and
        parameters (plans are deterministic); raises ``ValueError`` if it does not end in the stored grasp."""
        from .hand import Hand
        from .planner import Planner

        g = self[i]
        if g.status == "error":
            raise ValueError(f"grasp {i} has no plan (planning failed)")
        z = self.shard(g.shard)
        kwargs = next((h["kwargs"] for h in self.index["hands"] if h["label"] == g.hand), None)
        if kwargs is None:
            raise ValueError(f"grasp {i}: its hand {g.hand!r} is not among the index's hands")
        try:
            hand = Hand(**kwargs)
        except TypeError as exc:  # keywords a Hand does not take
            raise ValueError(f"grasp {i}: the index's hand {g.hand!r} is not a hugger.Hand's keywords ({exc})") from None
        params = {k: v for k, v in json.loads(str(z["params_json"])).items() if v is not None}
        rules = self.index["parameters"].get("rules")
        if rules is not None:
            params["rules"] = rules
        obj = self.object(g.object)
        traj = Planner(hand, obj, z["target"], g.start_pose, **params).plan()
        if not (np.array_equal(traj.palm_pose[-1], g.palm_pose) and np.array_equal(traj.joints[-1], g.joints)):
            raise ValueError(f"grasp {i}: re-planning did not reproduce the stored grasp (another hugger version?)")
        return traj

    def export_mjcf(self, i: int, path: str | os.PathLike[str] | None = None, **kwargs: Any) -> str:
        """Grasp i as MJCF (hand, object, the ``grasp`` keyframe): :func:`hugger.physics.export_mjcf`."""
        from . import physics

        return physics.export_mjcf(self.trajectory(i), path, **kwargs)
