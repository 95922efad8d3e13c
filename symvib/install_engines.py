"""The build step that compiles the paper curves' engines into the package (``setup.py`` runs it).

``python -m symvib.install_engines FOLDER [CURVE ...]`` compiles, for each curve (a catalogue
shape; default :data:`PAPER_SCENES`' curves), the specialized engine's entries that a user's
first runs and sweeps take (:data:`ENTRIES`) and their kernels, into ``FOLDER`` (the package's
``symvib/_installed/`` in the build folder), each curve in a process of its own, at most
:data:`JOBS` at a time.  How they are found and checked at run time:
:mod:`symvib.numeric.engine.installed`.  The build step must never fail an install:
``setup.py`` runs this in a child process, and on any failure warns and ships no engines.

``python -m symvib.install_engines --one FOLDER CURVE`` is one curve's child.
"""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

__all__ = ["PAPER_SCENES", "ENTRIES", "JOBS", "paper_curves", "compile_curve", "main"]

#: The packaged scenes whose curves get an engine compiled at install time.
PAPER_SCENES = ("paper-parabola", "paper-cycloid", "paper-circle-3.8", "paper-circle-7")
#: The entries compiled: a run, its samples, a sweep.
ENTRIES = ("simulate_bound", "sample_bound", "sweep_bound")
#: Curves compiled at once (each compile is one core for about 20-40 s).
JOBS = 2


def _paper_scenes() -> dict:
    """The first scene of :data:`PAPER_SCENES` of each of their catalogue shapes, by shape name, in order."""
    import symvib

    out = {}
    for name in PAPER_SCENES:
        scene = symvib.load_scene(name)
        out.setdefault(scene.shape.name, scene)
    return out


def paper_curves() -> list:
    """The catalogue shapes of :data:`PAPER_SCENES`, each once, in order."""
    return list(_paper_scenes())


def _scene_of(curve: str):
    """A packaged paper scene of ``curve``."""
    scenes = _paper_scenes()
    if curve not in scenes:
        raise SystemExit(f"install_engines: no paper scene of curve {curve!r} (one of {list(scenes)})")
    return scenes[curve]


def compile_curve(folder: Path, curve: str) -> None:
    """Compile ``curve``'s engine entries into ``folder`` (in this process) and write its record."""
    import symvib
    from symvib.numeric.engine import installed
    from symvib.numeric.kernels import load

    installed.building(folder)
    scene = _scene_of(curve)
    result = symvib.simulate(scene, backend="numba")
    result.samples   # noqa: B018 - the sample entry compiles at the first read
    symvib.sweep(scene, {"qdot0": [scene.qdot0, scene.qdot0 * 0.9]}, backend="numba")
    installed.write_record(load(scene.shape), ENTRIES)


def main(argv=None) -> int:
    """The command: compile ``FOLDER [CURVE ...]`` (each curve a child), or ``--one FOLDER CURVE``;
    the exit code is 1 when a curve failed."""
    args = list(sys.argv[1:] if argv is None else argv)
    if args[:1] == ["--one"]:
        compile_curve(Path(args[1]), args[2])
        return 0
    if not args:
        raise SystemExit(__doc__)
    folder = Path(args[0])
    curves = args[1:] or paper_curves()
    folder.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, SYMVIB_TIER="off")
    env.pop("SYMVIB_BACKEND", None)
    failed = []
    pending = list(curves)
    running = []
    while pending or running:
        while pending and len(running) < JOBS:
            curve = pending.pop(0)
            running.append((curve, subprocess.Popen([sys.executable, "-m", "symvib.install_engines", "--one",
                                                     str(folder), curve], env=env)))
        curve, child = running.pop(0)
        if child.wait() != 0:
            failed.append(curve)
    if failed:
        print(f"install_engines: no engine for {', '.join(failed)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
