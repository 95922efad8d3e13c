"""The ``symvib`` command line: one subcommand per job.

``symvib paper``          reproduce the paper: report, figures, errata (the main job)
``symvib derive SHAPE``   print the derivation of a catalogue shape (or of ``--z``/``--x``)
``symvib run SCENE.toml`` simulate a scene: event table, ``--json PATH``, ``--plot DIR``, ``--animate FILE``
``symvib generate``       write the kernel modules of the catalogue into generated/ (``--check``)
``symvib audit``          the paper's printed equations against the derivation (errata)
``symvib bench ...``      work-precision, stability, references (options: ``symvib bench --help``)
``symvib sweep ...``      parameter sweeps (options: ``symvib sweep --help``; :func:`sweep_main`)

Every error the user can cause (an unknown shape, a malformed expression, a
bad scene, a path that is a directory, a device or not writable) is reported
in one line naming the field or file, with exit status 2, never a traceback;
output paths are checked before any work is done.  Ctrl-C and SIGTERM end a job with
one line (exit status 130 and 143), after its child processes are stopped.
"""
from __future__ import annotations

import argparse
import dataclasses
import importlib
import logging
import math
import os
import sys

from symvib.shapes import CLOSED_FORMS

__all__ = ["main", "one_line", "build_parser", "build_bench_parser", "bench_main", "build_sweep_parser", "sweep_main"]

#: Exit status for bad input.
EXIT_BAD_INPUT = 2
#: Exit status of a run that ended with an error status (non_finite, energy_budget_mismatch).
EXIT_RUN_FAILED = 3
#: Exit status of ``symvib sweep`` when some scenes failed (their rows are written, with their
#: status): the status of ``symvib run`` for a failed run, one code for one meaning.
EXIT_FAILED_SCENES = EXIT_RUN_FAILED
#: Longest error message printed, in characters (a message may quote a long user text).
MAX_MESSAGE_LENGTH = 500


def one_line(message) -> str:
    """``message`` as one printable line of at most ``MAX_MESSAGE_LENGTH`` characters
    (control characters and line breaks escaped, the rest cut with ``...``)."""
    text = str(message)
    if not text.isprintable():
        text = "".join(ch if ch.isprintable() else repr(ch)[1:-1] for ch in text)
    if len(text) > MAX_MESSAGE_LENGTH:
        text = text[:MAX_MESSAGE_LENGTH - 3] + "..."
    return text


def _user_errors() -> tuple:
    """The exception classes a user's input can cause, reported as one line."""
    from symvib.numeric.kernels import KernelError

    return (ValueError, KeyError, OSError, KernelError, RecursionError, MemoryError)


#: Largest ``--budget`` of a derivation route, seconds (a day).
MAX_BUDGET_SECONDS = 86_400.0


def _budget(value, option: str = "--budget"):
    """``value`` (seconds per integration route) when it is a positive finite number (or None)."""
    import math

    if value is not None and not (math.isfinite(value) and 0.0 < value <= MAX_BUDGET_SECONDS):
        raise ValueError(f"{option}: must be a number of seconds in (0, {MAX_BUDGET_SECONDS:g}], got {value!r}")
    return value


def _refuse_corners(curve) -> None:
    """A curve with a corner (kink) has no derivation across it: one line naming the point (exit 2)."""
    from symvib.symbolic.branches import CurveError
    from symvib.symbolic.singular import corners

    found = corners(curve)
    if found:
        at, label = min(found, key=lambda c: abs(c[0]))  # the one nearest the origin
        raise CurveError(f"curve '{curve.name}': {curve.q} = {at:.6g} is a singular point ({label} jumps there: "
                         f"a corner), where eqs. 1-2 hold on each side but not across; derive each smooth piece "
                         f"(a run stops at the corner)" + (f"; {len(found) - 1} more corner(s)" if len(found) > 1
                                                           else ""))


def _cmd_derive(args) -> int:
    from symvib.shapes import shape
    from symvib.symbolic import curve as _curve
    from symvib.symbolic.derive import derive

    if args.z is not None:
        if args.x is not None:
            c = _curve.parametric(args.x, args.z, q=args.q or "q", name="user")
        else:
            c = _curve.graph(args.z, x=args.q or "x", name="user")
    elif args.shape:
        c = shape(args.shape).curve()
    else:
        raise ValueError("give a catalogue shape name, or --z (and --x) expressions")
    _budget(args.budget)
    _refuse_corners(c)
    d = derive(c, seconds=args.budget)
    if args.latex:
        for key, value in d.latex().items():
            print(f"{key}: {value}")
    else:
        print(f"curve {c.name}: x = {c.x}, z = {c.z}, q = {c.q}")
        print(f"  h = {c.h}, alpha = {c.alpha}, kappa = {c.kappa}")
        for s, br in d.branches.items():
            print(f"branch s = {s:+d}:")
            print(f"  eq. 1: {d.eom(s).lhs} = 0")
            print(f"  F_s  = {br.F.expr}    [route: {br.F.route}, verified: {br.F.verification}]")
            print(f"  eq. 2: {c.qdot}**2 = {br.qdot2}")
        check = d.check()
        print("back-substitution of eq. 2 into eq. 1:",
              ", ".join(f"s = {s:+d}: {how or 'FAILED'}" for s, how in check.items()))
    return 0


def _cmd_audit(args) -> int:
    from symvib.paper.audit import audit
    from symvib.paths import check_output_file

    if args.write:
        check_output_file(args.write, "--write file")
    verdicts = audit()
    if args.write:
        from symvib.paper.errata import write_errata

        print(f"wrote {write_errata(args.write, verdicts=verdicts)}")
    for v in verdicts:
        print(f"{v.shape:9s} {v.label:6s} {'matches' if v.matches else 'DIFFERS'}  {v.how}"
              + (f" ({v.origin})" if v.origin else ""))
    return 0


def _cmd_generate(args) -> int:
    from symvib.codegen import generate as codegen
    from symvib.numeric.kernels import generated_dir, module_name
    from symvib.paths import check_output_dir

    _budget(args.budget)
    if args.out:
        check_output_dir(args.out, "--out folder")
    if args.scene is not None:
        from symvib.numeric.scene import load_scene

        if not args.out:
            raise ValueError("--scene: the curve of a scene file is written where --out says")
        shape = load_scene(args.scene).shape
        path = codegen.generate(shape, args.out, name=module_name(shape.module), source=shape.source(),
                                seconds=args.budget)
        print(f"wrote {_inside(path, args.out)}")
        return 0
    if args.z is not None or args.x is not None:
        if args.z is None:
            raise ValueError("--x needs --z too (a parametric curve is x(q), z(q))")
        if not args.out:
            raise ValueError("a curve from expressions is written where --out says")
        from symvib.shapes import Shape

        kind = "parametric" if args.x is not None else "graph"
        user = Shape(name=args.name or "user", kind=kind, q=args.q or ("q" if args.x else "x"), z=args.z,
                     x=args.x)
        path = codegen.generate(user, args.out, name=module_name(user.module), source=user.source(),
                                seconds=args.budget)
        print(f"wrote {_inside(path, args.out)}")
        return 0
    out = args.out or generated_dir()
    if args.check:
        from symvib.codegen.jets import stale_jets

        problems = codegen.stale(out) + stale_jets(out, names=args.shapes or None)
        for line in problems:
            print(line)
        print("generated kernels are current" if not problems else f"{len(problems)} problem(s)")
        return 1 if problems else 0
    from symvib.codegen.jets import generate_jets_catalogue

    for path in codegen.generate_catalogue(out, names=args.shapes or None):
        print(f"wrote {path}")
    for path in generate_jets_catalogue(out, names=args.shapes or None):   # the sensitivities' jets
        print(f"wrote {path}")
    return 0


def _inside(path, folder):
    """``path``, after checking that it lies inside ``folder`` (what the user named)."""
    from symvib.paths import UserPathError, inside

    if not inside(path, folder):  # pragma: no cover - file names come from safe stems
        raise UserPathError(path, f"would be written outside {folder}")
    return path


def _cmd_fit(args) -> int:
    from pathlib import Path

    from symvib.api import fit
    from symvib.numeric.fit import read_observations
    from symvib.paths import UserPathError, check_output_file

    if args.plot:
        check_output_file(args.plot, "--plot file")
        if Path(args.plot).suffix.lower() != ".png":     # checked before the fit, not by Matplotlib after it
            raise UserPathError(args.plot, "the --plot file is a PNG figure: its name must end in .png")
        for given, what in ((args.data, "data"), (args.scene, "scene")):
            if Path(args.plot).resolve() == Path(given).resolve():
                raise UserPathError(args.plot, f"--plot would overwrite the {what} file")
    free = tuple(p.strip() for p in args.free.split(",") if p.strip())
    observed = read_observations(args.data)
    weights = None
    if args.sigma is not None:
        if not (math.isfinite(args.sigma) and args.sigma > 0):
            raise ValueError(f"--sigma: must be a positive number (s, or the samples' unit), got {args.sigma!r}")
        weights = [1 / args.sigma] * observed.count
    result = fit(args.scene, observed, free, weights=weights)
    print(result.summary())
    if args.plot:
        result.plot(args.plot)
        print(f"residual figure: {args.plot}")
    return 0 if result.status in ("converged", "no_error_estimate") else 1


def _cmd_run(args) -> int:
    from pathlib import Path

    from symvib.numeric.driver import ATOL, DEFAULT_WALL_TIME, RTOL, check_tolerances, check_wall_time, simulate
    from symvib.numeric.scene import load_scene
    from symvib.paths import UserPathError, check_output_dir, check_output_file

    # Every input and path first: no simulation is spent on a run whose output cannot be written.
    rtol, atol = check_tolerances(RTOL if args.rtol is None else args.rtol, ATOL if args.atol is None else args.atol)
    wall_time = check_wall_time(DEFAULT_WALL_TIME if args.wall_time is None else args.wall_time, "--wall-time")
    scene = load_scene(args.scene)
    if args.json:
        check_output_file(args.json, "--json file")
        if Path(args.json).resolve() == Path(args.scene).resolve():
            raise UserPathError(args.json, "--json would overwrite the scene file")
    if args.plot:
        check_output_dir(args.plot, "--plot folder")
    if args.animate:
        from symvib.numeric.animation import check_animation_path

        check_animation_path(args.animate, "--animate file")
        if Path(args.animate).resolve() == Path(args.scene).resolve():
            raise UserPathError(args.animate, "--animate would overwrite the scene file")
    changes = {}
    if args.restitution is not None:
        changes["k"] = args.restitution
    if args.t_max is not None:
        changes["t_max"] = args.t_max
    if args.max_events is not None:
        changes["max_events"] = args.max_events
    if args.closed_form is not None:
        if scene.shape.in_catalogue:
            raise ValueError(f"--closed-form: curve '{scene.shape.name}' is a catalogue shape, whose kernels are "
                             f"generated already; the option is for a curve given by expressions")
        changes["shape"] = dataclasses.replace(scene.shape, closed_form=args.closed_form)
    if changes:
        scene = scene.replace(**changes)
    from symvib.prepare import prepare

    result = simulate(scene, backend=args.backend, rtol=rtol, atol=atol, wall_time=wall_time,
                      prepared=prepare(scene))
    static = "" if scene.mu_s is None else f", mu_s = {scene.mu_s:.6g}"
    print(f"scene {scene.name}: {scene.shape.name}, mu = {scene.mu:.6g}{static}, k = {scene.k:g}, "
          f"limiters {scene.left} .. {scene.right}, {scene.shape.q}0 = {scene.q0:.6g}, "
          f"{scene.shape.q}dot0 = {scene.qdot0:.6g}")
    print(result.event_table(scene.shape.q))
    if args.json:
        from symvib import safeio

        with safeio.replacing_file(args.json, what="--json file") as fh:   # whole, never through a link
            fh.write((result.to_json(samples=args.samples) + "\n").encode("utf-8"))
        print(f"wrote {args.json}")
    if (args.plot or args.animate) and result.samples is None and result.error:
        print(f"symvib run: no figures: {result.error}", file=sys.stderr)
    if args.plot and result.samples is not None:  # a non_finite run has no samples to draw
        from symvib.numeric.figures import save_run_figures

        for path in save_run_figures(result, args.plot):
            print(f"wrote {path}")
    if args.animate and result.samples is not None:
        from symvib.numeric.animation import animate

        print(f"wrote {animate(result, args.animate)}")
    if not result.success:
        detail = f" ({result.stats['error']})" if result.stats.get("error") else ""
        print(f"symvib run: error: run failed with status {result.status.value}: {result.message}{detail}",
              file=sys.stderr)
        return EXIT_RUN_FAILED
    return 0


def _cmd_paper(args) -> int:
    from symvib.paper.report import main as paper_main
    from symvib.paths import check_output_dir

    check_output_dir(args.out, "--out folder")
    if not 0.0 <= args.restitution < 1.0:
        raise ValueError(f"--restitution: the k < 1 run needs 0 <= k < 1, got {args.restitution}")
    return paper_main(args.out, low_k=args.restitution, quiet=args.quiet, pdf=args.pdf)


class _BenchParser(argparse.ArgumentParser):
    """The parser of ``symvib bench``: its errors are one line (exit status 2), not a usage block."""

    def error(self, message):
        print(f"symvib bench: error: {message}", file=sys.stderr)
        raise SystemExit(EXIT_BAD_INPUT)


#: Default output folder of ``symvib bench`` (relative to the current directory).
BENCH_OUT = "symvib-bench"


def build_bench_parser() -> argparse.ArgumentParser:
    """The options of ``symvib bench`` (jobs in :mod:`symvib.checks.bench`)."""
    from symvib.checks.accuracy import ACCURACY_REFERENCE_NAME
    from symvib.checks.bench.paper_references import REFERENCE_NAME
    from symvib.checks.bench.scenes import RANDOM_SCENES
    from symvib.checks.bench.settings import PEER_BUDGET

    parser = _BenchParser(prog="symvib bench", description="work-precision charts and the stability suite")
    sub = parser.add_subparsers(dest="job", required=True)
    p = sub.add_parser("work-precision", help="error against CPU time on the paper scenes; wrong-sequence counts")
    p.add_argument("--out", default=BENCH_OUT, help=f"output folder (default: {BENCH_OUT})")
    p.add_argument("--quick", action="store_true", help="a small run (2 scenes, few settings, 20 random scenes)")
    p.add_argument("--random", type=int, default=None, help=f"random scenes (default {RANDOM_SCENES})")
    p.add_argument("--workers", type=int, default=1, help="processes for the random scenes (default 1)")
    p.add_argument("--budget", type=float, default=PEER_BUDGET, help="CPU seconds per peer run")
    p = sub.add_parser("stability", help="every method on every stability case, outcomes classified")
    p.add_argument("--out", default=BENCH_OUT, help=f"output folder (default: {BENCH_OUT})")
    p.add_argument("--quick", action="store_true", help="five of the cases")
    p.add_argument("--workers", type=int, default=1, help="processes (default 1)")
    p.add_argument("--budget", type=float, default=PEER_BUDGET, help="CPU seconds per peer run")
    p = sub.add_parser("reference", help="recompute the 30-digit time references of the paper scenes")
    p.add_argument("--write", action="store_true", help=f"store them in OUT/{REFERENCE_NAME}")
    p.add_argument("--out", default=BENCH_OUT,
                   help=f"folder of --write (default: {BENCH_OUT}; symvib/checks/data updates the shipped file)")
    p = sub.add_parser("accuracy-reference",
                       help="recompute the random scenes of the accuracy test and their references (minutes), "
                            "and compare them with the shipped ones")
    p.add_argument("--write", action="store_true", help=f"store them in OUT/{ACCURACY_REFERENCE_NAME}")
    p.add_argument("--out", default=BENCH_OUT,
                   help=f"folder of --write (default: {BENCH_OUT}; symvib/checks/data updates the shipped file)")
    p.add_argument("--workers", type=int, default=1, help="processes (default 1)")
    return parser


def bench_main(argv) -> int:
    """``symvib bench``: returns an exit status (2 for bad options)."""
    from pathlib import Path

    from symvib.checks.bench.paper_references import references
    from symvib.checks.bench.stability_job import stability
    from symvib.checks.bench.work_precision_job import work_precision
    from symvib.paths import check_output_dir

    try:
        args = build_bench_parser().parse_args(argv)
    except SystemExit as exc:
        return int(exc.code or 0)
    if getattr(args, "workers", 1) < 1 or getattr(args, "workers", 1) > os.cpu_count():
        print(f"symvib bench: error: --workers: must be between 1 and {os.cpu_count()}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if getattr(args, "budget", 1.0) <= 0 or (getattr(args, "random", None) or 0) < 0:
        print("symvib bench: error: --budget and --random must be positive", file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.job not in ("reference", "accuracy-reference") or args.write:
        check_output_dir(args.out, "--out folder")
    if args.job == "work-precision":
        work_precision(Path(args.out), quick=args.quick, n_random=args.random, workers=args.workers,
                       budget=args.budget)
    elif args.job == "stability":
        stability(Path(args.out), quick=args.quick, workers=args.workers, budget=args.budget)
    elif args.job == "accuracy-reference":
        from symvib.checks.accuracy import regenerate

        differs = regenerate(Path(args.out) if args.write else None, workers=args.workers)
        return 1 if differs and not args.write else 0
    else:
        references(Path(args.out) if args.write else None)
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="symvib", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("derive", help="derive eqs. 1-2 and the energies of a curve")
    p.add_argument("shape", nargs="?", help="catalogue shape name")
    p.add_argument("--z", help="z(q) (a graph in --q, default x, unless --x is given)")
    p.add_argument("--x", help="x(q) for a parametric curve")
    p.add_argument("--q", help="coordinate name")
    p.add_argument("--budget", type=float, default=10.0, help="seconds per integration route")
    p.add_argument("--latex", action="store_true", help="print LaTeX")
    p.set_defaults(func=_cmd_derive)

    p = sub.add_parser("paper", help="reproduce the paper: report, figures, errata (the main job)")
    p.add_argument("--out", default="symvib-paper", help="output folder (default: symvib-paper)")
    p.add_argument("--restitution", type=float, default=0.8, help="k of the run beside k = 1 (default 0.8)")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.add_argument("--pdf", action="store_true", help="also write report.pdf (text pages, then the figures)")
    p.set_defaults(func=_cmd_paper)

    p = sub.add_parser("run", help="simulate a scene file event by event")
    p.add_argument("scene", help="scene TOML file")
    p.add_argument("--json", metavar="PATH", help="write the result as JSON")
    p.add_argument("--samples", action="store_true", help="include the samples in the JSON")
    p.add_argument("--plot", metavar="DIR", help="write the phase portrait and energy figures (PNG)")
    p.add_argument("--animate", metavar="FILE", help="write an animation of the run: the particle on the curve "
                   "beside its phase portrait (.gif; .mp4 with ffmpeg)")
    p.add_argument("--restitution", type=float, help="override physics.restitution")
    p.add_argument("--t-max", type=float, help="override run.t_max")
    p.add_argument("--max-events", type=int, help="override run.max_events")
    p.add_argument("--rtol", type=float, default=None,
                   help="relative tolerance of every interval's time (default 1e-12; docs/physics.md, Accuracy)")
    p.add_argument("--atol", type=float, default=None, help="absolute tolerance of every interval's time, s "
                   "(default 0)")
    p.add_argument("--backend", default="auto", choices=("auto", "numba", "python"),
                   help="auto (default): the compiled engine where it is on disk, else plain Python; "
                        "numba: compile it on first use (seconds, once per curve: docs/benchmarks.md)")
    p.add_argument("--wall-time", type=float, default=None, metavar="SECONDS",
                   help="seconds the plain-Python engine may compute before the run ends with status "
                        "wall_time_limit (default 40; 0: no limit; the compiled engine has no limit)")
    p.add_argument("--closed-form", choices=CLOSED_FORMS, default=None,
                   help="override curve.closed_form of a curve given by expressions: how its F_sigma is found "
                        "when its kernels are first generated (auto: closed-form routes briefly, else numeric; "
                        "required: every route, fail without one; never: numeric at once)")
    p.set_defaults(func=_cmd_run)

    p = sub.add_parser("fit", help="fit mu, k, ... of a scene to measured event times or a sampled trajectory "
                                   "(CSV: t[, kind][, q], or t with q, x,z or s)")
    p.add_argument("scene", help="scene TOML file (its values of the free parameters are the start)")
    p.add_argument("data", help="CSV file with a header, its kind told by its columns: events (t in s, optional "
                                "kind, then optional q) or a sampled trajectory (t with q, or x,z, or s: the arc "
                                "length from the initial position, m; no kind column)")
    p.add_argument("--free", default="mu,k", help="parameters to fit, comma-separated (default mu,k; also "
                   "qdot0, q0, left, right, and the curve's parameters: p, or parameters.p)")
    p.add_argument("--sigma", type=float, default=None, help="standard deviation of each observation (s for "
                   "times, the coordinate's unit for samples; default: estimated from the residuals)")
    p.add_argument("--plot", metavar="PATH", help="write the residual figure (PNG)")
    p.set_defaults(func=_cmd_fit)

    p = sub.add_parser("generate", help="write the numeric kernel modules (generated/)")
    p.add_argument("shapes", nargs="*", help="catalogue shapes (default: all)")
    p.add_argument("--out", help="output folder (default: the project's generated/)")
    p.add_argument("--check", action="store_true", help="exit 1 when a module in the folder is stale")
    p.add_argument("--scene", help="a scene file whose curve to generate (with --out)")
    p.add_argument("--z", help="z(q) of a user curve (graph unless --x is given)")
    p.add_argument("--x", help="x(q) of a user curve")
    p.add_argument("--q", help="coordinate name of a user curve")
    p.add_argument("--name", help="name of a user curve")
    p.add_argument("--budget", type=float, default=None,
                   help="seconds per integration route for a user curve (default 10)")
    p.set_defaults(func=_cmd_generate)

    # Jobs with a parser of their own: listed here for the help, dispatched by main()
    # before parsing (argparse.REMAINDER drops a leading option).
    sub.add_parser("bench", help="work-precision charts and the stability suite", add_help=False)
    for name, (_, text) in FORWARDED.items():
        sub.add_parser(name, help=text, add_help=False)

    p = sub.add_parser("audit", help="compare the paper's printed equations with the derivation")
    p.add_argument("--write", metavar="PATH", help="write the errata document (docs/errata.md) to PATH")
    p.set_defaults(func=_cmd_audit)
    return parser


#: Jobs that parse their own options (with their parsers here): name -> (module:function taking
#: the words after the name, help).
FORWARDED = {
    "sweep": ("symvib.cli:sweep_main", "parameter sweeps over many scenes"),
}


# ----------------------------------------------------------------------------- symvib sweep

def _sweep_file(path) -> dict:
    """Read a sweep file as a scene file is read (:func:`symvib.paths.read_user_toml`:
    size cap, no device or folder, no TOML bomb), then check its keys."""
    from pathlib import Path

    from symvib.numeric.scene import SceneError
    from symvib.paths import read_user_toml

    data = read_user_toml(path, "sweep file")
    known = set(_SWEEP_FILE_TYPES)
    for key in data:
        if key not in known:
            raise SceneError(f"{path.name}:{key}", f"unknown key; known: {', '.join(sorted(known))}")
    _check_sweep_file(data, path)
    if "scene" in data:
        scene = Path(data["scene"])
        data["scene"] = str(scene if scene.is_absolute() or not (path.parent / scene).exists()
                            else path.parent / scene)
    if "out" in data:
        data["out"] = str(_out_of_sweep_file(data["out"], path))
    return data


def _out_of_sweep_file(text: str, path):
    """A sweep file's ``out``: a folder inside the sweep file's own folder (relative to it).

    Where results go elsewhere is the user's choice on the command line (``-o``), never
    the file's: an absolute path, ``..`` or a link leading out of the folder is refused.
    """
    from pathlib import Path

    from symvib.numeric.scene import SceneError
    from symvib.paths import inside

    folder = Path(path).parent
    out = Path(text)
    if out.is_absolute() or not inside(folder / out, folder) or Path(os.path.abspath(folder / out)) == \
            Path(os.path.abspath(folder)):
        raise SceneError(f"{Path(path).name}:out", f"{text!r} is not a folder inside the sweep file's folder "
                                                   f"{folder}; give -o OUT on the command line to write elsewhere")
    return folder / out


#: Types of the keys of a sweep file (``vary`` is a table; integers are checked by
#: :func:`symvib.numeric.sweep.make_spec`).
_SWEEP_FILE_TYPES = {"scene": str, "out": str, "vary": dict, "random": int, "seed": int, "chunk": int,
                     "log_events": int, "nodes": int, "format": str, "sensitivities": str}


def _check_sweep_file(data: dict, path) -> None:
    """Refuse keys of the wrong type in a sweep file, naming the file and key."""
    from symvib.numeric.scene import SceneError

    for key, kind in _SWEEP_FILE_TYPES.items():
        if key in data and (not isinstance(data[key], kind) or isinstance(data[key], bool)):
            raise SceneError(f"{path.name}:{key}", f"must be {'a table' if kind is dict else kind.__name__}, "
                                                   f"got {type(data[key]).__name__}")
    for key in ("scene", "out"):
        if key in data and (not data[key] or "\0" in data[key]):
            raise SceneError(f"{path.name}:{key}", "must be a non-empty path")


def _from_sweep_file(exc, conf: dict, args, given: set):
    """``exc`` with the sweep file's name before its field when the value it names came from the file
    (a ``[vary]`` key the command line did not give, or a key no option overrode), as
    :func:`_check_sweep_file` names it; else ``exc`` itself."""
    from symvib.numeric.scene import SceneError

    if not conf:
        return exc
    root, _, rest = exc.field.partition(".")
    from_file = (root == "vary" and rest in conf.get("vary", {}) and rest not in given) or (
        not rest and root in conf and getattr(args, root, None) is None)
    return SceneError(f"{args.file.name}:{exc.field}", exc.reason) if from_file else exc


def build_sweep_parser() -> argparse.ArgumentParser:
    """The options of ``symvib sweep`` (its own parser: :func:`main` forwards the words after ``sweep``)."""
    from pathlib import Path

    from symvib.numeric.sweep import DEFAULT_CHUNK

    ap = argparse.ArgumentParser(
        prog="symvib sweep", description="Run a parameter sweep over scenes of one curve.",
        epilog="example: symvib sweep paper-parabola --vary qdot=3:12:200 --vary mu=0.01:0.2:100 -o OUT --plot")
    ap.add_argument("scene", nargs="?", help="scene TOML file (or a packaged scene name, e.g. paper-parabola)")
    ap.add_argument("--file", type=Path, help="sweep file (TOML: scene, [vary], random, seed, chunk, log_events, out)")
    ap.add_argument("--vary", action="append", default=[], metavar="KEY=SPEC",
                    help="start:stop:count (grid), a,b,c (values) or start:stop (with --random)")
    ap.add_argument("--random", type=int, metavar="N", help="N random samples instead of a grid")
    ap.add_argument("--seed", type=int)
    ap.add_argument("--chunk", type=int, help=f"scenes per chunk (default {DEFAULT_CHUNK})")
    ap.add_argument("--log-events", type=int, metavar="L", help="keep the first L events of every scene")
    ap.add_argument("--nodes", type=int, help="Gauss-Legendre nodes per quadrature panel (default 16)")
    ap.add_argument("-o", "--out", help="output folder (resumed if it holds the same sweep)")
    ap.add_argument("--overwrite", action="store_true", help="replace a different sweep in the output folder")
    ap.add_argument("--format", choices=("npz", "zarr"), default=None,
                    help="chunk storage: npz files (default) or one Zarr store that xarray.open_zarr opens "
                         "(extra symvib[xarray])")
    ap.add_argument("--scheduler", metavar="ADDRESS", help="dask.distributed scheduler address (tcp://...)")
    ap.add_argument("--backend", default="auto", choices=("auto", "numba", "python"))
    ap.add_argument("--sensitivities", metavar="P,Q", help="add the exact derivatives of t_final, q_final, "
                    "friction_work, impact_loss with respect to these parameters (mu, k, qdot0, q0, left, right, or "
                    "the curve's: p or parameters.p) "
                    "as columns d_<column>_d_<parameter> and sensitivity_reason: each scene run again by the "
                    "single-scene driver, a slower path (docs/sweeps.md)")
    ap.add_argument("--plot", action="store_true", help="write maps over the first two varied fields")
    ap.add_argument("--quiet", action="store_true", help="no progress bar")
    return ap


def sweep_main(argv=None) -> int:
    """``symvib sweep``: returns the exit status (2 on bad input, :data:`EXIT_FAILED_SCENES` when
    some scenes failed)."""
    args = build_sweep_parser().parse_args(argv)
    try:
        return _cmd_sweep(args)
    except (ValueError, OSError) as exc:   # SceneError and SweepError are ValueErrors
        print(f"symvib sweep: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT


def _cmd_sweep(args) -> int:
    from pathlib import Path

    import numpy as np

    from symvib.numeric.layout import STATUSES
    from symvib.numeric.scene import SceneError, resolve_scene
    from symvib.numeric.sweep import DEFAULT_CHUNK, DEFAULT_NODES, sweep

    conf = _sweep_file(args.file) if args.file else {}
    scene_text = args.scene or conf.get("scene")
    if not scene_text:
        raise SceneError("scene", "give a scene file (or 'scene = ...' in the sweep file)")
    scene = resolve_scene(str(scene_text))
    vary = dict(conf.get("vary", {}))
    given = set()
    for item in args.vary:
        if "=" not in item:
            raise SceneError("--vary", f"expected KEY=SPEC, got {item!r}")
        key, value = item.split("=", 1)
        if key.strip() in given:
            raise SceneError(f"--vary {key.strip()}", "given twice; give each field once (a,b,c lists values)")
        given.add(key.strip())
        vary[key.strip()] = value.strip()
    out = args.out or conf.get("out")
    if not out:
        raise SceneError("--out", "give an output folder (-o OUT)")
    if args.plot and os.path.lexists(Path(out) / "maps"):
        from symvib import safeio

        safeio.check_root(Path(out) / "maps", "maps folder", create=False)   # before any work: not a link

    def pick(name, default):
        value = getattr(args, name)
        return value if value is not None else conf.get(name, default)

    from symvib.prepare import prepare

    try:
        res = sweep(scene, vary, prepared=prepare(scene), random=pick("random", None), seed=pick("seed", 0),
                    chunk=pick("chunk", DEFAULT_CHUNK), log_events=pick("log_events", 0),
                    nodes=pick("nodes", DEFAULT_NODES), out=out, overwrite=args.overwrite,
                    scheduler=args.scheduler, progress=not args.quiet, backend=args.backend,
                    storage=pick("format", "npz"), sensitivities=pick("sensitivities", ""))
    except SceneError as exc:
        raise _from_sweep_file(exc, conf, args, given) from None
    names = res.status_names()
    status = ", ".join(f"{s}: {int(np.sum(names == s))}" for s in STATUSES if np.any(names == s))
    events = int(np.sum(res["events"]))
    print(f"sweep of {res.count} scenes of {scene.name} into {out}: {len(res.computed)} chunk(s) computed, "
          f"{len(res.reused)} reused"
          + (f" ({len(res.discarded)} found truncated or foreign)" if res.discarded else ""))
    print(f"  status: {status}; {events} events; {np.mean(res['impacts']):.3g} impacts per scene on average")
    if "flights" in res.columns:   # a sweep of unilateral scenes (physics.md, "Flight and landing")
        flew = int(np.count_nonzero(res["flights"]))
        print(f"  flights: {int(np.sum(res['flights']))} in {flew} of {res.count} scenes; landings: "
              f"{int(np.sum(res['landings']))}; energy lost at landings: {float(np.nansum(res['landing_loss'])):.6g} J")
    if res.computed and res.seconds > 0:
        n = sum(len(res.spec.rows(i)[0]) for i in res.computed)
        print(f"  {n / res.seconds:,.0f} scenes/s over {res.seconds:.3g} s")
    if args.plot:
        from symvib.numeric.sweepmaps import sweep_maps

        for path in sweep_maps(res, Path(out) / "maps"):
            print(f"wrote {path}")
    failed = res.failed
    if failed.any():
        kinds = ", ".join(sorted(set(names[failed])))
        print(f"symvib sweep: error: {int(failed.sum())} of {res.count} scenes failed ({kinds}; first: row "
              f"{int(np.flatnonzero(failed)[0])}): their rows hold no result", file=sys.stderr)
        return EXIT_FAILED_SCENES
    return 0


def _one_line_warnings(command: str) -> None:
    """Show a cache-trust warning as one line (``symvib CMD: warning: ...``), not Python's two."""
    import warnings

    from symvib.cachetrust import CacheTrustWarning

    plain = getattr(warnings.formatwarning, "plain", warnings.formatwarning)
    prefix = f"symvib {command}" if command else "symvib"

    def fmt(message, category, filename, lineno, line=None):
        if issubclass(category, CacheTrustWarning):
            return f"{prefix}: warning: {one_line(message)}\n"
        return plain(message, category, filename, lineno, line)

    fmt.plain = plain
    warnings.formatwarning = fmt


def _progress_on_terminal(command: str, stream=None) -> None:
    """Show symvib's progress lines (``logging`` INFO of the ``symvib`` loggers: a new curve's
    derivation) on ``stream`` (stderr) when it is a terminal; piped or captured output gets none,
    so an error stays one line."""
    stream = sys.stderr if stream is None else stream
    logger = logging.getLogger("symvib")
    if not getattr(stream, "isatty", lambda: False)() or any(getattr(h, "symvib_progress", False)
                                                             for h in logger.handlers):
        return
    handler = logging.StreamHandler(stream)
    handler.setFormatter(logging.Formatter(f"symvib {command}: %(message)s" if command else "symvib: %(message)s"))
    handler.symvib_progress = True
    logger.addHandler(handler)
    logger.setLevel(logging.INFO)


def main(argv=None) -> int:
    """Entry point of the ``symvib`` command."""
    argv = sys.argv[1:] if argv is None else list(argv)
    _one_line_warnings(argv[0] if argv and argv[0].isidentifier() else "")
    if argv and argv[0] == "bench":
        command = "bench"
        run = lambda: bench_main(argv[1:])  # noqa: E731
    elif argv and argv[0] in FORWARDED:
        command = argv[0]
        module, function = FORWARDED[command][0].split(":")
        run = lambda: getattr(importlib.import_module(module), function)(argv[1:])  # noqa: E731
    else:
        args = build_parser().parse_args(argv)
        command = args.command
        run = lambda: args.func(args)  # noqa: E731
    import signal

    from symvib.children import Terminated, exit_code, terminate_as_exception

    def ended_by(signum):
        # Child processes were killed when the signal arrived, and the finally blocks on the way
        # here stopped the rest (symvib.children).
        print(f"symvib {command}: {'interrupted' if signum == signal.SIGINT else 'terminated'}", file=sys.stderr)
        return exit_code(signum)

    _progress_on_terminal(command)
    state = None
    try:
        with terminate_as_exception(f"symvib {command}") as state:
            outcome = run()
    except KeyboardInterrupt:
        return ended_by(signal.SIGINT)
    except Terminated:
        return ended_by(signal.SIGTERM)
    except BaseException as exc:
        if state is not None and state.signum is not None:
            # The signal's exception was lost on its way (raised inside a C extension's import it
            # became an ImportError; killed workers broke a pool): the signal is what happened.
            return ended_by(state.signum)
        if not isinstance(exc, _user_errors()):
            raise
        message = exc.args[0] if isinstance(exc, KeyError) and exc.args else exc
        if isinstance(exc, (RecursionError, MemoryError)):
            message = f"input too large or too deeply nested ({type(exc).__name__})"
        elif isinstance(exc, OSError) and not str(exc):
            message = type(exc).__name__
        print(f"symvib {command}: error: {one_line(message)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if state.signum is not None:  # the signal's exception was swallowed: the command did not finish
        return ended_by(state.signum)
    return outcome


def run() -> None:
    """The installed ``symvib`` command: :func:`main`, then :func:`leave` with its exit status.

    ``main`` returns normally, for callers in Python (the tests call it); the command
    itself skips the interpreter's teardown (:func:`leave`).
    """
    leave(main())


def leave(status) -> None:
    """End the process with ``status`` once the command has returned, without tearing the
    interpreter down.

    By the time a command returns, its files are written and closed and its child
    processes stopped (:mod:`symvib.children`); what CPython's teardown does after that is
    free every object one by one, numba's dispatchers and LLVM's modules among them:
    0.15-0.2 s of CPU, 0.2-0.3 s of wall time here, a third of a small sweep's start-up
    (docs/benchmarks.md, "Start-up").  So the exit handlers run (logging's, those of
    the libraries), both streams are flushed, and ``os._exit`` ends the process, as
    pyperformance's ``--exit`` does to time start-up alone.  A stream that cannot be
    flushed (a reader that closed the pipe) turns a success into status 1.
    """
    import atexit

    code = 0 if status is None else status if isinstance(status, int) else 1
    atexit._run_exitfuncs()  # what CPython itself calls at shutdown (a private name of atexit)
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            code = code or 1
    os._exit(code)


if __name__ == "__main__":  # pragma: no cover
    leave(main())
