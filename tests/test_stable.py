"""The numbers plans are made of do not depend on the processor (hugger._stable).

NumPy's loops and the BLAS kernels are chosen per processor. The test runs one script twice in
fresh interpreters: as this machine chooses, and with NumPy's AVX-512 loops switched off
(NPY_DISABLE_CPU_FEATURES) and OpenBLAS held to its SSE kernels (OPENBLAS_CORETYPE=Nehalem, no
fused multiply-adds), which is how a processor without them computes. The built-in objects,
start poses, hand rims, preset hands and their URDF files read back, approach directions, plans,
their contacts and grasp quality, and an approach search's choice must come out the same, bit for
bit.
"""
from __future__ import annotations

import math
import os
import platform
import subprocess
import sys

import numpy as np
import pytest

from hugger import _stable

def _other_processor_env() -> dict[str, str]:
    """The environment of a processor without AVX-512 and FMA, as far as NumPy and OpenBLAS go:
    NumPy's AVX-512 loops switched off (only targets it dispatches to and this processor has can
    be), OpenBLAS on its SSE4.2 kernels (x86-64 only)."""
    try:
        from numpy._core import _multiarray_umath as umath  # type: ignore[attr-defined]
    except ImportError:  # NumPy 1.x
        from numpy.core import _multiarray_umath as umath  # type: ignore[attr-defined,no-redef]
    env = dict(os.environ)
    if platform.machine().lower() in ("x86_64", "amd64"):
        env["OPENBLAS_CORETYPE"] = "Nehalem"
    dispatched, found = getattr(umath, "__cpu_dispatch__", []), getattr(umath, "__cpu_features__", {})
    off = [f for f in dispatched if (f.startswith("AVX512") or f == "X86_V4") and found.get(f)]
    if off:
        env["NPY_DISABLE_CPU_FEATURES"] = " ".join(off)
    return env


def _run(code: str, env: dict[str, str] | None = None) -> str:
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=300)
    assert out.returncode == 0, out.stderr
    return out.stdout


# NumPy's own functions on the same data: differ between the two settings on a processor whose
# choices matter (AVX-512 loops, FMA kernels in the BLAS).
_NUMPY_DIGEST = """
import hashlib, numpy as np
v = np.random.default_rng(0).normal(size=(2000, 3))
h = hashlib.sha256()
for a in (np.exp(v), np.sin(v), np.arccos(np.clip(v, -1, 1)), [np.linalg.norm(x) for x in v], v @ v[:3].T):
    h.update(np.ascontiguousarray(a).tobytes())
print(h.hexdigest())
"""

_HUGGER_DIGEST = """
import hashlib, numpy as np, hugger, hugger.scenarios as sc
from hugger import analysis
from hugger.search import approach_directions
h = hashlib.sha256()
def add(*arrays):
    for a in arrays:
        h.update(np.ascontiguousarray(a).tobytes())
for name in hugger.objects.names():
    c = sc.default_case(name)
    add(c.obj.vertices, c.obj.faces, c.target, c.palm_pose)
add(hugger.objects.blob(seed=3).vertices)
add(approach_directions(64, (0.3, -0.2, 0.9)))
hand = hugger.Hand.from_dict(dict(fingers=3, links=3, link_lengths=0.02, link_radius=0.004, palm_radius=0.03,
                                  palm_thickness=0.01, finger_angles=[0.1, 2.3, 4.4], rest_angles=[[0.0] * 3] * 3))
add(np.asarray(hand.to_json().encode()), sc.default_case("curvy", turn_deg=60.0).palm_pose)
import os, tempfile, hugger.hands as hands
for name in hands.PRESETS:  # the presets, and each read back from the URDF written for it
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "hand.urdf")
        with open(path, "w") as f:
            f.write(hands.to_urdf(hands.preset(name)))
        add(np.asarray(hands.preset(name).to_json().encode()), np.asarray(hugger.Hand.from_urdf(path).to_json().encode()))
for name in ("sphere", "curvy"):
    c = sc.default_case(name)
    t = hugger.Planner(c.hand, c.obj, c.target, c.palm_pose).plan()
    add(t.joints, t.palm_pose, t.angles)
    found = analysis.contacts(t, obj=c.obj)  # sampled on the links and the palm
    a = analysis.analyze(t, obj=c.obj)
    add(found.points, found.normals, np.array([a["epsilon"], a["volume"]]), np.array(a["wrap_angle_deg"]))
result = hugger.search(hugger.Hand(), hugger.objects.box(), approaches=4, pole=(0.3, 0.2, 1.0), threads=1)
add(np.array([result.best]), np.array([x.epsilon for x in result.candidates]))
print(h.hexdigest())
"""


def test_helpers_compute_in_a_fixed_order():
    v = np.random.default_rng(1).normal(size=(50, 3))
    assert _stable.norm(v).tolist() == [math.sqrt(x * x + y * y + z * z) for x, y, z in v.tolist()]
    assert float(_stable.norm(v[0])) == math.sqrt(sum(x * x for x in v[0].tolist()))
    m = np.random.default_rng(2).normal(size=(3, 4))
    expect = [[(a[0] * m[0, j] + a[1] * m[1, j]) + a[2] * m[2, j] for j in range(4)] for a in v.tolist()]
    assert _stable.matmul(v, m).tolist() == expect
    t = np.linspace(-3.0, 3.0, 101).reshape(1, 101)
    for f, g in ((_stable.sin, math.sin), (_stable.cos, math.cos), (_stable.exp, math.exp)):
        out = f(t)
        assert out.shape == t.shape and out.ravel().tolist() == [g(x) for x in t.ravel().tolist()]
    assert _stable.arccos(np.array([-1.0, 0.25, 1.0])).tolist() == [math.acos(x) for x in (-1.0, 0.25, 1.0)]
    assert _stable.matmul(m.T, v[0]).tolist() == [(v[0, 0] * m[0, j] + v[0, 1] * m[1, j]) + v[0, 2] * m[2, j]
                                                  for j in range(4)]
    assert _stable.matmul(v[0], m).tolist() == _stable.matmul(v[:1], m)[0].tolist()
    assert float(_stable.dot(v[0], v[1])) == (v[0, 0] * v[1, 0] + v[0, 1] * v[1, 1]) + v[0, 2] * v[1, 2]
    assert _stable.arctan2(v[:, 0], v[:, 1]).tolist() == [math.atan2(y, x) for y, x in v[:, :2].tolist()]
    with pytest.raises(ValueError, match="matmul"):
        _stable.matmul(np.ones((2, 3)), np.ones((2, 3)))
    with pytest.raises(ValueError, match="one shape"):
        _stable.arctan2(np.ones(2), np.ones(3))


def test_a_hand_with_an_infinite_finger_angle_is_refused():
    import hugger

    with pytest.raises(ValueError, match="finger_angles must be finite"):
        hugger.Hand.from_dict(dict(fingers=2, links=2, link_lengths=0.02, link_radius=0.004, palm_radius=0.03,
                                   palm_thickness=0.01, finger_angles=[0.0, math.inf], rest_angles=[[0.0] * 2] * 2))


def test_plans_and_their_inputs_are_the_same_on_another_processor():
    other = _other_processor_env()
    probe = subprocess.run([sys.executable, "-c", "import numpy"], capture_output=True, text=True, env=other, timeout=60)
    if probe.returncode != 0:
        pytest.skip(f"NumPy does not start with {other.get('NPY_DISABLE_CPU_FEATURES')} switched off: {probe.stderr[-200:]}")
    if _run(_NUMPY_DIGEST) == _run(_NUMPY_DIGEST, other):
        pytest.skip("NumPy and OpenBLAS compute alike here with AVX-512 loops and FMA kernels switched off, "
                    "so this machine cannot stand in for another processor")
    assert _run(_HUGGER_DIGEST) == _run(_HUGGER_DIGEST, other)


# The modules whose arithmetic makes the numbers plans and their figures are made of: NumPy's
# elementary functions, vector norms and matrix products stay out of them (hugger._stable's take
# their place), a guard for what the processor emulation above cannot reach (e.g. sin and cos of
# angles whose bits happen to agree on this machine).
_GUARDED = ("objects.py", "scenarios.py", "planner.py", "hand.py", "search.py", "analysis.py", "_rotation.py",
            "hands/robot.py")


def test_no_processor_dependent_numpy_in_plan_inputs():
    import re
    from pathlib import Path

    import hugger

    root = Path(hugger.__file__).parent
    banned = re.compile(r"np\.(sin|cos|tan|exp|log|arcsin|arccos|arctan2?|dot|einsum)\(|linalg\.norm\(|\S @ \S")
    found = []
    for name in _GUARDED:
        for i, line in enumerate((root / name).read_text().splitlines(), 1):
            code = line.split("#")[0]
            if banned.search(code):
                found.append(f"{name}:{i}: {line.strip()}")
    assert not found, "use hugger._stable instead:\n" + "\n".join(found)
