"""The ``hugger`` command: plan grasps, judge them, draw them.

    hugger plan OBJECT --out plan.npz [--json]   plan a grasp of a built-in object or a mesh file
    hugger demo [--out DIR]                       the paper's example, with figures and animation
    hugger render plan.npz --out fig.png|.gif|.mp4
    hugger info plan.npz [--json]                 what a trajectory file holds, and its grasp
    hugger objects                                the built-in objects
    hugger validate plan.npz [--json] [--robust]  hold test in MuJoCo (extra: physics)
    hugger generate OBJECT... --out DIR           a dataset: K approaches per object and hand
    hugger export-mjcf plan.npz --out hand.xml    the hand and object as MJCF

Exit status: 0 success, 2 bad input or a missing optional dependency (one line on standard
error, no traceback), 1 an internal error.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any, Sequence

from ._progress import Progress

EXIT_OK, EXIT_INTERNAL, EXIT_BAD_INPUT = 0, 1, 2


class UsageError(Exception):
    """Bad input from the command line: reported in one line, exit 2."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line, exit 2, no usage dump
        raise UsageError(f"{message} (see '{self.prog} --help')")


# ---------------------------------------------------------------------------------------------
# Shared pieces


def _hand_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("hand (defaults: the paper's 5 x 5 hand)")
    g.add_argument("--fingers", type=int, default=5, help="M, number of fingers (default 5)")
    g.add_argument("--links", type=int, default=5, help="N, links per finger (default 5)")
    g.add_argument("--link-length", type=float, default=0.02, help="link length, m (default 0.02)")
    g.add_argument("--link-radius", type=float, default=0.004, help="link (capsule) radius, m (default 0.004)")
    g.add_argument("--palm-radius", type=float, default=0.03, help="palm radius, m (default 0.03)")
    g.add_argument("--palm-thickness", type=float, default=0.01, help="palm thickness, m (default 0.01)")


def _planner_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("planner (defaults as hugger.Planner)")
    g.add_argument("--step", type=float, help="approach step, m (default shortest link / 20)")
    g.add_argument("--epsilon", type=float, help="tip-to-surface distance epsilon, m (default step / 10)")
    g.add_argument("--contact-tolerance", type=float, help="sensing distance delta, m (default 1e-4)")
    g.add_argument("--max-iterations", type=int, help="Phase 2 iteration limit (default 20000)")
    g.add_argument("--timeout", type=float, metavar="SECONDS",
                   help="stop planning after this long, with status 'timeout' and a valid partial plan")


def _case_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("scene (defaults: T the object's natural target, the palm at a safe distance facing T)")
    g.add_argument("--target", type=float, nargs=3, metavar=("X", "Y", "Z"), help="T, a point inside the object, m")
    g.add_argument("--start", type=float, nargs=3, metavar=("X", "Y", "Z"), help="initial palm centre, m")
    g.add_argument("--normal", type=float, nargs=3, metavar=("NX", "NY", "NZ"),
                   help="initial palm normal (default: towards T)")
    g.add_argument("--turn", type=float, default=0.0, metavar="DEG",
                   help="turn the default start away from T by DEG about the palm's y axis (default 0; "
                        "not with --start or --normal)")
    g.add_argument("--scale", type=float, default=1.0, help="multiply mesh coordinates (0.001 for millimetres)")


def _hand(args: argparse.Namespace):
    import hugger

    return hugger.Hand(fingers=args.fingers, links=args.links, link_length=args.link_length,
                       link_radius=args.link_radius, palm_radius=args.palm_radius, palm_thickness=args.palm_thickness)


def _params(args: argparse.Namespace) -> dict[str, Any]:
    from .batch import _PARAMS

    return {k: getattr(args, k) for k in _PARAMS}


def _load(path: str):
    import hugger

    if not os.path.isfile(path):
        raise UsageError(f"no such trajectory file: {path}")
    return hugger.Trajectory.load(path)


_ANALYSIS_KEYS = ("palm_contact", "links_in_contact", "links", "contacts", "force_closure", "epsilon", "volume",
                  "per_finger_contacts", "wrap_angle_deg", "mu")


def _report(traj, plan_time: float | None = None, obj=None) -> dict[str, Any]:
    """Status, sizes, timing and the grasp judgement of the final configuration (``obj``: the
    trajectory's object when already built)."""
    from . import analysis

    out: dict[str, Any] = {"status": traj.status, "configurations": len(traj),
                           "phase1_configurations": int((traj.phase == 1).sum())}
    if plan_time is not None:
        out["plan_time_s"] = round(plan_time, 6)
        out["configurations_per_s"] = round(len(traj) / plan_time, 1) if plan_time > 0 else None
    a = analysis.analyze(traj, obj=obj)
    out.update({key: a[key] for key in _ANALYSIS_KEYS})
    return out


def _print_table(d: dict[str, Any], stream=None) -> None:
    stream = stream or sys.stdout
    for key, value in d.items():
        if isinstance(value, float):
            value = f"{value:.6g}"
        elif isinstance(value, list):
            value = " ".join(f"{x:.4g}" if isinstance(x, float) else str(x) for x in value)
        print(f"{key:22s} {value}", file=stream)


def _note(message: str) -> None:
    print(f"hugger: {message}", file=sys.stderr)


def _plan(case, hand, params: dict[str, Any], label: str, timeout: float | None = None):
    import hugger

    t0 = time.perf_counter()
    planner = hugger.Planner(hand, case.obj, case.target, case.palm_pose, **params)
    with Progress(f"planning {label}"):
        traj = planner.plan(timeout=timeout)
    return traj, time.perf_counter() - t0


def _search(case, hand, args: argparse.Namespace):
    """``hugger plan --approaches K``: the best of K approaches around T (hugger.search)."""
    import hugger

    if args.start is not None or args.normal is not None or args.turn:
        raise UsageError("--approaches K > 1 chooses the start poses itself: not with --start, --normal or --turn")
    pole = case.palm_pose[:3, 3] - case.target
    with Progress(f"searching {args.approaches} approaches of {case.name}", total=args.approaches) as p:
        result = hugger.search(hand, case.obj, case.target, approaches=args.approaches, threads=args.threads,
                               pole=pole, timeout=args.timeout, progress=lambda i, n: p.update(i),
                               verify=args.verify, **{k: v for k, v in _params(args).items() if v is not None})
    chosen = result.chosen
    summary = {"approaches": len(result.candidates), "best": result.best,
               "direction": [float(x) for x in chosen.direction], "time_s": round(result.time_s, 6),
               "judged": sum(c.epsilon is not None for c in result.candidates),
               "candidates": [c.to_dict() for c in result.candidates]}
    return result.trajectory, chosen.plan_time_s, summary


# ---------------------------------------------------------------------------------------------
# Commands


def cmd_plan(args: argparse.Namespace) -> int:
    from .scenarios import default_case

    hand = _hand(args)
    case = default_case(args.object, hand, scale=args.scale, target=args.target, start=args.start, normal=args.normal,
                        turn_deg=args.turn)
    for r in case.repairs:
        _note(f"repaired {case.name}: {r}")
    searched = None
    if args.approaches != 1:
        traj, elapsed, searched = _search(case, hand, args)
    else:
        traj, elapsed = _plan(case, hand, _params(args), case.name, args.timeout)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    traj.save(out)
    report = {"object": case.name, "out": str(out), **_report(traj, elapsed, case.obj)}
    if searched is not None:
        report["search"] = searched
        if not args.json:  # the table: the search in three lines, not every candidate
            report.pop("search")
            report.update({"approaches": searched["approaches"], "chosen_approach": searched["best"],
                           "approach_direction": searched["direction"], "search_time_s": searched["time_s"]})
    if args.json:
        print(json.dumps(report))
    else:
        _print_table(report)
    if traj.status != "done":
        _note(f"the plan ended with status {traj.status!r}, not 'done'")
    return EXIT_OK


def cmd_demo(args: argparse.Namespace) -> int:
    """The paper's example: 5 fingers x 5 links on `curvy`, turned away from T so that Phase 1 shows."""
    import hugger

    from . import viz
    from .scenarios import default_case

    viz.require()  # fail early, before planning, when the viz extra is missing

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    hand = hugger.Hand(fingers=5, links=5, link_length=0.02, link_radius=0.004, palm_radius=0.03, palm_thickness=0.01)
    case = default_case("curvy", hand, turn_deg=60.0)
    traj, elapsed = _plan(case, hand, {}, "curvy")
    traj.save(out / "plan.npz")
    summary = {"object": "curvy", "hand": repr(hand), **_report(traj, elapsed, case.obj)}
    written = ["plan.npz"]
    with Progress("drawing figures", total=3) as p:
        viz.fig4(traj, out / "fig4.png")
        p.update(1)
        viz.fig5(traj, out / "fig5.png")
        p.update(2)
        viz.tipstate_plot(traj, out / "tipstate.png")
        p.update(3)
    written += ["fig4.png", "fig5.png", "tipstate.png"]
    movies = ["animation.gif"]
    if viz.ffmpeg_path() is not None:
        movies.append("animation.mp4")
    else:
        _note("ffmpeg not found: writing the GIF only (pip install imageio-ffmpeg for MP4)")
    for name in movies:
        with Progress(f"writing {name}", total=1) as p:
            viz.animate(traj, out / name, max_frames=120, progress=lambda i, n, p=p: (setattr(p, "total", n), p.update(i)))
        written.append(name)
    summary["files"] = written
    (out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    written.append("summary.json")
    _print_table(summary)
    print(f"written to {out}/: {', '.join(written)}")
    if traj.status != "done":
        _note(f"the plan ended with status {traj.status!r}, not 'done'")
    return EXIT_OK


def cmd_render(args: argparse.Namespace) -> int:
    from . import viz

    traj = _load(args.file)
    out = Path(args.out)
    if out.suffix.lower() not in viz.RENDER_SUFFIXES:
        raise UsageError(f"--out must end in one of {', '.join(viz.RENDER_SUFFIXES)}, got {out.name!r}")
    with Progress(f"rendering {out.name}", total=1) as p:
        viz.render(traj, out, progress=lambda i, n: (setattr(p, "total", n), p.update(i)))
    print(f"wrote {out}")
    return EXIT_OK


def cmd_info(args: argparse.Namespace) -> int:
    traj = _load(args.file)
    h, prm = traj.hand, traj.params
    obj = traj.object()
    lo, hi = obj.bounds
    info = {"file": args.file, "hand": f"{h['fingers']} fingers x {h['links']} links, link radius {h['link_radius']} m, "
                                      f"palm radius {h['palm_radius']} m",
            "object": f"{len(obj.faces)} triangles, {' x '.join(f'{1000 * e:.0f}' for e in hi - lo)} mm",
            "target": [float(x) for x in traj.target],
            "step_m": prm.get("step"), "tip_epsilon_m": prm.get("epsilon"), **_report(traj, obj=obj)}
    if args.json:
        print(json.dumps(info))
    else:
        _print_table(info)
    return EXIT_OK


def cmd_objects(args: argparse.Namespace) -> int:
    from .objects import BUILTINS

    for b in BUILTINS.values():
        print(f"{b.name:10s} {b.size:20s} {b.description}")
    return EXIT_OK


def cmd_validate(args: argparse.Namespace) -> int:
    from . import physics

    traj = _load(args.file)
    if args.robust:
        with Progress("simulating the perturbations"):
            result = physics.validate_robust(traj, workers=args.workers)
        if args.json:
            print(json.dumps(result))
        else:
            for name, r in result["perturbations"].items():
                lost = [d for d, v in r["directions"].items() if not v["held"]]
                print(f"{name:13s} {'held' if r['held'] else 'LOST ' + ' '.join(lost)}")
            print(f"held fraction {result['held_fraction']:.3f}; largest push held {result['max_force_N']:.2f} N "
                  f"({result['max_force_factor']:.1f} x weight)")
            print(f"verdict: {'robustly held' if result['robust'] else 'not robustly held'}")
        return EXIT_OK
    with Progress("simulating"):
        result = physics.validate(traj)
    if args.json:
        print(json.dumps(result))
    else:
        for d, r in result["directions"].items():
            if r.get("diverged"):
                print(f"{d:3s} the simulation diverged: LOST")
                continue
            print(f"{d:3s} moved {1000 * r['displacement_m']:7.2f} mm  turned {r['rotation_deg']:6.2f} deg  "
                  f"{'held' if r['held'] else 'LOST'}")
        print(f"verdict: {'held' if result['held'] else 'not held'}")
    return EXIT_OK


def cmd_generate(args: argparse.Namespace) -> int:
    from . import dataset

    if args.address is not None and args.backend != "ray":
        raise UsageError("--address applies to --backend ray only")
    interactive = sys.stderr.isatty()
    log = None if interactive else dataset._log_line  # plain lines in logs, a bar on a terminal
    argv = getattr(args, "argv", None) or sys.argv[1:]
    with Progress("generating shards", total=1, delay=0.0) as p:
        def progress(done: int, total: int) -> None:
            p.total = total
            p.update(done)

        index = dataset.generate(args.objects, args.out, approaches=args.approaches, hands=args.hands or ["5x5"],
                                 validate=args.validate, workers=args.workers, backend=args.backend,
                                 address=args.address, scale=args.scale, params=_params(args),
                                 command=["hugger", *argv], log=log, progress=progress)
    grasps = len(index["shards"]) * int(index["parameters"]["approaches"])
    print(f"wrote {args.out}/index.json: {len(index['shards'])} shards, {grasps} grasps")
    return EXIT_OK


def cmd_export_mjcf(args: argparse.Namespace) -> int:
    from . import physics

    traj = _load(args.file)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    physics.export_mjcf(traj, out, k=args.configuration)
    print(f"wrote {out}")
    return EXIT_OK


def build_parser() -> argparse.ArgumentParser:
    ap = _Parser(prog="hugger", description="Hugging grasps for multi-finger hands (Reznik & Lumelsky, ICRA 1994).",
                 epilog="Exit status: 0 success, 2 bad input or missing optional dependency, 1 internal error.")
    ap.add_argument("--version", action="version", version=f"hugger {_version()}")
    sub = ap.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True

    p = sub.add_parser("plan", help="plan a grasp of a built-in object or a mesh file")
    p.add_argument("object", help="a built-in object name (see 'hugger objects') or a mesh file (STL, OBJ, PLY, OFF, GLB)")
    p.add_argument("--out", required=True, help="trajectory file to write (.npz)")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    p.add_argument("--approaches", type=_count, default=1, metavar="K",
                   help="plan from K directions spread evenly around T and keep the firmest grasp "
                        "(default 1: the single default approach; see docs/generation.md)")
    p.add_argument("--threads", type=_count, default=None,
                   help="planning threads for --approaches (default: the CPUs available)")
    p.add_argument("--verify", type=int, default=0, metavar="V",
                   help="with --approaches: put the V best-ranked grasps through the physics test in turn and "
                        "keep the first that holds (hugger[physics]; default 0: no physics)")
    _hand_options(p)
    _planner_options(p)
    _case_options(p)
    p.set_defaults(func=cmd_plan)

    p = sub.add_parser("demo", help="the paper's example: plan, Fig. 4, Fig. 5, animation, summary.json")
    p.add_argument("--out", default="demo-out", help="output folder (default demo-out)")
    p.set_defaults(func=cmd_demo)

    p = sub.add_parser("render", help="draw a trajectory: PNG/PDF/SVG panel, GIF or MP4 animation")
    p.add_argument("file", help="trajectory file (.npz)")
    p.add_argument("--out", required=True, help="output path; its extension picks the kind")
    p.set_defaults(func=cmd_render)

    p = sub.add_parser("info", help="what a trajectory file holds, and the grasp it ends in")
    p.add_argument("file", help="trajectory file (.npz)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=cmd_info)

    p = sub.add_parser("objects", help="list the built-in objects: name, size, description")
    p.set_defaults(func=cmd_objects)

    p = sub.add_parser("validate", help="hold test of the final grasp in MuJoCo (needs hugger[physics])")
    p.add_argument("file", help="trajectory file (.npz)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--robust", action="store_true",
                   help="the test under perturbed mass, friction, servo stiffness and squeeze, and the largest push held")
    p.add_argument("--workers", type=_count, default=None, help="processes for --robust (default: the CPUs)")
    p.set_defaults(func=cmd_validate)

    p = sub.add_parser("generate", help="a dataset of grasps: K approaches per (object, hand), resumable")
    p.add_argument("objects", nargs="+", metavar="OBJECT", help="built-in object names or mesh files")
    p.add_argument("--out", required=True, help="dataset folder (index.json and shards/); an existing one is resumed")
    p.add_argument("--approaches", type=_count, default=26, metavar="K", help="approaches per object and hand (default 26)")
    p.add_argument("--hands", nargs="+", metavar="SPEC",
                   help="hands as MxN or MxN:key=value,... (link_length, link_radius, palm_radius, palm_thickness; "
                        "default 5x5, the default hand)")
    p.add_argument("--validate", action="store_true", help="the six-direction physics test of every grasp (hugger[physics])")
    p.add_argument("--workers", type=_count, default=None, help="worker processes or Ray tasks in flight (default: the CPUs)")
    p.add_argument("--backend", choices=("local", "ray"), default="local",
                   help="local: a process pool (default); ray: one Ray task per shard (hugger[cluster])")
    p.add_argument("--address", default=None, help="Ray cluster address for --backend ray (default: start a local Ray)")
    p.add_argument("--scale", type=float, default=1.0, help="multiply mesh coordinates (0.001 for millimetres)")
    g = p.add_argument_group("planner (defaults as hugger.Planner; no timeout: datasets are deterministic)")
    g.add_argument("--step", type=float, help="approach step, m (default shortest link / 20)")
    g.add_argument("--epsilon", type=float, help="tip-to-surface distance epsilon, m (default step / 10)")
    g.add_argument("--contact-tolerance", type=float, help="sensing distance delta, m (default 1e-4)")
    g.add_argument("--max-iterations", type=int, help="Phase 2 iteration limit (default 20000)")
    p.set_defaults(func=cmd_generate)

    p = sub.add_parser("export-mjcf", help="write the hand and object at a configuration as MJCF (hugger[physics])")
    p.add_argument("file", help="trajectory file (.npz)")
    p.add_argument("--out", required=True, help="MJCF file to write (.xml)")
    p.add_argument("--configuration", type=int, default=-1, help="configuration index (default -1, the last)")
    p.set_defaults(func=cmd_export_mjcf)
    return ap


def _count(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, got {value}")
    return value


def _version() -> str:
    from . import __version__

    return __version__


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    print(f"hugger: warning: {message}", file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("default")
        warnings.showwarning = _show_warning
        return _main(argv)


def _main(argv: Sequence[str] | None) -> int:
    try:
        args = build_parser().parse_args(argv)
        args.argv = list(argv) if argv is not None else sys.argv[1:]
        return int(args.func(args))
    except (UsageError, ValueError, FileNotFoundError, IsADirectoryError, PermissionError, ImportError) as exc:
        print(f"hugger: error: {exc}", file=sys.stderr)
    except KeyboardInterrupt:
        print("hugger: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # an internal error: keep the traceback for the report
        import traceback

        traceback.print_exc()
        print(f"hugger: internal error: {type(exc).__name__}: {exc} (please report it)", file=sys.stderr)
        return EXIT_INTERNAL
    return EXIT_BAD_INPUT


if __name__ == "__main__":
    sys.exit(main())
