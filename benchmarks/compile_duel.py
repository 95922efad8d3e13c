"""Compile time of the curve's engine at two revisions, alternated, each compile a fresh process on empty caches.

Usage, from the project folder::

    python benchmarks/compile_duel.py BASE [HEAD] [--rounds 3] [--entries simulate,sweep]

For each round and entry, one fresh process per revision (``sweep_duel.py``'s worktrees: BASE
checked out, HEAD the working tree by default), in turn (the order alternates by round), each
on new empty numba and kernel caches: bind the paper parabola's specialized engine and call
the entry once (``simulate``: what the tiered engine's child compiles; ``sweep``: a sweep of
one scene, what a first sweep compiles).  It reports each process's CPU time (its own, from
the bind to the end of the call) and wall time (the same span), the medians per revision and
entry, and the ratio head/base of the medians and the median of the per-round ratios.
Issue 28: the first 200,000-scene sweep within 10 s, the tiered loop within 20 s, both on
empty caches, where the compile is most of the wait.
"""
from __future__ import annotations

import argparse
import json
import os
import signal
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from compare_revisions import ROOT, checkout

#: One compile: that revision's symvib first on the path, the parabola's engine bound and its entry called once.
WORKER = """
import json, sys, time
sys.meta_path[:] = [f for f in sys.meta_path if "editable" not in repr(f).lower()]
sys.path.insert(0, {folder!r})
import numpy as np
import symvib
from symvib.numeric import driver
from symvib.numeric.engine.bind import bind
from symvib.prepare import prepare
assert driver.__file__.startswith({folder!r}), driver.__file__
scene = symvib.load_scene("paper-parabola")
mod = prepare(scene).kernels
cp, row, R = tuple(scene.param_values), driver.scene_row(scene), driver.rules(driver.NODES)
cpu, wall = time.process_time(), time.perf_counter()
engine = bind(mod, "numba")
if {entry!r} == "simulate":
    engine.simulate(cp, row, R, True)
else:
    engine.sweep(np.array([row]), np.array([cp]), R, 4)
print(json.dumps({{"cpu": time.process_time() - cpu, "wall": time.perf_counter() - wall}}))
"""


def compile_once(folder: Path, entry: str, caches: Path) -> dict:
    """CPU and wall seconds of one compile of ``entry`` at ``folder``, in a fresh process on empty caches."""
    env = {k: v for k, v in os.environ.items() if k not in ("SYMVIB_BACKEND", "SYMVIB_TIER")}
    env.update(NUMBA_CACHE_DIR=str(caches / "numba"), SYMVIB_CACHE=str(caches / "kernels"))
    done = subprocess.run([sys.executable, "-W", "ignore", "-c", WORKER.format(folder=str(folder), entry=entry)],
                          cwd=folder, env=env, capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"{folder}: the compile failed:\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("base")
    ap.add_argument("head", nargs="?", default=None, help="a revision (default: the working tree)")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--entries", default="simulate,sweep")
    opts = ap.parse_args(argv)
    # Killed (SIGTERM), leave by the same `finally` as an error does: the worktrees are removed; and
    # forget the worktrees of a run killed harder (SIGKILL) whose folders are gone.
    signal.signal(signal.SIGTERM, lambda signum, frame: sys.exit(128 + signum))
    subprocess.run(["git", "-C", str(ROOT), "worktree", "prune"], check=False)
    entries = [e for e in opts.entries.split(",") if e]
    results = {(side, e): [] for side in ("base", "head") for e in entries}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        folders = {"base": checkout(opts.base, tmp / "base")}
        folders["head"] = checkout(opts.head, tmp / "head") if opts.head else ROOT
        try:
            n = 0
            for r in range(opts.rounds):
                for entry in entries:
                    for side in (("base", "head") if r % 2 == 0 else ("head", "base")):
                        n += 1
                        out = compile_once(folders[side], entry, tmp / f"caches-{n}")
                        results[side, entry].append(out)
                        print(f"round {r + 1} {entry:8s} {side}: {out['cpu']:.1f} s CPU, {out['wall']:.1f} s wall "
                              f"(load {os.getloadavg()[0]:.1f})", flush=True)
        finally:
            for folder in folders.values():
                if folder != ROOT:
                    subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(folder)],
                                   check=False)
    for entry in entries:
        for what in ("cpu", "wall"):
            base = [x[what] for x in results["base", entry]]
            head = [x[what] for x in results["head", entry]]
            pairs = statistics.median(h / b for b, h in zip(base, head))
            print(f"{entry} {what}: base median {statistics.median(base):.1f} s, head median "
                  f"{statistics.median(head):.1f} s, head/base {statistics.median(head) / statistics.median(base):.3f} "
                  f"(median of the per-round ratios {pairs:.3f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
