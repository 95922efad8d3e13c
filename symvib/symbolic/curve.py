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
import random
from dataclasses import dataclass, field
from functools import cached_property

import mpmath
import sympy as sp

from symvib import expr as _expr
from symvib.symbolic.symbols import RESERVED

__all__ = ["Curve", "CurveError", "graph", "parametric", "to_sympy", "sample_points", "generic_branch"]

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
        Metric and continuous tangent angle.
    q_scale : sympy.Expr
        A characteristic length of ``q`` (sampling windows, quadrature panels).
    source : tuple of (str, str)
        The defining texts, for generated-file headers and hashing.
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
        return generic_branch(sp.simplify(sp.diff(self.h, self.q)), f"curve '{self.name}': h'")

    @cached_property
    def alphap(self) -> sp.Expr:
        """``alpha'(q) = (x' z'' - z' x'') / h**2`` (its generic branch)."""
        return generic_branch(sp.simplify(sp.diff(self.alpha, self.q)), f"curve '{self.name}': alpha'")

    @cached_property
    def kappa(self) -> sp.Expr:
        """Curvature ``kappa = alpha' / h`` (its generic branch)."""
        return generic_branch(sp.simplify(self.alphap / self.h), f"curve '{self.name}': kappa")

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
            if sp.simplify(expr) == 0:
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
            value = sp.N(expr.subs(subs), CHECK_DIGITS)
            size = max([abs(sp.N(t.subs(subs), CHECK_DIGITS)) for t in terms] + [sp.Integer(1)])
            if not value.is_number or value.has(sp.nan, sp.zoo) or abs(value) > CHECK_TOLERANCE * size:
                return False
    return True


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
    h2 = sp.simplify(xp**2 + zp**2)
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
    if h_hint is not None and identity_holds(h_hint**2 - h2, curve) is None:
        raise CurveError(f"curve '{name}': hint h = {h_hint} does not satisfy h^2 = x'^2 + z'^2 = {h2}")
    if alpha_hint is not None:
        for label, lhs, rhs in (("sin", h * sp.sin(alpha), zp), ("cos", h * sp.cos(alpha), xp)):
            if identity_holds(lhs - rhs, curve) is None:
                raise CurveError(f"curve '{name}': hint alpha = {alpha} does not satisfy "
                                 f"h {label}(alpha) = {'z' if label == 'sin' else 'x'}'")
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
