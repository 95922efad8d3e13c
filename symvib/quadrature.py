"""Gauss-Legendre rules with cumulative integration, and safeguarded root finders
for the driver (NumPy only).

A :class:`ChebRule` holds, for ``n`` Gauss-Legendre points on ``[-1, 1]``
(interior points: an integrand may be 0/0 at an end), the quadrature weights
(exact to degree ``2n - 1``), the cumulative-integration matrix ``S`` with
``(S @ f)[j] = Integral_{-1}^{x_j} f`` for the degree ``n - 1`` interpolant of
``f``, its weighted twin ``W`` with ``(W @ f)[j] = Integral_{-1}^{x_j} (x + 1) f``
(no loss of relative accuracy near ``x = -1``), and the map from values to
Legendre coefficients.  The cumulative form
lets the driver rebuild ``G = C - 2 g F`` at the nodes from an anchor without
cancellation (its integrand ``G'`` is smooth); totals use the Gauss weights,
which converge twice as fast near the square-root singularity of the other
end of an interval.

Examples
--------
>>> import numpy as np
>>> r = rule(16)
>>> float(r.weights @ np.exp(r.x))            # Integral of exp over [-1, 1]
2.3504023872876028
>>> bool(abs((r.cumulative @ np.cos(r.x))[-1] - (np.sin(r.x[-1]) + np.sin(1))) < 1e-15)
True
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.polynomial import legendre as _leg

__all__ = ["ChebRule", "rule", "safe_newton", "brent"]

#: Relative step at which root finders stop (a few units in the last place).
ROOT_RTOL = 4 * np.finfo(float).eps
#: Iterations after which a root finder gives up (never reached on a bracketed monotone function).
ROOT_MAXITER = 200


@dataclass(frozen=True)
class ChebRule:
    """Quadrature data for ``n`` Gauss-Legendre points on ``[-1, 1]`` (ascending)."""

    n: int
    x: np.ndarray
    weights: np.ndarray
    cumulative: np.ndarray
    to_coeffs: np.ndarray
    cumulative_weighted: np.ndarray


@lru_cache(maxsize=None)
def rule(n: int) -> ChebRule:
    """The :class:`ChebRule` with ``n`` nodes (cached; arrays read-only)."""
    x, weights = _leg.leggauss(n)
    vander = _leg.legvander(x, n - 1)
    to_coeffs = np.linalg.solve(vander, np.eye(n))
    cumulative = np.empty((n, n))
    weighted = np.empty((n, n))
    for i in range(n):
        c = _leg.legint(to_coeffs[:, i], lbnd=-1)
        cumulative[:, i] = _leg.legval(x, c)
        cw = _leg.legint(_leg.legadd(_leg.legmulx(to_coeffs[:, i]), to_coeffs[:, i]), lbnd=-1)
        weighted[:, i] = _leg.legval(x, cw)
    for a in (x, weights, cumulative, to_coeffs, weighted):
        a.setflags(write=False)
    return ChebRule(n, x, weights, cumulative, to_coeffs, weighted)


def safe_newton(f, df, a: float, b: float, fa: float, fb: float, *, xtol: float = 0.0) -> float:
    """Root of ``f`` in ``[a, b]`` where ``fa`` and ``fb`` have opposite signs (or one is 0).

    Newton steps from the better end, falling back to bisection whenever a
    step would leave the bracket or fails to halve it (``rtsafe``).  Stops
    when the bracket is narrower than ``xtol + ROOT_RTOL * |x|``.
    """
    if fa == 0.0:
        return a
    if fb == 0.0:
        return b
    if (fa > 0) == (fb > 0):
        raise ValueError(f"root not bracketed: f({a}) = {fa}, f({b}) = {fb}")
    lo, hi = (a, b) if fa < 0 else (b, a)  # f(lo) < 0 < f(hi)
    x = a if abs(fa) < abs(fb) else b
    dx_old = abs(b - a)
    dx = dx_old
    fx = fa if x == a else fb
    dfx = df(x)
    for _ in range(ROOT_MAXITER):
        tol = xtol + ROOT_RTOL * abs(x)
        newton_ok = dfx != 0.0 and ((x - hi) * dfx - fx) * ((x - lo) * dfx - fx) < 0.0
        if not newton_ok or abs(2.0 * fx) > abs(dx_old * dfx):
            dx_old, dx = dx, 0.5 * (hi - lo)
            x = lo + dx
        else:
            dx_old, dx = dx, fx / dfx
            x -= dx
        if abs(dx) <= tol or abs(hi - lo) <= tol:
            return x
        fx = f(x)
        if fx == 0.0:
            return x
        dfx = df(x)
        if fx < 0:
            lo = x
        else:
            hi = x
    return x


def brent(f, a: float, b: float, fa: float, fb: float, *, xtol: float = 0.0) -> float:
    """Brent's method on a bracket (no derivative); see :func:`safe_newton`."""
    if fa == 0.0:
        return a
    if fb == 0.0:
        return b
    if (fa > 0) == (fb > 0):
        raise ValueError(f"root not bracketed: f({a}) = {fa}, f({b}) = {fb}")
    c, fc = a, fa
    d = e = b - a
    for _ in range(ROOT_MAXITER):
        if (fb > 0) == (fc > 0):
            c, fc = a, fa
            d = e = b - a
        if abs(fc) < abs(fb):
            a, b, c = b, c, b
            fa, fb, fc = fb, fc, fb
        tol = xtol + ROOT_RTOL * abs(b)
        m = 0.5 * (c - b)
        if abs(m) <= tol or fb == 0.0:
            return b
        if abs(e) >= tol and abs(fa) > abs(fb):
            s = fb / fa
            if a == c:
                p, qq = 2.0 * m * s, 1.0 - s
            else:
                qq, r = fa / fc, fb / fc
                p = s * (2.0 * m * qq * (qq - r) - (b - a) * (r - 1.0))
                qq = (qq - 1.0) * (r - 1.0) * (s - 1.0)
            if p > 0:
                qq = -qq
            p = abs(p)
            if 2.0 * p < min(3.0 * m * qq - abs(tol * qq), abs(e * qq)):
                e, d = d, p / qq
            else:
                d = e = m
        else:
            d = e = m
        a, fa = b, fb
        b += d if abs(d) > tol else math.copysign(tol, m)
        fb = f(b)
    return b
