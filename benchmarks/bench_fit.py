"""Cost of a fit against the forward runs it needs (issue 26's target: 4 free parameters from 20
impact times under 1 s on the compiled engine, at most 3 times the cost of its forward runs).

Run from the project folder::

    python benchmarks/bench_fit.py [--repeat 3] [--backend numba] [--sweep N]

The truth: the paper parabola with ``mu = 0.01``, ``k = 0.95`` (at least 20 impacts); the data:
its first 20 impact times with 1 ms of Gaussian noise (``--seed``, 26 by default); the start 10-20 % off in
``mu``, ``k``, ``qdot0`` and the right limiter.  The fit runs with a counting wrapper around
the forward run, so one process reports, per repetition: the fit's wall time, the number of
forward runs and their own time, the time in the exact sensitivities (and how many), a Jacobian's
cost in forward runs (which does not depend on how many trials the path takes), and the ratio of
the fit's time to its forward runs' time.

``--sweep N`` measures instead the opt-in sensitivity columns of a sweep
(:mod:`symvib.numeric.sweep.sensitivity_columns`): the same sweep of ``N`` scenes of the
paper parabola (``qdot0`` from 6 to 8 rad/s, ``k = 0.8``) with and without
``sensitivities=("mu", "k")``, in one process, and reports the cost per scene of each and
their ratio (median of ``--repeat``).
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
import warnings

import numpy as np


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--backend", default="numba", choices=("numba", "python"))
    ap.add_argument("--sweep", type=int, default=0, metavar="N", help="measure a sweep of N scenes with and "
                    "without sensitivity columns instead of a fit")
    ap.add_argument("--seed", type=int, default=26, help="the noise's seed (26: the benchmark's data)")
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    if args.sweep:
        return sweep_columns(args.sweep, args.repeat, args.backend)
    import symvib
    from symvib.numeric import fit as fitmod
    from symvib.numeric import sensitivity
    from symvib.numeric.driver import simulate

    truth = symvib.load_scene("paper-parabola").replace(mu=0.01, k=0.95)
    # compile (numba) outside the timing: the engine, and the sensitivities' compiled quadratures
    sensitivity.sensitivities(simulate(truth, backend=args.backend, samples=False), ("mu",))
    impacts = [e.t for e in simulate(truth, backend=args.backend, samples=False).events
               if e.kind.value == "impact"][:20]
    assert len(impacts) == 20, len(impacts)
    rng = np.random.default_rng(args.seed)
    observed = fitmod.observed_events(np.array(impacts) + rng.normal(0, 1e-3, 20), kinds=["impact"] * 20)
    start = truth.replace(mu=0.012, k=0.9, qdot0=7.5, right=0.75)
    free = ("mu", "k", "qdot0", "right")
    rows = []
    for _ in range(args.repeat):
        spent = {"runs": 0, "run_s": 0.0, "sens_s": 0.0, "jacobians": 0}

        def run(scene):
            t0 = time.perf_counter()
            out = simulate(scene, backend=args.backend, samples=False)
            spent["run_s"] += time.perf_counter() - t0
            spent["runs"] += 1
            return out

        original = fitmod.sensitivities

        def timed_sensitivities(*a, **k):
            t0 = time.perf_counter()
            out = original(*a, **k)
            spent["sens_s"] += time.perf_counter() - t0
            spent["jacobians"] += 1
            return out

        fitmod.sensitivities = timed_sensitivities
        try:
            t0 = time.perf_counter()
            result = fitmod.fit(start, observed, free, run=run, weights=np.full(20, 1e3))
            wall = time.perf_counter() - t0
        finally:
            fitmod.sensitivities = original
        rows.append((wall, spent["runs"], spent["run_s"], spent["sens_s"], result, spent["jacobians"]))
    wall = statistics.median(r[0] for r in rows)
    runs = rows[0][1]
    run_s = statistics.median(r[2] for r in rows)
    sens_s = statistics.median(r[3] for r in rows)
    result = rows[0][4]
    print(f"# fit of {', '.join(free)} to 20 impact times (noise seed {args.seed}), backend {args.backend}, "
          f"median of {args.repeat}")
    print(f"status {result.status}; " + ", ".join(f"{k} = {v:.6g} +- {result.stderr[k]:.2g}"
                                                for k, v in result.estimates.items()))
    print(f"fit wall time              {wall:8.3f} s   (target < 1 s)")
    print(f"forward runs               {runs:8d}     {run_s:8.3f} s")
    jacobians = rows[0][5]
    print(f"exact sensitivities        {sens_s:8.3f} s   ({jacobians} Jacobians, {sensitivity.__name__})")
    per_run = (sens_s / jacobians) / (run_s / runs)
    print(f"a Jacobian / a forward run {per_run:8.2f}     (independent of the path's length)")
    print(f"fit / forward runs         {wall / run_s:8.2f}     (target <= 3)")
    return 0


def sweep_columns(n: int, repeat: int, backend: str) -> int:
    """Per-scene cost of a sweep with and without ``sensitivities=("mu", "k")``, and their ratio."""
    from symvib.numeric.scene import resolve_scene
    from symvib.numeric.sweep import sweep

    base = resolve_scene("paper-parabola").replace(k=0.8)
    vary = {"qdot": f"6:8:{n}"}
    sweep(base, {"qdot": "6:8:2"}, backend=backend, sensitivities=("mu",))     # compile outside the timing
    times = {False: [], True: []}
    for _ in range(repeat):
        for with_columns in (False, True):
            t0 = time.perf_counter()
            sweep(base, vary, backend=backend, sensitivities=("mu", "k") if with_columns else ())
            times[with_columns].append(time.perf_counter() - t0)
    plain, columns = (statistics.median(times[k]) for k in (False, True))
    print(f"# sweep of {n} scenes of the paper parabola (k = 0.8), backend {backend}, median of {repeat}")
    print(f"without sensitivities      {plain / n * 1e3:8.3f} ms per scene")
    print(f"with d/d(mu, k) columns    {columns / n * 1e3:8.3f} ms per scene")
    print(f"ratio                      {columns / plain:8.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
