"""Curves in the vertical plane and their geometry (physics.md, "Geometry").

A curve is given as a graph ``z = f(x)`` (coordinate ``q = x``) or
parametrically ``x(q), z(q)``.  Everything else follows from ``x(q)`` and
``z(q)`` (primes are ``d/dq``):

* metric ``h = sqrt(x'**2 + z'**2)``, ``ds = h dq``;
* tangent angle ``alpha`` with ``h sin(alpha) = z'`` and ``h cos(alpha) = x'``;
* curvature ``kappa = alpha' / h``.

Expressions may be SymPy objects or strings; strings go through the safe
parser :func:`symvib.expr.parse` and never through ``eval``/``sympify``.

Examples
--------
>>> c = parametric("R*(phi + sin(phi))", "R*(1 - cos(phi))", q="phi",
...                h="2*R*cos(phi/2)", alpha="phi/2", domain=("-pi", "pi"))
>>> c.kappa
1/(4*R*cos(phi/2))
>>> graph("x**2/(2*p)").alpha
atan(x/p)
"""
from __future__ import annotations

import keyword
import math
import random
from dataclasses import dataclass, field, replace
from functools import cached_property

import mpmath
import numpy as np
import sympy as sp

from symvib import expr as _expr
from symvib.symbolic import budget
from symvib.symbolic.symbols import RESERVED

__all__ = ["Curve", "CurveError", "graph", "parametric", "to_sympy", "sample_points", "reference_point",
           "generic_branch", "tangent_angle", "angle_jump", "removable_form", "tamed", "far_points"]

#: Parameter assumptions a curve may declare.
ASSUMPTIONS = {
    "positive": {"positive": True},
    "real": {"real": True},
    "nonnegative": {"nonnegative": True},
    "negative": {"negative": True},
}
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

_FUNCTIONS = {
    "sin": sp.sin, "cos": sp.cos, "tan": sp.tan, "asin": sp.asin, "acos": sp.acos,
    "atan": sp.atan, "atan2": sp.atan2, "sinh": sp.sinh, "cosh": sp.cosh, "tanh": sp.tanh,
    "asinh": sp.asinh, "acosh": sp.acosh, "atanh": sp.atanh, "exp": sp.exp, "log": sp.log,
    "sqrt": sp.sqrt, "abs": sp.Abs,
}
_CONSTANTS = {"pi": sp.pi, "e": sp.E}
_BINARY = {
    "+": lambda a, b: a + b,
    "-": lambda a, b: a - b,
    "*": lambda a, b: a * b,
    "/": lambda a, b: a / b,
    "**": lambda a, b: a**b,
}


class CurveError(ValueError):
    """A curve definition was rejected; the message says what to fix."""


#: Random points at which the two sides of an ``Eq`` condition are compared to tell a
#: measure-zero condition from one that holds identically (:func:`generic_branch`).
NULL_CHECK_POINTS = 3
#: ``|lhs - rhs|`` below this at every point (30 digits): the ``Eq`` holds identically.
NULL_CHECK_TOLERANCE = mpmath.mpf("1e-20")
#: What :func:`generic_branch` decides about a condition.
_GENERIC, _NULL = "generic", "null"


def generic_branch(expr: sp.Expr, field: str = "expression") -> sp.Expr:
    """``expr`` with every ``Piecewise`` replaced by its generic branch and every ``DiracDelta`` by 0.

    SymPy writes ``Piecewise((a, Eq(cos(phi), 0)), (b, True))`` when it simplifies
    the derivative of ``Abs(cos(phi))/cos(phi)**4``, and ``DiracDelta`` when it
    differentiates ``sign``.  A kernel module holds no conditional (the whitelist of
    :mod:`symvib.numeric.kernels` refuses ``if``/``==``), so each ``Piecewise`` is
    decided here, once, symbolically: a branch whose condition is an equality (``Eq``,
    or a conjunction with one, a set of measure zero on the real line) is dropped, and
    the first branch whose condition holds almost everywhere (``True``, ``Ne``, or a
    disjunction with one) is the value.

    Why this is sound: the kernels are evaluated on the open regular domain of the
    curve (:mod:`symvib.symbolic.singular`), and a point where an equality holds is
    there either a singular point, which bounds the domain and is never evaluated
    (``cos(phi) = 0`` on the parabola in its tangent angle), or a removable value of a
    function that is continuous through it, where the generic branch has the same
    limit (the derivative of ``x*Abs(x)`` at 0).  In both cases the generic branch is
    the function on the domain up to a set of measure zero, which quadratures and root
    finders never see.  An ``Eq`` that holds identically is no such set: it is checked
    at :data:`NULL_CHECK_POINTS` random points and refused.  ``DiracDelta`` vanishes
    off such a set: it is 0.  An equality in the parameters only (``Eq(a, 0)`` for a
    real parameter) holds for one value of ``a``: there the generic branch is not
    finite and a run ends ``non_finite``, never silently wrong.

    Parameters
    ----------
    expr : sympy.Expr
    field : str
        What ``expr`` is (named in the error).

    Returns
    -------
    sympy.Expr
        Without ``Piecewise`` or ``DiracDelta``.

    Raises
    ------
    CurveError
        When a condition is an inequality (``q > 0``): which branch applies depends
        on where the run is, so the kernels would need a conditional.

    Examples
    --------
    >>> phi = sp.Symbol("phi", real=True)
    >>> generic_branch(sp.Piecewise((4 * sp.sin(phi), sp.Eq(sp.cos(phi), 0)), (3 * sp.sin(phi), True)))
    3*sin(phi)
    >>> generic_branch(sp.diff(sp.sign(phi), phi) + 1)
    1
    """
    if not isinstance(expr, sp.Basic) or not expr.has(sp.Piecewise, sp.DiracDelta):
        return expr
    expr = expr.replace(lambda e: isinstance(e, sp.DiracDelta), lambda e: sp.Integer(0))

    def decide(pw):
        for value, cond in pw.args:
            kind = _condition_kind(cond, field)
            if kind == _GENERIC:
                return value
            if kind != _NULL:
                raise CurveError(f"{field}: SymPy gives a Piecewise on the condition {cond}, which depends on "
                                 "where the particle is, and a kernel holds no conditional; give a simpler "
                                 "verified form as a hint (curve.h / curve.alpha) or write the curve without it")
        raise CurveError(f"{field}: every branch of {sp.sstr(pw)[:80]} holds only on a set of measure zero")

    return expr.replace(lambda e: isinstance(e, sp.Piecewise), decide)


def removable_form(expr: sp.Expr) -> sp.Expr:
    """``expr`` with ``Abs(u) = u sign(u)`` where an ``Abs`` stands in a denominator, common factors taken out.

    The generic branch of a derivative often divides by something that vanishes
    with ``|u|`` where the function has a removable value: ``kappa = 2 q**2 / ((1 +
    q**4)**(3/2) |q|)`` for ``z = |q|**3/3`` is ``0/0`` at ``q = 0``, a point a kernel
    may well be evaluated at (a grid point, the middle of two limiters).  Written with
    ``|q| = q sign(q)`` and its common factors taken out (:func:`sympy.factor_terms`),
    SymPy cancels it to ``2 q / ((1 + q**4)**(3/2) sign(q))``, which the kernels
    evaluate with ``sign(0)`` printed as ``copysign(1, 0) = 1``: finite, and the limit
    from the right where the function jumps (``z = x abs(x)``: ``z'' = 2 sign(x)``).
    So is ``|u| / u`` (``z = x abs(x) + x**2``: ``kappa = 2 |q| / (q (4 q**2 + 1)**(3/2)) + ...``):
    ``sign(u)``.  An expression with ``Abs`` in numerators only, over denominators without
    its argument, is left as it is.

    Examples
    --------
    >>> q = sp.Symbol("q", real=True)
    >>> removable_form(q**2 / sp.Abs(q)), removable_form(sp.Abs(q) / sp.cos(q)), removable_form(sp.Abs(q) / q)
    (q/sign(q), Abs(q)/cos(q), sign(q))
    >>> removable_form((q + sp.Abs(q)) / (q * (1 + q * sp.Abs(q))))
    (sign(q) + 1)/(q**2*sign(q) + 1)
    """
    if not isinstance(expr, sp.Basic) or not expr.has(sp.Abs):
        return expr
    denominators = {p.base for p in expr.atoms(sp.Pow) if p.exp.is_negative}
    arguments = {a.args[0] for a in expr.atoms(sp.Abs)}
    if not (any(b.has(sp.Abs) for b in denominators) or arguments & denominators):
        return expr
    rewritten = expr.replace(lambda e: isinstance(e, sp.Abs), lambda e: e.args[0] * sp.sign(e.args[0]))
    try:
        return sp.factor_terms(rewritten)
    except Exception:  # noqa: BLE001 - factoring is optional; the rewritten form is equal
        return rewritten


def _condition_kind(cond, field: str) -> str | None:
    """``_GENERIC`` (holds almost everywhere), ``_NULL`` (a set of measure zero) or ``None`` (neither)."""
    if cond is sp.true:
        return _GENERIC
    if cond is sp.false:
        return _NULL
    if isinstance(cond, sp.Eq):
        return _NULL if not _holds_identically(cond.lhs - cond.rhs) else _GENERIC
    if isinstance(cond, sp.Ne):
        return _GENERIC if not _holds_identically(cond.lhs - cond.rhs) else _NULL
    if isinstance(cond, sp.Not):
        inner = _condition_kind(cond.args[0], field)
        return {_GENERIC: _NULL, _NULL: _GENERIC}.get(inner)
    if isinstance(cond, (sp.And, sp.Or)):
        kinds = [_condition_kind(a, field) for a in cond.args]
        strong, weak = (_NULL, _GENERIC) if isinstance(cond, sp.And) else (_GENERIC, _NULL)
        if strong in kinds:
            return strong
        return weak if all(k == weak for k in kinds) else None
    return None


def _holds_identically(difference) -> bool:
    """Whether ``difference`` is zero at :data:`NULL_CHECK_POINTS` random real points (30 digits)."""
    rng = random.Random(5)
    symbols = sorted(difference.free_symbols, key=lambda s: s.name)
    with mpmath.workdps(CHECK_DIGITS):
        for _ in range(NULL_CHECK_POINTS):
            subs = {s: sp.Float(0.5 + 1.5 * rng.random(), CHECK_DIGITS) for s in symbols}
            value = sp.N(difference.subs(subs), CHECK_DIGITS)
            if not (value.is_number and abs(value) < NULL_CHECK_TOLERANCE):
                return False
    return True


def to_sympy(parsed: _expr.Parsed, symbols: dict) -> sp.Expr:
    """Convert a safely parsed expression tree to SymPy.

    Decimal literals become exact rationals (``0.05 -> 1/20``) so that
    identities can be proven symbolically.
    """

    def conv(node):
        kind = node[0]
        if kind == "num":
            text = node[1]
            return sp.Integer(text) if text.isdigit() else sp.Rational(text)
        if kind == "const":
            return _CONSTANTS[node[1]]
        if kind == "sym":
            return symbols[node[1]]
        if kind == "neg":
            return -conv(node[1])
        if kind == "bin":
            a, b = conv(node[2]), conv(node[3])
            return _BINARY[node[1]](a, b)
        return _FUNCTIONS[node[1]](*(conv(a) for a in node[2:]))

    return conv(parsed.tree)


@dataclass(frozen=True)
class Curve:
    """A curve ``x(q), z(q)`` with its verified geometry.

    Build one with :func:`graph` or :func:`parametric`, not directly.

    Attributes
    ----------
    name : str
    kind : {"graph", "parametric"}
    q : sympy.Symbol
        The generalized coordinate.
    x, z : sympy.Expr
        Position on the curve, ``z`` up.
    params : tuple of sympy.Symbol
        Free parameters (lengths, usually positive), in declaration order.
    domain : tuple of sympy.Expr
        Open interval of ``q`` on which the parametrization is regular (``h > 0``).
    h, alpha : sympy.Expr
        Metric and tangent angle (:func:`tangent_angle`).
    q_scale : sympy.Expr
        A characteristic length of ``q`` (sampling windows, quadrature panels).
    source : tuple of (str, str)
        The defining texts, for generated-file headers and hashing.
    alpha_cut : bool
        ``True`` when ``alpha`` is ``atan2(z', x')``, no continuous closed form having
        been found: it jumps by ``2 pi`` where the tangent crosses the negative ``x``
        direction (``x' < 0`` and ``z'`` changing sign), and a run must not integrate
        across such a point as if it were continuous.  ``False`` when ``alpha`` is
        continuous wherever the curve is regular.
    """

    name: str
    kind: str
    q: sp.Symbol
    x: sp.Expr
    z: sp.Expr
    params: tuple
    domain: tuple
    h: sp.Expr
    alpha: sp.Expr
    q_scale: sp.Expr
    source: tuple = field(default=(), compare=False)
    alpha_cut: bool = False

    # --- derived geometry (physics.md, "Geometry") ---------------------------------
    @cached_property
    def xp(self) -> sp.Expr:
        """``x'(q)``."""
        return sp.diff(self.x, self.q)

    @cached_property
    def zp(self) -> sp.Expr:
        """``z'(q)``."""
        return sp.diff(self.z, self.q)

    @cached_property
    def hp(self) -> sp.Expr:
        """``h'(q)`` (its generic branch: :func:`generic_branch`)."""
        raw = sp.diff(self.h, self.q)
        return removable_form(generic_branch(tamed(budget.simplify(raw), raw, self), f"curve '{self.name}': h'"))

    @cached_property
    def alphap(self) -> sp.Expr:
        """``alpha'(q) = (x' z'' - z' x'') / h**2`` (its generic branch)."""
        raw = sp.diff(self.alpha, self.q)
        return removable_form(generic_branch(tamed(budget.simplify(raw), raw, self), f"curve '{self.name}': alpha'"))

    @cached_property
    def kappa(self) -> sp.Expr:
        """Curvature ``kappa = alpha' / h`` (its generic branch)."""
        raw = self.alphap / self.h
        return removable_form(generic_branch(tamed(budget.simplify(raw), raw, self), f"curve '{self.name}': kappa"))

    @property
    def coordinate(self) -> str:
        return self.q.name

    @cached_property
    def qdot(self) -> sp.Symbol:
        """The generalized velocity symbol (``phidot`` for ``q = phi``)."""
        return sp.Symbol(self.q.name + "dot", real=True)

    @cached_property
    def qddot(self) -> sp.Symbol:
        """The generalized acceleration symbol."""
        return sp.Symbol(self.q.name + "ddot", real=True)

    def latex_names(self) -> dict:
        """Symbol -> LaTeX name map for printing in the paper's style."""
        base = _greek(self.q.name)
        return {
            self.q: base,
            self.qdot: rf"\dot{{{base}}}",
            self.qddot: rf"\ddot{{{base}}}",
            **{p: _greek(p.name) for p in self.params},
        }

    def sample_points(self, n: int, *, seed: int = 0, margin: float = 0.1) -> list:
        """``n`` reproducible random values of ``q`` inside the domain (as mpmath numbers)."""
        return sample_points(self, n, seed=seed, margin=margin)

    def default_values(self) -> dict:
        """A value of 1 for every parameter (used for sampling when none are given)."""
        return {p: sp.Integer(1) for p in self.params}


def _greek(name: str) -> str:
    greek = {"phi": r"\varphi", "theta": r"\theta", "psi": r"\psi", "alpha": r"\alpha",
             "beta": r"\beta", "gamma": r"\gamma", "delta": r"\delta", "lambda_": r"\lambda",
             "rho": r"\rho", "tau": r"\tau", "chi": r"\chi", "xi": r"\xi", "eta": r"\eta"}
    return greek.get(name, name)


def sample_points(curve: Curve, n: int, *, seed: int = 0, margin: float = 0.1, values=None) -> list:
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


def far_points(curve: Curve, values=None) -> list:
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


def _finite_at(expr: sp.Expr, curve: Curve, points, values) -> np.ndarray:
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


def tamed(simplified: sp.Expr, raw: sp.Expr, curve: Curve) -> sp.Expr:
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


def identity_holds(expr: sp.Expr, curve: Curve, *, extra=None, points: int = IDENTITY_CHECK_POINTS,
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


def numeric_zero(expr: sp.Expr, curve: Curve, *, extra=None, points: int = IDENTITY_CHECK_POINTS,
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


# --- a continuous tangent angle ------------------------------------------------------
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


def tangent_angle(curve: Curve):
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


def reference_point(curve: Curve) -> sp.Expr:
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


def _accepted(candidate: sp.Expr, curve: Curve, q0: sp.Expr):
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


def angle_jump(alpha: sp.Expr, curve: Curve, values: dict):
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


# --- construction -------------------------------------------------------------------
def _check_name(what: str, name) -> None:
    """A coordinate or parameter name is a plain identifier: not a Python keyword and not
    starting with ``_`` (``__class__``, ``_Q``: the generated modules' own names start so)."""
    if not isinstance(name, str) or not name.isidentifier():
        raise CurveError(f"{what} name {name!r} is not a valid identifier")
    if keyword.iskeyword(name) or name.startswith("_"):
        raise CurveError(f"{what} name {name!r} is a Python keyword or starts with '_'; use a plain name")


def _symbol_table(coordinate: str, params) -> tuple:
    """Coordinate and parameter symbols, validated against the expressions."""
    _check_name("coordinate", coordinate)
    if coordinate in RESERVED:
        raise CurveError(f"coordinate name '{coordinate}' is reserved ({', '.join(sorted(RESERVED))} are)")
    q = sp.Symbol(coordinate, real=True)
    declared: dict[str, dict]
    if params is None:
        declared = None
    elif isinstance(params, dict):
        declared = {}
        for name, assumption in params.items():
            if assumption not in ASSUMPTIONS:
                raise CurveError(f"parameter '{name}': assumption {assumption!r} is not one of "
                                 f"{', '.join(ASSUMPTIONS)}")
            declared[name] = ASSUMPTIONS[assumption]
    else:
        declared = {name: ASSUMPTIONS["positive"] for name in params}
    for name in declared or ():
        _check_name("parameter", name)
        if name in RESERVED:
            raise CurveError(f"parameter name '{name}' is reserved for the physics "
                             f"({', '.join(sorted(RESERVED))} are); rename it")
        if name == coordinate:
            raise CurveError(f"parameter '{name}' has the name of the coordinate")
    return q, declared


def _parse_all(texts: dict, q: sp.Symbol, declared, field_prefix: str) -> tuple:
    """Parse the defining expressions; infer parameters when none are declared."""
    parsed = {}
    for key, text in texts.items():
        if text is None:
            continue
        if isinstance(text, sp.Basic):
            parsed[key] = text
            continue
        # Every plain identifier is taken as a symbol here; names are checked
        # against the declared parameters below, with a message that says so.
        parsed[key] = _parse_inferring(text, q.name, f"{field_prefix}{key}")
    names = set()
    for value in parsed.values():
        if isinstance(value, sp.Basic):
            names |= {s.name for s in value.free_symbols}
        else:
            names |= set(value.symbols)
    names.discard(q.name)
    for name in sorted(names):
        if name in RESERVED:
            raise CurveError(f"symbol '{name}' in the curve is reserved for the physics "
                             f"({', '.join(sorted(RESERVED))} are); rename it")
    if declared is None:
        declared = {name: ASSUMPTIONS["positive"] for name in sorted(names)}
    else:
        unknown = sorted(names - set(declared))
        if unknown:
            raise CurveError(f"unknown parameter name(s) {', '.join(unknown)}: declare them in params "
                             f"(declared: {', '.join(declared) or 'none'})")
    params = tuple(sp.Symbol(name, **assume) for name, assume in declared.items())
    table = {q.name: q, **{p.name: p for p in params}}
    out = {}
    for key, value in parsed.items():
        if isinstance(value, sp.Basic):
            out[key] = value.xreplace({s: table[s.name] for s in value.free_symbols if s.name in table})
        else:
            out[key] = to_sympy(value, table)
    return params, out


def _parse_inferring(text, coordinate, field):
    """Parse with every identifier that is not a function or constant taken as a symbol."""
    import ast

    try:
        names = {n.id for n in ast.walk(ast.parse(str(text).strip(), mode="eval")) if isinstance(n, ast.Name)}
    except (SyntaxError, ValueError, RecursionError, MemoryError):
        names = set()
    names = {n for n in names if n not in _expr.FUNCTIONS and n not in _expr.CONSTANTS
             and n.isidentifier() and not n.startswith("_")}
    return _expr.parse(text, symbols=names | {coordinate}, field=field)


def _finish(name, kind, q, params, x, z, domain, h_hint, alpha_hint, q_scale, source) -> Curve:
    if not (x.has(q) or z.has(q)):
        raise CurveError(f"curve '{name}': neither x nor z depends on the coordinate '{q}'; "
                         f"write the expressions in terms of {q}")
    if kind == "parametric" and not x.has(q):
        # x constant: a vertical line, which no particle can rest on; reject clearly.
        raise CurveError(f"curve '{name}': x = {x} does not depend on the coordinate '{q}' "
                         "(a vertical line is not a curve symvib can model)")
    for key, e in (("x", x), ("z", z)):
        if e.has(sp.I) or e.has(sp.zoo, sp.nan, sp.oo):
            raise CurveError(f"curve '{name}': {key} = {e} is not a finite real expression")
    xp, zp = sp.diff(x, q), sp.diff(z, q)
    h2 = budget.simplify(xp**2 + zp**2)
    if h2 == 0:
        raise CurveError(f"curve '{name}': the metric h = sqrt(x'^2 + z'^2) vanishes identically; "
                         "x(q) and z(q) do not trace a curve")
    # Domain.
    lo, hi = (sp.sympify(-sp.oo), sp.sympify(sp.oo)) if domain is None else domain
    if not (lo.is_infinite or hi.is_infinite):
        values = {p: sp.Integer(1) for p in params}
        if not sp.N(lo.subs(values)) < sp.N(hi.subs(values)):
            raise CurveError(f"curve '{name}': domain ({lo}, {hi}) is empty")
    # Metric and tangent angle: hints are verified; otherwise built from x', z'.
    if kind == "graph":
        h_auto, alpha_auto = sp.sqrt(1 + zp**2), sp.atan(zp)
    else:
        h_auto = sp.sqrt(h2)
        alpha_auto = sp.atan(zp / xp) if xp.is_positive else sp.atan2(zp, xp)
    h = h_hint if h_hint is not None else h_auto
    alpha = alpha_hint if alpha_hint is not None else alpha_auto
    scale = sp.Integer(1) if q_scale is None else q_scale
    curve = Curve(name=name, kind=kind, q=q, x=x, z=z, params=params, domain=(lo, hi), h=h,
                  alpha=alpha, q_scale=scale, source=source)
    if alpha_hint is None and alpha.has(sp.atan2):
        # atan2 jumps by 2 pi where the tangent points along -x: look for a continuous form.
        found = tangent_angle(curve)
        curve = replace(curve, alpha=found if found is not None else alpha, alpha_cut=found is None)
    if h_hint is not None and identity_holds(h_hint**2 - h2, curve) is None:
        raise CurveError(f"curve '{name}': hint h = {h_hint} does not satisfy h^2 = x'^2 + z'^2 = {h2}")
    if alpha_hint is not None:
        for label, lhs, rhs in (("sin", h * sp.sin(alpha), zp), ("cos", h * sp.cos(alpha), xp)):
            if identity_holds(lhs - rhs, curve) is None:
                raise CurveError(f"curve '{name}': hint alpha = {alpha} does not satisfy "
                                 f"h {label}(alpha) = {'z' if label == 'sin' else 'x'}'")
        jump = angle_jump(alpha, curve, curve.default_values())
        if jump is not None:
            raise CurveError(f"curve '{name}': hint alpha = {alpha} jumps at {q} = {jump:.6g} (parameters = 1), "
                             "where the curve is regular; give a continuous form of the tangent angle")
    # h must be positive inside the domain (checked at sample points).  A point where h
    # is not finite or not real is a singular point (a pole, the far side of a sqrt's
    # branch point): the run's regular interval ends before it (symvib.symbolic.singular).
    hf = sp.lambdify([q, *params], h, "mpmath")
    for qv in sample_points(curve, IDENTITY_CHECK_POINTS, seed=7):
        try:
            value = hf(qv, *[1] * len(params))
        except (ZeroDivisionError, ValueError, OverflowError):
            continue
        if not mpmath.isfinite(value) or mpmath.im(value) != 0:
            continue
        if not value > 0:
            raise CurveError(f"curve '{name}': h = {h} is not positive at {q} = {float(qv):.6g} "
                             f"(parameters = 1); narrow the domain or fix the hint")
    return curve


def _domain(domain, q, params, name):
    if domain is None:
        return None
    if len(domain) != 2:
        raise CurveError(f"curve '{name}': domain must be a pair (low, high)")
    table = {p.name: p for p in params}
    out = []
    for i, end in enumerate(domain):
        if isinstance(end, sp.Basic):
            out.append(end)
        elif isinstance(end, str) and end.strip().lstrip("+-") in ("oo", "inf"):
            out.append(-sp.oo if end.strip().startswith("-") else sp.oo)
        else:
            out.append(to_sympy(_expr.parse(end, symbols=table, field=f"curve.domain[{i}]"), table))
    return tuple(out)


def graph(z, *, x: str = "x", params=None, name: str = "", domain=None, h=None, alpha=None,
          q_scale=None) -> Curve:
    """A curve given as a graph ``z = f(x)``; the coordinate is ``q = x``.

    Parameters
    ----------
    z : str or sympy.Expr
        ``f(x)``.
    x : str
        Name of the coordinate (default ``"x"``).
    params : list of str or dict of str -> assumption, optional
        Parameter names (positive by default), or names mapped to
        ``"positive" | "real" | "nonnegative" | "negative"``.  When omitted,
        every free name is a positive parameter.
    domain : pair, optional
        Open interval of ``x`` (default the real line).
    h, alpha : optional
        Simpler equivalent forms of the metric and tangent angle; verified.
    q_scale : optional
        A characteristic length of ``x``.

    Examples
    --------
    >>> c = graph("a*(cosh(x/a) - 1)", alpha="atan(sinh(x/a))", h="cosh(x/a)")
    >>> c.kappa
    1/(a*cosh(x/a)**2)
    """
    name = name or "graph"
    q, declared = _symbol_table(x, params)
    texts = {"z": z, "h": h, "alpha": alpha, "q_scale": q_scale}
    ps, ex = _parse_all(texts, q, declared, "curve.")
    return _finish(name, "graph", q, ps, q, ex["z"], _domain(domain, q, ps, name), ex.get("h"),
                   ex.get("alpha"), ex.get("q_scale"), (("z", str(z)), ("q", x)))


def parametric(x, z, *, q: str = "q", params=None, name: str = "", domain=None, h=None, alpha=None,
               q_scale=None) -> Curve:
    """A curve given parametrically, ``x = x(q)``, ``z = z(q)``.

    Parameters are as for :func:`graph`.

    Examples
    --------
    >>> c = parametric("R*sin(phi)", "R*(1 - cos(phi))", q="phi", alpha="phi", h="R")
    >>> (c.h, c.alpha, c.kappa)
    (R, phi, 1/R)
    """
    name = name or "parametric"
    qs, declared = _symbol_table(q, params)
    texts = {"x": x, "z": z, "h": h, "alpha": alpha, "q_scale": q_scale}
    ps, ex = _parse_all(texts, qs, declared, "curve.")
    return _finish(name, "parametric", qs, ps, ex["x"], ex["z"], _domain(domain, qs, ps, name),
                   ex.get("h"), ex.get("alpha"), ex.get("q_scale"),
                   (("x", str(x)), ("z", str(z)), ("q", q)))
