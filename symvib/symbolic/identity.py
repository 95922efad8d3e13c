"""Numeric identity checks on a curve: expressions compared at random points of its domain.

SymPy does not always simplify a true identity to zero; :func:`identity_holds` then
evaluates it at :data:`CHECK_DIGITS` digits at :func:`sample_points`, with random
parameters.  :func:`tamed` keeps a simplified form only where it evaluates in double
precision as its original does (:func:`far_points`).

``curve`` is a :class:`~symvib.symbolic.curve.Curve` throughout (not imported here: the curve
imports this module).
"""
from __future__ import annotations

import math
import random

import mpmath
import numpy as np
import sympy as sp

from symvib.symbolic import budget

__all__ = ["IDENTITY_CHECK_POINTS", "CHECK_DIGITS", "CHECK_TOLERANCE", "sample_points", "far_points", "tamed",
           "identity_holds", "numeric_zero"]

#: Random points of a numeric identity check.
IDENTITY_CHECK_POINTS = 5
#: Working precision (decimal digits) of numeric identity checks.
CHECK_DIGITS = 30
#: Residual accepted by a numeric identity check at CHECK_DIGITS digits (relative).
CHECK_TOLERANCE = mpmath.mpf("1e-25")
#: Half width, in units of ``q_scale``, of the sampling window on an infinite domain.
SAMPLE_HALF_WIDTH = 2
#: Distances, in units of ``q_scale``, at which :func:`tamed` checks a simplified form for overflow
#: on an infinite end of the domain (``exp(x**2)`` overflows beyond ``x`` of about 27).
FAR_WIDTHS = (30.0, 1e3, 1e6)


def sample_points(curve, n: int, *, seed: int = 0, margin: float = 0.1, values=None) -> list:
    """Reproducible random coordinates inside ``curve.domain`` (mpmath numbers).

    A finite domain end is approached no closer than ``margin`` of its width;
    an infinite end is replaced by ``SAMPLE_HALF_WIDTH * q_scale``.
    """
    values = values or curve.default_values()
    rng = random.Random(seed)
    scale = float(curve.q_scale.subs(values))
    lo, hi = curve.domain
    lo = -SAMPLE_HALF_WIDTH * scale if lo.is_infinite else float(lo.subs(values))
    hi = SAMPLE_HALF_WIDTH * scale if hi.is_infinite else float(hi.subs(values))
    width = hi - lo
    lo, hi = lo + margin * width, hi - margin * width
    return [mpmath.mpf(lo + (hi - lo) * rng.random()) for _ in range(n)]


def far_points(curve, values=None) -> list:
    """Coordinates far out on the infinite ends of ``curve.domain`` (:data:`FAR_WIDTHS` times
    ``q_scale``), and the sample points in between; none beyond a finite end, where a curve may
    well be singular."""
    values = values or curve.default_values()
    scale = float(curve.q_scale.subs(values))
    lo, hi = curve.domain
    far = []
    if lo.is_infinite:
        far += [-w * scale for w in FAR_WIDTHS]
    if hi.is_infinite:
        far += [w * scale for w in FAR_WIDTHS]
    return far + [float(v) for v in sample_points(curve, IDENTITY_CHECK_POINTS, seed=3, values=values)]


def _finite_at(expr: sp.Expr, curve, points, values) -> np.ndarray:
    """Whether ``expr`` (the curve's parameters at ``values``) evaluates in double precision at
    ``points`` without overflowing on the way (a scalar kernel's ``math.exp`` raises where NumPy's
    gives ``inf``, so a form whose ``inf`` cancels later still fails a plain run)."""
    fn = sp.lambdify([curve.q], expr.subs(values), "numpy")
    out = []
    with np.errstate(over="raise", invalid="ignore", divide="ignore", under="ignore"):
        for qv in points:
            try:
                v = complex(fn(np.float64(qv)))
            except (ArithmeticError, ValueError, TypeError):   # (FloatingPointError is an ArithmeticError)
                out.append(False)
                continue
            out.append(math.isfinite(v.real) and math.isfinite(v.imag))
    return np.array(out, dtype=bool)


def tamed(simplified: sp.Expr, raw: sp.Expr, curve) -> sp.Expr:
    """``simplified``, unless it overflows in double precision where ``raw`` (the same function
    before simplification) does not: then ``raw``.

    SymPy's ``simplify`` clears denominators, which can turn a decaying factor into a growing
    one.  The Gaussian well ``z = -a exp(-x**2/b**2)`` is the case that showed it: its
    ``alpha'`` simplifies to ``2 a (b**2 - 2 x**2) exp(x**2/b**2) / (4 a**2 x**2 + b**4
    exp(2 x**2/b**2))``, which is ``inf/inf`` once ``x**2/b**2`` passes about 355, although
    ``alpha'`` there is a harmless ``0``.  Checked at :func:`far_points` with the parameters
    at 1.

    Examples
    --------
    >>> from symvib.symbolic.curve import graph
    >>> x = sp.Symbol("x", real=True)
    >>> c = graph("-exp(-x**2)")
    >>> tamed(sp.exp(x**2) / (1 + sp.exp(2 * x**2)), sp.exp(-x**2) / (sp.exp(-2 * x**2) + 1), c).has(sp.exp(x**2))
    False
    """
    if simplified == raw:
        return simplified
    try:
        values = curve.default_values()
        points = far_points(curve, values)
        worse = _finite_at(raw, curve, points, values) & ~_finite_at(simplified, curve, points, values)
    except Exception:  # noqa: BLE001 - a form numpy cannot evaluate: keep SymPy's simplification
        return simplified
    return raw if worse.any() else simplified


def identity_holds(expr: sp.Expr, curve, *, extra=None, points: int = IDENTITY_CHECK_POINTS,
                   seed: int = 1, simplify: bool = True) -> str | None:
    """Check that ``expr`` vanishes identically on the curve's domain.

    Returns ``"symbolic"`` when SymPy simplifies it to zero, ``"numeric"`` when
    it is below ``CHECK_TOLERANCE`` (relative to the size of its terms) at
    ``points`` random points at ``CHECK_DIGITS`` digits, and ``None`` otherwise.
    ``extra`` maps further symbols (``mu``, ``g``, ``C``) to sampling ranges.
    """
    if expr == 0:
        return "symbolic"
    if simplify:
        try:
            if budget.simplify(expr, budget.CHECK_SIMPLIFY_SECONDS, remember=False) == 0:
                return "symbolic"
        except Exception:  # noqa: BLE001 - simplify may fail on odd input; fall back
            pass
    return "numeric" if numeric_zero(expr, curve, extra=extra, points=points, seed=seed) else None


def numeric_zero(expr: sp.Expr, curve, *, extra=None, points: int = IDENTITY_CHECK_POINTS,
                 seed: int = 1) -> bool:
    """``True`` when ``expr`` is zero to ``CHECK_TOLERANCE`` at random points (30 digits)."""
    rng = random.Random(seed)
    extra = dict(extra or {})
    qs = sample_points(curve, points, seed=seed)
    terms = sp.Add.make_args(sp.expand(expr, deep=False))
    with mpmath.workdps(CHECK_DIGITS):
        for qv in qs:
            subs = {curve.q: sp.Float(qv, CHECK_DIGITS)}
            for p in curve.params:
                subs[p] = sp.Float(0.5 + 1.5 * rng.random(), CHECK_DIGITS)
            for sym, (a, b) in extra.items():
                subs[sym] = sp.Float(a + (b - a) * rng.random(), CHECK_DIGITS)
            try:
                value = sp.N(expr.subs(subs), CHECK_DIGITS)
                size = max([abs(sp.N(t.subs(subs), CHECK_DIGITS)) for t in terms] + [sp.Integer(1)])
                if not value.is_number or value.has(sp.nan, sp.zoo) or abs(value) > CHECK_TOLERANCE * size:
                    return False
            except TypeError:  # a NaN or an interval (AccumBounds) where a number belongs: not zero
                return False
    return True
