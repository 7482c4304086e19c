"""The ``hugger`` command: plan grasps, judge them, draw them.

    hugger plan OBJECT --out plan.npz [--json]   plan a grasp of a built-in object or a mesh file
    hugger demo [--out DIR]                       the paper's example, with figures and animation
    hugger render plan.npz --out fig.png|.pdf|.svg|.gif|.mp4 [--figure F --fps --frames --view --dpi]
    hugger info plan.npz [--json]                 what a trajectory file holds, and its grasp
    hugger objects                                the built-in objects
    hugger validate plan.npz [--json] [--robust]  hold test in MuJoCo (extra: physics); exit 1 if not held
    hugger generate OBJECT... --out DIR           a dataset: K approaches per object and hand
    hugger export-mjcf plan.npz --out hand.xml    the hand and object as MJCF
    hugger view a.npz [b.npz ...] [--port P]      interactive 3D view in the browser (extra: view)
    hugger export-scene plan.npz --out grasp.glb  the grasp as a glTF scene (extra: view)
    hugger export-urdf plan.npz --out hand.urdf   the hand and its grasp's joint values as URDF
    hugger hands                                  the preset hands (plan ... --hand PRESET|FILE)
    hugger simulate OBJECT [--push N] [--offset DX DY DZ] [--open-loop] [--json]
                                                  closed-loop hugging in MuJoCo (extra: physics)
    hugger baseline OBJECT [--out base.npz] [--validate] [--json]
                                                  the close-until-contact baseline (extra: physics)

Exit status: 0 success, 2 bad input or a missing optional dependency (one line on standard
error, no traceback), 1 an internal error (or, for ``validate``, a grasp that is not held).
Every output file is written atomically (a temporary name, then a rename) into a directory
that must exist, with the suffix its kind needs.
"""
from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Mapping, NoReturn, Sequence, TextIO

from ._files import check_replaceable, write_atomic
from ._progress import Progress, print_line
from ._core import RULES, SKINS
from ._types import VERSION

if TYPE_CHECKING:
    from .hand import Hand
    from .scenarios import Case
    from .trajectory import Trajectory
    from .world import Object

EXIT_OK, EXIT_INTERNAL, EXIT_BAD_INPUT = 0, 1, 2
#: ``hugger validate``: the grasp is not held (exit 1, like an internal error but without a traceback).
EXIT_NOT_HELD = 1
#: ``hugger validate`` says "lost" rather than a distance past this displacement (m): the object left the hand.
LOST_DISPLACEMENT = 0.2


class UsageError(Exception):
    """Bad input from the command line: reported in one line, exit 2."""


class _Parser(argparse.ArgumentParser):
    #: The subcommands' parsers, by name (the top-level parser's; empty for a subcommand's).
    commands: Mapping[str, argparse.ArgumentParser] = {}

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        # Options whole: a prefix such as --finger is refused, not taken for --fingers.
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> NoReturn:  # one line, exit 2, no usage dump
        raise UsageError(f"{message} (see '{self.prog} --help')")


# ---------------------------------------------------------------------------------------------
# Shared pieces


def _hand_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("hand (defaults: the paper's 5 x 5 hand)")
    # Defaults None: _hand() fills in hugger.Hand's defaults, and refuses these options beside --hand
    # (but --link-radius beside a URDF or MJCF file, whose links' radius it gives).
    g.add_argument("--fingers", type=int, help="M, number of fingers (default 5)")
    g.add_argument("--links", type=int, help="N, links per finger (default 5)")
    g.add_argument("--link-length", type=float, help="link length, m (default 0.02)")
    g.add_argument("--link-radius", type=float, help="link (capsule) radius, m (default 0.004)")
    g.add_argument("--palm-radius", type=float, help="palm radius, m (default 0.03)")
    g.add_argument("--palm-thickness", type=float, help="palm thickness, m (default 0.01)")
    g.add_argument("--hand", metavar="FILE|PRESET",
                   help="a preset hand (see 'hugger hands'), a URDF or MJCF file (.urdf, .xml, .mjcf: told apart by "
                        "the root element) or a hand JSON file; replaces the options above, which are refused "
                        "beside it but --link-radius with a URDF or MJCF file (URDF/MJCF need hugger[hands])")
    g.add_argument("--fixed-joint", action="append", default=[], metavar="NAME=RAD",
                   help="with --hand FILE: hold this joint at RAD (repeatable; e.g. a spread joint)")
    g.add_argument("--palm-link", metavar="NAME",
                   help="with --hand FILE: the palm, a URDF link or an MJCF body (default: the URDF's root link, the "
                        "MJCF's first body below the world with child bodies); e.g. the hand's base below a 'world' "
                        "link")


def _planner_params(g: Any) -> None:
    """The planner's parameters (a group of options), as hugger.Planner takes them."""
    g.add_argument("--step", type=_finite, help="approach step, m (default shortest link / 20)")
    g.add_argument("--epsilon", type=_finite,
                   help="overextension threshold epsilon of the planner, m (default step / 10); not the "
                        "Ferrari-Canny epsilon of the grasp quality")
    g.add_argument("--contact-tolerance", type=_finite, help="sensing distance delta, m (default 1e-4)")
    g.add_argument("--max-iterations", type=int, help="Phase 2 iteration limit (default 20000)")


_SKIN_HELP = "sensing skin: section (2D per finger plane, the default) or mesh (exact 3D queries, the reference)"


def _planner_options(p: argparse.ArgumentParser, skin_help: str = _SKIN_HELP, approaches: bool = True) -> None:
    """The planner's options; ``approaches``: the command has --approaches, which --timeout's help names."""
    g = p.add_argument_group("planner (defaults as hugger.Planner)")
    _planner_params(g)
    g.add_argument("--rules", choices=RULES, default="hug",
                   help="Phase 2 rule set: 'hug' (default; the paper's rules plus extensions for firmer "
                        "grasps) or 'paper' (the 1994 method with the documented decisions only)")
    g.add_argument("--skin", choices=SKINS, help=skin_help)
    g.add_argument("--timeout", type=float, metavar="SECONDS",
                   help="stop planning Phase 2 after this long, with status 'timeout' and a valid partial "
                        "plan (Phase 1 and the finger planes' regions come before it)"
                        + ("; with --approaches, each plan's bound (a plan it stops depends on the machine's speed, "
                           "so the search's result may)" if approaches else ""))


def _case_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("scene (defaults: T the object's natural target, the palm at a safe distance facing T)")
    g.add_argument("--target", type=float, nargs=3, metavar=("X", "Y", "Z"), help="T, a point inside the object, m")
    g.add_argument("--start", type=float, nargs=3, metavar=("X", "Y", "Z"), help="initial palm centre, m")
    g.add_argument("--normal", type=float, nargs=3, metavar=("NX", "NY", "NZ"),
                   help="initial palm normal (default: towards T); without --start the palm starts at the safe "
                        "distance from T against it, facing T along it")
    g.add_argument("--turn", type=float, default=0.0, metavar="DEG",
                   help="turn the default start away from T by DEG (-180 to 180) about the palm's y axis (default 0; "
                        "not with --start or --normal)")
    g.add_argument("--scale", type=float, help="multiply a mesh file's coordinates (0.001 for millimetres; "
                                               "not for built-in objects)")
    g.add_argument("--force", action="store_true",
                   help="plan even when the object's or the hand's size is implausible for a grasp "
                        "(millimetres read as metres)")


def _hand(args: argparse.Namespace) -> Hand:
    import inspect

    import hugger

    # The hand options of _hand_options are hugger.Hand's arguments, with its defaults.
    defaults = {k: p.default for k, p in inspect.signature(hugger.Hand).parameters.items()}
    given = [k for k in defaults if getattr(args, k, None) is not None]
    if getattr(args, "hand", None):
        from . import hands

        # A URDF or MJCF file may leave the links' radius to be given (its collisions are meshes).
        extra = {"link_radius": args.link_radius} if "link_radius" in given and args.hand not in hands.PRESETS \
            and os.path.splitext(args.hand)[1].lower() in hands.ROBOT_SUFFIXES else {}
        given = [k for k in given if k not in extra]
        if given:
            options = ", ".join("--" + k.replace("_", "-") for k in given)
            raise UsageError(f"--hand gives the whole hand; {options} cannot be combined with it"
                             + (" (a URDF or MJCF file takes --link-radius)" if "link_radius" in given else ""))

        fixed = {}
        for item in args.fixed_joint:
            name, sep, value = item.partition("=")
            try:
                fixed[name] = float(value)
            except ValueError:
                sep = ""
            if not sep or not name:
                raise UsageError(f"--fixed-joint must be NAME=RAD, got {item!r}")
            if sum(other.partition("=")[0] == name for other in args.fixed_joint) > 1:
                raise UsageError(f"--fixed-joint holds {name!r} more than once")
        return _plausible(args, lambda: hands.load(args.hand, fixed_joints=fixed or None, palm=args.palm_link,
                                                   **extra))
    for option in ("fixed_joint", "palm_link"):
        if getattr(args, option, None):
            raise UsageError(f"--{option.replace('_', '-')} needs --hand FILE")
    shape: dict[str, Any] = {k: getattr(args, k) if k in given else v for k, v in defaults.items()}
    for k, v in shape.items():  # as parsed with these defaults: the file's provenance records them
        setattr(args, k, v)
    return _plausible(args, lambda: hugger.Hand(**shape))


def _plausible(args: argparse.Namespace, make: Callable[[], Hand]) -> Hand:
    """The hand ``make()`` returns; for a command that takes ``--force`` (one that plans), refused
    unless ``--force`` when its size is implausible, as a mesh is (millimetres read as metres)."""
    if not hasattr(args, "force"):
        return make()
    from .hand import plausible_hand

    try:
        return plausible_hand(args.force, "--force to plan it anyway", make)
    except ValueError as exc:
        raise UsageError(str(exc)) from None


def _params(args: argparse.Namespace) -> dict[str, Any]:
    from .planner import PARAMS

    return {k: v for k in PARAMS if (v := getattr(args, k, None)) is not None}


def _load(path: str) -> Trajectory:
    import hugger

    if os.path.isdir(path):
        raise UsageError(f"{path} is a folder, not a trajectory file (.npz)")
    if not os.path.exists(path):
        raise UsageError(f"no such trajectory file: {path}")
    if not os.path.isfile(path):
        raise UsageError(f"{path} is not a regular file, not a trajectory file (.npz)")
    return hugger.Trajectory.load(path)


# --- output paths: an existing directory, the right suffix, written atomically ------------------

def _parent_exists(out: Path, option: str = "--out") -> None:
    """A UsageError (exit 2) unless the directory ``out`` goes into exists (nothing is created
    silently) and takes a new file there (an existing folder ``out``, what is written goes into
    it: it must take one): said before the work, not after it."""
    if not out.parent.is_dir():
        raise UsageError(f"{option}: no such directory {str(out.parent)!r} (create it first)")
    import tempfile

    where = out if out.is_dir() else out.parent
    try:
        with tempfile.TemporaryFile(dir=where):
            pass
    except OSError as exc:
        raise UsageError(f"{option}: cannot write in {str(where)!r}: {exc.strerror or exc}") from None


def _out_path(value: str, suffixes: Sequence[str], option: str = "--out") -> Path:
    """``value`` as an output path: its directory must exist (nothing is created silently) and
    its suffix must be one of ``suffixes`` (case-insensitive); otherwise a UsageError (exit 2)."""
    if not value:
        raise UsageError(f"{option} is empty, expected a file name ending in {' or '.join(suffixes)}")
    out = Path(value)
    if out.is_dir():
        raise UsageError(f"{option} {value!r} is a directory, expected a file name ending in {' or '.join(suffixes)}")
    if out.suffix.lower() not in suffixes:
        raise UsageError(f"{option} must end in {' or '.join(suffixes)}, got {out.name!r}")
    try:  # before the work, not after it: a pipe or device is not replaced (the writers' rule)
        target = check_replaceable(out)
    except ValueError as exc:
        raise UsageError(f"{option}: {exc}") from None
    _parent_exists(target, option)  # (a link's target is written, in its own folder)
    return out


def _out_dir(value: str, option: str = "--out") -> Path:
    """An output folder: created if missing, but its parent must exist."""
    if not value:
        raise UsageError(f"{option} is empty, expected a folder")
    out = Path(value)
    if out.exists() and not out.is_dir():
        raise UsageError(f"{option} {value!r} exists and is not a directory")
    _parent_exists(out, option)
    out.mkdir(exist_ok=True)
    return out


#: The analysis figures of ``plan``, ``info`` and ``demo`` reports, under names that say what they
#: are: (key in the report, key in :func:`hugger.analysis.analyze`). The planner's epsilon (a
#: parameter) is ``planner_epsilon_m``; the grasp quality's is ``ferrari_canny_epsilon``.
_ANALYSIS_KEYS = (("palm_contact", "palm_contact"), ("links_in_contact", "links_in_contact"), ("links", "links"),
                  ("contacts", "contacts"), ("force_closure", "force_closure"),
                  ("ferrari_canny_epsilon", "epsilon"), ("wrench_space_volume", "volume"),
                  ("per_finger_contacts", "per_finger_contacts"), ("wrap_angle_deg", "wrap_angle_deg"),
                  ("mu", "mu"), ("penetration_m", "penetration_m"))


def _report(traj: Trajectory, plan_time: float | None = None, obj: Object | None = None) -> dict[str, Any]:
    """Status, sizes, timing and the grasp judgement of the final configuration (``obj``: the
    trajectory's object when already built)."""
    from . import analysis

    out: dict[str, Any] = {"status": traj.status, "configurations": len(traj),
                           "phase1_configurations": int((traj.phase == 1).sum())}
    if plan_time is not None:
        out["plan_time_s"] = round(plan_time, 6)
        out["configurations_per_s"] = round(len(traj) / plan_time, 1) if plan_time > 0 else None
    a = analysis.analyze(traj, obj=obj)
    out.update({key: a[source] for key, source in _ANALYSIS_KEYS})
    return out


def _printable(text: str) -> str:
    """``text`` with its control characters written as escapes: a file's strings (an object's name)
    reach the terminal as text, never as its commands."""
    return "".join(c if c.isprintable() else c.encode("unicode_escape").decode("ascii") for c in text)


def _print_table(d: dict[str, Any], stream: TextIO | None = None) -> None:
    stream = stream or sys.stdout
    for key, value in d.items():
        if isinstance(value, float):
            value = f"{value:.6g}"
        elif isinstance(value, list):
            value = " ".join(f"{x:.4g}" if isinstance(x, float) else str(x) for x in value)
        print(f"{key:22s} {_printable(str(value))}", file=stream)


def _note(message: str) -> None:
    print_line(f"hugger: {message}")


def _plan(case: Case, hand: Hand, params: dict[str, Any], label: str,
          timeout: float | None = None) -> tuple[Trajectory, float]:
    import hugger

    t0 = time.perf_counter()
    planner = hugger.Planner(hand, case.obj, case.target, case.palm_pose, **params)
    with Progress(f"planning {label}"):
        traj = planner.plan(timeout=timeout)
    return traj, time.perf_counter() - t0


def _search(case: Case, hand: Hand, args: argparse.Namespace) -> tuple[Trajectory, float, dict[str, Any]]:
    """``hugger plan --approaches K``: the best of K approaches around T (hugger.search)."""
    import hugger

    if args.start is not None or args.normal is not None or args.turn:
        raise UsageError("--approaches K > 1 chooses the start poses itself: not with --start, --normal or --turn")
    if args.robust_verify and args.verify < 1:
        raise UsageError("--robust-verify checks the --verify V best-ranked grasps: give --verify V >= 1")
    pole = case.palm_pose[:3, 3] - case.target
    with Progress(f"searching {args.approaches} approaches of {case.name}", total=args.approaches) as p:
        result = hugger.search(hand, case.obj, case.target, approaches=args.approaches, threads=args.threads,
                               pole=pole, timeout=args.timeout, progress=p.update,
                               verify=args.verify, robust=args.robust_verify, workers=args.workers,
                               **_params(args))
    chosen = result.chosen
    summary = {"approaches": len(result.candidates), "best": result.best,
               "direction": [float(x) for x in chosen.direction], "time_s": round(result.time_s, 6),
               "judged": sum(c.firmness is not None for c in result.candidates), "verified": list(result.verified),
               "candidates": [c.to_dict() for c in result.candidates]}
    return result.trajectory, chosen.plan_time_s, summary


# ---------------------------------------------------------------------------------------------
# Commands


def _provenance(args: argparse.Namespace) -> dict[str, Any]:
    """What made a trajectory file: the command line (the arguments main() was given), its parsed
    options and the object's name or path."""
    from .objects import BUILTINS

    spec = os.fspath(args.object)
    builtin = spec in BUILTINS
    options = {k: v for k, v in sorted(vars(args).items()) if k not in ("func", "json") and not k.startswith("_")}
    return {"command": ["hugger", *args._argv],
            "object": spec if builtin else os.path.abspath(spec), "object_source": "builtin" if builtin else "file",
            "arguments": options}


def _case(args: argparse.Namespace, hand: Hand) -> Case:
    """The scene of ``plan`` and ``simulate``: the object (built-in or mesh file, --scale only for
    files, an implausible size refused unless --force), T and the start pose."""
    from .objects import BUILTINS
    from .scenarios import ImplausibleSize, judged_case

    if args.scale is not None and os.fspath(args.object) in BUILTINS:
        raise UsageError(f"--scale applies to mesh files only; {args.object!r} is a built-in object, sized in metres")
    try:
        case, message = judged_case(args.object, hand, scale=1.0 if args.scale is None else args.scale,
                                    force=args.force, target=args.target, start=args.start, normal=args.normal,
                                    turn_deg=args.turn)
    except ImplausibleSize as exc:
        raise UsageError(f"{exc.what}; refused (give --scale, or --force to plan it anyway)") from None
    if message:
        _note(f"warning: {message} (planning it anyway: --force)")
    for r in case.repairs:
        _note(f"repaired {case.name}: {r}")
    return case


def _optional_out_scene(args: argparse.Namespace) -> tuple[Path | None, Hand, Case]:
    """The trajectory file of an optional --out (.npz; None without it), the hand and the scene,
    in that order: a bad --out is refused before anything is built."""
    out = _out_path(args.out, (".npz",)) if args.out is not None else None
    hand = _hand(args)
    return out, hand, _case(args, hand)


def cmd_plan(args: argparse.Namespace) -> int:
    out = _out_path(args.out, (".npz",))
    hand = _hand(args)
    case = _case(args, hand)
    searched = None
    if args.approaches == 1 and (args.verify or args.robust_verify or args.workers is not None):
        raise UsageError("--verify, --robust-verify and --workers choose among the grasps of --approaches K > 1")
    if args.approaches == 1 and args.threads is not None:
        raise UsageError("--threads plans the approaches of --approaches K > 1 in parallel; one plan is one thread")
    if args.workers is not None and not args.robust_verify:
        raise UsageError("--workers runs the simulations of --robust-verify in parallel; give --robust-verify")
    if args.approaches != 1:
        traj, elapsed, searched = _search(case, hand, args)
    else:
        traj, elapsed = _plan(case, hand, _params(args), case.name, args.timeout)
    traj = traj.with_provenance(**_provenance(args))
    traj.save(out)
    report = {"object": case.name, "out": str(out), **_report(traj, elapsed, case.obj)}
    if searched is not None:
        report["search"] = searched
        if not args.json:  # the table: the search in three lines, not every candidate
            report.pop("search")
            report.update({"approaches": searched["approaches"], "chosen_approach": searched["best"],
                           "approach_direction": searched["direction"], "search_time_s": searched["time_s"]})
    if searched is not None and args.verify:  # what the simulations said of the grasp chosen
        chosen = searched["candidates"][searched["best"]]
        if not args.json:
            report.update({"verified": len(searched["verified"]), "chosen_held": chosen["held"]})
            if args.robust_verify:
                report["chosen_robust"] = chosen["robust"]
        if not (chosen["robust"] if args.robust_verify else chosen["held"]):
            kept = "the held one holding under the most perturbations" if chosen["held"] else "the ranking's best"
            _note(f"none of the {len(searched['verified'])} grasps verified was {'robustly ' if args.robust_verify else ''}"
                  f"held in simulation: kept {kept}")
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

    out = _out_dir(args.out)
    hand = hugger.Hand(fingers=5, links=5, link_length=0.02, link_radius=0.004, palm_radius=0.03, palm_thickness=0.01)
    case = default_case("curvy", hand, turn_deg=60.0)
    traj, elapsed = _plan(case, hand, {}, "curvy")
    traj = traj.with_provenance(command=["hugger", "demo", "--out", str(args.out)], object="curvy",
                                object_source="builtin", arguments={"turn": 60.0})
    traj.save(out / "plan.npz")
    summary = {"object": "curvy", "hand": repr(hand), **_report(traj, elapsed, case.obj)}
    written = ["plan.npz"]
    figures = ("fig4", "fig5", "tipstate")
    with Progress("drawing figures", total=len(figures)) as p:
        for i, figure in enumerate(figures, start=1):
            viz.render(traj, out / f"{figure}.png", figure=figure)  # (each writer writes atomically)
            p.update(i)
    written += [f"{figure}.png" for figure in figures]
    movies = ["animation.gif"]
    if viz.ffmpeg_path() is not None:
        movies.append("animation.mp4")
    else:
        _note("ffmpeg not found: writing the GIF only (pip install imageio-ffmpeg for MP4)")
    for name in movies:
        with Progress(f"writing {name}", total=1) as p:
            viz.animate(traj, out / name, max_frames=120, hold=1.0, progress=p.update)
        written.append(name)
    written.append("summary.json")
    summary["files"] = written
    write_atomic(out / "summary.json", json.dumps(summary, indent=2) + "\n")
    _print_table(summary)
    print(f"written to {out}/: {', '.join(written)}")
    if traj.status != "done":
        _note(f"the plan ended with status {traj.status!r}, not 'done'")
    return EXIT_OK


# --- render: figures and animations ---------------------------------------------------------------

def cmd_render(args: argparse.Namespace) -> int:
    from . import viz

    out = _out_path(args.out, viz.RENDER_SUFFIXES)
    try:
        figure = viz.pick_figure(out, args.figure)
    except ValueError as exc:  # "figure F writes ...": the figure does not write that extension
        raise UsageError(f"--{exc}") from None
    if figure != "animation":
        for option, value in (("--fps", args.fps), ("--frames", args.frames), ("--view", args.view)):
            if value is not None:
                raise UsageError(f"{option} applies to animations only (--figure animation, .gif or .mp4)")
    for value, check in ((args.fps, viz.check_fps), (args.dpi, viz.check_dpi)):
        if value is not None:
            try:
                check(value)
            except ValueError as exc:  # "fps must be ..."
                raise UsageError(f"--{exc}") from None
    if args.frames is not None and args.frames < 1:
        raise UsageError(f"--frames must be at least 1, got {args.frames}")
    traj = _load(args.file)
    options = (("dpi", args.dpi), ("fps", args.fps), ("max_frames", args.frames), ("view", args.view))
    kwargs: dict[str, Any] = {key: value for key, value in options if value is not None}
    if figure == "animation":
        kwargs["hold"] = 1.0
    with Progress(f"rendering {out.name}", total=1) as p:
        viz.render(traj, out, figure=figure, progress=p.update, **kwargs)
    print(f"wrote {out}")
    return EXIT_OK


def _hand_info(h: dict[str, Any]) -> dict[str, Any]:
    """The hand of a trajectory file as structured fields (sizes in m, angles in rad)."""
    keys = ("fingers", "links", "link_lengths", "link_radius", "palm_radius", "palm_thickness", "finger_angles",
            "finger_roots", "finger_directions", "joint_limits", "rest_angles", "name")
    return {k: h[k] for k in keys if k in h}


def _object_info(traj: Trajectory, obj: Object | None) -> dict[str, Any]:
    prov = traj.provenance
    if obj is None:  # planned with a skin that has no mesh
        return {"name": prov.get("object"), "source": prov.get("object_source"), "recorded": False}
    lo, hi = obj.bounds
    return {"name": prov.get("object"), "source": prov.get("object_source"), "sha256": traj.object_sha256(),
            "recorded": True, "triangles": int(len(obj.faces)), "vertices": int(len(obj.vertices)),
            "extent_m": [float(e) for e in hi - lo], "bounds_m": [[float(x) for x in lo], [float(x) for x in hi]],
            "volume_m3": float(obj.volume)}


def cmd_info(args: argparse.Namespace) -> int:
    import warnings

    from .analysis import collision_tolerance
    from .trajectory import FORMAT_VERSION

    traj = _load(args.file)
    prm = traj.params
    obj = traj.object() if traj.has_object else None
    if obj is not None:
        report = _report(traj, obj=obj)
        # A file's grasp judged as it stands: one the planner did not make (or whose object was
        # rescaled since) may sink the hand into the object, which the counts above do not show.
        if obj.size_warning is not None:  # (not warned of when the file's object was made)
            warnings.warn(obj.size_warning, UserWarning, stacklevel=1)
        tolerance = collision_tolerance(traj.hand["link_radius"])
        if report["penetration_m"] > tolerance:
            warnings.warn(f"the hand lies {1000 * report['penetration_m']:.3g} mm inside the object at the final "
                          f"configuration (beyond the checker's {1000 * tolerance:.3g} mm): not a grasp this planner "
                          f"makes; the contacts and the quality count it as touching", UserWarning, stacklevel=1)
    else:  # planned with a skin that has no mesh: the motion only
        report = {"status": traj.status, "configurations": len(traj), "phase1_configurations": int((traj.phase == 1).sum())}
    if args.json:
        info = {"file": args.file, "format_version": FORMAT_VERSION, "hand": _hand_info(traj.hand),
                "object": _object_info(traj, obj),
                "target": [float(x) for x in traj.target], "params": prm, "provenance": traj.provenance,
                "step_m": prm.get("step"), "planner_epsilon_m": prm.get("epsilon"), **report}
        print(json.dumps(info))
        return EXIT_OK
    h = traj.hand
    prov = traj.provenance
    if obj is not None:
        lo, hi = obj.bounds
        what = f"{prov.get('object', '(unnamed)')}: {len(obj.faces)} triangles, " \
               f"{' x '.join(f'{1000 * e:.0f}' for e in hi - lo)} mm"
    else:
        what = "none recorded (planned with a skin that has no mesh)"
    info = {"file": args.file, "hand": f"{h['fingers']} fingers x {h['links']} links, link radius {h['link_radius']:.6g} m, "
                                      f"palm radius {h['palm_radius']:.6g} m"
                    + (", general layout" if "finger_roots" in h else "")
                    + (f" ({h['name']})" if isinstance(h.get("name"), str) else ""),
            "object": what,
            "object_sha256": traj.object_sha256() if obj is not None else None,
            "hugger_version": prov.get("hugger_version", "(not recorded)"),
            "target": [float(x) for x in traj.target],
            "step_m": prm.get("step"), "planner_epsilon_m": prm.get("epsilon"), **report}
    _print_table(info)
    return EXIT_OK


def cmd_objects(args: argparse.Namespace) -> int:
    from .objects import BUILTINS

    for b in BUILTINS.values():
        print(f"{b.name:10s} {b.size:20s} {b.description}")
    return EXIT_OK


def _moved(r: dict[str, Any]) -> str:
    """One direction's result of the hold test, in words: a distance, or "lost" past LOST_DISPLACEMENT."""
    if r.get("diverged") or r.get("displacement_m") is None:
        return "the simulation diverged: LOST"
    d = float(r["displacement_m"])
    if d > LOST_DISPLACEMENT:
        return f"lost (moved more than {1000 * LOST_DISPLACEMENT:.0f} mm)"
    return (f"moved {1000 * d:7.2f} mm  turned {r['rotation_deg']:6.2f} deg  "
            f"{'held' if r['held'] else 'LOST'}")


def _hold_test(traj: Trajectory, as_json: bool) -> dict[str, Any]:
    """The six-direction hold test of the final grasp, printed as a table unless ``as_json``."""
    from . import physics

    with Progress("simulating"):
        result = physics.validate(traj)
    if not as_json:
        for d, r in result["directions"].items():
            print(f"{d:3s} {_moved(r)}")
        print(f"verdict: {'held' if result['held'] else 'not held'}")
    return result


def cmd_baseline(args: argparse.Namespace) -> int:
    """The close-until-contact baseline from the start ``hugger plan`` takes, with its hand options."""
    from .baselines import run_baseline

    out, hand, case = _optional_out_scene(args)
    run = run_baseline(hand, case.obj, case.target, case.palm_pose)
    traj = run.trajectory
    if out is not None:  # as the planner's files: the same input writes the same bytes
        traj.with_provenance(**_provenance(args)).save(out)
    report = {"object": case.name, "out": None if out is None else str(out), **_report(traj, obj=case.obj),
              "setup_time_s": round(run.setup_time_s, 6), "plan_time_s": round(run.plan_time_s, 6)}
    if not args.json:
        _print_table(report)
    held = _hold_test(traj, args.json) if args.validate else None
    if args.json:
        print(json.dumps({**report, **({"validate": held} if held is not None else {})}))
    return EXIT_OK


def cmd_validate(args: argparse.Namespace) -> int:
    """Exit 0 when the grasp is held in all six directions, 1 when it is not, 2 for bad input."""
    from . import physics

    if args.workers is not None and not args.robust:
        raise UsageError("--workers runs the perturbations of --robust in parallel; give --robust")
    traj = _load(args.file)
    if traj.status not in ("done", "stalled"):  # judged all the same: the grasp as it stands
        _note(f"note: the plan did not finish (status {traj.status}); its last configuration is judged")
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
        return EXIT_OK if result["robust"] else EXIT_NOT_HELD
    result = _hold_test(traj, args.json)
    if args.json:
        print(json.dumps(result))
    return EXIT_OK if result["held"] else EXIT_NOT_HELD


def cmd_generate(args: argparse.Namespace) -> int:
    from . import dataset
    from .scenarios import ImplausibleSize

    if not args.out:
        raise UsageError("--out is empty, expected the dataset's folder")
    _parent_exists(Path(args.out))  # the dataset's folder is made by dataset.generate
    argv = args._argv
    try:
        with Progress("generating shards", total=1, delay=0.0) as p:
            # plain lines in logs; on a terminal the same lines above a bar that shows the time go by
            index = dataset.generate(args.objects, args.out, approaches=args.approaches, hands=args.hands or ["5x5"],
                                     validate=args.validate, workers=args.workers, backend=args.backend,
                                     address=args.address, scale=args.scale, params=_params(args),
                                     command=["hugger", *argv], log=_note, progress=p.update, force=args.force)
    except ImplausibleSize as exc:
        raise UsageError(f"{exc.what}; refused (give --scale, or --force to make its shards anyway)") from None
    grasps = len(index["shards"]) * int(index["parameters"]["approaches"])
    print(f"wrote {args.out}/index.json: {len(index['shards'])} shards, {grasps} grasps")
    return EXIT_OK


def _configuration(traj: Trajectory, k: int) -> None:
    """Refuse a --configuration index outside the trajectory (negative ones count from the end),
    by trajectory.configuration_index's rule."""
    from .trajectory import configuration_index

    try:
        configuration_index(len(traj), k)
    except IndexError:
        raise UsageError(f"--configuration {k} is out of range for {len(traj)} configurations") from None


def cmd_export_mjcf(args: argparse.Namespace) -> int:
    from . import physics

    out = _out_path(args.out, (".xml", ".mjcf"))
    traj = _load(args.file)
    _configuration(traj, args.configuration)
    physics.export_mjcf(traj, out, k=args.configuration)
    print(f"wrote {out}")
    return EXIT_OK


# --- the 3D viewer and glTF export (extra: view) --------------------------------------------------

def cmd_view(args: argparse.Namespace) -> int:
    from . import viewer

    if not 0 <= args.port <= 65535:
        raise UsageError(f"--port must be in 0..65535, got {args.port}")
    if args.fps is not None:
        try:
            viewer.check_fps(args.fps)
        except ValueError as exc:  # "fps must be ...", as render says it
            raise UsageError(f"--{exc}") from None
    viewer._viser()  # the extra, before loading anything
    trajs = [_load(f) for f in args.files]
    labels = [f"{os.path.basename(f)}: {t.status}, {len(t)} configurations" for f, t in zip(args.files, trajs)]
    v = viewer.view(trajs, host=args.host, port=args.port, fps=args.fps or 20.0, labels=labels,
                    open_browser=not args.no_browser, block=False)
    print(f"hugger: serving {len(trajs)} plan{'s' if len(trajs) > 1 else ''} at {v.url} (Ctrl-C stops)", flush=True)
    v.serve()
    return EXIT_OK


def cmd_export_scene(args: argparse.Namespace) -> int:
    from . import viewer

    out = _out_path(args.out, (".glb",))
    viewer._trimesh()
    traj = _load(args.file)
    with Progress(f"writing {out.name}", total=1):
        scene = viewer.export_scene(traj, out, all_frames=args.all)
    print(f"wrote {out}: {len(scene.graph.nodes_geometry)} meshes"
          f"{f' over {len(traj)} configurations' if args.all else ' (the final configuration)'}")
    return EXIT_OK


def cmd_hands(args: argparse.Namespace) -> int:
    from .hands import PRESETS

    rows: list[dict[str, Any]] = []
    for p in PRESETS.values():
        h = p.build()
        rows.append({"name": p.name, "fingers": h.fingers, "links": h.links, "reach_m": round(h.reach, 4),
                     "limits": h.has_limits, "description": p.description, "source": p.source})
    if args.json:
        print(json.dumps(rows, indent=2))
        return EXIT_OK
    for r in rows:
        print(f"{r['name']:<16} {r['fingers']} x {r['links']}  reach {r['reach_m'] * 100:5.1f} cm  "
              f"{'limits' if r['limits'] else 'no limits':<9}  {r['description']}")
    return EXIT_OK


def cmd_export_urdf(args: argparse.Namespace) -> int:
    import hugger

    from .hands.robot import grasp_joint_values, to_mjcf, to_urdf

    traj = _load(args.file)
    _configuration(traj, args.configuration)
    hand = hugger.Hand.from_dict(traj.hand)
    angles = traj.angles[args.configuration]
    out = _out_path(args.out, hugger.hands.ROBOT_SUFFIXES)
    text = to_urdf(hand, angles) if out.suffix.lower() == ".urdf" else to_mjcf(hand, angles)
    write_atomic(out, text)
    if args.json:
        print(json.dumps({"out": str(out), "joint_values": grasp_joint_values(hand, angles)}))
    else:
        print(f"wrote {out}")
    return EXIT_OK


def cmd_simulate(args: argparse.Namespace) -> int:
    import numpy as np

    from . import mujoco_skin

    out, hand, case = _optional_out_scene(args)
    if args.push < 0 or not np.isfinite(args.push):
        raise UsageError(f"--push must be a force >= 0 (N), got {args.push}")
    if args.latency < 0:
        raise UsageError(f"--latency must be >= 0 control periods, got {args.latency}")
    offset = np.asarray(args.offset, dtype=np.float64)
    if not np.all(np.isfinite(offset)):
        raise UsageError("--offset must be finite (m)")
    params = _params(args)
    # The closed loop senses through MuJoCo; a skin chooses how the open loop's plan senses the mesh.
    skin = params.pop("skin", None)
    if skin is not None and not args.open_loop:
        raise UsageError("--skin chooses the sensing of the --open-loop plan on the static mesh; the closed "
                         "loop senses through MuJoCo")
    runs = {}
    with Progress(f"closed-loop hugging of {case.name} in MuJoCo"):
        runs["closed"] = mujoco_skin.simulate(hand, case.obj, case.target, case.palm_pose, offset=offset,
                                              push=args.push, latency=args.latency, **params)
    if args.open_loop:
        with Progress(f"open-loop replay on {case.name}"):
            runs["open"] = mujoco_skin.replay(hand, case.obj, case.target, case.palm_pose, offset=offset,
                                              push=args.push, **params, **({"skin": skin} if skin else {}))
    if out is not None:
        runs["closed"].trajectory.with_provenance(**_provenance(args)).save(out)  # atomically
    report = {"object": case.name, "offset_m": offset.tolist(), "push_N": args.push, "latency": args.latency,
              **{mode: r.as_dict() for mode, r in runs.items()}}
    if args.json:
        print(json.dumps(report))
    else:
        for mode, r in runs.items():
            d = r.as_dict()
            head = f"{mode:6s} status {d['status']:14s} configurations {d['configurations']:5d}  "
            if d["hold"].get("diverged"):  # where the reset left the object says nothing
                print(head + "the simulation went unstable (MuJoCo reset it): no figures, NOT held")
            else:
                print(head + f"object moved {1000 * d['object_moved_m']:6.2f} mm  links in contact "
                      f"{d['links_in_contact']:2d}  {'held' if d['held'] else 'NOT held'} in the six-direction test")
    return EXIT_OK


def build_parser() -> _Parser:
    ap = _Parser(prog="hugger", description="Hugging grasps for multi-finger hands (Reznik & Lumelsky, ICRA 1994).",
                 epilog="Exit status: 0 success, 2 bad input or missing optional dependency, 1 internal error "
                        "(hugger validate: 1 also when the grasp is not held).")
    ap.add_argument("--version", action="version", version=f"hugger {VERSION}")
    sub = ap.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    ap.commands = sub.choices
    from .viz import FIGURES

    p = sub.add_parser("plan", help="plan a grasp of a built-in object or a mesh file")
    p.add_argument("object", help="a built-in object name (see 'hugger objects') or a mesh file (STL, OBJ, PLY, OFF, GLB)")
    p.add_argument("--out", required=True, help="trajectory file to write (.npz), in an existing directory")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    p.add_argument("--approaches", type=_count, default=1, metavar="K",
                   help="plan from K directions spread evenly around T and keep the firmest grasp "
                        "(default 1: the single default approach; see docs/generation.md)")
    p.add_argument("--threads", type=_count, default=None,
                   help="planning threads for --approaches (default: the CPUs available)")
    p.add_argument("--verify", type=int, default=0, metavar="V",
                   help="with --approaches: put the V best-ranked grasps through the physics test in turn and "
                        "keep the first that holds (hugger[physics]; default 0: no physics)")
    p.add_argument("--robust-verify", action="store_true",
                   help="with --verify V: keep the first of the V that is robustly held (every perturbation of "
                        "'hugger validate --robust'), else the one holding the largest fraction of them")
    p.add_argument("--workers", type=_count, default=None, metavar="W",
                   help="simulation processes of --robust-verify (default: the CPUs available)")
    _hand_options(p)
    _planner_options(p)
    _case_options(p)
    p.set_defaults(func=cmd_plan)

    p = sub.add_parser("demo", help="the paper's example: plan, Fig. 4, Fig. 5, animation, summary.json")
    p.add_argument("--out", default="demo-out",
                   help="output folder, created in an existing directory (default demo-out)")
    p.set_defaults(func=cmd_demo)

    p = sub.add_parser("render", help="draw a trajectory: PNG/PDF/SVG figures, GIF or MP4 animation")
    p.add_argument("file", help="trajectory file (.npz)")
    p.add_argument("--out", required=True, help="output path (.png .pdf .svg .gif .mp4), in an existing directory")
    p.add_argument("--figure", choices=tuple(FIGURES),
                   help="what to draw: " + "; ".join(f"{k}: {what}" for k, (_, what) in FIGURES.items())
                        + " (default: sheet for .png/.pdf/.svg, animation for .gif/.mp4)")
    p.add_argument("--dpi", type=float, help="resolution, dots per inch (default 100 sheet and animation, 120 others; "
                                             "10 to 1200)")
    p.add_argument("--fps", type=float, help="animation: frames per second (default 30, at most 120)")
    p.add_argument("--frames", type=int, help="animation: at most this many frames, evenly spread (default 300)")
    p.add_argument("--view", choices=("oblique", "side", "normal"), help="animation: the camera (default oblique)")
    p.set_defaults(func=cmd_render)

    p = sub.add_parser("info", help="what a trajectory file holds, and the grasp it ends in")
    p.add_argument("file", help="trajectory file (.npz)")
    p.add_argument("--json", action="store_true", help="print one JSON object (hand, object, provenance structured)")
    p.set_defaults(func=cmd_info)

    p = sub.add_parser("objects", help="list the built-in objects: name, size, description")
    p.set_defaults(func=cmd_objects)

    p = sub.add_parser("validate", help="hold test of the final grasp in MuJoCo (needs hugger[physics]); "
                                        "exit 0 held, 1 not held, 2 bad input",
                       description="Hold test of the final grasp in MuJoCo (needs hugger[physics]): a force of 10 "
                                   "times the object's weight along +x, -x, +y, -y, +z, -z in turn. Exit status: "
                                   "0 held, 1 not held, 2 bad input.")
    p.add_argument("file", help="trajectory file (.npz)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--robust", action="store_true",
                   help="the test under perturbed mass, friction, servo stiffness and squeeze, and the largest push "
                        "held; exit 0 only when held under every perturbation")
    p.add_argument("--workers", type=_count, default=None, help="processes for --robust (default: the CPUs)")
    p.set_defaults(func=cmd_validate)

    p = sub.add_parser("baseline", help="the close-until-contact baseline (GraspIt!'s AutoGrasp) from the same "
                                        "start, for comparison (hugger[physics]; docs/comparison.md)")
    p.add_argument("object", help="a built-in object name (see 'hugger objects') or a mesh file (STL, OBJ, PLY, OFF, GLB)")
    p.add_argument("--out", default=None, help="trajectory file to write (.npz), in an existing directory")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    p.add_argument("--validate", action="store_true", help="then the six-direction hold test of its grasp")
    _hand_options(p)
    _case_options(p)
    p.set_defaults(func=cmd_baseline)

    p = sub.add_parser("simulate", help="closed-loop hugging in MuJoCo: plan from what a MuJoCo skin feels (hugger[physics])")
    p.add_argument("object", help="a built-in object name or a mesh file")
    p.add_argument("--offset", type=float, nargs=3, default=(0.0, 0.0, 0.0), metavar=("DX", "DY", "DZ"),
                   help="the planner is told T off by this much (m): the object is not where T was assumed")
    p.add_argument("--push", type=float, default=0.0, metavar="N",
                   help="push the object with N newtons across the approach for 0.1 s at the first touch")
    p.add_argument("--latency", type=int, default=0, help="the skin reads the object as it was this many control periods ago")
    p.add_argument("--open-loop", action="store_true", help="also replay a plan made on the static mesh, for comparison")
    p.add_argument("--out", help="write the closed-loop trajectory here (.npz, the object where the simulation left it: "
                                 "the configurations before it moved may overlap it there, so the file is for viewing "
                                 "and the hold test, not for check_trajectory.py)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    _hand_options(p)
    _planner_options(p, skin_help="sensing skin of the --open-loop plan on the static mesh: section (the default) "
                                  "or mesh; the closed loop senses through MuJoCo", approaches=False)
    _case_options(p)
    p.set_defaults(func=cmd_simulate)

    p = sub.add_parser("generate", help="a dataset of grasps: K approaches per (object, hand), resumable")
    p.add_argument("objects", nargs="+", metavar="OBJECT", help="built-in object names or mesh files")
    p.add_argument("--out", required=True, help="dataset folder (index.json and shards/); an existing one is resumed")
    p.add_argument("--approaches", type=_count, default=26, metavar="K", help="approaches per object and hand (default 26)")
    p.add_argument("--hands", nargs="+", action="extend", metavar="SPEC",
                   help="hands as MxN or MxN:key=value,... (link_length, link_radius, palm_radius, palm_thickness; "
                        "default 5x5, the default hand); repeated, the hands of each")
    p.add_argument("--validate", action="store_true", help="the six-direction physics test of every grasp (hugger[physics])")
    p.add_argument("--workers", type=_count, default=None, help="worker processes or Ray tasks in flight (default: the CPUs)")
    p.add_argument("--backend", choices=("local", "ray"), default="local",
                   help="local: a process pool (default); ray: one Ray task per shard (hugger[cluster])")
    p.add_argument("--address", default=None, help="Ray cluster address for --backend ray (default: start a local Ray)")
    p.add_argument("--scale", type=float, default=1.0, help="multiply mesh coordinates (0.001 for millimetres)")
    p.add_argument("--force", action="store_true",
                   help="make the shards of a mesh whose size is implausible for a hand (millimetres read as metres)")
    g = p.add_argument_group("planner (defaults as hugger.Planner; no timeout: datasets are deterministic)")
    _planner_params(g)
    g.add_argument("--rules", choices=RULES, default=None, help="Phase 2 rule set (default hug)")
    g.add_argument("--skin", choices=SKINS, help=_SKIN_HELP)
    p.set_defaults(func=cmd_generate)

    p = sub.add_parser("export-mjcf", help="write the hand and object at a configuration as MJCF (hugger[physics])")
    p.add_argument("file", help="trajectory file (.npz)")
    p.add_argument("--out", required=True, help="MJCF file to write (.xml or .mjcf), in an existing directory")
    p.add_argument("--configuration", type=int, default=-1, help="configuration index (default -1, the last)")
    p.set_defaults(func=cmd_export_mjcf)

    p = sub.add_parser("view", help="interactive 3D view of one or more plans in the browser (needs hugger[view])")
    p.add_argument("files", nargs="+", metavar="FILE", help="trajectory files (.npz), shown side by side")
    p.add_argument("--port", type=int, default=8080,
                   help="HTTP port (default 8080; 0 picks a free one; a port in use gives the next free one, "
                        "as the printed address says)")
    p.add_argument("--host", default="127.0.0.1", help="address to serve on (default 127.0.0.1, this machine only)")
    p.add_argument("--no-browser", action="store_true", help="do not open a web browser, just serve")
    p.add_argument("--fps", type=float, help="playback frames per second, 1 to 120 (default 20)")
    p.set_defaults(func=cmd_view)

    p = sub.add_parser("export-scene", help="write the final grasp (or every configuration) as a glTF scene "
                                            "(.glb; needs hugger[view])")
    p.add_argument("file", help="trajectory file (.npz)")
    p.add_argument("--out", required=True, help="glTF binary to write (.glb), in an existing directory")
    p.add_argument("--all", action="store_true", help="every configuration, one group of nodes k<k>/ each")
    p.set_defaults(func=cmd_export_scene)
    p = sub.add_parser("hands", help="list the preset hands: name, fingers x links, reach, source")
    p.add_argument("--json", action="store_true", help="print a JSON list")
    p.set_defaults(func=cmd_hands)

    p = sub.add_parser("export-urdf", help="write the hand with a configuration's joint values as URDF (hugger[hands])")
    p.add_argument("file", help="trajectory file (.npz)")
    p.add_argument("--out", required=True, help="URDF file to write (.urdf; .xml or .mjcf writes the hand alone as MJCF)")
    p.add_argument("--configuration", type=int, default=-1, help="configuration index (default -1, the last)")
    p.add_argument("--json", action="store_true", help="print the file and the joint values as JSON")
    p.set_defaults(func=cmd_export_urdf)
    return ap


def _finite(text: str) -> float:
    """A finite number (the planner's own checks then say what else it must be)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def _count(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, got {value}")
    return value


def _show_warning(message: Warning | str, category: type[Warning], filename: str, lineno: int,
                  file: TextIO | None = None, line: str | None = None) -> None:
    print_line(f"hugger: warning: {message}")  # above a progress bar being drawn


def main(argv: Sequence[str] | None = None, program: bool | None = None) -> int:
    """The ``hugger`` command on ``argv`` (default the command line's). ``program``: run as the
    program, which ends after this (default: when ``argv`` is None); then a Ctrl-C after an
    interrupted command ends the process at once."""
    import warnings

    from . import _signals

    with warnings.catch_warnings(), _signals.installed(program=argv is None if program is None else program):
        warnings.simplefilter("default")
        warnings.showwarning = _show_warning
        return _main(argv)


def _main(argv: Sequence[str] | None) -> int:
    try:
        parser = build_parser()
        args, extra = parser.parse_known_args(argv)
        if extra:  # said by the subcommand's parser, whose help lists what it takes
            parser.commands.get(getattr(args, "command", None) or "", parser).error(
                f"unrecognized arguments: {' '.join(extra)}")
        args._argv = [str(a) for a in argv] if argv is not None else sys.argv[1:]
        return int(args.func(args))
    except (UsageError, ValueError, FileNotFoundError, IsADirectoryError, NotADirectoryError, PermissionError,
            ImportError) as exc:
        print(f"hugger: error: {exc}", file=sys.stderr)
    except KeyboardInterrupt:
        print("hugger: interrupted", file=sys.stderr)
        return 130
    except OSError as exc:  # what the system refused (a full disk, ...), or the reader of our output left
        broken = isinstance(exc, BrokenPipeError)  # (hugger ... | head): not an error
        if not broken:
            with contextlib.suppress(OSError):
                print(f"hugger: error: {exc}", file=sys.stderr)
        with contextlib.suppress(OSError):
            sys.stdout = open(os.devnull, "w")  # (its buffer may hold what failed: not written again at exit)
        if broken:
            return EXIT_OK
    except Exception as exc:  # an internal error: keep the traceback for the report
        import traceback

        traceback.print_exc()
        print(f"hugger: internal error: {type(exc).__name__}: {exc} (please report it)", file=sys.stderr)
        return EXIT_INTERNAL
    return EXIT_BAD_INPUT


if __name__ == "__main__":
    sys.exit(main())
