"""A tangent angle continuous on the curve's domain (physics.md, "Geometry").

``atan2(z', x')`` jumps by ``2 pi`` where the tangent points along ``-x``;
:func:`tangent_angle` looks for a closed form without that jump, and
:func:`angle_jump` checks one densely in double precision.

``curve`` is a :class:`~symvib.symbolic.curve.Curve` throughout (not imported here: the curve
imports this module).
"""
from __future__ import annotations

import math
import random

import numpy as np
import sympy as sp

from symvib.symbolic import budget
from symvib.symbolic.branches import CurveError, generic_branch
from symvib.symbolic.identity import identity_holds

__all__ = ["tangent_angle", "reference_point", "angle_jump"]

#: Budget (seconds, wall clock, a child process each) of the symbolic integration of ``alpha'``,
#: and of the rotated forms, in :func:`tangent_angle`.
ALPHA_SECONDS = 2.0
ROTATION_SECONDS = 2.0
#: Reference angles ``beta`` of the rotated forms ``alpha = beta + atan(...)`` (:func:`_rotation_job`).
ROTATIONS = ("0", "q", "-q", "q/2", "-q/2", "pi - q", "pi + q")
#: Points of the dense check of a candidate tangent angle, and the half width (in ``q_scale``)
#: of its window where the domain is infinite.
ANGLE_POINTS = 8193
ANGLE_HALF_WIDTH = 64.0
#: Parameter sets of the dense check besides all ones: random values in (0.5, 2), like the identity checks.
ANGLE_RANDOM_SETS = 2
#: Agreement of a candidate with ``atan2(z', x')`` modulo ``2 pi`` at the grid points (absolute, radians).
ANGLE_TOL = 1e-8
#: Bisection steps that tell a jump of a candidate from a fast turn of the tangent between grid points.
ANGLE_BISECT = 60
#: ``h`` at a bracket below this fraction of ``h`` at the grid points around it: a cusp, where every
#: tangent angle jumps (the run's interval ends there, :mod:`symvib.symbolic.singular`).
ANGLE_CUSP_RTOL = 1e-6

#: Tangent angles already found, by the curve's defining expressions and domain.
_ANGLES: dict = {}


def tangent_angle(curve):
    """A closed form of the tangent angle of ``curve`` continuous on its domain, or ``None``.

    ``atan2(z', x')`` is the tangent angle only up to ``2 pi``: it jumps where the
    tangent points along ``-x``, while the phase trajectory's factor ``exp(-2 s mu
    alpha)`` needs the continuous angle (physics.md, "Geometry").  Candidates:

    1. ``alpha' = (x' z'' - z' x'') / h**2`` integrated symbolically (in a child process
       under :data:`ALPHA_SECONDS`; an ``Abs``/``sign`` takes its sign at the reference
       point, which the checks below confirm or refute); ``alpha = q`` on a circle
       ``x = R sin q``, ``z = R (1 - cos q)``;
    2. the tangent rotated by a reference angle ``beta`` (:data:`ROTATIONS`):
       ``alpha = beta + atan(Q/P)`` with ``P = x' cos(beta) + z' sin(beta)``, ``Q = z'
       cos(beta) - x' sin(beta)``, continuous where ``P > 0`` (under
       :data:`ROTATION_SECONDS`): ``q + atan((b - a) sin q cos q / (a cos**2 q + b sin**2 q))``
       on an ellipse ``x = a sin q``, ``z = b (1 - cos q)``.

    Each is shifted by a constant so that it equals ``atan2(z', x')`` at a reference point
    (exactly, symbolically), and accepted only if (a) ``h sin(alpha) = z'`` and ``h
    cos(alpha) = x'`` hold identically (:func:`identity_holds`, 30 digits at random
    points and parameters), and (b) it jumps nowhere the curve is regular
    (:func:`angle_jump`, with every parameter 1 and at :data:`ANGLE_RANDOM_SETS` random
    sets).  ``atan(b tan(q) / a)``, the integral SymPy may give for the ellipse, fails (b).

    Returns
    -------
    sympy.Expr or None
        ``None`` when no candidate passes; the caller keeps ``atan2`` and sets
        :attr:`Curve.alpha_cut`.
    """
    key = tuple(sp.srepr(e) for e in (curve.x, curve.z, curve.h, curve.domain, curve.q_scale))
    if key in _ANGLES:
        return _ANGLES[key]
    q0 = reference_point(curve)
    args = (sp.srepr(curve.xp), sp.srepr(curve.zp), curve.q.name, sp.srepr(q0))
    found = None
    for job, seconds in ((_integration_job, ALPHA_SECONDS), (_rotation_job, ROTATION_SECONDS)):
        outcome = budget.run(job, args, seconds=seconds)
        if outcome.status != "ok":
            continue
        for candidate in (outcome.value if isinstance(outcome.value, sp.Tuple) else ()):
            try:
                found = _accepted(candidate, curve, q0)
            except Exception:  # noqa: BLE001 - a candidate that cannot be checked is not taken
                found = None
            if found is not None:
                break
        if found is not None:
            break
    _ANGLES[key] = found
    return found


def reference_point(curve) -> sp.Expr:
    """A finite point inside the domain: 0 when it is inside, else the middle, or one
    ``q_scale`` inside the finite end of a half-infinite domain (whose middle is infinite)."""
    lo, hi = curve.domain
    if (lo.is_infinite or (lo < 0) == sp.true) and (hi.is_infinite or (hi > 0) == sp.true):
        return sp.Integer(0)
    if hi.is_infinite:
        return lo + curve.q_scale
    if lo.is_infinite:
        return hi - curve.q_scale
    return (lo + hi) / 2


def _signs_at(expr: sp.Expr, q: sp.Symbol, q0: sp.Expr) -> sp.Expr:
    """``expr`` with each ``Abs(w)``/``sign(w)`` whose sign at ``q0`` SymPy can tell written without it."""
    def fixed(e):
        w = e.args[0]
        at = sp.simplify(w.subs(q, q0))
        sgn = 1 if at.is_positive else -1 if at.is_negative else None
        if sgn is None:
            return e
        return sgn * w if isinstance(e, sp.Abs) else sp.Integer(sgn)

    return expr.replace(lambda e: isinstance(e, (sp.Abs, sp.sign)), fixed)


def _integration_job(xp: str, zp: str, qname: str, q0: str):
    """Child job: ``alpha'`` integrated, as a one-element ``Tuple`` (empty when SymPy finds no closed form)."""
    xp_e, zp_e, q0_e = sp.sympify(xp), sp.sympify(zp), sp.sympify(q0)
    q = next((s for s in (xp_e + zp_e).free_symbols if s.name == qname), sp.Symbol(qname, real=True))
    rate = (xp_e * sp.diff(zp_e, q) - zp_e * sp.diff(xp_e, q)) / (xp_e**2 + zp_e**2)
    rate = _signs_at(generic_branch(sp.simplify(rate)), q, q0_e)
    found = sp.integrate(rate, q)
    if found.has(sp.Integral):
        return sp.Tuple()
    try:
        found = generic_branch(found)
    except CurveError:  # a Piecewise on an inequality: no single closed form
        return sp.Tuple()
    return sp.Tuple(found)


def _rotation_job(xp: str, zp: str, qname: str, q0: str):
    """Child job: the rotated forms ``beta + atan(Q/P)`` of :data:`ROTATIONS` (a ``Tuple``)."""
    xp_e, zp_e = sp.sympify(xp), sp.sympify(zp)
    q = next((s for s in (xp_e + zp_e).free_symbols if s.name == qname), sp.Symbol(qname, real=True))
    out = []
    for text in ROTATIONS:
        beta = sp.sympify(text, locals={"q": q})
        P = sp.expand(sp.expand_trig(xp_e * sp.cos(beta) + zp_e * sp.sin(beta)))
        Q = sp.expand(sp.expand_trig(zp_e * sp.cos(beta) - xp_e * sp.sin(beta)))
        out.append(beta + sp.atan(sp.factor_terms(sp.cancel(Q / P))))
    return sp.Tuple(*out)


def _accepted(candidate: sp.Expr, curve, q0: sp.Expr):
    """``candidate`` shifted to equal ``atan2(z', x')`` at ``q0``, if it passes the checks (a), (b)."""
    unwanted = (sp.I, sp.nan, sp.zoo, sp.oo, sp.Integral, sp.Piecewise, sp.AccumBounds)
    if not isinstance(candidate, sp.Expr) or candidate.has(*unwanted):
        return None
    q = curve.q
    at = sp.atan2(curve.zp.subs(q, q0), curve.xp.subs(q, q0)) - candidate.subs(q, q0)
    try:
        shift = budget.simplify(at)
    except Exception:  # noqa: BLE001 - an odd form: the checks decide on the unsimplified one
        shift = at
    if shift.has(*unwanted) or shift.free_symbols - set(curve.params):
        return None
    alpha = candidate + shift if shift != 0 else candidate
    # The dense check in double precision first (milliseconds), then the identities at 30 digits.
    if angle_jump(alpha, curve, curve.default_values()) is not None:
        return None
    for lhs, rhs in ((curve.h * sp.sin(alpha), curve.zp), (curve.h * sp.cos(alpha), curve.xp)):
        if identity_holds(lhs - rhs, curve, simplify=False) is None:
            return None
    rng = random.Random(13)
    for _ in range(ANGLE_RANDOM_SETS if curve.params else 0):
        if angle_jump(alpha, curve, {p: sp.Float(0.5 + 1.5 * rng.random()) for p in curve.params}) is not None:
            return None
    return alpha


def angle_jump(alpha: sp.Expr, curve, values: dict):
    """Where ``alpha`` jumps at a regular point of ``curve`` with parameter ``values``, or ``None``.

    ``alpha`` is sampled at :data:`ANGLE_POINTS` points of the domain (its infinite
    ends cut at :data:`ANGLE_HALF_WIDTH` ``q_scale``) with ``atan2(z', x')``: it must
    agree with it modulo ``2 pi`` (within :data:`ANGLE_TOL`) wherever the curve is
    regular, and between neighbours change by what ``atan2`` turns (wrapped to ``(-pi,
    pi]``).  Where it changes by another multiple of ``2 pi``, or by ``pi``, the cell is
    bisected (:data:`ANGLE_BISECT` steps): a fast turn of the tangent resolves, a jump
    stays; a jump at a cusp (``h`` vanishing) or a pole is allowed, since no run crosses
    it.  Double precision, NumPy.
    """
    q = curve.q
    subs = {p: values[p] for p in curve.params}
    fns = [sp.lambdify([q], e.subs(subs), "numpy") for e in (alpha, curve.xp, curve.zp)]
    scale = float(curve.q_scale.subs(subs))
    lo, hi = (float(e.subs(subs)) if e.is_finite is not False else float(e) for e in curve.domain)
    center = 0.0 if not (math.isfinite(lo) or math.isfinite(hi)) else lo if math.isfinite(lo) else hi
    lo = lo if math.isfinite(lo) else min(center, hi) - ANGLE_HALF_WIDTH * scale
    hi = hi if math.isfinite(hi) else max(center, lo) + ANGLE_HALF_WIDTH * scale
    pad = (hi - lo) * 1e-9
    grid = np.linspace(lo + pad, hi - pad, ANGLE_POINTS)
    a, turn, h, regular = _angle_samples(fns, grid)
    with np.errstate(all="ignore"):
        agrees = np.abs(_wrap(a - turn)) <= ANGLE_TOL * (1.0 + np.abs(a))
        step = np.diff(a) - _wrap(np.diff(turn))
    bad = np.flatnonzero(regular & ~agrees)
    if bad.size:
        return float(grid[bad[0]])
    both = regular[:-1] & regular[1:]
    for j in np.flatnonzero(both & ~(np.abs(step) <= 1.0)):
        where = _bisect_jump(fns, grid[j], grid[j + 1], max(h[j], h[j + 1]))
        if where is not None:
            return where
    return None


def _wrap(v):
    return (v + np.pi) % (2 * np.pi) - np.pi


def _angle_samples(fns, grid):
    """``alpha``, ``atan2(z', x')``, ``h`` and where the curve is regular (finite, ``h > 0``) at ``grid``."""
    import warnings

    out = []
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        for fn in fns:
            try:
                v = np.broadcast_to(np.asarray(fn(grid), dtype=float), grid.shape).astype(float)
            except Exception:  # noqa: BLE001 - evaluated in complex below
                v = np.full(grid.shape, np.nan)
            if not np.all(np.isfinite(v)):
                try:
                    c = np.broadcast_to(np.asarray(fn(grid.astype(complex)), dtype=complex), grid.shape)
                    real = np.abs(c.imag) <= 1e-9 * (1.0 + np.abs(c.real))
                    v = np.where(np.isfinite(v), v, np.where(real, c.real, np.nan))
                except Exception:  # noqa: BLE001 - the NaN stays: not regular, or a jump
                    pass
            out.append(v)
    a, xp, zp = out
    h = np.hypot(xp, zp)
    regular = np.isfinite(xp) & np.isfinite(zp) & (h > 0)
    a = np.where(regular & ~np.isfinite(a), np.inf, a)  # a non-finite angle where the curve is regular
    return a, np.arctan2(zp, xp), h, regular


def _bisect_jump(fns, a: float, b: float, h_around: float):
    """The point of a jump of the angle in ``[a, b]`` (``None`` if the change resolves or is at a cusp)."""
    for _ in range(ANGLE_BISECT):
        mid = 0.5 * (a + b)
        if mid in (a, b):
            break
        pts = np.array([a, mid, b])
        ang, turn, h, regular = _angle_samples(fns, pts)
        if not regular[1] or h[1] <= ANGLE_CUSP_RTOL * h_around:
            return None  # a cusp or a pole: the run's interval ends there
        with np.errstate(all="ignore"):
            left = abs(ang[1] - ang[0] - _wrap(turn[1] - turn[0]))
            right = abs(ang[2] - ang[1] - _wrap(turn[2] - turn[1]))
        if left <= 1.0 and right <= 1.0:
            return None  # a fast turn of the tangent, resolved
        a, b = (a, mid) if left > 1.0 else (mid, b)
    ends = _angle_samples(fns, np.array([a, b]))
    if not np.all(ends[3]) or np.min(ends[2]) <= ANGLE_CUSP_RTOL * h_around:
        return None
    return 0.5 * (a + b)
