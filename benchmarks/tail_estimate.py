"""How honest is a panel's error estimate?  The engine's own estimator on 4000 test integrands.

Run from the project folder::

    python benchmarks/tail_estimate.py [--count 4000] [--seed 1]

The time quadrature (``symvib/numeric/engine/timing.py``) estimates the error of each
Gauss-Legendre panel from the four highest Legendre coefficients of its integrand
(:func:`symvib.numeric.engine.timing.tail_error`), trusting their extrapolated decay where
the nearest zero of ``G`` explains it (:func:`~symvib.numeric.engine.timing.zero_ratio`)
and taking half the decay elsewhere.  This script draws integrands on ``[-1, 1]`` of the
three shapes that matter, with exact integrals (mpmath):

* ``1/sqrt(e + (x - c)^2)``: a near-stop, ``G`` with a complex zero pair ``c +- i sqrt(e)``;
* ``1/sqrt(|x - x0|)``, ``x0`` outside the panel: a turning point beyond its end;
* ``1/(1 + a (x - c)^2)``: a pole of the curve's kernels off the real axis, where ``G`` is
  no help;

and reports, for the 12-node rule (panels off a root) and the cautious 16-node one
(panels from a root), how many estimates fell below a tolerance while the true error
was above it, the worst such ratio, and how many were above it while the error was 100
times below (wasted refinements).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import mpmath
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from symvib.numeric.driver import tail_rows
from symvib.numeric.engine.timing import tail_error, zero_ratio
from symvib.numeric.quadrature import rule

TOLERANCES = (1e-10, 1e-12, 1e-13)


def families(rng, count):
    """``(shape, parameters, f, G, G', exact)`` of ``count`` random integrands."""
    mpmath.mp.dps = 30
    for _ in range(count):
        kind = int(rng.integers(3))
        if kind == 0:
            e, c = 10 ** rng.uniform(-8, 1), rng.uniform(-1.5, 1.5)
            s = mpmath.sqrt(e)
            exact = float(mpmath.asinh((1 - c) / s) - mpmath.asinh((-1 - c) / s))
            yield "near-stop", (e, c), lambda x, e=e, c=c: e + (x - c) ** 2, lambda x, c=c: 2 * (x - c), exact, True
        elif kind == 1:
            x0 = (-1 - 10 ** rng.uniform(-3, 1.5)) * (1 if rng.random() < 0.5 else -1)
            exact = float(2 * mpmath.sqrt(1 - x0) - 2 * mpmath.sqrt(-1 - x0)) if x0 < -1 else \
                float(2 * mpmath.sqrt(x0 + 1) - 2 * mpmath.sqrt(x0 - 1))
            sign = 1.0 if x0 < -1 else -1.0
            yield ("root beyond", (x0,), lambda x, x0=x0, sg=sign: sg * (x - x0), lambda x, sg=sign: sg + 0 * x,
                   exact, True)
        else:
            a, c = 10 ** rng.uniform(-1, 3), rng.uniform(-1.5, 1.5)
            s = mpmath.sqrt(a)
            exact = float((mpmath.atan(s * (1 - c)) - mpmath.atan(s * (-1 - c))) / s)
            # f = 1/(1 + a (x-c)^2) is no 1/sqrt(G): its G is unknown to the engine (zero ratio 0).
            yield "kernel pole", (a, c), lambda x, a=a, c=c: (1 + a * (x - c) ** 2) ** 2, None, exact, False


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--count", type=int, default=4000)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args(argv)
    for n, cautious in ((12, False), (16, True)):
        r = rule(n)
        E = tail_rows(r.x, r.weights)
        stats = {}
        for shape, _, G, dG, exact, has_zero in families(np.random.default_rng(args.seed), args.count):
            Gx = G(r.x)
            f = 1.0 / np.sqrt(Gx)
            c = E @ f
            integral = float(r.weights @ f)
            r_geom = 0.0
            if has_zero and not cautious:
                j = int(np.argmin(Gx))
                j0, j1 = max(j - 1, 0), min(j + 1, n - 1)
                slopes = dG(r.x)
                curv = (slopes[j1] - slopes[j0]) / (r.x[j1] - r.x[j0])
                r_geom = zero_ratio(float(r.x[j]), float(Gx[j]), float(slopes[j]), float(curv), 0.0, 1.0)
            est = tail_error(c[0], c[1], c[2], c[3], n, cautious, r_geom, 0.0) / abs(exact)
            err = abs(integral - exact) / abs(exact)
            row = stats.setdefault(shape, {"count": 0, "hidden": {t: 0 for t in TOLERANCES}, "worst": 0.0,
                                           "wasted": {t: 0 for t in TOLERANCES}})
            row["count"] += 1
            for t in TOLERANCES:
                if est < t and err > t:
                    row["hidden"][t] += 1
                    row["worst"] = max(row["worst"], err / t)
                elif est >= t and err < t / 100:
                    row["wasted"][t] += 1
        label = "16 nodes, cautious (panels from a root)" if cautious else "12 nodes (panels off a root)"
        print(f"# {label}")
        print(f"{'integrand':12s} {'count':>6s} " + " ".join(f"{'hidden@' + format(t, 'g'):>13s}" for t in TOLERANCES)
              + f" {'worst err/tol':>14s} " + " ".join(f"{'wasted@' + format(t, 'g'):>13s}" for t in TOLERANCES))
        for shape, row in stats.items():
            print(f"{shape:12s} {row['count']:6d} " + " ".join(f"{row['hidden'][t]:13d}" for t in TOLERANCES)
                  + f" {row['worst']:14.3g} " + " ".join(f"{row['wasted'][t]:13d}" for t in TOLERANCES))
    return 0


if __name__ == "__main__":
    sys.exit(main())
