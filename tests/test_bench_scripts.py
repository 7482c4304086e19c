"""The benchmark scripts of bench/ run and report sane figures (speed itself is never asserted)."""
from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys

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


def _run_script(script: str, *args: str, timeout: float = 60) -> subprocess.CompletedProcess[str]:
    """bench/<script>.py run as a user runs it: its own interpreter, its exit status and both streams."""
    return subprocess.run([sys.executable, str(helpers.BENCH / f"{script}.py"), *args], cwd=helpers.ROOT,
                          capture_output=True, encoding="utf-8", timeout=timeout,
                          env={**os.environ, "PYTHONIOENCODING": "utf-8"})


#: (script, arguments, words the error line must hold): a bad value of one option each. Options
#: that, accepted, would start planning come with ``--objects sphere`` or the like, so that a
#: script that lets them through fails here in seconds, not after a whole table.
BAD_ARGUMENTS = [
    ("bench_search", ["--repeat", "0"], ["--repeat"]),
    ("bench_search", ["--repeat", "-1"], ["--repeat", "-1"]),
    ("bench_search", ["--threads", "0"], ["--threads"]),
    ("bench_search", ["--approaches", "0"], ["--approaches"]),
    ("search_table", ["--objects", "sphere", "--threads", "0"], ["--threads"]),
    ("search_table", ["--objects", "sphere", "--approaches", "0"], ["--approaches"]),
    ("search_table", ["--objects", "sphere", "--workers", "0"], ["--workers"]),
    ("search_table", ["--objects", "sphere", "--rules", "foo"], ["--rules", "foo", "paper", "hug"]),
    ("search_table", ["--objects", "nope"], ["--objects", "nope", "sphere"]),
    ("search_table", ["--objects"], ["--objects", "none given"]),
    ("search_table", ["--objects", "torus"], ["torus", "fit"]),  # known, but does not fit the hand
    ("search_table", ["--blobs", "-1", "--only-generated"], ["--blobs", "-1"]),
    ("search_table", ["--only-generated"], ["--only-generated", "--blobs"]),
    ("search_table", ["--objects", "sphere", "--verify", "-1"], ["--verify"]),
    ("search_table", ["--objects", "sphere", "--robust-verify"], ["--robust-verify", "--verify"]),
    ("objects_table", ["--rules", "foo"], ["--rules", "foo", "paper, hug"]),
    ("objects_table", ["--rules", ","], ["--rules", "none given"]),
    ("hands_table", ["--rules", "foo"], ["--rules", "foo", "paper, hug"]),
    ("hands_table", ["--hands", "nope"], ["--hands", "nope", "barrett_bh8", "thumb_urdf"]),
    ("hug_metrics", ["--cases", "0"], ["--cases"]),
    ("hug_metrics", ["--cases", "-1"], ["--cases", "-1"]),
    ("compare_baseline", ["--objects", "nope", "--no-validate"], ["--objects", "nope", "sphere"]),
    ("compare_baseline", ["--objects", ",", "--no-validate"], ["--objects", "no object named"]),
]


@pytest.mark.parametrize(("script", "args", "named"), BAD_ARGUMENTS,
                         ids=[f"{s}:{' '.join(a)}" for s, a, _ in BAD_ARGUMENTS])
def test_bench_scripts_refuse_bad_arguments_in_one_line(script, args, named, tmp_path):
    """A bad option value: the usage and one "error:" line naming it, exit status 2, before any
    planning -- never a traceback, nor a silent empty table."""
    run = _run_script(script, *args, "--out", str(tmp_path / "out.md")) if script == "compare_baseline" \
        else _run_script(script, *args, timeout=30)
    assert run.returncode == 2, (run.returncode, run.stdout[-500:], run.stderr[-2000:])
    assert "Traceback" not in run.stderr, run.stderr
    assert run.stdout == ""  # refused before any row, progress line or header
    lines = run.stderr.splitlines()
    errors = [line for line in lines if "error:" in line]
    assert len(errors) == 1 and lines[-1] == errors[0], run.stderr
    for word in named:
        assert word in errors[0], (word, errors[0])
    assert not (tmp_path / "out.md").exists()


def test_plan_digest_help_gives_every_option_its_values_and_default():
    run = _run_script("plan_digest", "--help", timeout=30)
    assert run.returncode == 0, run.stderr
    text = " ".join(run.stdout.split())  # argparse wraps the help at the terminal's width
    for option, values, default in (("--skins", "mesh, section", "default mesh,section"),
                                     ("--rules", "paper, hug", "default paper,hug"),
                                     ("--objects", "sphere, apple", "default all")):
        help_text = text.split(f"{option} {option[2:].upper()} ", 1)[1].split(" --", 1)[0]
        assert values in help_text and default in help_text, (option, help_text)


def _table(lines: list[str]) -> list[list[str]]:
    return [[c.strip() for c in line.strip().strip("|").split("|")] for line in lines]


def test_objects_table_prints_on_stdout_the_table_it_writes(tmp_path, capsys, monkeypatch):
    mod = bench_module("objects_table")
    monkeypatch.setattr(mod, "SHARED", tmp_path / "no-shared")  # the built-ins only: 7 plans, quick
    out = tmp_path / "objects.md"
    assert mod.main(["--rules", "hug", "--out", str(out)]) == 0
    captured = capsys.readouterr()
    assert captured.out == out.read_text()  # the header and |---| line included
    table = _table(captured.out.splitlines())
    assert table[0][:3] == ["object", "triangles", "rules"] and set(table[1][0]) == {"-"}
    assert [row[0] for row in table[2:]] == list(mod.hugger.objects.names())
    assert all(len(row) == len(table[0]) for row in table)
    assert captured.err.splitlines()[-1] == "7 objects, rules hug: 7 plans"  # readable, not JSON


def test_objects_table_check_without_the_checker_says_so_and_plans_on(tmp_path, capsys, monkeypatch):
    mod = bench_module("objects_table")
    monkeypatch.setattr(mod, "SHARED", tmp_path / "no-shared")
    monkeypatch.setattr(mod, "checker_unavailable", lambda: "../shared is absent: the check is skipped")
    assert mod.main(["--rules", "hug", "--check"]) == 0  # a traceback before, at the first plan
    captured = capsys.readouterr()
    assert captured.err.splitlines()[0] == "note: ../shared is absent: the check is skipped"
    table = _table(captured.out.splitlines())
    assert "checker" not in table[0] and len(table) == 2 + len(mod.hugger.objects.names())


def test_search_table_prints_its_header_before_the_rows():
    run = _run_script("search_table", "--objects", "sphere", "box", "--approaches", "1", "--threads", "1",
                      "--no-physics", timeout=120)
    assert run.returncode == 0, run.stderr[-2000:]
    lines = run.stdout.splitlines()
    table = _table(lines[:lines.index("")])  # the table, then a blank line and the summary
    assert table[0][:3] == ["object", "single: links", "ε"] and set(table[1][0]) == {"-"}
    assert [row[0] for row in table[2:]] == ["sphere", "box"]
    assert all(len(row) == len(table[0]) for row in table)
    assert lines[-1].startswith("2 objects: ")


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
