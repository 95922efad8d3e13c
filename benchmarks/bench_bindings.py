"""The two compiled bindings, measured: compile CPU time for N corpus curves, and the sweep's speed.

Usage, from the project folder (needs numba; expensive: the specialized binding compiles
the whole engine once per curve, a few minutes of CPU each)::

    python benchmarks/bench_bindings.py [--curves 10] [--params 2] [--scenes 3000] [--rounds 5]

:func:`symvib.numeric.engine.bind.bind` compiles the engine on numba in two ways
(docs/design.md, "Two compiled bindings"): **specialized** (the default) once per curve, its
kernels inlined as compile-time constants; **shared** (``shared=True``) once per number of curve
parameters, the kernels as first-class functions in one structure, so a new curve costs its
kernels only.  This script

1. generates (once, into ``--kernels``, by default a temporary folder) the kernels of the first
   ``--curves`` entries of the corpus (:mod:`symvib.checks.corpus`) with ``--params`` parameters,
   as ``tests/test_corpus.py`` does (an entry tagged ``numeric`` with its numeric ``F_sigma`` at
   once);
2. for each binding, in a fresh process with an empty numba cache, runs each curve's corpus
   scene once on numba and reports the CPU time (``time.process_time``, compile and run; the
   run itself is milliseconds) per curve and in total;
3. for each binding, in a fresh process, compiles the paper parabola's sweep and times
   ``--rounds`` sweeps of ``--scenes`` scenes of the benchmark grid (``phidot0`` in ``[3, 12]``,
   ``mu`` in ``[0.01, 0.2]``, ``k = 0.8``; one thread, thread CPU time), and prints the
   specialized binding's throughput relative to the shared one's (ratio of the medians).

Compile times depend on the machine and on its load: run it on an idle machine, and write
the date, the machine and the load next to the figures (docs/benchmarks.md).
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from sweep_duel import GRID  # the benchmark's grid, written once

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

#: A child process: run each corpus scene once on numba with one binding, print CPU seconds per curve.
COMPILE_WORKER = """
import functools, json, sys, time, warnings
warnings.simplefilter("ignore")
sys.path.insert(0, {root!r})
from symvib.checks.corpus import entry
from symvib.numeric import backends, driver
from symvib.numeric.engine.bind import bind
from symvib.numeric.scene import scene_from_dict
from symvib.prepare import prepare
backends.bind = functools.partial(bind, shared={shared!r})
out = {{}}
for name in {names!r}:
    scene = scene_from_dict(entry(name).scene())
    prepare(scene)
    start = time.process_time()
    result = driver.simulate(scene, backend="numba", samples=False)
    out[name] = [time.process_time() - start, result.status.value, len(result.events)]
print(json.dumps(out))
"""

#: A child process: the paper parabola's sweep with one binding, timed over rounds.
SWEEP_WORKER = """
import functools, json, sys, time, warnings
warnings.simplefilter("ignore")
sys.path.insert(0, {root!r})
import numba, numpy as np
numba.set_num_threads(1)
from symvib.numeric import backends, driver
from symvib.numeric.engine.bind import bind
from symvib.numeric.scene import load_scene
backends.bind = functools.partial(bind, shared={shared!r})
scene = load_scene({root!r} + "/symvib/scenes/paper-parabola.toml")
{grid}times, events = [], 0
for _ in range({rounds}):
    start = time.thread_time()
    out, _ = fn(rows, params, 16, 0)
    times.append(time.thread_time() - start)
    events = int(out[:, 1].sum())
print(json.dumps({{"times": times, "events": events}}))
"""


def corpus_names(count: int, params: int) -> list:
    """The first ``count`` corpus entries with ``params`` parameters."""
    from symvib.checks.corpus import CORPUS

    return [e.name for e in CORPUS if len(e.parameters) == params][:count]


def generate(names: list, kernels: Path) -> None:
    """The entries' kernels generated into the kernel cache ``kernels`` as ``tests/test_corpus.py``
    generates them (an entry tagged ``numeric`` with the numeric ``F_sigma`` at once), and their
    singular points prepared."""
    env = dict(os.environ, SYMVIB_CACHE=str(kernels))
    code = f"""
import sys, warnings
warnings.simplefilter("ignore")
sys.path.insert(0, {str(ROOT)!r})
from symvib import provenance
from symvib.checks.corpus import entry
from symvib.codegen import generate as codegen
from symvib.numeric import kernels
from symvib.numeric.scene import scene_from_dict
from symvib.prepare import prepare
from symvib.symbolic.integrals import ROUTE_SECONDS, ROUTES
ROUTES_OF = {{"secant-sqrt": ("tangent-angle",), "tilted-parabola": ("tangent-angle",)}}  # as tests/test_corpus.py
for name in {names!r}:
    e = entry(name)
    scene = scene_from_dict(e.scene())
    source = scene.shape.source()
    stem = f"{{kernels.module_name(scene.shape.module)}}_{{provenance.input_hash(source)[:16]}}"
    if not (kernels.cache_dir() / f"{{stem}}.py").exists():
        codegen.generate(scene.shape, kernels.cache_dir(), name=stem, source=source,
                         routes=() if "numeric" in e.tags else ROUTES_OF.get(name, ROUTES),
                         seconds=2 * ROUTE_SECONDS)
    prepare(scene)
"""
    subprocess.run([sys.executable, "-c", code], env=env, check=True)


def child(code: str, kernels: Path, numba_cache: Path) -> dict:
    env = dict(os.environ, SYMVIB_CACHE=str(kernels), NUMBA_CACHE_DIR=str(numba_cache))
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise SystemExit(done.stderr[-3000:])
    return json.loads(done.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--curves", type=int, default=10, help="corpus curves to compile (default 10)")
    ap.add_argument("--params", type=int, default=2, help="their number of curve parameters (default 2)")
    ap.add_argument("--scenes", type=int, default=3000, help="scenes per sweep (default 3000)")
    ap.add_argument("--rounds", type=int, default=5, help="sweeps timed per binding (default 5)")
    ap.add_argument("--kernels", type=Path, default=None, help="kernel cache to generate into and reuse")
    ap.add_argument("--skip-compile", action="store_true", help="only the sweep's speed")
    opts = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        kernels = opts.kernels or tmp / "kernels"
        print(f"{time.strftime('%Y-%m-%d %H:%M', time.gmtime())} UTC, load {os.getloadavg()[0]:.2f}, "
              f"{os.cpu_count()} cores")
        if not opts.skip_compile:
            names = corpus_names(opts.curves, opts.params)
            print(f"{len(names)} corpus curves with {opts.params} parameters: {', '.join(names)}")
            start = time.monotonic()
            generate(names, kernels)
            print(f"kernels generated in {time.monotonic() - start:.0f} s")
            totals = {}
            for shared in (True, False):
                label = "shared" if shared else "specialized"
                out = child(COMPILE_WORKER.format(root=str(ROOT), shared=shared, names=names), kernels,
                            tmp / f"numba-compile-{label}")
                totals[label] = sum(v[0] for v in out.values())
                for name, (seconds, status, events) in out.items():
                    print(f"  {label:11s} {name:28s} {seconds:8.1f} s CPU  ({status}, {events} events)")
                print(f"{label}: {totals[label]:.0f} s CPU for {len(out)} curves (load now "
                      f"{os.getloadavg()[0]:.2f})")
            print(f"compile CPU, specialized / shared: {totals['specialized'] / totals['shared']:.2f}")
        medians = {}
        for shared in (True, False):
            label = "shared" if shared else "specialized"
            out = child(SWEEP_WORKER.format(root=str(ROOT), shared=shared, scenes=opts.scenes, rounds=opts.rounds,
                                     grid=GRID.format(scenes=opts.scenes)),
                        kernels, tmp / f"numba-sweep-{label}")
            medians[label] = statistics.median(out["times"])
            print(f"sweep {label}: {out['events']} events, median {medians[label]:.4f} s, "
                  f"{opts.scenes / medians[label]:,.0f} scenes/s")
        print(f"sweep throughput, specialized / shared: {medians['shared'] / medians['specialized']:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
