"""The ``symvib sweep`` command: its parser, its sweep file and :func:`sweep_main`
(the sweep itself is :func:`symvib.numeric.sweep.sweep`)."""
from __future__ import annotations

import argparse
import os
import sys

from symvib.cli.common import EXIT_BAD_INPUT, EXIT_FAILED_SCENES

__all__ = ["build_sweep_parser", "sweep_main"]


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
    """The options of ``symvib sweep`` (its own parser: :func:`symvib.cli.command.main` forwards the words
    after ``sweep``)."""
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
