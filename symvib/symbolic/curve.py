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
from dataclasses import dataclass, field, replace
from functools import cached_property

import mpmath
import sympy as sp

from symvib import expr as _expr
from symvib.symbolic import budget
from symvib.symbolic.angle import angle_jump, tangent_angle
from symvib.symbolic.branches import CurveError, generic_branch, removable_form
from symvib.symbolic.identity import IDENTITY_CHECK_POINTS, identity_holds, sample_points, tamed
from symvib.symbolic.symbols import RESERVED

__all__ = ["Curve", "graph", "parametric", "to_sympy"]

#: Parameter assumptions a curve may declare.
ASSUMPTIONS = {
    "positive": {"positive": True},
    "real": {"real": True},
    "nonnegative": {"nonnegative": True},
    "negative": {"negative": True},
}

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
