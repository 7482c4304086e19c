"""The numbers plans are made of do not depend on the processor (hugger._stable).

NumPy's loops and the BLAS kernels are chosen per processor. The test runs one script twice in
fresh interpreters: as this machine chooses, and with NumPy's AVX-512 loops switched off
(NPY_DISABLE_CPU_FEATURES) and OpenBLAS held to its SSE kernels (OPENBLAS_CORETYPE=Nehalem, no
fused multiply-adds), which is how a processor without them computes. The built-in objects,
start poses, hand rims, preset hands and their URDF files read back, approach directions and plans
must come out the same, bit for bit.
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

# What a processor without AVX-512 and FMA computes, as far as NumPy and OpenBLAS go.
_AVX512 = ("X86_V4", "AVX512_SPR", "AVX512_ICL", "AVX512_CNL", "AVX512_CLX", "AVX512_SKX", "AVX512_KNM",
           "AVX512_KNL", "AVX512F")


def _other_processor_env() -> dict[str, str]:
    try:
        from numpy._core._multiarray_umath import __cpu_features__ as found  # type: ignore[import-not-found]
    except ImportError:  # NumPy 1.x
        from numpy.core._multiarray_umath import __cpu_features__ as found  # type: ignore[import-not-found,no-redef]

    env = dict(os.environ)
    if platform.machine().lower() in ("x86_64", "amd64"):
        env["OPENBLAS_CORETYPE"] = "Nehalem"  # SSE4.2 kernels: on every x86-64 processor since 2008
    off = [f for f in _AVX512 if found.get(f)]
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
                                  palm_thickness=0.01, finger_angles=[0.1, 2.3, 4.4]))
add(np.asarray(hand.to_json().encode()))
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
    with pytest.raises(ValueError, match="matmul"):
        _stable.matmul(np.ones((2, 3)), np.ones((2, 3)))


def test_plans_and_their_inputs_are_the_same_on_another_processor():
    other = _other_processor_env()
    if _run(_NUMPY_DIGEST) == _run(_NUMPY_DIGEST, other):
        pytest.skip("NumPy and OpenBLAS compute alike here with AVX-512 loops and FMA kernels switched off, "
                    "so this machine cannot stand in for another processor")
    assert _run(_HUGGER_DIGEST) == _run(_HUGGER_DIGEST, other)
