"""Root finders of the engine: safeguarded Newton on ``G`` and the Illinois method.

numba compiles no function arguments into fast code, so each finder of a
function other than ``G`` is written once per function (in the module of that
function), and shares :func:`illinois_point` and :func:`illinois_update`.

Examples
--------
>>> illinois_point(0.0, 1.0, -1.0, 1.0)
0.5
"""
from __future__ import annotations

import numpy as np

from symvib.numeric.engine.laws import Fs, dFs

__all__ = ["root_G", "illinois_point", "illinois_update", "ROOT_RTOL", "ROOT_MAXITER"]

#: Relative bracket width at which root finders stop.
ROOT_RTOL = 4 * np.finfo(float).eps
#: Iterations after which a root finder stops (not reached on a bracketed monotone function).
ROOT_MAXITER = 200
#: Absolute bracket width at which the Illinois method stops (roots at q = 0).
ROOT_ATOL = 1e-300


def root_G(s, C, a, b, Ga, Gb, g2, mu, K, cp):
    """rtsafe for G = C - 2 g F_s on [a, b] with G(a) > 0 >= G(b)."""
    if Gb == 0.0:
        return b
    lo, hi = b, a  # G(lo) < 0 < G(hi)
    x = a if Ga < -Gb else b
    fx = Ga if x == a else Gb
    dfx = -g2 * dFs(s, x, mu, K, cp)
    dx_old = abs(b - a)
    dxx = dx_old
    for _ in range(ROOT_MAXITER):
        tol = ROOT_RTOL * abs(x)
        ok = dfx != 0.0 and ((x - hi) * dfx - fx) * ((x - lo) * dfx - fx) < 0.0
        if (not ok) or abs(2.0 * fx) > abs(dx_old * dfx):
            dx_old = dxx
            dxx = 0.5 * (hi - lo)
            x = lo + dxx
        else:
            dx_old = dxx
            dxx = fx / dfx
            x = x - dxx
        if abs(dxx) <= tol or abs(hi - lo) <= tol:
            return x
        fx = C - g2 * Fs(s, x, mu, K, cp)
        if fx == 0.0:
            return x
        dfx = -g2 * dFs(s, x, mu, K, cp)
        if fx < 0.0:
            lo = x
        else:
            hi = x
    return x

def illinois_point(a, b, fa, fb):
    """Next point of the Illinois method (regula falsi, or bisection if that leaves the bracket)."""
    x = b - fb * (b - a) / (fb - fa)
    if not (min(a, b) < x < max(a, b)):
        x = 0.5 * (a + b)
    return x


def illinois_update(a, b, fa, fb, x, fx):
    """The bracket after evaluating f(x) = fx: halve the stale end's value (Illinois); done?"""
    if (fx > 0.0) == (fb > 0.0):
        fa = 0.5 * fa
    else:
        a, fa = b, fb
    b, fb = x, fx
    return a, b, fa, fb, fx == 0.0 or abs(b - a) <= ROOT_RTOL * abs(b) + ROOT_ATOL


