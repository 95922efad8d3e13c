"""The tiered engine, measured: a loop of default ``simulate`` calls in a fresh process on empty caches.

Run from the project folder, in the environment to measure (the main install, numba included)::

    python benchmarks/bench_tiered.py [--n 100000] [--plain-prefix 2000]

Issue 28's target: 100,000 default ``symvib.simulate(scene)`` calls of ``paper-parabola`` with
varied ``qdot0``, in a fresh process on empty caches, within 20 s wall.  Three fresh processes,
one after the other, each timed from its start to its exit (start-up included):

1. **tiered**: empty caches (``$SYMVIB_CACHE`` and ``$NUMBA_CACHE_DIR`` new temporary
   folders), ``--n`` calls; reports the wall time, the call at which the compiled engine took
   over (``Result.stats["backend"]``), when, and the compile child's CPU time (the process's
   reaped children, ``RUSAGE_CHILDREN``);
2. **plain only**: ``$SYMVIB_TIER=off`` and ``$SYMVIB_INSTALLED_ENGINES=off``, the first
   ``--plain-prefix`` calls of the same sequence, on new empty caches; the plain-only time of
   ``--n`` calls is **extrapolated** from that prefix (its per-call time times ``--n``;
   measured outright when the prefix is ``--n``), since 100,000 plain calls take minutes;
3. **cached**: ``--n`` calls again with the caches of (1), whose numba cache now holds the
   parabola's compiled engine: every call takes it from the first.

Each process runs in a temporary folder, so that it imports the installed package, not the
checkout (engines compiled at install time ship only in an installed package); the JSON names the
``symvib`` it imported.  ``SYMVIB_INSTALLED_ENGINES=off python benchmarks/bench_tiered.py`` measures
without the installed engines.

``--compile`` measures instead what the compile child costs, each in a fresh process on empty
caches: the CPU time of binding the parabola's engine and running it once, for the specialized
binding's ``simulate`` entry (what the child compiles), the shared binding's ``simulate`` entry
alone (its other entries skipped) and the shared binding whole.

``qdot0`` runs through ``[5, 9]`` rad/s along the golden-ratio sequence, so any prefix of the
calls samples the whole range (a faster start bounces more, and costs more).  Each process
prints one JSON line; this script prints them and a summary.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: Issue 28's target for 100,000 calls on empty caches, seconds of wall time.
TARGET_SECONDS = 20.0

#: The loop: ``n`` default ``symvib.simulate`` calls; one JSON line of what happened.
WORKER = """
import json, math, resource, sys, time
t0 = time.perf_counter()
import symvib
n = int(sys.argv[1])
scene = symvib.load_scene("paper-parabola")
GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0
first, t_first, events = None, None, 0
for i in range(n):
    result = symvib.simulate(scene.replace(qdot0=5.0 + 4.0 * ((i * GOLDEN) % 1.0)))
    events += len(result.events)
    if first is None and result.stats["backend"] == "numba":
        first, t_first = i, time.perf_counter() - t0
loop = time.perf_counter() - t0
child = resource.getrusage(resource.RUSAGE_CHILDREN)
print(json.dumps({"n": n, "seconds_in_process": loop, "symvib": symvib.__file__, "first_compiled_call": first,
                  "compiled_from_second": t_first, "events": events,
                  "child_cpu": child.ru_utime + child.ru_stime}))
"""


#: One compile on empty caches: bind the parabola's engine (``shared``), run it once; CPU seconds as JSON.
COMPILE = """
import json, sys, time
import symvib
from symvib.numeric import driver
from symvib.numeric.engine.bind import bind
from symvib.prepare import prepare
shared, simulate_only = sys.argv[1] == "shared", sys.argv[2] == "simulate"
if shared and simulate_only:   # the shared binding's sample and sweep entries are not compiled
    from numba.core.dispatcher import Dispatcher
    compile_ = Dispatcher.compile
    def compile_some(self, sig):
        if self.py_func.__name__ in ("sample_scene", "sweep_block"):
            return None
        return compile_(self, sig)
    Dispatcher.compile = compile_some
    disable_ = Dispatcher.disable_compile
    Dispatcher.disable_compile = lambda self, val=True: disable_(self, val) if self.signatures else None
scene = symvib.load_scene("paper-parabola")
mod = prepare(scene).kernels
start = time.process_time()
engine = bind(mod, "numba", shared=shared)
engine.simulate(tuple(scene.param_values), driver.scene_row(scene), driver.rules(driver.NODES), True)
print(json.dumps({"cpu": time.process_time() - start}))
"""


def compile_cpu(binding: str, entries: str, caches: Path) -> float:
    """CPU seconds of one compile (:data:`COMPILE`) in a fresh process on the empty caches under ``caches``."""
    environ = {k: v for k, v in os.environ.items() if k not in ("SYMVIB_BACKEND", "SYMVIB_TIER")}
    environ.update(SYMVIB_CACHE=str(caches / "kernels"), NUMBA_CACHE_DIR=str(caches / "numba"))
    done = subprocess.run([sys.executable, "-c", COMPILE, binding, entries], env=environ, cwd=caches.parent,
                          capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])["cpu"]


def run(n: int, caches: Path, **env) -> dict:
    """One fresh process of :data:`WORKER` on the caches under ``caches``; its JSON and its wall time."""
    environ = {k: v for k, v in os.environ.items() if k not in ("SYMVIB_BACKEND", "SYMVIB_TIER")}
    environ.update(SYMVIB_CACHE=str(caches / "kernels"), NUMBA_CACHE_DIR=str(caches / "numba"), **env)
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", WORKER, str(n)], env=environ, cwd=caches.parent, capture_output=True,
                          text=True, check=True)
    wall = time.perf_counter() - start
    out = json.loads(done.stdout.strip().splitlines()[-1])
    out["wall"] = wall
    return out


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=100_000, help="simulate calls per loop (default 100,000)")
    parser.add_argument("--plain-prefix", type=int, default=2000,
                        help="plain-only calls measured; the plain time of --n calls is extrapolated from them")
    parser.add_argument("--compile", action="store_true",
                        help="measure the compile CPU of each binding on empty caches instead")
    args = parser.parse_args(argv)
    print(f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, load {os.getloadavg()[0]:.1f}, "
          f"{os.cpu_count()} cores", flush=True)
    if args.compile:
        for binding, entries in (("specialized", "simulate"), ("shared", "simulate"), ("shared", "all")):
            with tempfile.TemporaryDirectory(prefix="bench-tiered-") as tmp:
                cpu = compile_cpu(binding, entries, Path(tmp))
            print(f"  {binding} binding, {entries} entries: {cpu:.1f} s of CPU (load {os.getloadavg()[0]:.1f})",
                  flush=True)
        return
    with tempfile.TemporaryDirectory(prefix="bench-tiered-") as tmp:
        tiered = run(args.n, Path(tmp) / "tiered")
        print("tiered, empty caches:", json.dumps(tiered), flush=True)
        prefix = min(args.plain_prefix, args.n)
        plain = run(prefix, Path(tmp) / "plain", SYMVIB_TIER="off", SYMVIB_INSTALLED_ENGINES="off")
        print("plain only (SYMVIB_TIER=off, SYMVIB_INSTALLED_ENGINES=off):", json.dumps(plain), flush=True)
        cached = run(args.n, Path(tmp) / "tiered")
        print("cached engine, second process:", json.dumps(cached), flush=True)
    per_call = plain["seconds_in_process"] / prefix
    how = "measured" if prefix == args.n else f"extrapolated from {prefix:,} calls"
    print(f"\n{args.n:,} calls of paper-parabola, varied qdot0 (wall, start-up included):")
    print(f"  tiered, empty caches: {tiered['wall']:.1f} s (target {TARGET_SECONDS:g} s for 100,000); compiled "
          f"from call {tiered['first_compiled_call']} at {tiered['compiled_from_second'] or float('nan'):.1f} s; "
          f"compile child {tiered['child_cpu']:.1f} s CPU")
    print(f"  plain only: {per_call * 1e3:.2f} ms a call, {per_call * args.n:.1f} s for {args.n:,} ({how}); "
          f"ratio plain/tiered {per_call * args.n / tiered['wall']:.1f}")
    print(f"  compiled engine cached: {cached['wall']:.1f} s (compiled from call {cached['first_compiled_call']})")


if __name__ == "__main__":
    main()
