#!/usr/bin/env python3
"""Speed of Hugger against the close-until-contact baseline, from the same start, on the built-in objects.

For every built-in object (``hugger.objects.names()``, or ``--objects``), from
:func:`hugger.scenarios.default_case`'s start with the default hand (5 x 5 links of 2 cm), three
planners are timed, wall clock (``time.perf_counter``):

  mesh, section  Hugger with ``skin="mesh"`` and ``skin="section"`` (rules ``hug``, the default).
                 setup = building the ``hugger.Object`` from the case's vertex and face arrays
                 (the engine's checks, normals, BVH) + constructing the Planner (its checks,
                 Phase 1 and, with the section skin, the regions of the finger planes, which the
                 constructor builds once Phase 1 has ended; the speed targets, docs/performance.md,
                 count the object build and the sections as setup); plan = ``Planner.plan()`` (Phase 2 and the trajectory
                 handed to Python).
  baseline       :func:`hugger.baselines.run_baseline`, measured as bench/compare_baseline.py does
                 it: setup = its ``setup_time_s`` (building and compiling the MuJoCo model,
                 convex pieces from the cache; the Object is given ready-made), plan = its
                 ``plan_time_s`` (the loop of collision queries; the joints' forward
                 kinematics and the Trajectory built afterwards are outside it, and reported in
                 ``--json`` as ``call_s``, the whole call).

One untimed warm-up round runs first (it imports MuJoCo and fills the convex-decomposition
cache, which the baseline's setup then reads). Then R repeats, each a round robin over
object x planner, so that machine load falls on every planner alike. Reported: per object and
planner the medians over the repeats of setup, plan and setup + plan; over the objects that every
planner planned, the median of the per-object medians (plan only, setup + plan) and the ratios
baseline / Hugger for each skin. The machine's load average (before and after), ``os.cpu_count()``
and the CPU model are printed with the table: figures taken under load are slower and noisier.
Speed is reported, never asserted.

With ``--check`` every Hugger plan made (warm-up included) is saved to a temporary file and given
to the independent checker ``../shared/tools/check_trajectory.py`` (all checks, motion included;
needs python-fcl); without ``../shared`` the check is skipped, and the output says so.

    python bench/plan_vs_baseline.py [--objects sphere,box] [--repeat 5] [--check] [--out FILE.md] [--json]

Progress goes to stderr; the markdown table to stdout (and atomically to ``--out``), or with
``--json`` every figure as JSON to stdout instead.
"""
from __future__ import annotations

import argparse
import contextlib
import datetime
import hashlib
import io
import json
import os
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

import hugger
from hugger import baselines, scenarios
from hugger._files import write_atomic

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import plan_digest  # noqa: E402
from helpers import CHECKER, checker_unavailable, load_checker  # noqa: E402

SKINS = ("mesh", "section")
PLANNERS = (*SKINS, "baseline")


def cpu_model() -> str:
    """The CPU's model name from /proc/cpuinfo ("unknown" where there is none)."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as fh:
            for line in fh:
                key, _, value = line.partition(":")
                if key.strip() in ("model name", "Model", "Hardware", "cpu model"):
                    return value.strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def load_average() -> list[float] | None:
    return [round(x, 2) for x in os.getloadavg()] if hasattr(os, "getloadavg") else None


def digest(traj: hugger.Trajectory) -> str:
    """A plan's digest (plan_digest.py's, bit for bit): the same plan, the same digest."""
    h = hashlib.sha256()
    plan_digest.update(h, traj)
    return h.hexdigest()[:16]


def checker_verdict(path: Path) -> tuple[bool, list[str]]:
    """Run check_trajectory.py's own main (every check, motion included) on ``path``."""
    mod = load_checker()
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = mod.main([str(path), "--json"])
    try:
        failures = list(json.loads(out.getvalue()).get("failures", []))
    except ValueError:
        failures = [out.getvalue().strip()[-300:]]
    return code == 0, failures


def run_hugger(hand: hugger.Hand, case: scenarios.Case, vertices: np.ndarray, faces: np.ndarray,
               skin: str) -> tuple[dict[str, Any], hugger.Trajectory]:
    t0 = time.perf_counter()
    obj = hugger.Object(vertices, faces)
    planner = hugger.Planner(hand, obj, case.target, case.palm_pose, skin=skin)
    t1 = time.perf_counter()
    traj = planner.plan()
    t2 = time.perf_counter()
    return {"setup_s": t1 - t0, "plan_s": t2 - t1}, traj


def run_baseline(hand: hugger.Hand, case: scenarios.Case) -> tuple[dict[str, Any], hugger.Trajectory]:
    t0 = time.perf_counter()
    run = baselines.run_baseline(hand, case.obj, case.target, case.palm_pose)
    call = time.perf_counter() - t0
    return {"setup_s": run.setup_time_s, "plan_s": run.plan_time_s, "call_s": call}, run.trajectory


def run_one(planner: str, hand: hugger.Hand, case: scenarios.Case, arrays: tuple[np.ndarray, np.ndarray]
            ) -> tuple[dict[str, Any], hugger.Trajectory | None]:
    """One timed plan: figures (or ``error``) and the trajectory."""
    try:
        if planner == "baseline":
            r, traj = run_baseline(hand, case)
        else:
            r, traj = run_hugger(hand, case, *arrays, skin=planner)
    except ValueError as exc:
        return {"error": str(exc)}, None
    r.update(status=traj.status, configurations=len(traj), digest=digest(traj))
    return r, traj


def median(xs: list[float]) -> float:
    return float(statistics.median(xs))


def summarise(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Medians over the repeats of one object and planner."""
    ok = [r for r in runs if "error" not in r]
    if not ok:
        return {"error": runs[0]["error"] if runs else "not run", "repeats": 0}
    out: dict[str, Any] = {
        "repeats": len(ok),
        "setup_s": median([r["setup_s"] for r in ok]),
        "plan_s": median([r["plan_s"] for r in ok]),
        "total_s": median([r["setup_s"] + r["plan_s"] for r in ok]),
        "statuses": sorted({r["status"] for r in ok}),
        "configurations": sorted({r["configurations"] for r in ok}),
        "same_plan_every_repeat": len({r["digest"] for r in ok}) == 1,
    }
    if "call_s" in ok[0]:
        out["call_s"] = median([r["call_s"] for r in ok])
    if len(ok) < len(runs):
        out["errors"] = sorted({r["error"] for r in runs if "error" in r})
    return out


def overall(per_object: dict[str, dict[str, dict[str, Any]]]) -> dict[str, Any]:
    """Medians over the objects every planner planned, and the ratios baseline / Hugger."""
    common = [name for name, row in per_object.items() if all("error" not in row[p] for p in PLANNERS)]
    out: dict[str, Any] = {"objects": common, "planners": {}, "ratios": {}}
    if not common:
        return out
    for p in PLANNERS:
        out["planners"][p] = {"plan_s": median([per_object[n][p]["plan_s"] for n in common]),
                              "total_s": median([per_object[n][p]["total_s"] for n in common])}
    base = out["planners"]["baseline"]
    for skin in SKINS:
        h = out["planners"][skin]
        out["ratios"][skin] = {"plan": base["plan_s"] / h["plan_s"], "with_setup": base["total_s"] / h["total_s"]}
    return out


def ms(x: float) -> str:
    """Seconds as milliseconds, one decimal."""
    return f"{x * 1e3:.1f}"


def markdown(result: dict[str, Any]) -> str:
    m = result["machine"]
    lines = [
        "# Hugger vs close-until-contact baseline: speed",
        "",
        f"Generated by `{result['command']}` on {result['date']}: hugger {result['hugger_version']}, "
        f"MuJoCo {result['mujoco_version']}, Python {result['python']}. Machine: {m['cpu_model']}, "
        f"os.cpu_count() = {m['cpu_count']}, load average (1, 5, 15 min) {m['load_before']} before and "
        f"{m['load_after']} after.",
        "",
        f"Wall clock (time.perf_counter), medians over {result['repeat']} repeats after one untimed warm-up "
        "round; each repeat a round robin over object x planner. Start: `hugger.scenarios.default_case`, "
        "default hand (5 x 5 links of 2 cm). mesh / section: Hugger (rules hug) with that skin; setup = "
        "`hugger.Object(V, F)` + `Planner(...)` (checks, BVH, Phase 1, the section skin's regions), plan = "
        "`.plan()` (Phase 2). baseline: "
        "`hugger.baselines.plan_baseline`; setup = building and compiling the MuJoCo model (Object given, "
        "convex pieces from the cache), plan = its loop of collision queries (as bench/compare_baseline.py "
        "measures them). Speed is reported, not asserted.",
        "",
        "| object | triangles | planner | status | configs | setup (ms) | plan (ms) | setup + plan (ms) | check |",
        "|---|---:|---|---|---:|---:|---:|---:|---|",
    ]
    checks = result.get("check", {})
    for name, row in result["objects"].items():
        for p in PLANNERS:
            r = row["planners"][p]
            if "error" in r:
                lines.append(f"| {name} | {row['triangles']} | {p} | error: {r['error']} | | | | | |")
                continue
            verdict = ""
            if p in SKINS and "by_object" in checks:
                c = checks["by_object"][name][p]
                verdict = f"{c['passed']}/{c['checked']}"
            status = "/".join(r["statuses"]) + ("" if r["same_plan_every_repeat"] else " (plans differ)")
            configs = "/".join(str(c) for c in r["configurations"])
            lines.append(f"| {name} | {row['triangles']} | {p} | {status} | {configs} | {ms(r['setup_s'])} | "
                         f"{ms(r['plan_s'])} | {ms(r['total_s'])} | {verdict} |")
    s = result["summary"]
    lines += ["", f"Over the {len(s['objects'])} built-in objects every planner planned "
              f"({', '.join(s['objects']) or 'none'}): the median of the per-object medians.", ""]
    if s["planners"]:
        lines += ["| planner | plan (ms) | setup + plan (ms) | baseline / this, plan | baseline / this, with setup |",
                  "|---|---:|---:|---:|---:|"]
        for p in PLANNERS:
            f = s["planners"][p]
            ratio = s["ratios"].get(p)
            cells = [f"{ratio['plan']:.2f}", f"{ratio['with_setup']:.2f}"] if ratio else ["", ""]
            lines.append(f"| {p} | {ms(f['plan_s'])} | {ms(f['total_s'])} | {' | '.join(cells)} |")
    lines.append("")
    if "skipped" in checks:
        lines.append(f"Check: {checks['skipped']}.")
    elif checks:
        lines.append(f"Check (../shared/tools/check_trajectory.py, every check, motion included): "
                     f"{checks['passed']} of {checks['checked']} Hugger plans pass (warm-up included).")
        for f in checks["failures"][:20]:
            lines.append(f"- {f}")
    else:
        lines.append("Check: not run (--check).")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--objects", default=None, help="comma-separated built-in objects (default: all built-ins)")
    ap.add_argument("--repeat", type=int, default=5, help="repeats, each a round robin over object x planner (default 5)")
    ap.add_argument("--check", action="store_true", help="check every Hugger plan with ../shared/tools/check_trajectory.py")
    ap.add_argument("--out", type=Path, default=None, help="write the markdown table here (atomically)")
    ap.add_argument("--json", action="store_true", help="print every figure as JSON on stdout instead of the table")
    args = ap.parse_args(argv)
    if args.repeat < 1:
        ap.error(f"--repeat must be at least 1, got {args.repeat}")
    names = hugger.objects.names()
    if args.objects is not None:
        chosen = [s.strip() for s in args.objects.split(",") if s.strip()]
        unknown = [s for s in chosen if s not in names]
        if not chosen or unknown:
            ap.error(f"--objects: unknown {', '.join(unknown) or '(none given)'}; built-ins: {', '.join(names)}")
        names = list(dict.fromkeys(chosen))
    if args.out is not None and not args.out.parent.is_dir():
        ap.error(f"--out: no such directory: {args.out.parent}")
    try:
        import mujoco
    except ImportError:
        print("plan_vs_baseline.py: the baseline needs MuJoCo: pip install 'hugger[physics]'", file=sys.stderr)
        return 2

    def say(text: str) -> None:
        print(text, file=sys.stderr, flush=True)

    command = "python bench/plan_vs_baseline.py" + (f" --objects {','.join(names)}" if args.objects else "") + \
        f" --repeat {args.repeat}" + (" --check" if args.check else "")
    load_before = load_average()
    hand = hugger.Hand()
    cases = {n: scenarios.default_case(n, hand) for n in names}
    # the arrays Hugger's setup builds its Object from (private copies, made before any clock)
    arrays = {n: (np.array(c.obj.vertices), np.array(c.obj.faces)) for n, c in cases.items()}
    check_reason = checker_unavailable() if args.check else None
    if check_reason:
        say(f"--check: {check_reason}")
    tmp = tempfile.TemporaryDirectory(prefix="plan_vs_baseline-") if args.check and not check_reason else None
    saved: list[tuple[str, str, int, Path]] = []  # (object, skin, repeat (-1: warm-up), file)

    def keep(name: str, planner: str, rep: int, traj: hugger.Trajectory | None) -> None:
        if tmp is not None and traj is not None and planner in SKINS:
            path = Path(tmp.name) / f"{name}-{planner}-{rep + 1}.npz"
            traj.save(path)
            saved.append((name, planner, rep, path))

    runs: dict[str, dict[str, list[dict[str, Any]]]] = {n: {p: [] for p in PLANNERS} for n in names}
    warmup: dict[str, dict[str, Any]] = {n: {} for n in names}
    t_start = time.perf_counter()
    say(f"warm-up: {len(names)} objects x {len(PLANNERS)} planners")
    for n in names:
        for p in PLANNERS:
            t0 = time.perf_counter()
            r, traj = run_one(p, hand, cases[n], arrays[n])
            warmup[n][p] = {"wall_s": time.perf_counter() - t0, **({"error": r["error"]} if "error" in r else {})}
            keep(n, p, -1, traj)
            say(f"  {n:10s} {p:8s} " + (f"error: {r['error']}" if "error" in r else
                                         f"{r['status']:14s} {warmup[n][p]['wall_s'] * 1e3:9.1f} ms"))
    for rep in range(args.repeat):
        say(f"repeat {rep + 1}/{args.repeat}")
        for n in names:
            for p in PLANNERS:
                r, traj = run_one(p, hand, cases[n], arrays[n])
                runs[n][p].append(r)
                keep(n, p, rep, traj)
                say(f"  {n:10s} {p:8s} " + (f"error: {r['error']}" if "error" in r else
                                             f"setup {r['setup_s'] * 1e3:8.1f} ms  plan {r['plan_s'] * 1e3:9.1f} ms"))
    bench_s = time.perf_counter() - t_start
    load_after = load_average()

    per_object = {n: {p: summarise(runs[n][p]) for p in PLANNERS} for n in names}
    result: dict[str, Any] = {
        "command": command,
        "date": datetime.datetime.now().astimezone().isoformat(timespec="seconds"),
        "hugger_version": hugger.__version__,
        "mujoco_version": mujoco.__version__,
        "python": platform.python_version(),
        "machine": {"cpu_model": cpu_model(), "cpu_count": os.cpu_count(), "load_before": load_before,
                    "load_after": load_after},
        "repeat": args.repeat,
        "benchmark_wall_s": bench_s,
        "objects": {n: {"triangles": int(len(cases[n].obj.faces)), "planners": per_object[n], "warmup": warmup[n],
                        "runs": runs[n]} for n in names},
        "summary": overall(per_object),
    }

    if args.check:
        if check_reason:
            result["check"] = {"skipped": check_reason}
        else:
            say(f"checking {len(saved)} Hugger plans with {CHECKER}")
            by_object = {n: {s: {"checked": 0, "passed": 0} for s in SKINS} for n in names}
            failures = []
            for name, skin, rep, path in saved:
                ok, why = checker_verdict(path)
                c = by_object[name][skin]
                c["checked"] += 1
                c["passed"] += int(ok)
                if not ok:
                    which = "warm-up" if rep < 0 else f"repeat {rep + 1}"
                    failures.append(f"{name} {skin} ({which}): " + "; ".join(why))
                say(f"  {path.name:28s} {'pass' if ok else 'FAIL'}")
            result["check"] = {"checked": len(saved), "passed": len(saved) - len(failures), "failures": failures,
                               "by_object": by_object}
            result["machine"]["load_after_check"] = load_average()
    if tmp is not None:
        tmp.cleanup()

    text = markdown(result)
    if args.out is not None:
        write_atomic(args.out, text)
        say(f"written to {args.out}")
    if args.json:
        json.dump(result, sys.stdout, indent=2, allow_nan=False)
        print()
    else:
        print(text, end="")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
