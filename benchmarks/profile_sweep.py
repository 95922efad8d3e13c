"""Where a sweep's time goes: samples of the compiled loop by function, with Linux ``perf``.

Run from the project folder (needs numba and ``perf``; ``-e cpu-clock`` works
on machines without hardware counters)::

    python benchmarks/profile_sweep.py [--seconds 5] [--threads 1]

The script compiles the parabola's engine afresh (into a temporary numba
cache, so that the compiled functions' addresses are known), writes them to
``/tmp/perf-<pid>.map`` (the file ``perf`` reads to name code it cannot find in
a binary), runs the benchmark sweep of ``bench_sweep.py`` (``phidot0`` in
``[3, 12]``, ``mu`` in ``[0.01, 0.2]``, ``k = 0.8``) over and over while
``perf record`` samples this process, and prints ``perf report``'s share of
the samples per function: the core's functions (``quad``, ``map_extend``,
``root_G``, ...) and the C library's (``__tan_fma``, ``__cos_fma``, ...).

``--callers`` samples the call stacks too (``perf record --call-graph dwarf``): under each
function above 2 %, the compiled function that called it (the C library's functions unwind
one frame into the compiled code, which is as far as ``perf`` can follow it) and the C library's
own inlined parts (``libc_feholdsetround_sse_ctx``: the rounding-mode guard every ``sin``,
``cos``, ``sincos`` and ``tan`` of glibc 2.36 enters with).
"""
from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def perf_map(dispatchers, path):
    """Write the addresses of every function compiled for ``dispatchers`` (name -> numba dispatcher)."""
    entries = set()
    for dispatcher in dispatchers.values():
        for cres in getattr(dispatcher, "overloads", {}).values():
            library = cres.library
            for fn in library._final_module.functions:  # numba internals: fine for a diagnostic
                if fn.is_declaration:
                    continue
                address = library.get_pointer_to_function(fn.name)
                if address:
                    entries.add((address, _short(fn.name)))
    rows = sorted(entries)
    with open(path, "w") as fh:
        for (address, name), following in zip(rows, rows[1:] + [(rows[-1][0] + 4096, "")]):
            fh.write(f"{address:x} {max(min(following[0] - address, 1 << 16), 16):x} {name}\n")
    return len(rows)


def _short(mangled):
    """``module.function`` from a numba-mangled name (``_ZN<len><part>...``)."""
    if not mangled.startswith("_ZN"):
        return mangled
    parts, i = [], 3
    while i < len(mangled) and mangled[i].isdigit():
        j = i
        while mangled[j].isdigit():
            j += 1
        size = int(mangled[i:j])
        parts.append(mangled[j:j + size])
        i = j + size
    return parts[-1] if parts else mangled


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=5.0, help="sampling time")
    ap.add_argument("--threads", type=int, default=1, help="numba threads")
    ap.add_argument("--callers", action="store_true", help="who calls each function (call stacks; slower)")
    args = ap.parse_args(argv)
    if shutil.which("perf") is None:
        sys.exit("profile_sweep: needs Linux perf (Debian: apt-get install linux-perf)")
    os.environ["NUMBA_CACHE_DIR"] = tempfile.mkdtemp(prefix="symvib-profile-")
    import numba

    from symvib.numeric import driver
    from symvib.numeric.kernels import load
    from symvib.numeric.scene import load_scene
    from symvib.numeric.sweep import sweep

    numba.set_num_threads(args.threads)
    base = load_scene(ROOT / "symvib" / "scenes" / "paper-parabola.toml").replace(k=0.8, mu=0.05)
    vary = {"qdot": "3:12:200", "mu": "0.01:0.2:100"}
    result = sweep(base, vary, backend="numba", progress=False)  # compiles the engine
    # The curve's engine as compiled for it (symvib.numeric.engine.bind._specialized_engine).
    count = perf_map(load(base.shape)._symvib_specialized_engine, f"/tmp/perf-{os.getpid()}.map")
    events = int(result["events"].sum())
    print(f"# {count} compiled functions mapped; {result.count} scenes, {events} events per sweep, "
          f"{args.threads} thread(s), {driver.NODES} nodes")
    data = Path(tempfile.mkdtemp(prefix="symvib-perf-")) / "perf.data"
    done = threading.Event()
    sweeps = [0, 0.0]

    def work():
        while not done.is_set():
            start = time.perf_counter()
            sweep(base, vary, backend="numba", progress=False)
            sweeps[0] += 1
            sweeps[1] += time.perf_counter() - start

    worker = threading.Thread(target=work)
    worker.start()
    stacks = ["-F", "1000", "--call-graph", "dwarf,4096"] if args.callers else ["-F", "2000"]
    try:
        subprocess.run(["perf", "record", "-q", "-e", "cpu-clock", *stacks, "-p", str(os.getpid()),
                        "-o", str(data), "--", "sleep", str(args.seconds)], check=True)
    finally:
        done.set()
        worker.join()
    if sweeps[0]:
        per_event = sweeps[1] / sweeps[0] / events * 1e6
        print(f"# {sweeps[0]} sweeps while sampling: {per_event:.2f} microseconds per event and sweep")
    graph = ["-G", "--percent-limit", "2"] if args.callers else ["-g", "none", "--percent-limit", "0.5"]
    report = subprocess.run(["perf", "report", "-i", str(data), "--no-children", "--sort", "sym", *graph, "--stdio"],
                            capture_output=True, text=True, check=True)
    for line in report.stdout.splitlines():
        if "%" in line and not line.startswith("#"):
            print(line.rstrip()[:100])


if __name__ == "__main__":
    main()
