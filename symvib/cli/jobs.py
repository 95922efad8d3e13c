"""The ``symvib`` command line: one subcommand per job.

``symvib paper``          reproduce the paper: report, figures, errata (the main job)
``symvib derive SHAPE``   print the derivation of a catalogue shape (or of ``--z``/``--x``)
``symvib run SCENE.toml`` simulate a scene: event table, ``--json PATH``, ``--plot DIR``, ``--animate FILE``
``symvib generate``       write the kernel modules of the catalogue into generated/ (``--check``)
``symvib audit``          the paper's printed equations against the derivation (errata)
``symvib bench ...``      work-precision, stability, references (options: ``symvib bench --help``)
``symvib sweep ...``      parameter sweeps (options: ``symvib sweep --help``; :func:`symvib.cli.sweep.sweep_main`)

Every error the user can cause (an unknown shape, a malformed expression, a
bad scene, a path that is a directory, a device or not writable) is reported
in one line naming the field or file, with exit status 2, never a traceback;
output paths are checked before any work is done.  Ctrl-C and SIGTERM end a job with
one line (exit status 130 and 143), after its child processes are stopped.
"""
from __future__ import annotations

import argparse
import dataclasses
import math
import sys

from symvib.cli.common import EXIT_RUN_FAILED
from symvib.shapes import CLOSED_FORMS

__all__ = ["build_parser", "FORWARDED", "MAX_BUDGET_SECONDS"]


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


#: Jobs that parse their own options (each with its parser in its module): name -> (module:function
#: taking the words after the name, help).
FORWARDED = {
    "sweep": ("symvib.cli.sweep:sweep_main", "parameter sweeps over many scenes"),
}
