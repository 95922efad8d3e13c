"""The one bridge: derivation -> plain NumPy kernel module.

:func:`module_text` turns a :class:`~symvib.symbolic.derive.Derivation` into the source
of a Python module that needs only NumPy (and :mod:`math` for the scalar
path): one function per kernel and per branch, common subexpressions
eliminated (:func:`sympy.cse`), and no conditional: every ``Piecewise`` is
replaced by its generic branch before cse
(:func:`~symvib.symbolic.branches.generic_branch`: the branches SymPy adds on
equalities such as ``Eq(cos(phi), 0)`` hold on a set of measure zero, a singular
point or a removable value), ``sign(f)`` prints as ``math.copysign(1.0, f)`` /
``numpy.copysign(1.0, f)`` and ``Abs`` as ``abs`` / ``numpy.abs`` (a power of ``Abs(u)``
in a denominator as one of ``u sign(u)``, so that a removable value such as ``q**2 /
|q|`` at 0 is finite: :func:`~symvib.symbolic.branches.removable_form`); a condition that is an
inequality is a :class:`~symvib.symbolic.branches.CurveError`.  Functions
broadcast over NumPy arrays of ``q``, the state and the parameters; every
kernel also has a ``*_scalar`` twin built on :mod:`math`, which is several
times faster for one float (root finding in the driver).

Kernels (argument order in each docstring and in ``SIGNATURES``); ``cp`` are
the curve parameters in declaration order, ``_p``/``_m`` the branches
``s = +1``/``-1``:

============================  =========================================================
``x z h alpha kappa``         geometry, ``(q, *cp)``
``dx dz dh dalpha``           ``x' z' h' alpha'``, ``(q, *cp)``
``F_p dF_p ddF_p``            ``F_s`` (eq. 2), its integrand and derivative, ``(q, mu, *cp)``
``w_p qdot2_p``               ``w(q; C)`` and ``qdot**2`` (eq. 2), ``(q, C, g, mu, *cp)``
``qddot_p``                   eq. 1 solved for ``qddot``, ``(q, qdot, g, mu, *cp)``
``N_w``                       normal force per mass ``kappa w + g cos(alpha)``, ``(q, w, g, *cp)``
``F_N P_mu Ek Ep E``          energy analysis (physics.md), state form ``(q, qdot, ...)``
``domain q_scale``            the regular interval of ``q`` and its scale, ``(*cp)``
============================  =========================================================

The constant ``ALPHA_CUT`` (:attr:`~symvib.symbolic.curve.Curve.alpha_cut`) is ``True``
when the kernel ``alpha`` is ``atan2(z', x')``, no continuous closed form having been
found: it jumps by ``2 pi`` where ``x' < 0`` and ``z'`` changes sign, so the engine
must not integrate across such a point as if ``alpha`` were continuous.

On the numeric route ``F_s`` integrates ``dF_s`` from ``Q_REF`` by the rule of
:mod:`symvib.antiderivative`: pieces no wider than ``PANEL * q_scale``, each one
16-point Gauss-Legendre panel where the Legendre tail of ``dF_s`` on it says that
is enough (``TOL``, 1e-15 of its integral of ``|dF_s|``), else walked with halved
and doubled panels (``_F_p_panel_scalar`` is one panel: its integral, error
estimate and tolerance), so that a narrow feature of a curve whose ``q_scale`` is
1 (a Gaussian well, a sine track of small width) is resolved where it is: ``F_s``
within a few rounding errors of the integral of ``|dF_s|``.  ``F_p_scalar``
calls its ``dF_p_scalar`` by name and decides without a conditional (the
whitelist has none: ``math.copysign`` steps, ``range`` of 0 or 1); ``F_p`` is
``F_p_scalar`` at every point of the broadcast arguments.

The output is deterministic (no timings, sorted data), so generating twice
gives the same bytes; the header records the inputs' hash
(:mod:`symvib.provenance`), and a digest of the body so hand edits show.

Examples
--------
>>> from symvib.symbolic.derive import derive
>>> text = module_text(derive("circle"), {"name": "circle"})
>>> "def F_p(q, mu, R):" in text and "import sympy" not in text
True
"""
from __future__ import annotations

import builtins
import hashlib
import keyword
import math
import re
import sys
import unicodedata
from dataclasses import dataclass
from pathlib import Path

import sympy as sp
from sympy.printing.numpy import NumPyPrinter
from sympy.printing.pycode import PythonCodePrinter

from symvib import antiderivative, provenance, safeio
from symvib.codegen import gauss
from symvib.kernelformat import DIGEST_PREFIX, verify_text
from symvib.symbolic.branches import CurveError, generic_branch, removable_form
from symvib.symbolic.derive import Derivation, derive
from symvib.symbolic.symbols import C, g, mu

__all__ = ["module_text", "generate", "generate_catalogue", "stale", "check_param_names", "KERNEL_FUNCTIONS",
           "DIGEST_PREFIX", "route_plan", "module_source", "Plan", "AUTO_SEARCH_SECONDS", "AUTO_ROUTES",
           "AUTO_ROUTE_SECONDS", "kernel_forms"]

#: Gauss-Legendre nodes per panel of a numeric-route antiderivative (:mod:`symvib.antiderivative`).
QUAD_NODES = antiderivative.NODES
#: Widest panel of a numeric-route antiderivative, in units of ``q_scale``.
PANEL = antiderivative.PANEL
#: Functions every kernel module defines (each also as ``<name>_scalar``).
KERNEL_FUNCTIONS = frozenset({
    "x", "z", "h", "alpha", "kappa", "dx", "dz", "dh", "dalpha", "N_w", "F_N", "P_mu", "Ek", "Ep", "E",
    "q_scale", "domain", *(f"{k}_{b}" for k in ("F", "dF", "ddF", "w", "qdot2", "qddot", "node")
                              for b in ("p", "m"))})
#: Constants every kernel module defines.
KERNEL_CONSTANTS = frozenset({"NAME", "COORDINATE", "PARAMS", "F_ROUTES", "Q_REF", "PANEL", "INPUT_HASH",
                              "SYMPY_VERSION", "GENERATOR_VERSION", "SOURCE", "SIGNATURES", "ALPHA_CUT"})
#: Names a curve parameter may not have in a kernel module: its arguments, modules and
#: module-level names (a parameter is a Python argument of every kernel, so it would shadow them).
KERNEL_RESERVED = frozenset({"q", "qdot", "w", "numpy", "math"} | KERNEL_FUNCTIONS
                            | {f"{k}_scalar" for k in KERNEL_FUNCTIONS} | KERNEL_CONSTANTS)
#: Unicode categories a user text may not bring into a docstring (controls, separators, surrogates).
_UNSAFE_CATEGORIES = frozenset({"Cc", "Cs", "Zl", "Zp"})

#: Integers at least this large (in magnitude) are printed as float literals: a Python
#: int beyond int64 makes NumPy fall back to objects and numba fail to type the kernel,
#: and beyond 2**53 a float is what the kernel computes with anyway.
BIG_INTEGER = 2**53

_Q = sp.Symbol("q", real=True)
_QDOT = sp.Symbol("qdot", real=True)
_W = sp.Symbol("w", real=True)
_BRANCH = {1: "p", -1: "m"}


def _float_literal(value) -> str:
    """``repr(float(value))`` for a number too large for an integer literal in a kernel.

    Raises
    ------
    CurveError
        When the number does not fit a float either.
    """
    try:
        out = float(value)
    except OverflowError:
        out = math.inf
    if not math.isfinite(out):
        raise CurveError(f"curve: the number {sp.sstr(value)[:40]} is too large for a float kernel "
                         f"(beyond {sys.float_info.max:.3g})")
    return repr(out)


class _BigNumbers:
    """Printing of integers and rationals that a kernel cannot hold as machine integers."""

    def _print_Integer(self, expr):
        return super()._print_Integer(expr) if abs(expr.p) < BIG_INTEGER else _float_literal(expr)

    def _print_Rational(self, expr):
        if abs(expr.p) < BIG_INTEGER and expr.q < BIG_INTEGER:
            return super()._print_Rational(expr)
        return _float_literal(expr)


class _NoConditionals:
    """Printing that never writes a conditional: a kernel module holds no ``if`` and no comparison.

    Every ``Piecewise`` is decided before printing (:func:`~symvib.symbolic.branches.generic_branch`);
    what reaches a printer as a condition is a generator error, raised here with its name
    rather than written as ``(a) if (c) else (b)`` for the whitelist to refuse later.
    """

    def _refuse(self, expr):
        raise CurveError(f"{type(expr).__name__} {sp.sstr(expr)[:60]} would print as a conditional, which a "
                         "kernel may not hold")

    _print_Piecewise = _print_Relational = _print_ITE = _print_KroneckerDelta = _print_Heaviside = _refuse
    _print_BooleanTrue = _print_BooleanFalse = _print_And = _print_Or = _print_Not = _refuse


class _NumPy(_NoConditionals, _BigNumbers, NumPyPrinter):
    suffix = ""

    def __init__(self):
        super().__init__({"fully_qualified_modules": True, "allow_unknown_functions": False})

    def _print_AppliedUndef(self, expr):
        # The only undefined functions in a kernel are calls of F_p / F_m.
        return f"{expr.func.__name__}{self.suffix}(" + ", ".join(self.doprint(a) for a in expr.args) + ")"

    def _print_Abs(self, expr):
        return f"numpy.abs({self.doprint(expr.args[0])})"

    def _print_sign(self, expr):
        # copysign as in the scalar twin (_Math), not numpy.sign: sign(0) = 0 would make
        # q / sign(q) (removable_form) infinite at 0, and the twins differ there.
        return f"numpy.copysign(1.0, {self.doprint(expr.args[0])})"


class _Math(_NoConditionals, _BigNumbers, PythonCodePrinter):
    suffix = "_scalar"

    def __init__(self):
        super().__init__({"fully_qualified_modules": True, "allow_unknown_functions": False})

    _print_AppliedUndef = _NumPy._print_AppliedUndef

    def _print_Abs(self, expr):
        return f"abs({self.doprint(expr.args[0])})"

    def _print_sign(self, expr):
        # sign(0) = 0 where copysign gives +-1: they differ on a set of measure zero only, where
        # the kernel's value is its generic one (generic_branch), finite (removable_form);
        # SymPy's own printer writes a conditional here.
        return f"math.copysign(1.0, {self.doprint(expr.args[0])})"


def _shared_trig(pre: list, exprs: list) -> tuple:
    """The sines and cosines of a kernel computed once, its tangents from them: ``(prelude, pre, exprs)``.

    Where a kernel takes ``tan(a)`` and also ``cos(a)`` or ``sin(a)``, the prelude assigns
    ``_sin0 = sin(a)``, ``_cos0 = cos(a)``, ``_tan0 = _sin0 / _cos0`` and the expressions take those
    symbols: a sine and a cosine cost about what a tangent alone does (the paper's parabola in
    ``phi``: a node of the time quadrature took ``tan(phi)`` and ``cos(phi)**3``).

    >>> a = sp.Symbol("a")
    >>> prelude, _, exprs = _shared_trig([], [sp.tan(a) ** 2 * sp.cos(a) ** 3, sp.tan(2 * a)])
    >>> prelude, exprs
    ([(_sin0, sin(a)), (_cos0, cos(a)), (_tan0, _sin0/_cos0)], [_cos0**3*_tan0**2, tan(2*a)])
    """
    everything = [e for _, e in pre] + exprs
    found = set().union(*(e.atoms(sp.tan, sp.sin, sp.cos) for e in everything))
    shared = {f.args[0] for f in found if isinstance(f, (sp.sin, sp.cos))}
    angles = sorted({f.args[0] for f in found if isinstance(f, sp.tan) and f.args[0] in shared},
                    key=sp.default_sort_key)
    prelude, swap = [], {}
    for i, angle in enumerate(angles):
        sin, cos, tan = (sp.Symbol(f"_{f}{i}") for f in ("sin", "cos", "tan"))
        prelude += [(sin, sp.sin(angle)), (cos, sp.cos(angle)), (tan, sin / cos)]
        swap.update({sp.sin(angle): sin, sp.cos(angle): cos, sp.tan(angle): tan})
    if not swap:
        return [], pre, exprs
    return prelude, [(sym, e.xreplace(swap)) for sym, e in pre], [e.xreplace(swap) for e in exprs]


def _function(name: str, args: tuple, expr, doc: str, printer) -> str:
    """Source of one kernel: cse'd assignments, then the return (a tuple for an ``sp.Tuple``).

    An expression may hold placeholders ``_e0, _e1, ...`` (:data:`_PRE`): they are
    computed first, so that SymPy does not rewrite ``exp(a)**2`` as ``exp(2 a)``.
    """
    pre = []
    if isinstance(expr, tuple) and len(expr) == 2 and isinstance(expr[0], dict):
        pre = sorted(expr[0].items(), key=lambda kv: kv[0].name)
        expr = expr[1]
    exprs = list(expr) if isinstance(expr, sp.Tuple) else [expr]
    prelude, pre, exprs = _shared_trig(pre, exprs)
    replacements, reduced = sp.cse([e for _, e in pre] + exprs, symbols=sp.numbered_symbols("_t"),
                                   order="canonical")
    pre_reduced, reduced = reduced[:len(pre)], reduced[len(pre):]
    lines = [f"def {name}({', '.join(args)}):", f'    """{doc}"""']

    def text(e):
        try:
            return printer.doprint(e)
        except CurveError as err:
            raise CurveError(f"kernel {name}: {err}") from None

    for sym, sub in prelude:
        lines.append(f"    {sym} = {text(sub)}")
    for sym, sub in replacements:
        lines.append(f"    {sym} = {text(sub)}")
    for (sym, _), red in zip(pre, pre_reduced):
        lines.append(f"    {sym} = {text(red)}")
    bodies = []
    placeholders = {str(sym) for sym, _ in pre + prelude}
    for part, red in zip(exprs, reduced):
        body = text(red)
        used = {str(s) for s in part.free_symbols} | _called_args(part)
        for sym, value in pre + prelude[::-1]:
            if str(sym) in used:
                used |= {str(x) for x in value.free_symbols}
        used -= placeholders
        if set(args) - used and isinstance(printer, _NumPy):
            # Broadcast over every argument even where the expression ignores some
            # (h = R on a circle), so that kernels map arrays to arrays of one shape.
            body = f"_broadcast({body}, {', '.join(args)})"
        elif not isinstance(printer, _NumPy) and _may_be_int(part):
            body = f"float({body})"  # a scalar kernel returns a float; float(x) of a float only costs a call
        bodies.append(body)
    lines.append(f"    return {', '.join(bodies)}" if len(bodies) > 1 else f"    return {bodies[0]}")
    return "\n".join(lines)


#: Functions whose printed scalar code may give an int for float arguments (``max(q, 0)``).
_INT_VALUED = (sp.Piecewise, sp.Max, sp.Min, sp.floor, sp.ceiling, sp.sign, sp.Heaviside)


def _may_be_int(expr) -> bool:
    """Whether the scalar code of ``expr`` may give an int for float arguments: a constant
    (``0``, ``2``), or an expression with one of :data:`_INT_VALUED`.

    >>> q = sp.Symbol("q")
    >>> _may_be_int(sp.Integer(2)), _may_be_int(sp.Max(q, 0)), _may_be_int(2 * sp.cos(q))
    (True, True, False)
    """
    return not expr.free_symbols or expr.has(*_INT_VALUED)


def _generic(expr, field: str):
    """A kernel's expression (or its ``(placeholders, Tuple)`` form) with every ``Piecewise``
    decided once, before cse (:func:`~symvib.symbolic.branches.generic_branch`)."""
    if isinstance(expr, tuple):
        pre, body = expr
        return {k: _generic(v, field) for k, v in pre.items()}, _generic(body, field)
    return removable_form(generic_branch(expr, field))


def _called_args(expr) -> set:
    return {str(s) for f in expr.atoms(sp.core.function.AppliedUndef) for a in f.args for s in a.free_symbols}


def _kernel_exprs(d: Derivation) -> list:
    """(name, argument names, expression, one-line description) of every closed-form kernel."""
    c = d.curve
    cp = tuple(p.name for p in c.params)
    to_kernel = {c.q: _Q, c.qdot: _QDOT}
    K = lambda e: sp.sympify(e).xreplace(to_kernel)  # noqa: E731
    geo = ("q", *cp)
    out = [
        ("x", geo, K(c.x), "x(q): horizontal position"),
        ("z", geo, K(c.z), "z(q): height"),
        ("h", geo, K(c.h), "h(q) = sqrt(x'^2 + z'^2): metric, ds = h dq"),
        ("alpha", geo, K(c.alpha), "alpha(q): tangent angle, h sin(alpha) = z', h cos(alpha) = x'"),
        ("kappa", geo, K(c.kappa), "kappa(q) = alpha'/h: curvature"),
        ("dx", geo, K(c.xp), "x'(q)"),
        ("dz", geo, K(c.zp), "z'(q)"),
        ("dh", geo, K(c.hp), "h'(q)"),
        ("dalpha", geo, K(c.alphap), "alpha'(q)"),
    ]
    for s, br in d.branches.items():
        b = _BRANCH[s]
        sign = "+" if s > 0 else "-"
        f = K(br.F.integrand)
        out.append((f"dF_{b}", ("q", "mu", *cp), f,
                    f"F_{sign}'(q) = exp({sign}2 mu alpha) (z' {sign} mu x'): integrand of eq. 2"))
        out.append((f"ddF_{b}", ("q", "mu", *cp), sp.diff(f, _Q), f"F_{sign}''(q)"))
        if br.F.closed:
            out.append((f"F_{b}", ("q", "mu", *cp), K(br.F.expr),
                        f"F_{sign}(q): antiderivative of eq. 2 (route: {br.F.route})"))
        out.append((f"w_{b}", ("q", "C", "g", "mu", *cp),
                    K(sp.exp(-2 * s * mu * c.alpha)) * (C - 2 * g * sp.Symbol(f"__F_{b}")),
                    f"w(q; C) = exp({'-' if s > 0 else ''}2 mu alpha) [C - 2 g F_{sign}(q)] (eq. 2, s = {s:+d})"))
        out.append((f"qdot2_{b}", ("q", "C", "g", "mu", *cp),
                    K(sp.exp(-2 * s * mu * c.alpha) / c.h**2) * (C - 2 * g * sp.Symbol(f"__F_{b}")),
                    f"qdot^2(q; C) = w / h^2 (eq. 2, s = {s:+d})"))
        out.append((f"qddot_{b}", ("q", "qdot", "g", "mu", *cp), K(br.qddot(c.qdot)),
                    f"qddot = -A qdot^2 - B (eq. 1, s = {s:+d})"))
        # What the driver's time quadrature needs at a node, fused so that shared
        # subexpressions are computed once: F_s' = e^2 (z' + s mu x') with
        # e = exp(s mu alpha), then h, e, kappa, cos(alpha).
        e1 = sp.Symbol("_e0")
        out.append((f"node_{b}", ("q", "mu", *cp),
                    ({e1: K(sp.exp(s * mu * c.alpha))},
                     sp.Tuple(e1**2 * K(c.zp + s * mu * c.xp), K(c.h), e1, K(c.kappa), K(c.xp / c.h))),
                    f"(F_{sign}', h, exp({sign}mu alpha), kappa, cos(alpha)) at once, for the time quadrature"))
    e = d.energies
    out += [
        ("N_w", ("q", "w", "g", *cp), K(c.kappa) * _W + g * K(sp.cos(c.alpha)),
         "N = kappa w + g cos(alpha): normal force per unit mass"),
        ("F_N", ("q", "qdot", "g", "m", *cp), K(e["F_N"]), "F_N = m (kappa v^2 + g cos(alpha))"),
        ("P_mu", ("q", "qdot", "g", "m", "mu", *cp), K(e["P_mu"]), "P_mu = -mu |F_N| |v|: power of friction"),
        ("Ek", ("q", "qdot", "m", *cp), K(e["Ek"]), "Ek = m v^2 / 2"),
        ("Ep", ("q", "g", "m", *cp), K(e["Ep"]), "Ep = m g z"),
        ("E", ("q", "qdot", "g", "m", *cp), K(e["E"]), "E = Ek + Ep"),
        ("q_scale", cp, c.q_scale, "characteristic length of q"),
    ]
    return out


def _literal(values) -> str:
    return "(" + ", ".join(repr(float(v)) for v in values) + ",)"


_BROADCAST = '''

def _broadcast(value, *args):
    """value as an array of the broadcast shape of args."""
    return value * numpy.ones(numpy.broadcast(*args).shape)
'''

_QUAD_HELPERS = '''
_GL_X = {x}
_GL_W = {w}
_GL_T1 = {t1}
_GL_T2 = {t2}
_GL_T3 = {t3}
_GL_T4 = {t4}
_F_TOL = {tol!r}
_F_FLAT = {flat!r}
_F_UNRESOLVED = {unresolved!r}
_F_POWER = {power!r}
_F_TRIES = {tries!r}
_F_NARROWEST = {narrowest!r}
'''

# One panel of a numeric F_s, and F_s itself (symvib.antiderivative), per branch: formatted with
# {b} (p or m), {args} (q, mu, cp), {pargs} (left, width, mu, cp), {cargs} (mu, cp), {ref}, {scale}.
# The scalar F_s calls its panel and dF by name (not as functions passed in): numba caches a
# compiled function on disk only without such values, so the compiled engine is found again.
# No conditional, no comparison (the whitelist, symvib.kernelformat): 0.5 + 0.5 copysign(1, x) is
# 1 where x >= 0 and 0 where x < 0 (and 0 or 1 for NaN), and range(n) with n 0 or 1 is a branch.
_PANEL_TEMPLATE = '''def _F_{b}_panel_scalar({pargs}):
    \"\"\"(integral, error estimate, tolerance) of dF_{b} over [left, left + width]: one panel of
    Gauss-Legendre nodes, the error from the Legendre tail of dF_{b} (symvib.antiderivative).

    Arguments: ({pargs}). Floats only (math).\"\"\"
    total = 0.0
    size = 0.0
    c1 = 0.0
    c2 = 0.0
    c3 = 0.0
    c4 = 0.0
    for xk, wk, t1, t2, t3, t4 in zip(_GL_X, _GL_W, _GL_T1, _GL_T2, _GL_T3, _GL_T4):
        v = dF_{b}_scalar(left + 0.5 * width * (xk + 1.0), {cargs})
        total += wk * v
        size += wk * abs(v)
        c1 += t1 * v
        c2 += t2 * v
        c3 += t3 * v
        c4 += t4 * v
    tail = max(abs(c1), abs(c2))
    ratio = min(1.0, math.sqrt(tail / (max(abs(c3), abs(c4)) + 1e-300)))
    flat = 0.5 + 0.5 * math.copysign(1.0, ratio - _F_UNRESOLVED)
    real = 0.5 + 0.5 * math.copysign(1.0, tail - flat * _F_FLAT * 0.5 * size)
    return 0.5 * width * total, 2.0 * tail * max(ratio ** _F_POWER, flat) * real, _F_TOL * size'''

_F_TEMPLATE = '''def F_{b}_scalar({args}):
    \"\"\"{doc} Floats only (math).\"\"\"
    q_ref = {ref}
    length = q - q_ref
    panels = max(1, math.ceil(abs(length) / (PANEL * q_scale_scalar({scale}))))
    step = length / panels
    total = 0.0
    for k in range(panels):
        left = q_ref + k * step
        value, error, tol = _F_{b}_panel_scalar(left, step, {cargs})
        passed = max(0.5 + 0.5 * math.copysign(1.0, tol - error), 1.0 - int(math.isfinite(error)))
        total += passed * value
        done = passed
        width = 0.5
        tries = int((_F_TRIES - 1) * (1.0 - passed))
        for attempt in range(tries):
            todo = int(0.5 - 0.5 * math.copysign(1.0, done - 1.0))
            for once in range(todo):
                width = min(width, 1.0 - done)
                value, error, tol = _F_{b}_panel_scalar(left + done * step, width * step, {cargs})
                passed = max(0.5 + 0.5 * math.copysign(1.0, tol - error), 1.0 - int(math.isfinite(error)),
                             0.5 + 0.5 * math.copysign(1.0, _F_NARROWEST - width))
                total += passed * value
                done += passed * width
                width = min(1.0, width * (0.5 + 1.5 * passed))
        todo = int(0.5 - 0.5 * math.copysign(1.0, done - 1.0))
        for once in range(todo):
            total += _F_{b}_panel_scalar(left + done * step, (1.0 - done) * step, {cargs})[0]
    return total'''

_F_ARRAY_TEMPLATE = '''def F_{b}({args}):
    \"\"\"{doc}\"\"\"
    points = numpy.broadcast({args})
    values = [F_{b}_scalar(*[float(v) for v in point]) for point in points]
    return numpy.reshape(numpy.array(values, dtype=float), points.shape) * 1.0'''


def module_text(d: Derivation, source: dict) -> str:
    """The full text of the kernel module for derivation ``d``.

    ``source`` is the curve's defining data (hashed into the header).
    """
    c = d.curve
    cp = check_param_names(p.name for p in c.params)
    kernels = _kernel_exprs(d)
    numeric = {s: not br.F.closed for s, br in d.branches.items()}
    F_sub = {}
    for s in (1, -1):
        b = _BRANCH[s]
        F_sub[sp.Symbol(f"__F_{b}")] = sp.Function(f"F_{b}")(_Q, mu, *c.params)
    np_printer, math_printer = _NumPy(), _Math()
    parts = []
    signatures = {}
    for name, args, expr, doc in kernels:
        expr = _generic(expr, f"curve '{c.name}': kernel {name}")
        if not isinstance(expr, tuple):
            expr = expr.xreplace(F_sub)
        signatures[name] = args
        argdoc = f"{doc}.\n\n    Arguments: ({', '.join(args)})."
        parts.append(_function(name, args, expr, argdoc, np_printer))
        parts.append(_function(name + "_scalar", args, expr, argdoc + " Floats only (math).", math_printer))
    # Numeric-route antiderivatives.
    needs_quad = any(numeric.values())
    for s in (1, -1):
        if numeric[s] and not d.branches[s].F.q_ref.is_finite:
            raise CurveError(f"curve.domain: the reference point {d.branches[s].F.q_ref} of the numeric "
                             "antiderivative is not finite")
    for s in (1, -1):
        if not numeric[s]:
            continue
        b = _BRANCH[s]
        sign = "+" if s > 0 else "-"
        args = ("q", "mu", *cp)
        signatures[f"F_{b}"] = args
        call_args = ", ".join(("mu", *cp))
        ref_s = math_printer.doprint(d.branches[s].F.q_ref.xreplace({c.q: _Q}))
        scale = ", ".join(cp)
        doc = (f"F_{sign}(q): integral of dF_{b} from Q_REF (numeric route: no closed form; the rule of "
               f"symvib.antiderivative).\n\n    Arguments: ({', '.join(args)}).")
        fill = {"b": b, "args": ", ".join(args), "pargs": ", ".join(("left", "width", "mu", *cp)),
                "cargs": call_args, "ref": ref_s, "scale": scale}
        parts.append(_F_ARRAY_TEMPLATE.format(doc=doc + " F_" + b + "_scalar at every point (broadcasts).",
                                              **fill))
        parts.append(_F_TEMPLATE.format(doc=doc, **fill))
        parts.append(_PANEL_TEMPLATE.format(**fill))
    # Domain as numbers.
    lo, hi = c.domain
    dom = lambda e, p: "math.inf" if e == sp.oo else "-math.inf" if e == -sp.oo else p.doprint(e)  # noqa: E731
    signatures["domain"] = cp
    parts.append(f"def domain({', '.join(cp)}):\n    \"\"\"Open interval of q where the curve is regular.\n\n"
                 f"    Arguments: ({', '.join(cp)}).\"\"\"\n"
                 f"    return ({dom(lo, math_printer)}, {dom(hi, math_printer)})")
    routes = {s: br.F.route for s, br in d.branches.items()}
    header = _header(d, source, routes)
    consts = [
        f"NAME = {source.get('name', c.name)!r}",
        f"COORDINATE = {c.q.name!r}",
        f"PARAMS = {cp!r}",
        f"F_ROUTES = {{1: {routes[1]!r}, -1: {routes[-1]!r}}}",
        f"Q_REF = {float(d.branches[1].F.q_ref.subs({p: 1 for p in c.params})) if needs_quad else 0.0!r}",
        f"PANEL = {PANEL!r}",
        f"ALPHA_CUT = {bool(c.alpha_cut)!r}",
        f"INPUT_HASH = {provenance.input_hash(source)!r}",
        f"SYMPY_VERSION = {sp.__version__!r}",
        f"GENERATOR_VERSION = {provenance.GENERATOR_VERSION!r}",
        f"SOURCE = {_py_literal(source)}",
        "SIGNATURES = {\n" + "".join(f"    {k!r}: {v!r},\n" for k, v in sorted(signatures.items())) + "}",
    ]
    quad = ""
    if needs_quad:
        x, w, t1, t2, t3, t4 = antiderivative.tail_rows(QUAD_NODES)
        quad = _QUAD_HELPERS.format(x=_literal(x), w=_literal(w), t1=_literal(t1), t2=_literal(t2),
                                    t3=_literal(t3), t4=_literal(t4), tol=antiderivative.TOL,
                                    flat=antiderivative.FLAT, unresolved=antiderivative.UNRESOLVED,
                                    power=antiderivative.TAIL_POWER, tries=antiderivative.TRIES,
                                    narrowest=antiderivative.NARROWEST)
    body = (header + "import math\n\nimport numpy\n\n" + "\n".join(consts) + "\n" + _BROADCAST + quad
            + "\n\n" + "\n\n\n".join(parts) + "\n")
    digest = hashlib.sha256(body.encode()).hexdigest()
    return f"{DIGEST_PREFIX}{digest}\n" + body


def check_param_names(names) -> tuple:
    """The parameter names as a tuple, if each can be a Python argument of a kernel.

    A name must be an ASCII identifier (Python folds other identifiers by NFKC,
    so two parameters could become one argument), not a keyword, not start with
    ``_`` (the kernels' temporaries) and not be a builtin or one of
    :data:`KERNEL_RESERVED`.

    Raises
    ------
    CurveError
        Naming ``curve.params`` and the offending name.
    """
    names = tuple(names)
    for name in names:
        why = ("is not an ASCII identifier" if not (isinstance(name, str) and name.isascii() and name.isidentifier())
               else "is a Python keyword" if keyword.iskeyword(name)
               else "starts with '_' (kept for the kernels' temporaries)" if name.startswith("_")
               else "is reserved in kernel modules" if name in KERNEL_RESERVED or hasattr(builtins, name)
               else "")
        if why:
            raise CurveError(f"curve.params: parameter name {name!r} {why}; rename it")
    return names


def _doc_text(text: str, instead: str) -> str:
    """``text`` if it may stand in a docstring as it is, else ``instead``.

    User text is never interpolated into a docstring when it holds a quote, a
    backslash, a control or line/paragraph separator: those could close the
    docstring (``\"\"\"``), start an escape or a new line of code.
    """
    text = str(text)
    if any(ch in "\"\\" or unicodedata.category(ch) in _UNSAFE_CATEGORIES for ch in text):
        return instead
    return text


def _py_literal(obj, field: str = "source") -> str:
    """A Python literal of plain data with dict keys sorted (deterministic).

    Only strings, numbers, booleans, ``None``, lists, tuples and dicts with
    string keys are accepted (each printed by :func:`repr`); a non-finite
    float is printed as ``float('inf')``.

    Raises
    ------
    CurveError
        For any other value, naming its field.
    """
    if isinstance(obj, dict):
        for k in obj:
            if not isinstance(k, str):
                raise CurveError(f"{field}: key {k!r} is not a string")
        return "{" + ", ".join(f"{k!r}: {_py_literal(obj[k], f'{field}.{k}')}" for k in sorted(obj)) + "}"
    if isinstance(obj, (list, tuple)):
        inner = ", ".join(_py_literal(v, f"{field}[{i}]") for i, v in enumerate(obj))
        return f"[{inner}]" if isinstance(obj, list) else f"({inner}{',' if len(obj) == 1 else ''})"
    if isinstance(obj, float) and not math.isfinite(obj):
        return f"float({repr(obj)!r})"
    if obj is None or isinstance(obj, (str, bool, int, float)):
        return repr(obj)
    raise CurveError(f"{field}: {type(obj).__name__} value {obj!r} is not plain data (a string or a number)")


def _header(d: Derivation, source: dict, routes: dict) -> str:
    c = d.curve
    lines = [
        f'"""Kernels of the curve {_doc_text(repr(source.get("name", c.name)), "named in NAME")}: '
        'generated by `symvib generate`; do not edit.',
        "",
        f"Curve ({c.kind}): x = {c.x}, z = {c.z}, coordinate {c.q} (passed as q),",
        f"parameters {', '.join(p.name for p in c.params) or 'none'}, domain ({c.domain[0]}, {c.domain[1]}).",
        f"Geometry: h = {c.h}, alpha = {c.alpha}, kappa = {c.kappa}.",
        ("ALPHA_CUT: alpha is atan2(z', x'), which jumps by 2 pi where x' < 0 and z' changes sign."
         if c.alpha_cut else "ALPHA_CUT = False: alpha is continuous wherever the curve is regular."),
        "",
        "Phase trajectory (eq. 2), branch s = +1 (p) and -1 (m):",
        "    w(q; C) = exp(-2 s mu alpha) [C - 2 g F_s(q)],  qdot^2 = w / h^2.",
    ]
    for s in (1, -1):
        F = d.branches[s].F
        text = str(F.expr) if F.closed else f"numeric quadrature of {F.integrand} from {F.q_ref}"
        lines.append(f"F_{_BRANCH[s]} (route {routes[s]}): {text}")
    lines += [
        "",
        f"SymPy {sp.__version__}; generator {provenance.GENERATOR_VERSION}; "
        f"input hash {provenance.input_hash(source)}.",
        "Each function's docstring gives its argument order; SIGNATURES lists them all.",
        '"""',
    ]
    # Only the first line opens and only the last closes the docstring; user text in the
    # lines between is shown only when it cannot end it (_doc_text).
    body = [lines[0]] + [_doc_text(line, "(not shown: see SOURCE)") for line in lines[1:-1]]
    return "\n".join(_wrap(line) for line in body) + '\n"""\n'


def _wrap(line: str, width: int = 100) -> str:
    if len(line) <= width:
        return line
    return "\n    ".join(line[i:i + width] for i in range(0, len(line), width))


def module_name(name: str) -> str:
    """Python module name for a curve name (``parabola-x`` -> ``parabola_x``)."""
    out = re.sub(r"\W", "_", name)
    return out if out[:1].isalpha() else "c_" + out


def _resolved(curve, source, name):
    """``(curve, source, name)`` of a catalogue name, a Shape, or a Curve with its ``source``."""
    from symvib.shapes import Shape, shape

    if isinstance(curve, str):
        curve = shape(curve)
    if isinstance(curve, Shape):
        source = curve.source() if source is None else source
        name = name or curve.module
        curve = curve.curve()
    if source is None:
        raise ValueError("generate() needs the curve's defining data (source) to hash")
    return curve, source, name


#: Budget of the whole closed-form search (s, all routes together) for a curve with
#: ``closed_form = "auto"``: a closed form SymPy finds quickly is taken (checked numerically),
#: and otherwise the numeric ``F_sigma``, so that a new curve's first run waits seconds rather
#: than every route's full budget (:data:`~symvib.symbolic.integrals.ROUTE_SECONDS` each).
AUTO_SEARCH_SECONDS = 4.0
#: Budget of one route under ``closed_form = "auto"`` (s; at most what is left of
#: :data:`AUTO_SEARCH_SECONDS`).
AUTO_ROUTE_SECONDS = 2.0
#: The order of the routes under ``closed_form = "auto"``: the tangent-angle route first, which
#: finds the parabolas' forms in 0.5-1.5 s where ``integrate`` takes 3-6 s on their branch -1.
AUTO_ROUTES = ("tangent-angle", "sympy", "split")


@dataclass(frozen=True)
class Plan:
    """How the derivation of a curve searches ``F_sigma`` in closed form (:func:`route_plan`).

    Attributes
    ----------
    routes : tuple of str
        The closed-form routes, in order (:data:`~symvib.symbolic.integrals.ROUTES`); empty for
        the numeric ``F_sigma`` at once.
    seconds : float
        Budget of one route.
    total : float or None
        Budget of all the routes together (``None``: each route its own ``seconds``).
    check : {"symbolic", "numeric"}
        How a closed form found is checked (:func:`symvib.symbolic.integrals.verify`).
    """

    routes: tuple
    seconds: float
    total: float | None
    check: str


def route_plan(closed_form: str = "auto") -> Plan:
    """The :class:`Plan` of the derivation of a curve whose ``F_sigma`` is found as
    ``closed_form`` says (:data:`symvib.shapes.CLOSED_FORMS`).

    Examples
    --------
    >>> route_plan("never").routes
    ()
    >>> plan = route_plan("auto")
    >>> plan.total == AUTO_SEARCH_SECONDS, plan.check
    (True, 'numeric')
    >>> route_plan("required").total is None
    True
    """
    from symvib.shapes import CLOSED_FORMS
    from symvib.symbolic.integrals import ROUTE_SECONDS, ROUTES

    assert sorted(AUTO_ROUTES) == sorted(ROUTES)
    plans = {"auto": Plan(AUTO_ROUTES, AUTO_ROUTE_SECONDS, AUTO_SEARCH_SECONDS, "numeric"),
             "required": Plan(ROUTES, ROUTE_SECONDS, None, "symbolic"),
             "never": Plan((), ROUTE_SECONDS, None, "symbolic")}
    if closed_form not in plans:
        raise ValueError(f"curve.closed_form: {closed_form!r} is not one of {', '.join(CLOSED_FORMS)}")
    return plans[closed_form]


def kernel_forms(source: dict) -> str:
    """The forms (:data:`symvib.symbolic.derive.FORMS`) of the kernels of the curve ``source``.

    A catalogue shape's module keeps the simplest forms (``"simplest"``: ``generated/`` and the
    paper's equations as they were); a user curve's is derived with its expressions as
    differentiated (``"direct"``), seconds sooner; whoever generates it (``symvib run``,
    ``symvib generate``), one input hash gives one module.

    Examples
    --------
    >>> from symvib.shapes import shape
    >>> kernel_forms(shape("circle").source()), kernel_forms({"name": "circle", "z": "x**4"})
    ('simplest', 'direct')
    """
    from symvib.shapes import CATALOGUE

    catalogue = CATALOGUE.get(source.get("name"))
    return "simplest" if catalogue is not None and catalogue.source() == source else "direct"


def module_source(curve, *, source: dict | None = None, seconds: float | None = None, routes=None,
                  closed_form: str | None = None, origin="<generated module>") -> str:
    """Derive ``curve`` and return the text of its kernel module, checked by the loader's whitelist.

    Arguments as :func:`generate`'s; ``origin`` names the module in errors.  Nothing is written.
    ``closed_form`` (``"auto"``, ``"required"``, ``"never"``: :func:`route_plan`) chooses the routes
    and their budget where ``routes`` and ``seconds`` are not given; ``"required"`` raises a
    ValueError naming ``curve.closed_form`` when a branch has no closed form.  The coefficients
    of eq. 1 are written in the forms :func:`kernel_forms` gives the curve.
    """
    from symvib.symbolic.integrals import ROUTE_SECONDS, ROUTES

    curve, source, _ = _resolved(curve, source, None)
    check_param_names(p.name for p in curve.params)  # before the derivation: fail in milliseconds
    _py_literal(source)
    closed_form = source.get("closed_form") if closed_form is None else closed_form
    plan = Plan(ROUTES, ROUTE_SECONDS, None, "symbolic") if closed_form is None else route_plan(closed_form)
    if seconds is not None or routes is not None:   # a budget or routes of one's own: every route its seconds
        plan = Plan(plan.routes if routes is None else tuple(routes), plan.seconds if seconds is None else seconds,
                    None, plan.check)
    d = derive(curve, seconds=plan.seconds, routes=plan.routes, total=plan.total, check=plan.check,
               forms=kernel_forms(source))
    missing = [s for s, br in d.branches.items() if br.F.route == "numeric"] if closed_form == "required" else []
    if missing:
        tried = "; ".join(f"{a.route}: {a.outcome}" for a in d.branches[missing[0]].F.attempts)
        raise ValueError(f"curve.closed_form: 'required', but F_sigma of branch {missing[0]:+d} has no closed "
                         f"form within the routes' budgets ({tried}); give closed_form = \"auto\" (the numeric "
                         f"F_sigma) or a longer budget (symvib generate --budget)")
    text = module_text(d, source)
    verify_text(text, origin)  # what a generator writes must pass what a loader checks
    return text


def generate(curve, out_dir, *, name: str | None = None, source: dict | None = None,
             seconds: float | None = None, routes=None) -> Path:
    """Derive ``curve`` and write its kernel module into ``out_dir``; returns the path.

    ``curve`` is a catalogue name, a :class:`~symvib.shapes.Shape` or a
    :class:`~symvib.symbolic.curve.Curve` (then give ``source``, its defining data).
    ``seconds`` and ``routes`` are :func:`~symvib.symbolic.derive.derive`'s (default: every
    route of :data:`~symvib.symbolic.integrals.ROUTES`, :data:`~symvib.symbolic.integrals.ROUTE_SECONDS`
    each); ``routes=()`` takes the numeric route at once, as a curve with no closed-form
    ``F_sigma`` ends up doing after the budgets of every route.  The module is written whole
    or not at all, never through a symbolic link (:func:`symvib.safeio.write_text`).
    """
    curve, source, name = _resolved(curve, source, name)
    stem = module_name(name or curve.name)
    out = safeio.check_root(out_dir, "output folder")
    text = module_source(curve, source=source, seconds=seconds, routes=routes, origin=out / f"{stem}.py")
    return safeio.write_text(out, f"{stem}.py", text)


def _generate_one(args):
    shape_name, out_dir = args
    return str(generate(shape_name, out_dir))


def generate_catalogue(out_dir, *, names=None, processes: int | None = None) -> list:
    """Write the kernel module of every catalogue shape (in parallel processes).

    With the whole catalogue, the driver's Gauss-Legendre table
    (:mod:`symvib.codegen.gauss`) is rewritten too.
    """
    import multiprocessing as mproc

    from symvib.shapes import CATALOGUE
    from symvib.symbolic.budget import worker_pool

    names = sorted(CATALOGUE) if names is None else list(names)
    jobs = [(n, str(out_dir)) for n in names]
    table = [] if len(names) < len(CATALOGUE) else [str(gauss.write_table(out_dir))]
    if processes == 1 or len(jobs) == 1:
        return table + [_generate_one(j) for j in jobs]
    with worker_pool(processes or min(len(jobs), mproc.cpu_count())) as pool:
        return table + list(pool.map(_generate_one, jobs))


def stale(out_dir, *, names=None) -> list:
    """Problems with the catalogue modules in ``out_dir`` (empty when all are current).

    A module is stale when it is missing, its input hash differs from the
    current one (the shape's data or the generator changed), or its body does
    not match its recorded digest (edited by hand).  No derivation is run.  With
    the whole catalogue, the Gauss-Legendre table is recomputed and compared.
    """
    from symvib.shapes import CATALOGUE

    out = Path(out_dir)
    names = sorted(CATALOGUE) if names is None else list(names)
    problems = []
    for n in names:
        shape_ = CATALOGUE[n]
        path = out / f"{module_name(shape_.module)}.py"
        if not path.exists():
            problems.append(f"{path}: missing")
            continue
        problems += _file_problems(path, provenance.input_hash(shape_.source()))
    expected = {f"{module_name(CATALOGUE[n].module)}.py" for n in names} | {"__init__.py",
                                                                             f"{gauss.TABLE_MODULE}.py"}
    if names == sorted(CATALOGUE):
        problems += gauss.table_problems(out)
        for extra in sorted(p.name for p in out.glob("*.py")):
            if extra not in expected:
                problems.append(f"{out / extra}: not a catalogue shape (remove it)")
    return problems


def _file_problems(path: Path, want_hash: str) -> list:
    text = path.read_text(encoding="utf-8")
    first, _, body = text.partition("\n")
    problems = []
    if not first.startswith(DIGEST_PREFIX) or first[len(DIGEST_PREFIX):] != hashlib.sha256(body.encode()).hexdigest():
        problems.append(f"{path}: edited by hand (body digest mismatch)")
    match = re.search(r"^INPUT_HASH = '([0-9a-f]{64})'$", body, re.M)
    if not match or match.group(1) != want_hash:
        problems.append(f"{path}: stale (inputs or generator changed); run `symvib generate`")
    return problems
