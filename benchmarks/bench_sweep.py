"""Sweep throughput and accuracy against a loop of solve_ivp, measured in one run.

Run from the project folder (needs numba for the compiled sweep, SciPy for the peer)::

    python benchmarks/bench_sweep.py [--qdot 400] [--mu 250] [--sample 24] [--repeat 3]

The sweep: the paper's parabola (``p = 1``, limiters at ``-pi/6`` and
``pi/4``, ``alpha0`` replaced by ``mu``) with ``phidot0`` on a grid over
``[3, 12]`` rad/s and ``mu`` over ``[0.01, 0.2]``, ``k = 0.8``, every scene run
to arrest.  The script reports

* symvib's sweep (:func:`symvib.numeric.sweep.sweep`, in memory and into chunk files),
  scenes per second and events per second, best of ``--repeat`` after a warm-up
  call that compiles it (compile time shown apart), on all threads numba uses
  and on one;
* a loop of :func:`symvib.checks.peers.solve_ivp_events` (DOP853, ``rtol = 1e-10``,
  ``atol = 1e-12``) over a random subsample of ``--sample`` scenes of the grid;
* on that subsample, both methods' event sequences and largest event-time
  error against the 30-digit reference :func:`symvib.checks.reference.phase_reference`
  (mpmath; it does not share the driver's code path);
* the anchor: a hand-written kernel of this one curve in closed forms
  (``benchmarks/parabola_anchor.py``), on one thread over the same grid, with the
  ratio of symvib's one-thread speed to it, and its agreement with symvib (event and
  impact counts of every scene, final times).

The ratio is the sweep's scenes per second over the solve_ivp loop's.
"""
from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))  # parabola_anchor

from symvib.checks.peers import solve_ivp_events  # noqa: E402
from symvib.checks.reference import phase_reference  # noqa: E402
from symvib.numeric import driver  # noqa: E402
from symvib.numeric.scene import load_scene  # noqa: E402
from symvib.numeric.sweep import sweep  # noqa: E402

QDOT = (3.0, 12.0)
MU = (0.01, 0.2)
K = 0.8
RTOL = 1e-10


def run_sweep(base, args, **kw):
    return sweep(base, {"qdot": f"{QDOT[0]}:{QDOT[1]}:{args.qdot}", "mu": f"{MU[0]}:{MU[1]}:{args.mu}"},
                 chunk=args.chunk, backend=args.backend, **kw)


def best(fn, repeat):
    best_t, out = math.inf, None
    for _ in range(repeat):
        start = time.perf_counter()
        out = fn()
        best_t = min(best_t, time.perf_counter() - start)
    return best_t, out


def anchor(base, res, n, t_one, repeat):
    """The hand-written parabola kernel on the same grid, one thread, beside symvib's one-thread time."""
    import parabola_anchor

    qdot0, mu = np.asarray(res["initial.qdot"], float), np.asarray(res["physics.mu"], float)
    args = (qdot0, mu, base.k, base.left, base.right, base.g, dict(base.params)["p"], base.q0, base.max_events)
    start = time.perf_counter()
    parabola_anchor.sweep(*args)
    compile_s = time.perf_counter() - start
    t_anchor, out = best(lambda: parabola_anchor.sweep(*args), repeat)
    same = np.array_equal(out[:, 1], res["events"]) and np.array_equal(out[:, 2], res["impacts"])
    rel = np.abs(out[:, 3] - res["t_final"]) / res["t_final"]
    print(f"hand-written parabola kernel:  {n / t_anchor:12,.0f} scenes/s {out[:, 1].sum() / t_anchor:14,.0f} events/s "
          f"({t_anchor:.3f} s, one thread; compiled in {compile_s:.1f} s)")
    print(f"symvib one thread / hand-written kernel: {t_anchor / t_one:.2f} (scenes/s ratio); event and impact counts "
          f"{'identical' if same else 'DIFFER'} on all {n} scenes; final times: median relative difference "
          f"{np.median(rel):.1e}, max {rel.max():.1e}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--qdot", type=int, default=400, help="grid points in phidot0")
    ap.add_argument("--mu", type=int, default=250, help="grid points in mu")
    ap.add_argument("--sample", type=int, default=24, help="scenes checked against the reference and solve_ivp")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--chunk", type=int, default=25_000)
    ap.add_argument("--backend", default="numba" if driver.backend_available("numba") else "python")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args(argv)
    base = load_scene(ROOT / "symvib" / "scenes" / "paper-parabola.toml").replace(k=K, mu=0.05)
    n = args.qdot * args.mu
    print(f"# sweep of the paper parabola: {args.qdot} x {args.mu} = {n} scenes, phidot0 in {QDOT}, mu in {MU}, "
          f"k = {K}, to arrest; backend {args.backend}; {os.cpu_count()} cores")

    start = time.perf_counter()
    run_sweep(base, args)
    print(f"first call (compiles the engine, or loads it from the cache): {time.perf_counter() - start:.1f} s")
    t_mem, res = best(lambda: run_sweep(base, args), args.repeat)
    events = int(res["events"].sum())
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        run_sweep(base, args, out=Path(tmp) / "sweep")
        t_disk = time.perf_counter() - start
    t_one = None
    if args.backend == "numba":
        import numba

        threads = numba.get_num_threads()
        numba.set_num_threads(1)
        t_one, _ = best(lambda: run_sweep(base, args), args.repeat)
        numba.set_num_threads(threads)
    statuses = {s: int(np.sum(res.status_names() == s)) for s in set(res.status_names())}
    print(f"events: {events} ({events / n:.2f} per scene, {int(res['impacts'].sum())} impacts); status {statuses}")
    print(f"symvib sweep, in memory:       {n / t_mem:12,.0f} scenes/s {events / t_mem:14,.0f} events/s "
          f"({t_mem:.3f} s)")
    print(f"symvib sweep, chunks on disk:  {n / t_disk:12,.0f} scenes/s {events / t_disk:14,.0f} events/s "
          f"({t_disk:.3f} s, one run)")
    if t_one is not None:
        print(f"symvib sweep, one thread:      {n / t_one:12,.0f} scenes/s {events / t_one:14,.0f} events/s "
              f"({t_one:.3f} s)")

    if t_one is not None:
        anchor(base, res, n, t_one, args.repeat)
    if args.sample <= 0:
        return
    rng = np.random.default_rng(args.seed)
    rows = np.sort(rng.choice(n, size=min(args.sample, n), replace=False))
    t_ivp = 0.0
    ivp_events = 0
    worst = {"symvib": 0.0, "DOP853": 0.0}
    wrong = {"symvib": 0, "DOP853": 0}
    for row in rows:
        scene = base.replace(qdot0=float(res["initial.qdot"][row]), mu=float(res["physics.mu"][row]))
        ref = phase_reference(scene)
        kinds = [r.kind.value if hasattr(r.kind, "value") else r.kind for r in ref]
        start = time.perf_counter()
        run = solve_ivp_events(scene, "DOP853", RTOL, RTOL * 1e-2)
        t_ivp += time.perf_counter() - start
        ivp_events += len(run.events)
        one = driver.simulate(scene, samples=False, backend=args.backend)
        # the sweep's own row: its events are the driver's (tests/test_sweep.py checks that to 1e-12)
        got = {"symvib": [(e.kind.value, e.t, e.q) for e in one.events], "DOP853": list(run.events)}
        if int(res["events"][row]) != len(one.events):
            wrong["symvib"] += 1
        for name, evs in got.items():
            if [e[0] for e in evs] != kinds:
                wrong[name] += 1
                continue
            err = max((abs(e[1] - float(r.t)) for e, r in zip(evs, ref)), default=0.0)
            worst[name] = max(worst[name], err)
    m = len(rows)
    print(f"solve_ivp DOP853 rtol {RTOL:g} loop: {m / t_ivp:12,.1f} scenes/s {ivp_events / t_ivp:14,.0f} events/s "
          f"({m} scenes, {t_ivp:.2f} s)")
    print(f"ratio (scenes/s, sweep in memory over the solve_ivp loop): {(n / t_mem) / (m / t_ivp):,.0f}")
    print(f"against the 30-digit mpmath reference on {m} random scenes of the grid:")
    for name in ("symvib", "DOP853"):
        print(f"  {name:7s} wrong event sequences {wrong[name]:3d}, max event-time error {worst[name]:.1e} s")


if __name__ == "__main__":
    main()
