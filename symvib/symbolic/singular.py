"""Singular points of a curve: where its geometry stops being finite and real.

physics.md ("Assumptions", regular curve) asks for ``x``, ``z`` twice
differentiable and ``h > 0`` on the open interval the particle uses, bounded
by the singular points (poles, cusps, the ends of a ``sqrt``).  A run must
never integrate ``F_sigma`` or the time across such a point, so the prepare
step (:mod:`symvib.prepare`) asks this module for the largest open interval around the initial position
on which ``x, z, x', z', h, 1/h, alpha`` and ``kappa`` are all finite and
real, *with the scene's parameter values* (a pole of ``1/(x - a)`` moves with
``a``).

Two searches are combined on a finite window of ``q`` (the declared domain,
cut at :data:`SCAN_HALF_WIDTH` ``q_scale`` from the origin or the initial
position where it is infinite):

* symbolic: :func:`sympy.calculus.util.continuous_domain` of each function,
  in a child process under :data:`SYMBOLIC_SECONDS` (:mod:`symvib.symbolic.budget`);
  it finds exact poles and branch points of elementary functions;
* numeric: the functions evaluated (complex NumPy) on :data:`SCAN_POINTS`
  points of the window; a point where one of them is not finite or not
  real is singular, and the edge of such a region is located by bisection.

This module is on the symbolic side (SymPy).

Examples
--------
>>> from symvib.symbolic.curve import graph
>>> c = graph("x**2 + 1/(x - a)", params=["a"])
>>> r = regular_interval(c, {"a": 0.3}, 0.5, (-float("inf"), float("inf")))
>>> r.lo, r.hi, r.lo_reason
(0.3, inf, 'z is not finite')
"""
from __future__ import annotations

import math
import warnings
from functools import lru_cache

import numpy as np
import sympy as sp

from symvib.regular import CORNER, CUSP, NOT_FINITE, NOT_REAL, SCAN_HALF_WIDTH, Regular, interval_in, scan_window
from symvib.symbolic import budget

__all__ = ["Regular", "regular_interval", "singular_pieces", "geometry", "corners"]

#: Wall-clock budget (seconds) of the symbolic search (continuous_domain of every function).
SYMBOLIC_SECONDS = 5.0
#: Points of the numeric scan over the window.
SCAN_POINTS = 4097
#: Bisection steps locating the edge of a region where the geometry is not finite and real.
BISECT_STEPS = 60
#: The first-order geometry, where an ``Abs``/``sign`` whose argument changes sign may make a corner.
FIRST_ORDER_LABELS = ("x'", "z'", "h", "alpha")
#: One-sided values of a first-order function that differ by more than this (relative to ``h``,
#: and to ``1 + |alpha|`` for ``alpha``) make a corner; evaluated in double precision at the point.
CORNER_RTOL = 1e-8
#: A corner within this distance (relative to ``max(1, |q|)``) of a piece found otherwise is that piece.
MERGE_RTOL = 1e-9
#: Relative imaginary part above which a value counts as not real.
IMAG_RTOL = 1e-12
#: A sign change is a pole when the function, bisected to adjacent doubles, exceeds its
#: values at the grid points around it this many times.
POLE_RATIO = 1e6
#: A local minimum of h below this fraction of h at the grid points around it is a cusp (h
#: computed as sqrt of a difference has a floor near sqrt(eps) there, not 0).
CUSP_RTOL = 1e-6
#: A grid point is searched for a cusp only where h there is at most this fraction of h at the
#: larger of its neighbours: near a cusp ``h ~ c |q - q*|**p`` dips to at most ``3**-p`` of it
#: (0.58 for ``p = 1/2``), while a constant ``h`` (a line, a circle: every point a local minimum
#: within rounding) is not searched 4000 times.
CUSP_DIP = 0.9
#: Steps between the probes of :func:`_levels_off` (each this many times closer to the minimum than
#: the last), and how close the last one comes: this many rounding units of ``q``.  At a cusp
#: ``h ~ c |q - q*|**p`` (``p >= 1/2``) is then still 30 or more times its value at the minimum.
LEVEL_STEP, LEVEL_FLOOR = 10.0, 1e3
#: ``h`` within this factor of its value at the minimum: it has levelled off (a smooth minimum).
LEVEL_RATIO = 2.0
#: :func:`_floor`: ``h`` stopped falling when a probe 10 times closer is not this many times smaller
#: (a power law ``|q - m|**p`` with ``p >= 1/2`` falls 3.16 times or more).
FLOOR_FALL = 2.0
#: A cusp's piece spans at most where ``h`` is within this many times its rounding floor (:func:`_floor`).
FLOOR_MARGIN = 10.0
#: Functions of the geometry searched symbolically (the others only numerically: SymPy is slow on them).
SYMBOLIC_LABELS = ("x", "z", "x'", "z'")


def geometry(curve) -> tuple:
    """``(label, expression)`` of the functions that must be finite and real.

    ``kappa`` is taken as ``alpha' / h`` unsimplified (the cheap form).
    """
    q = curve.q
    xp, zp = sp.diff(curve.x, q), sp.diff(curve.z, q)
    return (("x", curve.x), ("z", curve.z), ("x'", xp), ("z'", zp), ("h", curve.h),
            ("1/h", 1 / curve.h), ("alpha", curve.alpha), ("kappa", sp.diff(curve.alpha, q) / curve.h))


def _substituted(curve, values: dict) -> tuple:
    """The geometry with parameter values substituted exactly (decimal text -> rational)."""
    subs = {p: sp.Rational(repr(float(values[p.name]))) for p in curve.params}
    return tuple((label, e.xreplace(subs)) for label, e in geometry(curve))


def _domain_job(items: list, qname: str, lo: float, hi: float) -> list:
    """Child job: the pieces ``(a, b, label, kind)`` of ``[lo, hi]`` where a function is not continuous.

    A function whose domain SymPy cannot determine is left to the numeric scan.
    """
    from sympy.calculus.util import continuous_domain

    window = sp.Interval(sp.Rational(repr(lo)), sp.Rational(repr(hi)))
    pieces = []
    for label, text in items:
        e = sp.sympify(text)  # srepr made in the parent from a parsed curve, never user text
        q = next((s for s in e.free_symbols if s.name == qname), sp.Symbol(qname, real=True))
        try:
            bad = window - continuous_domain(e, q, window)
        except Exception:  # noqa: BLE001 - NotImplementedError and friends: the scan decides
            continue
        parts = bad.args if isinstance(bad, sp.Union) else (bad,)
        for part in parts:
            if isinstance(part, sp.FiniteSet):
                pieces += [(float(p), float(p), label, NOT_FINITE) for p in part if p.is_real]
            elif isinstance(part, sp.Interval):
                pieces.append((float(part.inf), float(part.sup), label, NOT_REAL))
            elif part is not sp.S.EmptySet:
                return [("unknown", None, label, "")]
    return pieces


def _symbolic(items, qname, lo, hi) -> list:
    outcome = budget.run(_domain_job, (items, qname, lo, hi), seconds=SYMBOLIC_SECONDS)
    if outcome.status != "ok" or any(p[0] == "unknown" for p in outcome.value):
        return []
    return list(outcome.value)


def _bad(fns, q: np.ndarray) -> np.ndarray:
    """Label index (+1) of the first function not finite and real at each point, 0 where all are."""
    out = np.zeros(q.shape, dtype=int)
    z = q.astype(complex)
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        for i, fn in enumerate(fns):
            try:
                v = np.broadcast_to(np.asarray(fn(z), dtype=complex), q.shape)
            except Exception:  # noqa: BLE001 - a function NumPy cannot evaluate is not checked
                continue
            bad = ~np.isfinite(v) | (np.abs(v.imag) > IMAG_RTOL * (1.0 + np.abs(v.real)))
            out = np.where((out == 0) & bad, i + 1, out)
    return out


def _numeric(labels, fns, lo, hi) -> list:
    """Pieces ``(a, b, label, kind)`` where the scan finds a function not finite, not real, or a pole."""
    grid = np.linspace(lo, hi, SCAN_POINTS)
    flags = _bad(fns, grid)
    pieces = []
    i = 0
    while i < grid.size:
        if not flags[i]:
            i += 1
            continue
        j = i
        while j + 1 < grid.size and flags[j + 1]:
            j += 1
        a = grid[i] if i == 0 else _edge(fns, grid[i - 1], grid[i])
        b = grid[j] if j == grid.size - 1 else _edge(fns, grid[j + 1], grid[j])
        pieces.append((float(a), float(b), labels[flags[i] - 1], NOT_REAL))
        i = j + 1
    return pieces + _poles(labels, fns, grid, flags)


def _edge(fns, good: float, bad: float) -> float:
    """The boundary between a regular point and a singular one, by bisection (returns the singular side)."""
    for _ in range(BISECT_STEPS):
        mid = 0.5 * (good + bad)
        if mid in (good, bad):
            break
        if _bad(fns, np.array([mid]))[0]:
            bad = mid
        else:
            good = mid
    return bad


def _real(fn, q: np.ndarray) -> np.ndarray:
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        try:
            return np.broadcast_to(np.asarray(fn(q.astype(complex)), dtype=complex), q.shape).real
        except Exception:  # noqa: BLE001 - a function NumPy cannot evaluate is not checked
            return np.full(q.shape, np.nan)


def _poles(labels, fns, grid, flags) -> list:
    """Poles between regular grid points: a sign change of a function that grows without bound.

    A pole of ``z`` of any order is a pole of odd order of ``z`` or of ``z'``,
    where the function changes sign; the change is bisected to adjacent
    doubles, and it is a pole when the function there exceeds the grid's
    values :data:`POLE_RATIO` times (at a zero it vanishes instead).  A cusp
    (``h -> 0`` without changing sign) is a local minimum of ``h`` that
    golden-section search drives below :data:`CUSP_RTOL` of ``h`` at the grid points around it.
    """
    pieces = []
    ok = flags == 0
    for label, fn in zip(labels, fns):
        v = _real(fn, grid)
        change = np.flatnonzero(ok[:-1] & ok[1:] & (np.sign(v[:-1]) * np.sign(v[1:]) < 0.0))  # (no overflow)
        a, b = _bisect_sign_changes(fn, grid[change], grid[change + 1], v[change])
        ends_a, ends_b = _real(fn, a), _real(fn, b)
        size = np.maximum(np.maximum(np.abs(v[change]), np.abs(v[change + 1])), np.finfo(float).tiny)
        with np.errstate(invalid="ignore"):
            pole = ~(np.isfinite(ends_a) & np.isfinite(ends_b)) | \
                (np.minimum(np.abs(ends_a), np.abs(ends_b)) > POLE_RATIO * size)
        pieces += [(float(a[i]), float(b[i]), label, NOT_FINITE) for i in np.flatnonzero(pole)]
        if label == "h":
            pieces += _cusps(fn, grid, v, ok, _speed(labels, fns))
    return pieces


def _bisect_sign_changes(fn, a: np.ndarray, b: np.ndarray, fa: np.ndarray) -> tuple:
    """Each sign change of ``fn`` in ``[a_i, b_i]`` (``fn(a_i) = fa_i``) bisected to adjacent doubles,
    all at once (one evaluation of ``fn`` per step: a curve that oscillates a million times has
    thousands of changes on the scan grid); where ``fn`` is not finite or 0 at a midpoint, both
    ends stop there.  Returns the final ``(a, b)``."""
    a, b, fa = a.copy(), b.copy(), fa.copy()
    active = np.ones(a.shape, dtype=bool)
    for _ in range(BISECT_STEPS * 2):
        if not active.any():
            break
        mid = 0.5 * (a + b)
        active &= (mid != a) & (mid != b)
        fm = _real(fn, mid)
        stop = active & (~np.isfinite(fm) | (fm == 0.0))
        a[stop] = b[stop] = mid[stop]
        active &= ~stop
        left = active & ((fm < 0.0) == (fa < 0.0))
        a[left], fa[left] = mid[left], fm[left]
        right = active & ~left
        b[right] = mid[right]
    return a, b


def _speed(labels, fns):
    """``hypot(x', z')`` from the components (no rounding floor near a cusp, where ``h`` written as
    the square root of a difference keeps about ``sqrt(eps)``), or None without them."""
    named = dict(zip(labels, fns))
    if "x'" not in named or "z'" not in named:
        return None
    return lambda q: np.hypot(_real(named["x'"], q), _real(named["z'"], q))


def _golden_minimum(fn, a: float, b: float) -> float:
    """A local minimum of ``fn`` in ``[a, b]`` by golden-section search, to adjacent doubles."""
    ratio = (math.sqrt(5.0) - 1.0) / 2.0
    for _ in range(BISECT_STEPS * 2):
        c, d = b - ratio * (b - a), a + ratio * (b - a)
        if not a < c < d < b:
            break
        fc, fd = _real(fn, np.array([c, d]))
        if fc <= fd:
            b = d
        else:
            a = c
    return 0.5 * (a + b)


def _cusps(fn, grid, v, ok, speed=None) -> list:
    """Points where ``h`` has a local minimum that reaches 0 (cusps), by golden-section search; with
    ``speed`` (``h`` from its components) a minimum where the speed levels off above 0 is none
    (:func:`_levels_off`)."""
    out = []
    inside = (ok[:-2] & ok[1:-1] & ok[2:] & (v[1:-1] <= v[:-2]) & (v[1:-1] <= v[2:])
              & (v[1:-1] <= CUSP_DIP * np.maximum(v[:-2], v[2:])))
    for j in np.flatnonzero(inside) + 1:
        m = _golden_minimum(fn, grid[j - 1], grid[j + 1])
        small = CUSP_RTOL * max(v[j - 1], v[j + 1])
        if abs(_real(fn, np.array([m]))[0]) > small:
            continue
        if speed is not None:
            m_speed = _golden_minimum(speed, grid[j - 1], grid[j + 1])
            if _levels_off(speed, m_speed, abs(speed(np.array([m_speed]))[0]), grid[j + 1] - grid[j]):
                continue
        # h is at rounding level on a small interval around the cusp: keep all of it.  Rounding level
        # is measured near the cusp too (_floor): the grid's neighbours of a cusp at a length far
        # below the grid's spacing see h at millions of times its local scale.
        small = min(small, FLOOR_MARGIN * _floor(fn, m, grid[j + 1] - grid[j]))
        edges = []
        for far in (grid[j - 1], grid[j + 1]):
            near = m
            for _ in range(BISECT_STEPS * 2):
                mid = 0.5 * (near + far)
                if mid in (near, far):
                    break
                if abs(_real(fn, np.array([mid]))[0]) > small:
                    far = mid
                else:
                    near = mid
            edges.append(far)
        out.append((float(edges[0]), float(edges[1]), "h", CUSP))
    return out


def _floor(fn, m: float, spacing: float) -> float:
    """The rounding floor of ``h`` at a cusp ``m``: ``max |h(m +- d)|`` at the probe ``d`` (from
    ``spacing`` down, each :data:`LEVEL_STEP` times closer) where it stops falling by at least
    :data:`FLOOR_FALL`, or at the last probe (a few rounding units of ``m``) if it never does.

    Near a cusp ``h ~ c |q - m|**p`` with ``p >= 1/2`` falls by ``10**p >= 3.16`` a probe until
    rounding, so the floor is where the power law breaks: about ``sqrt(eps)`` of ``h``'s terms
    for ``h`` written as the square root of a difference, and next to nothing for ``h`` computed
    without cancellation (the semicubical parabola's ``|q| sqrt(9 q**2 + 4)``).
    """
    before = math.inf
    for step in _probes(m, spacing):
        now = float(np.max(np.abs(_real(fn, np.array([m - step, m + step])))))
        if not now * FLOOR_FALL <= before:
            return before
        before = now
    return before


def _probes(m: float, spacing: float):
    """Distances from ``m`` closing in on it: ``spacing / LEVEL_STEP``, each :data:`LEVEL_STEP` times
    closer than the last, down to :data:`LEVEL_FLOOR` rounding units of ``m``."""
    last = LEVEL_FLOOR * np.spacing(max(1.0, abs(m)))
    step = spacing / LEVEL_STEP
    while step >= last:
        yield step
        step /= LEVEL_STEP


def _levels_off(fn, m: float, h_m: float, spacing: float) -> bool:
    """Whether the speed ``fn`` comes within :data:`LEVEL_RATIO` of its minimum ``h_m`` (at ``m``) on
    both sides somewhere between ``spacing`` and :data:`LEVEL_FLOOR` rounding units of ``m``: a
    smooth minimum above 0, not a cusp.

    The grid's test (``h_m`` far below ``h`` at the neighbouring grid points) cannot tell the two
    apart where ``h`` varies on a length far below the grid's spacing: a user curve whose
    parameters are micrometres, scanned with ``q_scale = 1``, has ``h`` at the grid points a
    million times its value at a minimum of ``h = sqrt(1 + z'^2) >= 1``.  Near a cusp the speed
    from its components keeps falling towards ``h_m`` as the probes close in, down to rounding.
    """
    for step in _probes(m, spacing):
        around = np.abs(_real(fn, np.array([m - step, m + step])))
        if np.all(around <= LEVEL_RATIO * h_m):
            return True
    return False


def _corners(items, qsym, labels, fns, lo: float, hi: float) -> list:
    """Corners: points where the argument of an ``Abs``/``sign`` of the first-order geometry changes
    sign (between regular points of the scan) and a first-order function is discontinuous.

    At such a point ``q*`` each side is an analytic expression: every ``Abs(w)`` is ``+-w`` and
    every ``sign(w)`` is ``+-1`` with the sign ``w`` has just left or right of ``q*``.  Both are
    evaluated at ``q*``: where ``x', z', h`` and ``alpha`` agree (``z = abs(x)**3``, ``z =
    x*abs(x)``: the slope is continuous, only a higher derivative jumps) the point is regular;
    where one differs by more than :data:`CORNER_RTOL` the tangent or the speed jumps (``z =
    abs(x)``), which the model (physics.md, "Assumptions", regular curve) does not cover, so it
    bounds the run's interval like a cusp.
    """
    first = [(label, e) for label, e in items if label in FIRST_ORDER_LABELS]
    atoms = sorted({a for _, e in first for a in e.atoms(sp.Abs, sp.sign)}, key=sp.default_sort_key)
    if not atoms:
        return []
    grid = np.linspace(lo, hi, SCAN_POINTS)
    ok = _bad(fns, grid) == 0
    args = sorted({a.args[0] for a in atoms}, key=sp.default_sort_key)
    arg_fns = [sp.lambdify([qsym], w, "numpy") for w in args]
    out = []
    for fn in arg_fns:
        v = _real(fn, grid)
        sign = np.sign(v)
        idx = np.flatnonzero(ok & np.isfinite(v) & (sign != 0))
        for i, k in zip(idx[:-1], idx[1:]):
            if sign[i] == sign[k] or not ok[i:k + 1].all():
                continue
            a, b = (grid[i + 1], grid[k - 1]) if k > i + 1 else _sign_change(fn, grid[i], grid[k], v[i])
            jump = _jump(first, atoms, args, arg_fns, qsym, 0.5 * (a + b), 0.5 * (grid[i] + a),
                         0.5 * (b + grid[k]))
            if jump:
                out.append((float(a), float(b), jump, CORNER))
    return out


def _value(fn, point: float) -> float:
    """``fn(point)`` in real arithmetic (``atan2`` takes no complex argument), else the real part of
    its complex value; NaN when neither can be computed."""
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        try:
            value = float(np.asarray(fn(np.float64(point)), dtype=float))
        except Exception:  # noqa: BLE001 - e.g. a real sqrt of a negative: try complex below
            value = math.nan
    return value if math.isfinite(value) else float(_real(fn, np.array([point]))[0])


def _sign_change(fn, a: float, b: float, fa: float) -> tuple:
    """The bracket ``(a, b)`` of adjacent doubles around a sign change of ``fn`` (bisection)."""
    for _ in range(BISECT_STEPS * 2):
        mid = 0.5 * (a + b)
        if mid in (a, b):
            break
        fm = _real(fn, np.array([mid]))[0]
        if fm == 0.0 or not np.isfinite(fm):
            return mid, mid
        if (fm < 0.0) == (fa < 0.0):
            a, fa = mid, fm
        else:
            b = mid
    return a, b


def _jump(first, atoms, args, arg_fns, qsym, at: float, left: float, right: float) -> str:
    """The label of the first first-order function whose one-sided values at ``at`` differ ("" if none)."""
    sides = []
    for point in (left, right):
        signs = {w: (1 if s >= 0 else -1) for w, s in
                 zip(args, (_real(fn, np.array([point]))[0] for fn in arg_fns))}
        rep = {a: signs[a.args[0]] * (a.args[0] if isinstance(a, sp.Abs) else 1) for a in atoms}
        values = {}
        for label, e in first:
            values[label] = _value(sp.lambdify([qsym], e.xreplace(rep), "numpy"), at)
        sides.append(values)
    lhs, rhs = sides
    scale = max(abs(lhs.get("h", 0.0)), abs(rhs.get("h", 0.0)))
    if not (np.isfinite(scale) and scale > 0.0):
        return "h"
    for label, _ in first:
        size = 1.0 + abs(lhs[label]) if label == "alpha" else scale
        if not abs(lhs[label] - rhs[label]) <= CORNER_RTOL * size:  # a NaN counts as a jump
            return label
    return ""


@lru_cache(maxsize=64)
def singular_pieces(curve, values: tuple, lo: float, hi: float) -> tuple:
    """Sorted pieces ``(a, b, label, kind)`` of ``[lo, hi]`` where the curve is not regular.

    ``values`` is a tuple of ``(name, value)`` of the parameters.  A piece is
    a closed interval holding the singular set: a pole or a cusp (``kind =
    NOT_FINITE``, ``[a, b]`` the bracket of adjacent doubles around it, or
    ``a == b`` when exact), a corner (``CORNER``, :func:`_corners`), or a region
    where a function is not real (``NOT_REAL``).  ``label`` names the function (``"z"``, ``"h"``, ``"kappa"``).
    """
    items = _substituted(curve, dict(values))
    labels = [label for label, _ in items]
    symbolic = _symbolic([(label, sp.srepr(e)) for label, e in items if label in SYMBOLIC_LABELS],
                         curve.q.name, lo, hi)
    fns = [sp.lambdify([curve.q], e, "numpy") for _, e in items]
    pieces = symbolic + _numeric(labels, fns, lo, hi)
    for corner in _corners(items, curve.q, labels, fns, lo, hi):
        near = MERGE_RTOL * max(1.0, abs(corner[0]))
        if not any(a - near <= corner[0] and corner[1] <= b + near for a, b, _, _ in pieces):
            pieces.append(corner)
    order = {label: i for i, label in enumerate(labels)}
    return tuple(sorted(pieces, key=lambda p: (p[0], p[1], order[p[2]], p[3])))


def corners(curve, values: dict | None = None) -> tuple:
    """The corners (kinks) of ``curve`` on its declared domain: ``(q, label)`` of each.

    At a corner (``abs(x)`` at 0) the first-order geometry jumps, so the derivation's
    ``alpha'`` and ``kappa`` hold a ``DiracDelta`` there: eqs. 1-2 hold on each side of it,
    never across.  An infinite end of the domain is cut at :data:`SCAN_HALF_WIDTH` ``q_scale``.

    Parameters
    ----------
    curve : symvib.symbolic.curve.Curve
    values : dict, optional
        Parameter values by name (default: every parameter 1).

    Returns
    -------
    tuple of (float, str)
        Each corner's position and the function that jumps there (``"z'"``).
    """
    values = {p.name: 1.0 for p in curve.params} if values is None else values
    subs = {p: values[p.name] for p in curve.params}
    scale = abs(float(sp.N(sp.sympify(curve.q_scale).subs(subs))))
    ends = []
    for end, sign in zip(curve.domain, (-1, 1)):
        ends.append(sign * SCAN_HALF_WIDTH * scale if end.is_infinite else float(sp.N(end.subs(subs))))
    pieces = singular_pieces(curve, tuple(sorted(values.items())), *ends)
    return tuple(((a + b) / 2, label) for a, b, label, kind in pieces if kind == CORNER)


def regular_interval(curve, values: dict, q0: float, domain: tuple, *, reach=()) -> Regular:
    """The largest open interval around ``q0`` inside ``domain`` free of singular points.

    Parameters
    ----------
    curve : Curve
    values : dict of str -> float
        The scene's parameter values.
    q0 : float
        The initial position.
    domain : (float, float)
        The declared domain, with the scene's values (ends may be infinite).
    reach : iterable of float
        Further points the window must cover (the limiters).

    Returns
    -------
    Regular
        ``at_start`` names the function that fails when ``q0`` itself is singular.
    """
    lo, hi = (float(v) for v in domain)
    scale = float(curve.q_scale.subs({p: values[p.name] for p in curve.params}))
    key = tuple((p.name, float(values[p.name])) for p in curve.params)
    return interval_in(singular_pieces(curve, key, *scan_window(lo, hi, scale, [q0, *reach])), q0, lo, hi)
