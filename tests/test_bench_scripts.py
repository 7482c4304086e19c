"""The benchmark scripts of bench/ run and report sane figures (speed itself is never asserted)."""
from __future__ import annotations

import json
import math
import re

import pytest

import helpers
from helpers import bench_module


def test_plan_vs_baseline_reports_every_planner(tmp_path, capsys, monkeypatch):
    pytest.importorskip("mujoco", reason="the baseline needs the physics extra (pip install 'hugger[physics]')")
    monkeypatch.setenv("HUGGER_CACHE_DIR", str(tmp_path / "cache"))  # not the user's cache (sphere: convex, no CoACD)
    mod = bench_module("plan_vs_baseline")
    out = tmp_path / "speed.md"
    assert mod.main(["--objects", "sphere", "--repeat", "1", "--out", str(out), "--json"]) == 0
    figures = json.loads(capsys.readouterr().out)

    rows = {}
    for line in out.read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if cells[0] == "sphere":
            rows[cells[2]] = cells
    assert sorted(rows) == ["baseline", "mesh", "section"]
    for planner, cells in rows.items():
        assert cells[3] == "done", (planner, cells)
        setup, plan, total = (float(c) for c in cells[5:8])
        assert all(math.isfinite(x) and x > 0 for x in (setup, plan, total)), (planner, cells)
        assert total == pytest.approx(setup + plan, abs=0.15), (planner, cells)  # rounded to 0.1 ms

    s = figures["summary"]
    assert s["objects"] == ["sphere"]
    for skin in ("mesh", "section"):
        for key in ("plan", "with_setup"):
            assert math.isfinite(s["ratios"][skin][key]) and s["ratios"][skin][key] > 0
    assert figures["machine"]["cpu_count"] >= 1
    assert re.search(r"load average \(1, 5, 15 min\)", out.read_text())


@pytest.mark.parametrize("args", [["--repeat", "0"], ["--objects", "no-such-object"], ["--repeat", "x"]])
def test_plan_vs_baseline_refuses_bad_arguments(args, capsys):
    mod = bench_module("plan_vs_baseline")
    with pytest.raises(SystemExit) as exc:
        mod.main(args)
    assert exc.value.code == 2
    assert "error:" in capsys.readouterr().err


def test_plan_digest_is_repeatable_and_tells_plans_apart(capsys):
    mod = bench_module("plan_digest")
    digests = []
    for rules in ("hug", "hug", "paper"):
        assert mod.main(["--objects", "box", "--skins", "section", "--rules", rules, "--json"]) == 0
        out = json.loads(capsys.readouterr().out)
        assert out["plans_per_skin"] == 4
        digests.append(out["digests"]["section"])
    assert digests[0] == digests[1]  # the same plans, bit for bit
    assert digests[0] != digests[2]  # other plans: another digest
    with pytest.raises(SystemExit) as bad:
        mod.main(["--objects", "no-such-object"])
    assert bad.value.code == 2


def test_bench_python_reports_the_streaming_figures(capsys):
    mod = bench_module("bench_python")
    assert mod.main(["--repeat", "1", "--cases", "1", "--threads", "1", "--json"]) == 0
    f = json.loads(capsys.readouterr().out)
    assert f["status"] == "done"
    assert f["step_configurations"] == f["configurations"]  # step() hands out the plan() trajectory's configurations
    assert f["constructor_s"] > 0 and f["step_p50_phase2_us"] > 0 and f["step_max_ms"] > 0
    assert f["plan_many_identical_results"] is True


OPTIONAL = {"mujoco", "ray", "viser", "matplotlib", "coacd", "trimesh", "yourdfpy", "imageio", "imageio_ffmpeg", "fcl"}


@pytest.mark.parametrize("script", sorted(p.stem for p in (helpers.ROOT / "bench").glob("*.py")))
def test_every_bench_script_imports(script):
    """A bench script that imports what no longer exists (a test helper renamed, say) fails here,
    not when someone next re-measures a table."""
    try:
        mod = bench_module(script)
    except ModuleNotFoundError as e:
        if e.name and e.name.split(".")[0] in OPTIONAL:
            pytest.skip(f"bench/{script}.py needs {e.name}, an optional extra not installed here")
        raise
    if "__main__" in (helpers.ROOT / "bench" / f"{script}.py").read_text():  # a script, not a shared module
        assert callable(getattr(mod, "main", None)), f"bench/{script}.py has no main()"
