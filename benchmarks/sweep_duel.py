"""Sweep throughput of two revisions, alternated sweep by sweep in two persistent processes on one core.

Usage, from the project folder::

    python benchmarks/sweep_duel.py BASE [HEAD] [--scenes 3000] [--rounds 50] [--cpu 1]

``compare_revisions.py`` starts a fresh process per revision and round, so each
figure carries the start-up, the compile cache and whatever else the shared
machine ran in those seconds; its rounds vary by 10-30 % here.  This script
starts one process per revision (a git worktree, as ``compare_revisions.py``
makes them; HEAD defaults to the working tree), each with its own numba cache,
compiles the paper parabola's sweep, takes ``--scenes`` scenes of the
benchmark's grid (``phidot0`` in ``[3, 12]``, ``mu`` in ``[0.01, 0.2]``, ``k =
0.8``, a fixed random subset of a 100 x 100 grid), and then asks the two
processes in turn for one sweep each (one thread, thread CPU time), ``--rounds``
times, both pinned to the core ``--cpu`` (``taskset``, where there is one).
Each pair of neighbouring sweeps saw about the same machine, so the median of
the per-pair ratios is steadier than a ratio of two medians.  It prints the
events (which must agree), each side's best and median time, and HEAD's
throughput relative to BASE: the median pair ratio and the ratio of the best
times.
"""
from __future__ import annotations

import argparse
import os
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from compare_revisions import ROOT, checkout

#: The benchmark's grid in a worker (``scene`` and ``driver`` loaded): the paper parabola's sweep
#: compiled, ``{scenes}`` scenes of a 100 x 100 grid of ``phidot0`` x ``mu`` (``k = 0.8``) picked at random
#: (seeded), and one small sweep to warm it.  ``bench_bindings.py`` uses it too.
GRID = """fn = driver.sweep_function(scene, "numba")
rows = np.array([driver.scene_row(scene.replace(qdot0=float(a), mu=float(b), k=0.8))
                 for a in np.linspace(3, 12, 100) for b in np.linspace(0.01, 0.2, 100)])
params = np.array([scene.param_values] * len(rows))
pick = np.random.default_rng(0).permutation(len(rows))[:{scenes}]
rows, params = rows[pick], params[pick]
fn(rows[:10], params[:10], 16, 0)
"""

#: The worker: that revision's symvib first on the path, the sweep compiled, then one sweep per line read.
WORKER = """
import sys, time
sys.meta_path[:] = [f for f in sys.meta_path if "editable" not in repr(f).lower()]
sys.path.insert(0, {folder!r})
import numpy as np, numba
numba.set_num_threads(1)
from symvib.numeric import driver
from symvib.numeric.scene import load_scene
assert driver.__file__.startswith({folder!r}), driver.__file__
scene = load_scene({folder!r} + "/symvib/scenes/paper-parabola.toml")
{grid}print("ready", flush=True)
for _ in sys.stdin:
    start = time.thread_time()
    out, _ = fn(rows, params, 16, 0)
    print(time.thread_time() - start, int(out[:, 1].sum()), flush=True)
"""


def start(folder: Path, scenes: int, cpu: str, caches: Path) -> subprocess.Popen:
    env = dict(os.environ, NUMBA_CACHE_DIR=str(caches / "numba"), SYMVIB_CACHE=str(caches / "kernels"))
    pin = ["taskset", "-c", cpu] if cpu and shutil.which("taskset") else []
    proc = subprocess.Popen([*pin, sys.executable, "-W", "ignore", "-c",
                             WORKER.format(folder=str(folder), scenes=scenes, grid=GRID.format(scenes=scenes))],
                            cwd=folder, env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    if proc.stdout.readline().strip() != "ready":
        raise SystemExit(f"{folder}: the worker did not start")
    return proc


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("base")
    ap.add_argument("head", nargs="?", default=None, help="a revision (default: the working tree)")
    ap.add_argument("--scenes", type=int, default=3000)
    ap.add_argument("--rounds", type=int, default=50)
    ap.add_argument("--cpu", default="1", help="the core both processes are pinned to ('' for none)")
    opts = ap.parse_args(argv)
    # Killed (SIGTERM), leave by the same `finally` as an error does: the worktrees are removed; and
    # forget the worktrees of a run killed harder (SIGKILL) whose folders are gone.
    signal.signal(signal.SIGTERM, lambda signum, frame: sys.exit(128 + signum))
    subprocess.run(["git", "-C", str(ROOT), "worktree", "prune"], check=False)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        folders = {"base": checkout(opts.base, tmp / "base")}
        folders["head"] = checkout(opts.head, tmp / "head") if opts.head else ROOT
        procs = {}
        try:
            for side, folder in folders.items():
                procs[side] = start(folder, opts.scenes, opts.cpu, tmp / f"cache-{side}")
            times = {side: [] for side in procs}
            events = {}
            for r in range(opts.rounds):
                for side in (("base", "head") if r % 2 == 0 else ("head", "base")):
                    procs[side].stdin.write("go\n")
                    procs[side].stdin.flush()
                    seconds, count = procs[side].stdout.readline().split()
                    times[side].append(float(seconds))
                    events[side] = int(count)
        finally:
            for proc in procs.values():
                proc.stdin.close()
                proc.wait()
            for folder in folders.values():
                if folder != ROOT:
                    subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(folder)],
                                   check=False)
    for side in times:
        print(f"{side}: {events[side]} events per sweep of {opts.scenes} scenes; best {min(times[side]):.4f} s, "
              f"median {statistics.median(times[side]):.4f} s")
    pairs = [b / h for b, h in zip(times["base"], times["head"])]
    print(f"head/base throughput: median of {len(pairs)} pair ratios {statistics.median(pairs):.3f}, "
          f"ratio of the best times {min(times['base']) / min(times['head']):.3f}")
    return 0 if events["base"] == events["head"] else 1


if __name__ == "__main__":
    sys.exit(main())
