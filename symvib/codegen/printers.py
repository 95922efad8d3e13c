"""The code printers of a kernel module: SymPy expressions -> NumPy and :mod:`math` source text.

:class:`NumPy` and :class:`Math` print an expression for the broadcasting kernels and for their
``*_scalar`` twins: integers and rationals too large for a machine integer as float literals
(:data:`BIG_INTEGER`), and never a conditional (a ``Piecewise`` or a relation that reaches a
printer is a :class:`~symvib.symbolic.branches.CurveError`).  :func:`generic` decides every
``Piecewise`` of a kernel's expression before printing; :func:`function` writes one kernel (cse'd
assignments, then the return; :data:`BROADCAST` defines the ``_broadcast`` it may call).
:func:`doc_text` and :func:`py_literal` bring user text and data into a module only where they
cannot end a docstring or run.  The kernel module (:mod:`symvib.codegen.kernel_text`) and the jets
module (:mod:`symvib.codegen.jets`) are printed by these.

Examples
--------
>>> NumPy().doprint(sp.sympify("x*10**30")), Math().doprint(sp.sign(sp.Symbol("q")))
('1e+30*x', 'math.copysign(1.0, q)')
"""
from __future__ import annotations

import math
import sys
import unicodedata

import sympy as sp
from sympy.printing.numpy import NumPyPrinter
from sympy.printing.pycode import PythonCodePrinter

from symvib.symbolic.branches import CurveError, generic_branch, removable_form

__all__ = ["NumPy", "Math", "function", "generic", "BROADCAST", "BIG_INTEGER", "doc_text", "py_literal"]

#: Unicode categories a user text may not bring into a docstring (controls, separators, surrogates).
_UNSAFE_CATEGORIES = frozenset({"Cc", "Cs", "Zl", "Zp"})

#: Integers at least this large (in magnitude) are printed as float literals: a Python
#: int beyond int64 makes NumPy fall back to objects and numba fail to type the kernel,
#: and beyond 2**53 a float is what the kernel computes with anyway.
BIG_INTEGER = 2**53


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


class NumPy(_NoConditionals, _BigNumbers, NumPyPrinter):
    """The printer of the broadcasting kernels (NumPy)."""

    suffix = ""

    def __init__(self):
        super().__init__({"fully_qualified_modules": True, "allow_unknown_functions": False})

    def _print_AppliedUndef(self, expr):
        # The only undefined functions in a kernel are calls of F_p / F_m.
        return f"{expr.func.__name__}{self.suffix}(" + ", ".join(self.doprint(a) for a in expr.args) + ")"

    def _print_Abs(self, expr):
        return f"numpy.abs({self.doprint(expr.args[0])})"

    def _print_sign(self, expr):
        # copysign as in the scalar twin (Math), not numpy.sign: sign(0) = 0 would make
        # q / sign(q) (removable_form) infinite at 0, and the twins differ there.
        return f"numpy.copysign(1.0, {self.doprint(expr.args[0])})"


class Math(_NoConditionals, _BigNumbers, PythonCodePrinter):
    """The printer of the ``*_scalar`` kernels (:mod:`math`, floats only)."""

    suffix = "_scalar"

    def __init__(self):
        super().__init__({"fully_qualified_modules": True, "allow_unknown_functions": False})

    _print_AppliedUndef = NumPy._print_AppliedUndef

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


def function(name: str, args: tuple, expr, doc: str, printer) -> str:
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
        if set(args) - used and isinstance(printer, NumPy):
            # Broadcast over every argument even where the expression ignores some
            # (h = R on a circle), so that kernels map arrays to arrays of one shape.
            body = f"_broadcast({body}, {', '.join(args)})"
        elif not isinstance(printer, NumPy) and _may_be_int(part):
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


def generic(expr, field: str):
    """A kernel's expression (or its ``(placeholders, Tuple)`` form) with every ``Piecewise``
    decided once, before cse (:func:`~symvib.symbolic.branches.generic_branch`)."""
    if isinstance(expr, tuple):
        pre, body = expr
        return {k: generic(v, field) for k, v in pre.items()}, generic(body, field)
    return removable_form(generic_branch(expr, field))


def _called_args(expr) -> set:
    return {str(s) for f in expr.atoms(sp.core.function.AppliedUndef) for a in f.args for s in a.free_symbols}


BROADCAST = '''

def _broadcast(value, *args):
    """value as an array of the broadcast shape of args."""
    return value * numpy.ones(numpy.broadcast(*args).shape)
'''


def doc_text(text: str, instead: str) -> str:
    """``text`` if it may stand in a docstring as it is, else ``instead``.

    User text is never interpolated into a docstring when it holds a quote, a
    backslash, a control or line/paragraph separator: those could close the
    docstring (``\"\"\"``), start an escape or a new line of code.
    """
    text = str(text)
    if any(ch in "\"\\" or unicodedata.category(ch) in _UNSAFE_CATEGORIES for ch in text):
        return instead
    return text


def py_literal(obj, field: str = "source") -> str:
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
        return "{" + ", ".join(f"{k!r}: {py_literal(obj[k], f'{field}.{k}')}" for k in sorted(obj)) + "}"
    if isinstance(obj, (list, tuple)):
        inner = ", ".join(py_literal(v, f"{field}[{i}]") for i, v in enumerate(obj))
        return f"[{inner}]" if isinstance(obj, list) else f"({inner}{',' if len(obj) == 1 else ''})"
    if isinstance(obj, float) and not math.isfinite(obj):
        return f"float({repr(obj)!r})"
    if obj is None or isinstance(obj, (str, bool, int, float)):
        return repr(obj)
    raise CurveError(f"{field}: {type(obj).__name__} value {obj!r} is not plain data (a string or a number)")

