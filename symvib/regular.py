"""The regular interval of a run, from a curve's singular pieces, in plain numbers (ground floor).

physics.md ("Assumptions", regular curve) asks for the geometry to be finite
and real on the open interval the particle uses.  The symbolic wing finds the
*singular pieces* of a curve on a window of ``q``
(:func:`symvib.symbolic.singular.singular_pieces`: poles, cusps, corners,
regions where a function is not real); this module turns them into the
numbers a run needs, without SymPy or NumPy, so that the prepare step
(:mod:`symvib.prepare`) and the numeric wing (:mod:`symvib.numeric.prepared`)
share one account:

* :func:`scan_window`: the window searched for a start and its limiters;
* :func:`interval_in`: the largest open interval around the start free of pieces;
* :func:`run_domain`: the ends a run uses (kept :data:`EDGE_RTOL` inside a
  singular point, where the kernels are still finite), its length scale
  (narrower next to a singular point, so the quadrature's panels resolve it)
  and the reference point of a numeric ``F_sigma`` inside the interval.

Examples
--------
>>> r = interval_in([(0.3, 0.3, "z", "not finite")], 0.5, -math.inf, math.inf)
>>> r.lo, r.hi, r.lo_reason
(0.3, inf, 'z is not finite')
>>> d = run_domain(r, 0.5, 1.0)
>>> d.lo > 0.3, d.hi, d.scale, round(d.q_ref, 9), d.narrowed
(True, inf, 0.2, 0.5, True)
"""
from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["Regular", "RunDomain", "scan_window", "interval_in", "run_domain", "reference_point",
           "SCAN_HALF_WIDTH", "EDGE_RTOL", "MIN_SCALE_RATIO", "KINDS", "LABELS"]

#: Half width, in units of q_scale, of the searched window where the domain is infinite.
SCAN_HALF_WIDTH = 64.0
#: Distance, relative to q_scale (and to |q| beyond 1), kept between a run's domain end and a
#: singular point, so that the kernels are finite at the end.
EDGE_RTOL = 1e-12
#: Smallest q_scale of a narrowed run, relative to the curve's (bounds the engine's work).
MIN_SCALE_RATIO = 1 / 64
#: What a piece of a singular set is (its reason in messages).
NOT_FINITE, NOT_REAL, CUSP = "not finite", "not finite and real", "zero (a cusp)"
#: A corner: the argument of an ``Abs`` or ``sign`` in the first-order geometry changes sign and
#: ``x', z', h`` or ``alpha`` jumps there.
CORNER = "discontinuous (a corner)"
#: Every kind of piece.
KINDS = (NOT_FINITE, NOT_REAL, CUSP, CORNER)
#: The functions of the geometry that must be finite and real (a piece names one).
LABELS = ("x", "z", "x'", "z'", "h", "1/h", "alpha", "kappa")


@dataclass(frozen=True)
class Regular:
    """The open interval ``(lo, hi)`` around a point on which the curve is regular.

    ``lo_reason``/``hi_reason`` say which function fails at a singular end
    (``""`` where the end is the declared domain's).  ``at_start`` is set
    instead when the point itself is singular.
    """

    lo: float
    hi: float
    lo_reason: str = ""
    hi_reason: str = ""
    at_start: str = ""


@dataclass(frozen=True)
class RunDomain:
    """What a run of a curve uses on its regular interval (plain numbers).

    ``lo, hi``: the run's domain ends; ``scale``: its length scale (``q_scale``);
    ``q_ref``: the point a numeric ``F_sigma`` is integrated from;
    ``narrowed``: whether a singular point inside the declared domain bounds it.
    """

    lo: float
    hi: float
    scale: float
    q_ref: float
    narrowed: bool


def scan_window(lo: float, hi: float, scale: float, points) -> tuple:
    """The window of ``q`` searched for singular points: the declared domain ``(lo, hi)``, an
    infinite end cut :data:`SCAN_HALF_WIDTH` ``scale`` beyond the origin and beyond ``points``
    (the start and the limiters)."""
    width = SCAN_HALF_WIDTH * scale
    points = list(points)
    return (lo if math.isfinite(lo) else min(-width, min(points) - width),
            hi if math.isfinite(hi) else max(width, max(points) + width))


def interval_in(pieces, q0: float, lo: float, hi: float) -> Regular:
    """The largest open interval around ``q0`` inside ``(lo, hi)`` free of ``pieces``.

    Parameters
    ----------
    pieces : iterable of (a, b, label, kind)
        Closed intervals holding the singular set, sorted by ``a``
        (:func:`symvib.symbolic.singular.singular_pieces`).
    q0 : float
        The start.
    lo, hi : float
        The declared domain (ends may be infinite).

    Returns
    -------
    Regular
        ``at_start`` names the function that fails when ``q0`` itself lies in a piece.
    """
    left, right, lo_reason, hi_reason = lo, hi, "", ""
    for a, b, label, kind in pieces:
        reason = f"{label} is {kind}"
        if a <= q0 <= b:
            return Regular(q0, q0, at_start=reason)
        if left < b < q0:
            left, lo_reason = b, reason
        if q0 < a < right:
            right, hi_reason = a, reason
    return Regular(left, right, lo_reason, hi_reason)


def reference_point(lo: float, hi: float, scale: float) -> float:
    """A finite point inside ``(lo, hi)``: 0 when it is inside, else the middle, or one ``scale``
    inside the finite end of a half-infinite interval (as the symbolic wing's
    :func:`symvib.symbolic.angle.reference_point` for a declared domain)."""
    if lo < 0.0 < hi:
        return 0.0
    if math.isinf(hi):
        return lo + scale
    if math.isinf(lo):
        return hi - scale
    return (lo + hi) / 2


def run_domain(r: Regular, q0: float, scale: float) -> RunDomain:
    """The domain, length scale and ``F_sigma`` reference point of a run on the regular interval ``r``.

    An end that is a singular point is kept :data:`EDGE_RTOL` (of ``scale``, and of ``|q|``
    beyond 1) inside it, where the kernels are still finite (the engine evaluates them at
    its ends).  Next to a singular point the quadrature's panels (``scale`` wide) would
    converge slowly, so the scale becomes the start's distance to the nearest singular end
    when that is shorter, but no less than :data:`MIN_SCALE_RATIO` of the curve's.

    Parameters
    ----------
    r : Regular
        The regular interval around the start (:func:`interval_in`).
    q0 : float
        The start.
    scale : float
        The curve's ``q_scale`` at the scene's parameter values.
    """
    margin = EDGE_RTOL * scale
    lo = r.lo + margin * max(1.0, abs(r.lo)) if r.lo_reason else r.lo
    hi = r.hi - margin * max(1.0, abs(r.hi)) if r.hi_reason else r.hi
    near = min([abs(q0 - e) for e, why in ((r.lo, r.lo_reason), (r.hi, r.hi_reason)) if why] + [scale])
    run_scale = max(near, MIN_SCALE_RATIO * scale) if near < scale else scale
    narrowed = bool(r.lo_reason or r.hi_reason)
    return RunDomain(lo, hi, run_scale, reference_point(lo, hi, run_scale), narrowed)
