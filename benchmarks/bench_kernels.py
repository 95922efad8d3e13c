"""Generated kernels against plain lambdify and SymPy evalf; import times.

Run from the project folder::

    python benchmarks/bench_kernels.py [--n 100000] [--repeat 7]

Every figure is a ratio measured in this one run (the machine is shared and
noisy): the best of ``--repeat`` timings of each contender on the same inputs.

* ``w_p`` (eq. 2 with its antiderivative) and ``qddot_p`` (eq. 1) over ``n``
  values of ``q``: the generated NumPy kernel (cse), ``sympy.lambdify`` of
  the same expression without cse, and ``evalf`` (per point, on a subsample).
* one float: the generated ``*_scalar`` kernel (math) against the NumPy kernel.
* import: a fresh interpreter importing the generated module and evaluating
  it, against one importing SymPy (each minus an empty interpreter).
"""
from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from symvib.numeric import kernels  # noqa: E402


def best(fn, repeat):
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


def interpreter_seconds(code: str, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=100_000)
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--evalf-points", type=int, default=200)
    args = ap.parse_args(argv)

    import sympy as sp

    from symvib.codegen.kernel_text import kernel_exprs
    from symvib.symbolic.derive import derive
    from symvib.symbolic.integrals import ROUTES
    from symvib.symbolic.symbols import C, g, mu

    print(f"# symvib kernel benchmark: n = {args.n}, best of {args.repeat}; numpy {np.__version__}, "
          f"sympy {sp.__version__}")
    print(f"{'curve':10s} {'kernel':8s} {'generated':>12s} {'lambdify':>12s} {'evalf':>12s} "
          f"{'lambdify/gen':>13s} {'evalf/gen':>10s}")
    rng = np.random.default_rng(0)
    for name, pvals in (("parabola", (1.0,)), ("cycloid", (0.05,)), ("catenary", (1.0,))):
        mod = kernels.load(name)
        d = derive(name, routes=() if mod.F_ROUTES[1] == "numeric" else ROUTES)
        exprs = {k: (a, e) for k, a, e, _ in kernel_exprs(d)}
        lo, hi = mod.domain(*pvals)
        lo, hi = max(lo, -2.0), min(hi, 2.0)
        q = rng.uniform(lo + 0.1 * (hi - lo), hi - 0.1 * (hi - lo), args.n)
        qs = sp.Symbol("q", real=True)
        Fp = d.branches[1].F.expr.xreplace({d.curve.q: qs})
        for kname in ("w_p", "qddot_p"):
            argnames, expr = exprs[kname]
            expr = expr.xreplace({sp.Symbol("__F_p"): Fp})
            values = {"q": q, "C": 60.0, "g": 9.81, "mu": 0.05, "qdot": 3.0,
                      **dict(zip(mod.PARAMS, pvals))}
            call = [values[a] for a in argnames]
            gen = getattr(mod, kname)
            t_gen = best(lambda: gen(*call), args.repeat)
            syms = {"q": qs, "C": C, "g": g, "mu": mu, "qdot": sp.Symbol("qdot", real=True),
                    **{p.name: p for p in d.curve.params}}
            if expr.has(sp.Integral):
                t_lam = float("nan")
                t_ev = float("nan")
            else:
                lam = sp.lambdify([syms[a] for a in argnames], expr, "numpy", cse=False)
                t_lam = best(lambda: lam(*call), args.repeat)
                k = args.evalf_points
                subs_list = [{syms[a]: (values[a][i] if isinstance(values[a], np.ndarray) else values[a])
                              for a in argnames} for i in range(k)]
                start = time.perf_counter()
                for sub in subs_list:
                    expr.evalf(subs=sub)
                t_ev = (time.perf_counter() - start) / k * args.n
            print(f"{name:10s} {kname:8s} {t_gen * 1e3:10.2f}ms {t_lam * 1e3:10.2f}ms {t_ev * 1e3:10.0f}ms "
                  f"{t_lam / t_gen:13.2f} {t_ev / t_gen:10.0f}")
    # Scalar path.
    mod = kernels.load("parabola")
    reps = 20000
    t_vec = best(lambda: [mod.w_p(0.3, 60.0, 9.81, 0.05, 1.0) for _ in range(reps)], 3) / reps
    t_sca = best(lambda: [mod.w_p_scalar(0.3, 60.0, 9.81, 0.05, 1.0) for _ in range(reps)], 3) / reps
    print(f"\none float, parabola w_p: numpy kernel {t_vec * 1e6:.2f} us, scalar kernel {t_sca * 1e6:.2f} us, "
          f"ratio {t_vec / t_sca:.1f}")
    # Import times.
    empty = interpreter_seconds("pass", args.repeat)
    t_kern = interpreter_seconds(
        "from symvib.numeric.kernels import load; load('parabola').w_p(0.3, 60.0, 9.81, 0.05, 1.0)",
        args.repeat) - empty
    t_numpy = interpreter_seconds("import numpy", args.repeat) - empty
    t_sympy = interpreter_seconds("import sympy", args.repeat) - empty
    print(f"import (median of {args.repeat}, minus an empty interpreter): generated module + numpy "
          f"{t_kern * 1e3:.0f} ms (numpy alone {t_numpy * 1e3:.0f} ms), sympy {t_sympy * 1e3:.0f} ms, "
          f"ratio sympy/generated {t_sympy / t_kern:.1f}")


if __name__ == "__main__":
    main()
