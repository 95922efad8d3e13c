"""The generic branch of a SymPy expression: what a kernel, which holds no conditional, evaluates.

SymPy writes ``Piecewise`` and ``DiracDelta`` when it differentiates ``Abs`` and
``sign``; :func:`generic_branch` decides each once, symbolically, and
:func:`removable_form` writes an ``Abs`` in a denominator so that a removable value
stays finite.  :class:`CurveError` is the error of a rejected curve definition, here
and in every step after (:mod:`symvib.symbolic.curve`, :mod:`symvib.codegen.generate`).
"""
from __future__ import annotations

import random

import mpmath
import sympy as sp

from symvib.symbolic.identity import CHECK_DIGITS

__all__ = ["CurveError", "generic_branch", "removable_form"]


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
