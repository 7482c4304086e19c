"""Shared helpers of the test suite: random scenarios, the independent checker, plans and their
comparison, mesh files."""
from __future__ import annotations

import functools
import importlib.util
import math
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import hugger
from hugger import cli

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared"
CHECKER = SHARED / "tools" / "check_trajectory.py"
OBJECTS_DIR = SHARED / "data" / "objects"
SHARED_MISSING = "../shared (checker and meshes beside the project root) is not present in this checkout"
BENCH = ROOT / "bench"


def bench_module(name: str):
    """The benchmark script bench/<name>.py, imported as a module (with bench/ on the path)."""
    spec = importlib.util.spec_from_file_location(f"hugger_bench_{name}", BENCH / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    sys.path.insert(0, str(BENCH))
    try:
        spec.loader.exec_module(mod)
    finally:
        sys.path.remove(str(BENCH))
    return mod


def start(height=0.2):
    """The palm ``height`` above the origin, facing it."""
    return hugger.look_at([0.0, 0.0, height], [0, 0, 0])


def ico(subdivisions=2, radius=0.04):
    """An icosphere of ``radius`` (m) as (vertices, faces) arrays."""
    v, f = hugger.objects.icosphere(subdivisions)
    return v * radius, f.copy()


def no_warnings(fn, *args, **kwargs):
    """Call fn and assert it warned nothing."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = fn(*args, **kwargs)
    assert not caught, [str(w.message) for w in caught]
    return out


# palm poses that are not rigid (shared by the hand's kinematics tests and the planner's)

def _linear(m):
    pose = start()
    pose[:3, :3] = pose[:3, :3] @ np.asarray(m, dtype=float)
    return pose


def _entry(i, j, x):
    pose = start()
    pose[i, j] = x
    return pose


BAD_POSES = [
    (_linear(np.eye(3) * 1.001), "rigid"),
    (_linear(np.diag([1, 1, 0.5])), "rigid"),
    (_linear([[1, 0.05, 0], [0, 1, 0], [0, 0, 1]]), "rigid"),
    (_linear(np.diag([1, 1, -1])), "rigid|reflect"),
    (_linear(-np.eye(3)), "rigid|reflect"),
    (_linear(np.zeros((3, 3))), "rigid"),
    (_entry(0, 0, np.nan), "finite"),
    (_entry(1, 3, np.inf), "finite"),
    (_entry(3, 3, 2.0), "last row"),
    (_entry(3, 0, 0.1), "last row"),
    (start()[:3], r"\(4, 4\)"),
    (start().ravel(), r"\(4, 4\)"),
    (start()[None], r"\(4, 4\)"),
    (None, r"\(4, 4\)|palm_pose"),
]


def checker_unavailable() -> str | None:
    """Why the independent checker cannot run here (a sentence for the user), or None when it can."""
    if not CHECKER.is_file():
        return f"{CHECKER.parent.parent} is absent ({CHECKER} not found): the check is skipped"
    if importlib.util.find_spec("fcl") is None:
        return "the checker needs python-fcl (pip install python-fcl): the check is skipped"
    return None


@functools.lru_cache(maxsize=None)
def load_checker():  # loaded once per process, not once per plan
    spec = importlib.util.spec_from_file_location("check_trajectory", CHECKER)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def checker_or_note():
    """The checker where it can run; else None, having said why on standard error (a script's
    --check then plans on without it)."""
    reason = checker_unavailable()
    if reason:
        print(f"note: {reason}", file=sys.stderr)
        return None
    return load_checker()


def check_file(checker, path: Path, every: int = 1, motion: bool = False,
               swept_every: int = 1) -> tuple[bool, list[str], dict]:
    """Run the independent checker on a saved trajectory; (ok, failures, figures). With ``motion``
    also its motion check (DONE angles, joint steps <= 4 s, swept collision every ``swept_every``
    steps)."""
    d = checker.load(str(path))
    rep = checker.Report()
    if checker.check_structure(d, rep):
        layout = checker.hand_layout(d)
        tol = max(0.02 * layout.r, 5e-5)
        checker.check_kinematics(d, rep, checker.LIN_TOL)
        checker.check_algorithm(d, rep, checker.LIN_TOL)
        # one collision mesh for both checks (the checker builds its own when given none)
        mq = checker.MeshQuery(d["object_vertices"].astype(float), d["object_faces"].astype(np.int32), layout, tol)
        cache = checker.check_collision(d, rep, tol, every, mq)
        if motion:
            checker.check_motion(d, rep, checker.LIN_TOL, tol, mq, cache, 4.0, swept_every)
    return rep.ok(), rep.failures, rep.figures


def run_cli(args, capsys) -> tuple[int, str, str]:
    """``hugger ARGS`` in this process (paths and numbers as strings): (exit code, stdout, stderr)."""
    code = cli.main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


def assert_names_the_extra(module: str, args, extra: str) -> None:
    """``hugger ARGS`` in a new process in which ``module`` cannot be imported: exit status 2 and an
    error naming ``extra`` (``hugger[...]``), no traceback."""
    code = (f"import sys; sys.modules[{module!r}] = None\n"
            f"from hugger.cli import main; sys.exit(main({[str(a) for a in args]!r}))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert r.returncode == 2, r.stderr
    assert extra in r.stderr and "Traceback" not in r.stderr


def assert_checked(checker, path: Path, every: int = 1, motion: bool = False, swept_every: int = 1,
                   samples: int | None = None, context=None) -> dict:
    """Run the independent checker on the trajectory file ``path`` (see :func:`check_file`) and
    assert that it passes, its failures (after ``context``, when given) the message. ``samples``:
    check about that many configurations, every (K // samples)-th, instead of every ``every``-th.
    Returns the checker's figures."""
    if samples is not None:
        with np.load(path) as z:
            every = max(1, len(z["angles"]) // samples)
    ok, failures, figures = check_file(checker, path, every, motion, swept_every)
    assert ok, failures if context is None else (context, failures)
    return figures


def save_and_check(checker, traj: hugger.Trajectory, path: Path, **kwargs) -> dict:
    """Save ``traj`` to ``path``, then :func:`assert_checked` the file (same keywords)."""
    traj.save(path)
    return assert_checked(checker, path, **kwargs)


def sphere_grasp(hand: hugger.Hand, obj: hugger.Object) -> hugger.Trajectory:
    """``hand``'s plan around ``obj`` (a sphere about the origin) from :func:`start`, T at the
    origin; asserted ``done``."""
    traj = hugger.plan(hand, obj, [0.0, 0.0, 0.0], start())
    assert traj.status == "done"
    return traj


#: The arrays of a plan's motion, and every array of a trajectory file.
MOTION = ("palm_pose", "joints", "angles", "tip_state")
FILE_ARRAYS = MOTION + ("phase", "object_vertices", "object_faces", "target")


def same(a: hugger.Trajectory, b: hugger.Trajectory, arrays=MOTION, fields=("status",)) -> bool:
    """True when ``a`` and ``b`` hold the same ``arrays`` bit for bit and equal ``fields``."""
    return (all(np.array_equal(getattr(a, n), getattr(b, n)) for n in arrays)
            and all(getattr(a, f) == getattr(b, f) for f in fields))


def write_ball(path: Path, radius: float = 0.04, subdivisions: int = 2, inside_out: bool = False) -> Path:
    """An icosphere of ``radius`` (in the file's units) written to the mesh file ``path`` (STL,
    OBJ, ...: by its suffix) by trimesh, one vertex list as given (``inside_out``: its faces facing
    inward); skips where trimesh is absent."""
    trimesh = pytest.importorskip("trimesh")
    v, f = hugger.objects.icosphere(subdivisions)
    trimesh.Trimesh(radius * v, f[:, ::-1] if inside_out else f, process=False).export(path)
    return Path(path)


def read_obj(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Minimal Wavefront OBJ reader (v and f lines; polygons fanned into triangles)."""
    verts, faces = [], []
    for line in Path(path).read_text().splitlines():
        if line.startswith("v "):
            verts.append([float(x) for x in line.split()[1:4]])
        elif line.startswith("f "):
            idx = [int(tok.split("/")[0]) for tok in line.split()[1:]]
            idx = [i - 1 if i > 0 else len(verts) + i for i in idx]
            faces += [(idx[0], idx[k], idx[k + 1]) for k in range(1, len(idx) - 1)]
    return np.array(verts, dtype=float), np.array(faces, dtype=np.int64)


def ycb_paths() -> list[Path]:
    return sorted(OBJECTS_DIR.glob("*.obj")) if OBJECTS_DIR.is_dir() else []


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def safe_start(rng: np.random.Generator, obj: hugger.Object, hand: hugger.Hand, target: np.ndarray) -> np.ndarray:
    """A random palm pose far enough from O to turn freely in Phase 1, randomly oriented."""
    d = rng.normal(size=3)
    d /= np.linalg.norm(d)
    dist = hugger.scenarios.safe_distance(obj, hand, target) + rng.uniform(0.0, 0.03)
    pose = np.eye(4)
    pose[:3, :3] = random_rotation(rng)
    pose[:3, 3] = target + dist * d
    return pose


def random_object(rng: np.random.Generator, kind: str, size: float) -> tuple[hugger.Object, np.ndarray]:
    """A built-in shape of about ``size`` (bounding radius, m) and a point inside it."""
    o = hugger.objects
    if kind == "sphere":
        obj = o.sphere(size, subdivisions=3)
    elif kind == "ellipsoid":
        obj = o.ellipsoid(size * rng.uniform(0.5, 1.0, size=3), subdivisions=3)
    elif kind == "box":
        obj = o.box(2 * size * rng.uniform(0.4, 0.7, size=3), divisions=3)
    elif kind == "cylinder":
        obj = o.cylinder(size * rng.uniform(0.4, 0.7), 2 * size * rng.uniform(0.5, 0.8), sections=32, rings=4)
    elif kind == "blob":
        obj = o.blob(size * 0.8, amplitude=rng.uniform(0.2, 0.4), seed=int(rng.integers(1 << 30)), subdivisions=3)
    else:
        raise ValueError(kind)
    pose = np.eye(4)
    pose[:3, :3] = random_rotation(rng)
    v = obj.vertices @ pose[:3, :3].T
    obj = hugger.Object(v, obj.faces)
    return obj, np.zeros(3)


def random_hand(rng: np.random.Generator, size: float) -> hugger.Hand:
    """A hand with M in 2..8, N in 2..8, sized to the object; link radius 0 or > 0."""
    m, n = int(rng.integers(2, 9)), int(rng.integers(2, 9))
    palm = size * rng.uniform(0.5, 0.9)
    finger = size * rng.uniform(1.5, 3.0)
    link = finger / n
    radius = 0.0 if rng.random() < 0.4 else min(rng.uniform(0.02, 0.12) * size, 0.4 * link,
                                                 0.45 * palm * math.sin(math.pi / m))
    lengths = link * rng.uniform(0.8, 1.2, size=(m, n)) if rng.random() < 0.3 else link
    return hugger.Hand(fingers=m, links=n, link_length=lengths, link_radius=radius, palm_radius=palm,
                       palm_thickness=0.3 * palm)


def proc_file(pid: int, name: str) -> str:
    """/proc/PID/NAME, or "" once the process is gone."""
    try:
        return Path(f"/proc/{pid}/{name}").read_text(errors="replace")
    except OSError:
        return ""


def children(pid: int) -> set[int]:
    """The processes whose parent is ``pid`` (Linux /proc)."""
    found = set()
    for entry in Path("/proc").iterdir():
        stat = proc_file(int(entry.name), "stat") if entry.name.isdigit() else ""
        if stat and int(stat.rsplit(")", 1)[1].split()[1]) == pid:
            found.add(int(entry.name))
    return found
