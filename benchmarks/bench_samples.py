"""Cost of the driver's samples against the number of events: linear (now) vs quadratic (before).

Run from the project folder (numba recommended)::

    python benchmarks/bench_samples.py [--max-events 32000] [--skip-old-above 16000]

For a frictionless, ideally elastic parabola scene bounded by ``max_events``
(1k, 2k, ... events), one run logs its intervals; then both
``driver._samples`` (one stable sort, blocks placed by offsets) and the former
``driver._samples_quadratic`` (``nodes[index == i]`` per interval) build the
samples from the same log.  Both results are checked to be bitwise identical,
and the ratio old / new is measured in the same run.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


from symvib.numeric import driver  # noqa: E402
from symvib.numeric.engine import bind  # noqa: E402
from symvib.numeric.kernels import load  # noqa: E402
from symvib.numeric.scene import resolve_scene as _resolve_scene  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--max-events", type=int, default=32000)
    ap.add_argument("--skip-old-above", type=int, default=32000, help="do not time the old code beyond this")
    args = ap.parse_args(argv)
    base = _resolve_scene("paper-parabola").replace(mu=0.0, k=1.0, t_max=1e9)
    mod = load(base.shape)
    eng = bind(mod, driver.resolve_backend("auto"))
    R = driver.rules(driver.NODES)
    cp = tuple(float(v) for v in base.param_values)
    print(f"{'events':>8} {'new [s]':>10} {'old [s]':>10} {'old/new':>8}")
    n = 1000
    while n <= args.max_events:
        sc = base.replace(max_events=n)
        row = driver.scene_row(sc)
        out = eng.simulate(cp, row, R, True)
        ni, ivs = out.n_intervals, out.intervals
        start = time.perf_counter()
        new = driver._samples(eng, cp, row, ivs, ni, R, sc, mod)
        t_new = time.perf_counter() - start
        if n <= args.skip_old_above:
            start = time.perf_counter()
            old = driver._samples_quadratic(eng, cp, row, ivs, ni, R, sc, mod)
            t_old = time.perf_counter() - start
            for name in new.__dataclass_fields__:
                if getattr(new, name).tobytes() != getattr(old, name).tobytes():
                    raise SystemExit(f"samples differ in {name} at {n} events")
            print(f"{n:>8} {t_new:>10.3f} {t_old:>10.3f} {t_old / t_new:>8.1f}")
        else:
            print(f"{n:>8} {t_new:>10.3f} {'-':>10} {'-':>8}")
        n *= 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
