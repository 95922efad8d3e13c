"""Cost of the driver's samples against the number of events: linear.

Run from the project folder (numba recommended)::

    python benchmarks/bench_samples.py [--max-events 32000]

For a frictionless, ideally elastic parabola scene bounded by ``max_events``
(1k, 2k, ... events), one run logs its intervals; then ``run_samples.samples_of``
(one pass of the engine, one stable sort) builds the samples from the log at the
default density.  The time per event should stay flat as the events double.
(The former quadratic code, ``nodes[index == i]`` per interval, took 10-100 times
longer at 16,000 events; it was removed with issue 16.)
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


from symvib.numeric import driver, run_samples  # noqa: E402
from symvib.numeric.engine import bind  # noqa: E402
from symvib.numeric.kernels import load  # noqa: E402
from symvib.numeric.scene import resolve_scene as _resolve_scene  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--max-events", type=int, default=32000)
    args = ap.parse_args(argv)
    base = _resolve_scene("paper-parabola").replace(mu=0.0, k=1.0, t_max=1e9)
    mod = load(base.shape)
    eng = bind(mod, driver.resolve_backend("auto"))
    R = driver.rules(driver.NODES)
    pieces = driver.sample_pieces(driver.SAMPLES_PER_INTERVAL, driver.NODES)
    cp = tuple(float(v) for v in base.param_values)
    print(f"{'events':>8} {'samples':>10} {'time [s]':>10} {'us/event':>10}")
    n = 1000
    while n <= args.max_events:
        sc = base.replace(max_events=n)
        row = driver.scene_row(sc)
        out = eng.simulate(cp, row, R, True)
        ni, ivs = out.n_intervals, out.intervals
        start = time.perf_counter()
        S = run_samples.samples_of(eng, cp, row, ivs, ni, R, sc, mod, pieces)
        elapsed = time.perf_counter() - start
        print(f"{n:>8} {len(S.t):>10} {elapsed:>10.3f} {1e6 * elapsed / n:>10.1f}")
        n *= 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
