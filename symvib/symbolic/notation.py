"""Derived results printed in the paper's notation (physics.md, eqs. 1-2).

The derivation (:mod:`symvib.symbolic.derive`) keeps SymPy's forms: ``mu`` for the
friction coefficient, ``tan``, one branch at a time.  The paper writes the same
equations with the friction angle ``alpha0`` (``mu = tg alpha0``), ``tg`` for the
tangent, ``cos(phi +- alpha0)`` where a sine and a cosine combine, and one "double"
equation with ``+-``/``-+`` for the two branches (upper sign for ``v > 0``, ``N > 0``):

    phiddot +- phidot^2 tg alpha0 + g/(R cos alpha0) sin(phi +- alpha0) = 0    (circle, eq. 7)

How a branch becomes the double form: every derived quantity depends on the branch
``s`` through ``s mu`` only (physics.md, "Equation of motion (paper eq. 1)"), so with
``mu = tg alpha0`` the branch ``s`` is the ``s = +1`` expression at the angle
``s alpha0``.  :func:`paper_expr` rewrites the ``s = +1`` expression (``a cos u +
b sin u`` with ``mu`` in ``a``, ``b`` becomes a multiple of ``cos(u + alpha0)`` and
``sin(u + alpha0)`` where that is shorter), then replaces ``alpha0`` by ``PM alpha0``
and folds the odd and even functions (``cos(PM alpha0) = cos alpha0``,
``tg(PM alpha0) = PM tg alpha0``); ``PM`` prints as ``+-`` and ``-PM`` as ``-+``.

:class:`PaperForm` keeps the SymPy expression (in :data:`PM` and :data:`ALPHA0`),
its LaTeX and its plain text; :meth:`PaperForm.branch` gives a branch back in
``mu``, and :func:`parse_text` reads the plain text back, so both can be compared
with the derivation (``tests/test_notation.py``).

Examples
--------
>>> from symvib.symbolic.derive import derive
>>> d = derive("circle")
>>> print(eom(d).text)
phiddot ± phidot^2*tg(alpha0) + g*sin(phi ± alpha0)/(R*cos(alpha0)) = 0
>>> print(phase(d).latex)  # doctest: +ELLIPSIS
\\dot{\\varphi}^{2} = \\frac{C e^{\\mp 2 \\varphi \\operatorname{tg}{\\alpha_0}}}{R^{2}} + ...
"""
from __future__ import annotations

import re
from dataclasses import dataclass

import sympy as sp
from sympy.printing.latex import LatexPrinter
from sympy.printing.str import StrPrinter

from symvib import expr as _expr
from symvib.symbolic.curve import Curve, to_sympy
from symvib.symbolic.symbols import LATEX_NAMES, C, g, m, mu

__all__ = ["ALPHA0", "PM", "PaperForm", "paper_expr", "eom", "phase", "expression", "to_latex", "to_text",
           "parse_text", "markdown"]

#: The friction angle, ``mu = tg alpha0``.
ALPHA0 = sp.Symbol("alpha0", positive=True)
#: The branch sign as printed: ``PM`` is the paper's upper/lower sign ``+-`` (+1 for ``v > 0``, ``N > 0``).
PM = sp.Symbol("PM")
#: Text of the branch signs in plain text and LaTeX.
TEXT_PM, TEXT_MP = "±", "∓"
LATEX_PM, LATEX_MP = r"\pm", r"\mp"


# --- rewriting --------------------------------------------------------------------------
def _shortest(expr: sp.Expr) -> sp.Expr:
    """The shortest of a few cheap equivalent forms (by operation count)."""
    forms = [expr]
    for op in (sp.factor, lambda e: sp.trigsimp(sp.factor(e)), sp.cancel):
        try:
            forms.append(op(expr))
        except Exception:  # noqa: BLE001 - a simplifier may fail on odd input; keep what we have
            pass
    return min(forms, key=sp.count_ops)


def _rotated(add: sp.Expr) -> sp.Expr:
    """``a cos u + b sin u + rest`` (``mu`` in ``a``, ``b``) as ``cos(u + alpha0)``, ``sin(u + alpha0)``.

    With ``mu = tg alpha0``: ``a cos u + b sin u = cos(alpha0) [(a - b mu) cos(u + alpha0) +
    (a mu + b) sin(u + alpha0)]``, and where ``1 + mu^2`` divides both brackets the
    factor becomes ``1/cos(alpha0)`` (``cos^2 alpha0 (1 + mu^2) = 1``).  The result is
    returned in ``alpha0`` (no ``mu``) when it is shorter than ``add`` is.
    """
    k = 1 + mu**2
    best = add.subs(mu, sp.tan(ALPHA0))
    for f in sorted(add.atoms(sp.sin, sp.cos), key=sp.default_sort_key):
        u = f.args[0]
        c_, s_ = sp.Dummy("c"), sp.Dummy("s")
        expanded = sp.expand(add.subs({sp.cos(u): c_, sp.sin(u): s_}))
        a, b = expanded.coeff(c_, 1), expanded.coeff(s_, 1)
        rest = sp.expand(expanded - a * c_ - b * s_)
        if rest.has(c_, s_) or a.has(c_, s_) or b.has(c_, s_) or not (a.has(mu) or b.has(mu)):
            continue
        P, Q = sp.factor(a - b * mu), sp.factor(a * mu + b)
        Pk, Qk = sp.cancel(P / k), sp.cancel(Q / k)
        if sp.denom(Pk).has(mu) or sp.denom(Qk).has(mu):
            P_, Q_, scale = P, Q, sp.cos(ALPHA0)
        else:
            P_, Q_, scale = sp.factor(Pk), sp.factor(Qk), 1 / sp.cos(ALPHA0)
        if P_.could_extract_minus_sign():
            P_, Q_, scale = -P_, -Q_, -scale
        inner = sp.Add(P_ * sp.cos(u + ALPHA0), Q_ * sp.sin(u + ALPHA0))
        new = (scale * inner + rest).subs(mu, sp.tan(ALPHA0))
        if sp.count_ops(new) < sp.count_ops(best):
            best = new
    return best


def _walk(e: sp.Expr) -> sp.Expr:
    """Apply :func:`_rotated` to every sum, innermost first."""
    if not e.args:
        return e
    rebuilt = e.func(*[_walk(a) for a in e.args])
    return _rotated(rebuilt) if isinstance(rebuilt, sp.Add) and rebuilt.has(mu) else rebuilt


def _fold_branch(e: sp.Expr) -> sp.Expr:
    """``alpha0 -> PM alpha0`` with the odd and even functions folded and ``PM**2 = 1``."""
    e = e.subs(ALPHA0, PM * ALPHA0)
    e = e.replace(lambda x: isinstance(x, sp.cos) and x.args[0] == PM * ALPHA0, lambda x: sp.cos(ALPHA0))
    e = e.replace(lambda x: isinstance(x, (sp.sin, sp.tan)) and x.args[0] == PM * ALPHA0,
                  lambda x: PM * x.func(ALPHA0))
    e = e.replace(lambda x: x.is_Pow and x.base == PM and x.exp.is_integer,
                  lambda x: sp.Integer(1) if x.exp.is_even else PM)
    # 1 + tg^2 alpha0 = 1/cos^2 alpha0.
    return e.subs(sp.tan(ALPHA0) ** 2 + 1, 1 / sp.cos(ALPHA0) ** 2)


def paper_expr(expr: sp.Expr, *, angle: bool = True) -> sp.Expr:
    """The double (``PM``) form of the ``s = +1`` branch's ``expr``.

    Parameters
    ----------
    expr : sympy.Expr
        An expression of the ``s = +1`` branch, in ``mu``.
    angle : bool
        Write the friction as the angle, ``mu = tg alpha0``, and combine
        ``sin``/``cos`` pairs into ``sin(u +- alpha0)``, ``cos(u +- alpha0)``
        (the paper's circle); ``False`` keeps ``+- mu`` (its parabola).

    Returns
    -------
    sympy.Expr
        In :data:`PM` (and :data:`ALPHA0` when ``angle``).

    Examples
    --------
    >>> from sympy.abc import phi
    >>> paper_expr(sp.sin(phi) + mu * sp.cos(phi))
    sin(PM*alpha0 + phi)/cos(alpha0)
    >>> paper_expr(sp.sin(phi) + mu * sp.cos(phi), angle=False)
    PM*mu*cos(phi) + sin(phi)
    """
    if not angle:
        return expr.subs(mu, PM * mu)
    plain = expr.subs(mu, sp.tan(ALPHA0))
    rotated = _walk(expr).subs(mu, sp.tan(ALPHA0))
    return _fold_branch(min((rotated, plain), key=sp.count_ops))


def _branch_value(expr: sp.Expr, s: int) -> sp.Expr:
    """A double-form expression on branch ``s``, back in ``mu``."""
    return expr.subs(PM, s).subs(ALPHA0, sp.atan(mu))


# --- printing -----------------------------------------------------------------------------
def _pm_factor(expr) -> sp.Expr | None:
    """``expr / PM`` when ``PM`` is a factor of the product ``expr``, else None."""
    if isinstance(expr, sp.Mul) and PM in expr.args:
        return sp.Mul(*[a for a in expr.args if a != PM])
    return None


def _pm_last(terms: list) -> list:
    """Terms of a sum with those carrying the branch sign last: ``phi + PM alpha0``."""
    return sorted(terms, key=lambda t: _pm_factor(t) is not None or t == PM)


def _signed(rest_text: str, upper: str, lower: str) -> str:
    if rest_text == "1":
        return upper
    if rest_text == "-1":
        return lower
    return lower + rest_text[1:] if rest_text.startswith("-") else upper + rest_text


class _Text(StrPrinter):
    """Plain text: ``tg``, ``±``/``∓``, branch-sign terms last."""

    def _print_tan(self, expr):
        return f"tg({self._print(expr.args[0])})"

    def _print_Mul(self, expr):
        rest = _pm_factor(expr)
        if rest is None:
            return super()._print_Mul(expr)
        return _signed(self._print(rest), TEXT_PM, TEXT_MP)

    def _print_Symbol(self, expr):
        return TEXT_PM if expr == PM else super()._print_Symbol(expr)

    def _as_ordered_terms(self, expr, order=None):
        return _pm_last(super()._as_ordered_terms(expr, order=order))


class _Latex(LatexPrinter):
    """LaTeX: ``\\operatorname{tg}``, ``\\pm``/``\\mp``, branch-sign terms last."""

    def _print_tan(self, expr, exp=None):
        arg = self._print(expr.args[0])
        name = r"\operatorname{tg}" if exp is None else rf"\operatorname{{tg}}^{{{exp}}}"
        return rf"{name}{{{arg}}}" if expr.args[0].is_Atom else rf"{name}{{\left({arg} \right)}}"

    def _print_Mul(self, expr):
        rest = _pm_factor(expr)
        if rest is None:
            return super()._print_Mul(expr)
        return _signed(self._print(rest), LATEX_PM + " ", LATEX_MP + " ")

    def _print_Symbol(self, expr, style="plain"):
        return LATEX_PM if expr == PM else super()._print_Symbol(expr, style=style)

    def _as_ordered_terms(self, expr, order=None):
        return _pm_last(super()._as_ordered_terms(expr, order=order))


def _tidy(text: str, upper: str, lower: str) -> str:
    """``a + ±b`` -> ``a ± b``, ``a - ±b`` -> ``a ∓ b`` (and the same for ``∓``)."""
    up, low = upper.strip(), lower.strip()
    for before, after in ((f"- {up}", low), (f"- {low}", up), (f"+ {up}", up), (f"+ {low}", low)):
        text = text.replace(before, after + " ")
    return re.sub(r"  +", " ", text)


def _latex_names(curve: Curve | None) -> dict:
    names = {**LATEX_NAMES, ALPHA0: r"\alpha_0", PM: LATEX_PM}
    if curve is not None:
        names.update(curve.latex_names())
    return names


def to_latex(expr: sp.Expr, curve: Curve | None = None) -> str:
    r"""LaTeX of a double-form expression: ``\pm``/``\mp``, ``\operatorname{tg}``, ``\dot q``.

    >>> from sympy.abc import phi
    >>> to_latex(paper_expr(sp.sin(phi) + mu * sp.cos(phi)))
    '\\frac{\\sin{\\left(\\phi \\pm \\alpha_0 \\right)}}{\\cos{\\left(\\alpha_0 \\right)}}'
    """
    text = _Latex({"symbol_names": _latex_names(curve)}).doprint(expr)
    return _tidy(text, LATEX_PM + " ", LATEX_MP + " ")


def to_text(expr: sp.Expr) -> str:
    """Plain text of a double-form expression: ``±``/``∓``, ``tg(...)``, ``^`` for powers.

    >>> from sympy.abc import phi
    >>> to_text(paper_expr(sp.sin(phi) + mu * sp.cos(phi)))
    'sin(phi ± alpha0)/cos(alpha0)'
    """
    text = _Text({"order": None}).doprint(expr).replace("**", "^")
    return _tidy(text, TEXT_PM, TEXT_MP)


@dataclass(frozen=True)
class PaperForm:
    """One result in the paper's notation.

    Attributes
    ----------
    lhs, rhs : sympy.Expr
        ``lhs = rhs``, in :data:`PM` (the branch sign) and :data:`ALPHA0`.
    latex, text : str
        The printed equation.
    """

    lhs: sp.Expr
    rhs: sp.Expr
    latex: str
    text: str

    def branch(self, s: int) -> sp.Expr:
        """``lhs - rhs`` on branch ``s`` (+1: upper signs), in ``mu``, to compare with the derivation."""
        if s not in (1, -1):
            raise ValueError(f"branch s must be +1 or -1, not {s!r}")
        return _branch_value(self.lhs - self.rhs, s)

    def _repr_latex_(self) -> str:
        return f"$${self.latex}$$"

    def __str__(self) -> str:
        return self.text


def eom(d, *, angle: bool = True) -> PaperForm:
    """Eq. 1 as the paper prints it: ``qddot +- A qdot^2 + B = 0`` (both branches in one).

    Parameters
    ----------
    d : Derivation
        From :func:`symvib.symbolic.derive.derive`.
    angle : bool
        See :func:`paper_expr`.
    """
    c = d.curve
    br = d.branches[1]
    A, B = paper_expr(br.A, angle=angle), paper_expr(_shortest(br.B), angle=angle)
    terms = [c.qddot, A * c.qdot**2, B]
    lhs = sp.Add(*terms)
    latex = " ".join(_signed_term(to_latex(t, c), i) for i, t in enumerate(terms)) + " = 0"
    text = " ".join(_signed_term(to_text(t), i) for i, t in enumerate(terms)) + " = 0"
    return PaperForm(lhs=lhs, rhs=sp.Integer(0), latex=_tidy(latex, LATEX_PM + " ", LATEX_MP + " "),
                     text=_tidy(text, TEXT_PM, TEXT_MP))


def _signed_term(text: str, index: int) -> str:
    """A term of a sum printed on its own: ``+ x``, ``- x``, or the sign it carries (``± x``)."""
    for sign in (TEXT_PM, TEXT_MP, LATEX_PM, LATEX_MP):
        if text.startswith(sign):
            return f"{sign} {text[len(sign):].lstrip()}"
    if index == 0:
        return text
    return f"- {text[1:]}" if text.startswith("-") else f"+ {text}"


def phase(d, *, angle: bool = True) -> PaperForm:
    """Eq. 2 as the paper prints it: ``qdot^2 = C e^(-+2 alpha tg alpha0) / h^2 + particular``.

    The ``C`` term and the rest are printed apart, as the paper does (the
    exponential cancels in the rest); ``C`` is the derivation's constant.  Where
    ``F`` has no closed form (the numeric route) it is printed as ``F_+-``; the
    form's ``rhs`` keeps the integral.
    """
    c = d.curve
    F = d.branches[1].F
    h2 = _shortest(c.h**2)
    decay = sp.exp(-2 * mu * c.alpha)
    C_form = paper_expr(C * decay / h2, angle=angle)
    rest = _shortest(sp.powsimp(sp.expand(-2 * g * F.expr * decay / h2)))
    rest_form = paper_expr(rest, angle=angle)
    rhs = sp.Add(C_form, rest_form)
    names = _latex_names(c)
    if F.closed:
        shown_latex, shown_text = to_latex(rest_form, c), to_text(rest_form)
    else:  # a quadrature: printed as F_+- (its integrand is the docstring's)
        F_pm = sp.Symbol("F_PM")
        shown = paper_expr(-2 * g * F_pm * decay / h2, angle=angle)
        names = {**names, F_pm: r"F_{\pm}"}
        shown_latex = _tidy(_Latex({"symbol_names": names}).doprint(shown), LATEX_PM + " ", LATEX_MP + " ")
        shown_text = to_text(shown).replace("F_PM", "F_±")
    latex = f"{names[c.qdot]}^{{2}} = {to_latex(C_form, c)} {_signed_term(shown_latex, 1)}"
    text = f"{c.qdot}^2 = {to_text(C_form)} {_signed_term(shown_text, 1)}"
    return PaperForm(lhs=c.qdot**2, rhs=rhs, latex=_tidy(latex, LATEX_PM + " ", LATEX_MP + " "),
                     text=_tidy(text, TEXT_PM, TEXT_MP))


def expression(name: str, expr_plus: sp.Expr, curve: Curve | None = None, *, angle: bool = True) -> PaperForm:
    """Any ``s = +1`` branch expression (an energy, ``F_+``) as ``name = ...`` in the double form."""
    form = paper_expr(expr_plus, angle=angle)
    lhs = sp.Symbol(name)
    return PaperForm(lhs=lhs, rhs=form, latex=f"{sp.latex(lhs)} = {to_latex(form, curve)}",
                     text=f"{name} = {to_text(form)}")


def parse_text(text: str, curve: Curve) -> tuple:
    """Read a printed equation back: ``(lhs, rhs)`` in :data:`PM` and :data:`ALPHA0`.

    ``±``/``∓`` become ``+PM*``/``-PM*``, ``tg`` becomes ``tan`` and ``^`` ``**``;
    the rest goes through the safe parser :func:`symvib.expr.parse` (never ``eval``).

    >>> from symvib.symbolic.derive import derive
    >>> d = derive("circle")
    >>> lhs, rhs = parse_text(eom(d).text, d.curve)
    >>> sp.simplify(_branch_value(lhs - rhs, 1) - d.eom(1).lhs)
    0
    """
    if text.count("=") != 1:
        raise ValueError(f"a printed equation has one '=', got {text.count('=')}: {text[:60]!r}")
    plain = text.replace(TEXT_PM, "+PM*").replace(TEXT_MP, "-PM*").replace("^", "**")
    plain = re.sub(r"\btg\(", "tan(", plain)
    table = {s.name: s for s in (curve.q, curve.qdot, curve.qddot, *curve.params, g, m, mu, C, ALPHA0, PM)}
    sides = []
    for i, side in enumerate(plain.split("=")):
        parsed = _expr.parse(side.strip(), symbols=set(table), field=f"side {i + 1}")
        sides.append(to_sympy(parsed, table))
    return tuple(sides)


def markdown(d, *, angle: bool = True) -> str:
    """A Markdown block with eqs. 1-2 of a derivation in the paper's notation."""
    c = d.curve
    return "\n".join([
        f"**{c.name}** in the paper's notation (upper sign for $v > 0$, $N > 0$; "
        r"$\mu = \operatorname{tg}\alpha_0$):" if angle else f"**{c.name}** in the paper's notation:",
        "", f"$${eom(d, angle=angle).latex}$$", "", f"$${phase(d, angle=angle).latex}$$",
    ])
