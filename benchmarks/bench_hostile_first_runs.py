"""The hostile scenes of the trust issue as a new user meets them: empty caches, fresh processes.

Run from the project folder, in the environment to measure::

    python benchmarks/bench_hostile_first_runs.py [--bound 60]

Each scene (a curve that oscillates a million times, a vertical tangent, a tower of
exponentials, a pole at the end of the declared domain, huge initial speeds, a
frictionless elastic run to ``t_max = 1e6``) runs as ``symvib run`` in a new process with
its own empty kernel and numba caches, derivation included; ``symvib derive`` of the
oscillating curves too.  The report gives, per command, the wall time, the exit code,
the status line and the number of lines on stderr, and whether it ended within
``--bound`` seconds with at most one line on stderr (the trust issue's promise: a result
or a one-line error within 60 s, no traceback).
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

PHYSICS = "[physics]\nmu = {mu}\nrestitution = {k}\n[initial]\nq = {q}\nqdot = {qdot}\n[run]\nt_max = {t_max}\n"
PARABOLA = '[curve]\nshape = "parabola"\n[parameters]\np = 1.0\n[limiters]\nleft = "-pi/6"\nright = "pi/4"\n'
#: name -> (curve text, physics and start).
SCENES = {
    "oscillating, 1e-6 m": ('[curve]\nz = "1e-6*cos(x/1e-6)"\n[limiters]\nleft = -1e-5\nright = 1e-5\n',
                            dict(mu=0.1, k=0.8, q=0.0, qdot=0.01, t_max=5)),
    "oscillating, 1e6 x": ('[curve]\nz = "cos(1000000*x)/1000000"\n', dict(mu=0.1, k=0.8, q=0.0, qdot=0.01, t_max=5)),
    "vertical tangent": ('[curve]\nz = "sqrt(x)"\n', dict(mu=0.1, k=0.8, q=0.5, qdot=1.0, t_max=20)),
    "tower of exp": ('[curve]\nz = "exp(exp(exp(exp(x))))"\n', dict(mu=0.1, k=0.8, q=-3.0, qdot=1.0, t_max=20)),
    "pole at the domain's end": ('[curve]\nz = "x**2 + 1/(x - 0.3)"\ndomain = [-1, 0.3]\n',
                                 dict(mu=0.1, k=0.8, q=0.0, qdot=1.0, t_max=20)),
    "qdot0 = 1e6": (PARABOLA, dict(mu=0.1, k=0.8, q=0.0, qdot=1e6, t_max=20)),
    "qdot0 = 1e154": (PARABOLA, dict(mu=0.1, k=0.8, q=0.0, qdot=1e154, t_max=20)),
    "mu = 0, k = 1, t_max = 1e6": (PARABOLA, dict(mu=0.0, k=1.0, q=0.0, qdot=7.0, t_max=1e6)),
}
DERIVE = ("cos(1000000*x)/1000000", "1e-6*cos(x/1e-6)")


def timed(command, folder: Path) -> tuple:
    """``(seconds, exit code, stdout, stderr)`` of ``command`` in a new process with empty caches."""
    env = dict(os.environ, SYMVIB_CACHE=str(folder / "kernels"), NUMBA_CACHE_DIR=str(folder / "numba"))
    start = time.perf_counter()
    out = subprocess.run(command, capture_output=True, text=True, env=env)
    return time.perf_counter() - start, out.returncode, out.stdout, out.stderr


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bound", type=float, default=60.0, help="seconds a command may take (default 60)")
    args = ap.parse_args(argv)
    symvib = [sys.executable, "-m", "symvib.cli"]
    print(f"{'command':34s} {'s':>6s} exit stderr  status")
    within = True
    with tempfile.TemporaryDirectory() as tmp:
        jobs = []
        for i, (name, (curve, values)) in enumerate(SCENES.items()):
            path = Path(tmp) / f"scene{i}.toml"
            path.write_text(curve + PHYSICS.format(**values))
            jobs.append((f"run: {name}", [*symvib, "run", str(path)]))
        jobs += [(f"derive: {z}", [*symvib, "derive", "--z", z]) for z in DERIVE]
        for i, (name, command) in enumerate(jobs):
            seconds, code, out, err = timed(command, Path(tmp) / f"caches{i}")
            status = next((line.split(" (")[0] for line in out.splitlines() if line.startswith("status:")), "")
            if name.startswith("derive"):
                status = next((line for line in out.splitlines() if line.startswith("back-substitution")), "")
            lines = len(err.strip().splitlines())
            ok = seconds <= args.bound and lines <= 1
            within &= ok
            print(f"{name:34s} {seconds:6.1f} {code:4d} {lines:6d}  {status[:70]}{'' if ok else '  <- NOT within'}")
    print(f"every command within {args.bound:g} s with at most one line on stderr: {'yes' if within else 'NO'}")
    return 0 if within else 1


if __name__ == "__main__":
    sys.exit(main())
