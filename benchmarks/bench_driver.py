"""symvib's driver against scipy's solve_ivp (DOP853, rtol 1e-10) on the paper's scenes.

Run from the project folder (needs SciPy; numba for the compiled driver)::

    python benchmarks/bench_driver.py [--repeat 30]

For every paper scene with k = 1 and k = 0.8, one run measures:

* the wall time of ``simulate(scene, samples=False)`` (best of ``--repeat``,
  after a warm-up call that compiles it; the compile time is shown apart) on
  each available backend;
* the wall time of :func:`symvib.checks.peers.solve_ivp_events` with DOP853,
  ``rtol = 1e-10``, ``atol = 1e-12``, terminal events, branch fixed per segment,
  restarted at every event, on the same generated kernels (best of 3);
* both methods' largest event-time and event-position errors against the
  30-digit reference :func:`symvib.checks.reference.phase_reference`, and whether
  they found the reference's event sequence.

The ratio is solve_ivp's time over symvib's, measured in the same run.
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from symvib.checks.peers import event_errors, solve_ivp_events  # noqa: E402
from symvib.checks.reference import phase_reference  # noqa: E402
from symvib.numeric import driver  # noqa: E402
from symvib.numeric.scene import load_scene  # noqa: E402

SCENES = ("paper-parabola", "paper-cycloid", "paper-circle-3.8", "paper-circle-7")


def best_time(fn, repeat):
    best = math.inf
    out = None
    for _ in range(repeat):
        start = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - start)
    return best, out


def symvib_errors(result, ref):
    events = [(e.kind.value, e.t, e.q) for e in result.events]
    return event_errors(events, ref)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=30)
    ap.add_argument("--rtol", type=float, default=1e-10)
    args = ap.parse_args(argv)
    backends = [b for b in ("numba", "python") if driver.backend_available(b)]
    print(f"# symvib driver vs solve_ivp DOP853 rtol={args.rtol:g}; backends: {', '.join(backends)}")
    header = (f"{'scene':18s} {'k':>4s} {'events':>6s} {'backend':>7s} {'symvib':>10s} {'DOP853':>10s} "
              f"{'ratio':>7s} {'symvib dt err':>13s} {'DOP853 dt err':>13s} {'DOP853 seq':>10s}")
    print(header)
    totals = {b: 0.0 for b in backends}
    totals_default = {b: 0.0 for b in backends}  # simulate(scene) with its defaults (samples on first use)
    total_ivp = 0.0
    for name in SCENES:
        for k in (1.0, 0.8):
            scene = load_scene(ROOT / "symvib" / "scenes" / f"{name}.toml").replace(k=k)
            ref = phase_reference(scene)
            t_ivp, run = best_time(lambda: solve_ivp_events(scene, "DOP853", args.rtol, args.rtol * 1e-2), 3)
            same_ivp, dt_ivp, _ = event_errors(run.events, ref)
            total_ivp += t_ivp
            for b in backends:
                start = time.perf_counter()
                driver.simulate(scene, samples=False, backend=b)
                warm = time.perf_counter() - start
                t_sym, res = best_time(lambda: driver.simulate(scene, samples=False, backend=b), args.repeat)
                totals_default[b] += best_time(lambda: driver.simulate(scene, backend=b), args.repeat)[0]
                _, dt_sym, _ = symvib_errors(res, ref)
                totals[b] += t_sym
                print(f"{name:18s} {k:4.1f} {len(ref):6d} {b:>7s} {t_sym * 1e3:8.3f}ms {t_ivp * 1e3:8.2f}ms "
                      f"{t_ivp / t_sym:7.0f} {dt_sym:13.1e} {dt_ivp:13.1e} {str(same_ivp):>10s}"
                      + (f"   (first call {warm:.1f} s: compile)" if warm > 0.5 else ""))
    print()
    for b in backends:
        print(f"all 8 scenes, {b}: symvib {totals[b] * 1e3:.2f} ms, DOP853 {total_ivp * 1e3:.1f} ms, "
              f"ratio {total_ivp / totals[b]:.0f}")
        print(f"all 8 scenes, {b}: simulate(scene) with its defaults {totals_default[b] * 1e3:.2f} ms, "
              f"{totals_default[b] / totals[b]:.2f} times samples=False")


if __name__ == "__main__":
    main()
