"""Derive the double equation of motion, the double phase trajectory and the
energy expressions of a curve (physics.md; paper eqs. 1-2).

For a curve ``x(q), z(q)`` with metric ``h``, tangent angle ``alpha`` and
curvature ``kappa = alpha'/h``, on the branch ``s = sigma * sign(N)``
(``sigma = sign(v)``):

    qddot + A_s(q) qdot**2 + B_s(q) = 0,                       (eq. 1)
    A_s = h'/h + s mu alpha',   B_s = g (z' + s mu x') / h**2,

    qdot**2 = w / h**2,  w = exp(-2 s mu alpha) [C - 2 g F_s(q)],   (eq. 2)

with ``F_s`` from :mod:`symvib.symbolic.integrals`.  The paper's "double" equation is
the pair ``s = +1`` (upper signs, ``v > 0``) and ``s = -1``, written for a
positive normal force; where ``N < 0`` the branch with ``s = -sigma`` applies.

Energies (physics.md, "Energies"): ``Ek = m w / 2``, ``Ep = m g z``, ``E = Ek + Ep``,
``F_N = m (kappa w + g cos alpha)``, ``P_mu = -mu |F_N| |v|``.

Examples
--------
>>> d = derive("circle")
>>> d.eom(+1)
Eq(mu*phidot**2 + phiddot + g*(mu*cos(phi) + sin(phi))/R, 0)
>>> d.check()
{1: 'symbolic', -1: 'symbolic'}
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from functools import cached_property

import sympy as sp

from symvib.symbolic import budget
from symvib.symbolic.curve import Curve
from symvib.symbolic.identity import identity_holds
from symvib.symbolic.integrals import ROUTE_SECONDS, ROUTES, Antiderivative, antiderivatives
from symvib.symbolic.symbols import LATEX_NAMES, C, g, m, mu, sigma

#: The value of a numeric route's ``F_sigma`` at a check point (:meth:`Derivation.residual`): free,
#: as ``C`` is, since eq. 2 satisfies eq. 1 whatever it is.
PHI = sp.Symbol("Phi", real=True)

__all__ = ["Branch", "Derivation", "derive", "coefficients", "pm_latex", "FORMS"]

#: How :func:`derive` writes the coefficients ``A``, ``B`` of eq. 1: ``"simplest"`` takes the
#: shortest of a few simplified forms (``cancel``, ``trigsimp``, ``simplify``: the catalogue's
#: kernels and the paper's equations; seconds of SymPy for a curve with trigonometric terms),
#: ``"direct"`` the expressions as differentiated from the curve's own (already simplified)
#: ``h``, ``h'``, ``alpha'``, ``x'``, ``z'`` (a new user curve's first run: milliseconds).
FORMS = ("simplest", "direct")


def _simplest(expr: sp.Expr) -> sp.Expr:
    """The shortest of a few cheap equivalent forms."""
    forms = [expr]
    for op in (sp.cancel, sp.trigsimp, sp.simplify):
        forms.append(budget.simplify(expr, how=op))  # the input where one fails or runs out of time
    return min(forms, key=sp.count_ops)


def _as_differentiated(expr: sp.Expr) -> sp.Expr:
    """``expr`` as it stands (the ``"direct"`` forms of :data:`FORMS`)."""
    return expr


@dataclass(frozen=True)
class Branch:
    """One branch ``s`` of the double equations.

    Attributes
    ----------
    s : int
        +1 or -1: the sign multiplying ``mu`` (``sigma * sign(N)``).
    A, B : sympy.Expr
        Coefficients of ``qddot + A qdot**2 + B = 0`` (eq. 1).
    F : Antiderivative
        ``F_s`` with its route and verification.
    w : sympy.Expr
        Squared speed ``w(q; C) = exp(-2 s mu alpha) [C - 2 g F_s]`` (eq. 2).
    qdot2 : sympy.Expr
        ``qdot**2 = w / h**2``.
    """

    s: int
    A: sp.Expr
    B: sp.Expr
    F: Antiderivative
    w: sp.Expr
    qdot2: sp.Expr

    def qddot(self, qdot: sp.Symbol) -> sp.Expr:
        """Right-hand side ``qddot = -A qdot**2 - B``."""
        return -self.A * qdot**2 - self.B


@dataclass(frozen=True)
class Derivation:
    """Everything :func:`derive` finds for a curve (immutable).

    Attributes
    ----------
    curve : Curve
    branches : dict of int -> Branch
        Keyed by ``s`` = +1 and -1.
    A, B : sympy.Expr
        Coefficients of eq. 1 with the symbol ``sigma`` standing for ``s``.
    """

    curve: Curve
    branches: dict
    A: sp.Expr
    B: sp.Expr

    # --- equations -----------------------------------------------------------------
    def branch(self, sigma_: int, normal_sign: int = 1) -> Branch:
        """The branch that applies for velocity sign ``sigma_`` and normal-force sign."""
        if sigma_ not in (1, -1) or normal_sign not in (1, -1):
            raise ValueError("sigma and normal_sign must be +1 or -1")
        return self.branches[sigma_ * normal_sign]

    def eom(self, sigma_: int | None = None, normal_sign: int = 1) -> sp.Eq:
        """Eq. 1 as ``qddot + A qdot**2 + B = 0``; ``sigma_=None`` keeps the symbol ``sigma``."""
        c = self.curve
        if sigma_ is None:
            A, B = self.A.subs(sigma, sigma * normal_sign), self.B.subs(sigma, sigma * normal_sign)
        else:
            br = self.branch(sigma_, normal_sign)
            A, B = br.A, br.B
        return sp.Eq(c.qddot + A * c.qdot**2 + B, 0)

    def phase(self, sigma_: int, normal_sign: int = 1) -> sp.Eq:
        """Eq. 2 as ``qdot**2 = exp(-2 s mu alpha) [C - 2 g F_s] / h**2``."""
        return sp.Eq(self.curve.qdot**2, self.branch(sigma_, normal_sign).qdot2)

    @cached_property
    def qddot_general(self) -> sp.Expr:
        """``qddot`` valid for any sign of ``N``: friction ``mu sigma |N|`` (physics.md).

        ``(-g sin(alpha) - mu sigma |kappa h**2 qdot**2 + g cos(alpha)| - h' qdot**2) / h``,
        with ``sigma`` the sign of ``qdot``; used by references that integrate in time.
        """
        c = self.curve
        N = c.kappa * c.h**2 * c.qdot**2 + g * sp.cos(c.alpha)
        return (-g * sp.sin(c.alpha) - mu * sp.sign(c.qdot) * sp.Abs(N) - c.hp * c.qdot**2) / c.h

    # --- energies (physics.md, "Energies") -----------------------------------------------------
    @cached_property
    def energies(self) -> dict:
        """``Ek, Ep, E, F_N, P_mu`` as functions of the state ``(q, qdot)``."""
        c = self.curve
        v2 = c.h**2 * c.qdot**2
        Ek = m * v2 / 2
        Ep = m * g * c.z
        F_N = m * (c.kappa * v2 + g * sp.cos(c.alpha))
        P_mu = -mu * sp.Abs(F_N) * c.h * sp.Abs(c.qdot)
        return {"Ek": Ek, "Ep": Ep, "E": Ek + Ep, "F_N": F_N, "P_mu": P_mu}

    def energies_on_branch(self, s: int) -> dict:
        """The energies along branch ``s`` as functions of ``(q; C)``, as the paper prints them.

        ``P_mu`` assumes ``N > 0`` there, as the paper does.
        """
        c = self.curve
        w_ = self.branches[s].w
        F_N = m * (c.kappa * w_ + g * sp.cos(c.alpha))
        return {"Ek": m * w_ / 2, "Ep": m * g * c.z, "E": m * w_ / 2 + m * g * c.z, "F_N": F_N,
                "P_mu": -mu * F_N * sp.sqrt(w_)}

    # --- verification -----------------------------------------------------------------
    def residual(self, s: int) -> sp.Expr:
        """Eq. 2 substituted back into eq. 1: ``(qdot**2)'/2 + A qdot**2 + B`` (zero when right)."""
        br = self.branches[s]
        q, qdot2 = self.curve.q, br.qdot2
        integrals = qdot2.atoms(sp.Integral)
        if integrals:
            # The numeric route's F = Integral(F', (u, q_ref, q)): its value at a point is a quadrature
            # (of an integrand that may oscillate a million times: minutes), but eq. 2 must satisfy
            # eq. 1 whatever that value, as whatever C.  So F becomes a free value Phi with Phi' = F'
            # (the fundamental theorem), and the residual is checked at random Phi as at random C.
            Fq = sp.Function("Phi")(q)
            qdot2 = qdot2.xreplace({i: Fq for i in integrals})
            d = sp.diff(qdot2, q)
            for i in integrals:
                (u, _, upper), = i.limits
                d = d.subs(sp.Derivative(Fq, q), i.function.subs(u, upper))
            return (d / 2 + br.A * qdot2 + br.B).subs(Fq, PHI)
        return sp.diff(qdot2, q) / 2 + br.A * qdot2 + br.B

    def check(self) -> dict:
        """Back-substitute each phase trajectory; ``{s: "symbolic" | "numeric" | None}``.

        ``"numeric"`` means the residual is below 1e-25 (relative) at 30 digits
        at random points of the domain, parameters, ``mu``, ``g`` and ``C``.
        """
        extra = {mu: (0.01, 0.5), g: (1.0, 20.0), C: (5.0, 50.0), PHI: (-1.0, 1.0)}
        return {s: identity_holds(self.residual(s), self.curve, extra=extra) for s in (1, -1)}

    # --- display -------------------------------------------------------------------------
    def latex(self, *, pm: bool = True) -> dict:
        """LaTeX of every result, in the paper's style (``qddot + ... = 0``).

        With ``pm=True`` the branch sign prints as the paper's ``\\pm``/``\\mp``
        (upper sign for ``v > 0`` and ``N > 0``), otherwise as ``\\sigma``.
        Keys: ``"eom"``, ``"phase"``, ``"F+"``, ``"F-"``, ``"F_N"``, ``"P_mu"``,
        ``"Ek"``, ``"Ep"``, ``"E"``, ``"geometry"``.
        """
        c = self.curve
        names = {**LATEX_NAMES, **c.latex_names()}
        # A display symbol whose name sorts before every lower-case name, so that
        # SymPy prints "\pm \mu" rather than "\mu \pm".
        shown = sp.Symbol("PM") if pm else sigma
        names[shown] = r"\pm" if pm else r"\sigma"

        def tex(e):
            return pm_latex(sp.latex(e.subs(sigma, shown), symbol_names=names, order="none"))

        lhs = c.qddot + self.A * c.qdot**2 + self.B
        Fs = sp.Symbol("F_sigma")
        names[Fs] = r"F_{\pm}" if pm else r"F_{\sigma}"
        phase_rhs = sp.exp(-2 * sigma * mu * c.alpha) * (C - 2 * g * Fs) / c.h**2
        out = {
            "geometry": rf"h = {tex(c.h)},\quad \alpha = {tex(c.alpha)},\quad \kappa = {tex(c.kappa)}",
            "eom": tex(_collect(lhs, c)) + " = 0",
            "phase": rf"{names[c.qdot]}^{{2}} = {tex(phase_rhs)}",
        }
        for s, label in ((1, "F+"), (-1, "F-")):
            F = self.branches[s].F
            out[label] = rf"F_{{{'+' if s > 0 else '-'}}} = {tex(F.expr)}"
        for key, value in self.energies.items():
            out[key] = tex(value)
        return out

    def markdown(self) -> str:
        """A Markdown block with the LaTeX of :meth:`latex` (renders in notebooks)."""
        t = self.latex()
        c = self.curve
        routes = ", ".join(f"F_{'+' if s > 0 else '-'}: {b.F.route} ({b.F.verification})"
                           for s, b in self.branches.items())
        lines = [
            f"**{c.name}**: $x = {sp.latex(c.x, symbol_names=c.latex_names())}$, "
            f"$z = {sp.latex(c.z, symbol_names=c.latex_names())}$",
            "", f"$${t['geometry']}$$",
            "", "Double equation of motion (eq. 1), upper sign for $v > 0$, $N > 0$:",
            "", f"$${t['eom']}$$",
            "", "Double phase trajectory (eq. 2):", "", f"$${t['phase']}$$",
            "", f"$${t['F+']}$$", "", f"$${t['F-']}$$", "", f"Routes: {routes}.",
        ]
        return "\n".join(lines)

    def _repr_markdown_(self) -> str:
        return self.markdown()


def pm_latex(text: str) -> str:
    r"""LaTeX ``text`` with the branch sign ``\pm`` written as printed: ``- \pm`` becomes ``\mp``.

    SymPy prints a product with the branch-sign symbol as ``- \pm`` or
    ``+ \pm``; the paper writes ``\mp`` and ``\pm``.  Used by
    :meth:`Derivation.latex` and the audit (:mod:`symvib.paper.audit`).

    Parameters
    ----------
    text : str
        LaTeX in which the branch-sign symbol is printed as ``\pm``.

    Returns
    -------
    str

    Examples
    --------
    >>> pm_latex(r"a - \pm b + \pm c - 2 \pm d")
    'a \\mp b \\pm c \\mp 2 d'
    """
    text = re.sub(r"- (\d+) \\pm", r"\\mp \1", text)
    return text.replace(r"- \pm", r"\mp").replace(r"+ \pm", r"\pm").replace(r"-\pm", r"\mp")


def coefficients(xp, zp, h, hp, alphap, *, forms: str = "simplest") -> tuple:
    """``A, B`` of eq. 1 with the symbol ``sigma`` for the branch sign.

    ``A = h'/h + sigma mu alpha'`` and ``B = g (z' + sigma mu x') / h**2``, from
    ``dv/dt = h qddot + h' qdot**2 = -g sin(alpha) - sigma mu (kappa v**2 + g cos(alpha))``
    with ``v = h qdot``, ``h sin(alpha) = z'``, ``h cos(alpha) = x'``, ``kappa h = alpha'``;
    each ratio in the ``forms`` of :data:`FORMS`.
    """
    tidy = _form_maker(forms)
    A = tidy(hp / h) + sigma * mu * alphap
    B = g * (tidy(zp / h**2) + sigma * mu * tidy(xp / h**2))
    return A, B


def _form_maker(forms: str):
    """The function that writes an expression in the ``forms`` of :data:`FORMS`."""
    makers = {"simplest": _simplest, "direct": _as_differentiated}
    if forms not in makers:
        raise ValueError(f"forms: {forms!r} is not one of {', '.join(FORMS)}")
    return makers[forms]


def _collect(lhs: sp.Expr, c: Curve) -> sp.Expr:
    expanded = sp.expand(lhs)
    coeff = expanded.coeff(c.qdot, 2)
    rest = budget.simplify(expanded - coeff * c.qdot**2 - c.qddot)
    return sp.Add(c.qddot, _simplest(coeff) * c.qdot**2, _simplest(rest), evaluate=False)


def derive(curve, *, seconds: float = ROUTE_SECONDS, routes=ROUTES, forms: str = "simplest",
           total: float | None = None, check: str = "symbolic") -> Derivation:
    """Derive eqs. 1-2 and the energy expressions of ``curve``.

    Parameters
    ----------
    curve : Curve, Shape or str
        A curve, or the name of a catalogue shape.
    seconds : float
        Budget of each symbolic integration route (see :mod:`symvib.symbolic.integrals`).
    routes : sequence of str
        Closed-form routes to try for ``F_sigma``.
    forms : {"simplest", "direct"}
        How the coefficients of eq. 1 are written (:data:`FORMS`): ``"simplest"`` (the default:
        the catalogue's and the paper's forms) or ``"direct"`` (as differentiated, no
        simplification: a new user curve's kernels in a fraction of the time).
    total : float, optional
        Budget of all the routes together (default: none but each route's ``seconds``).
    check : {"symbolic", "numeric"}
        How a closed form found is checked (:func:`symvib.symbolic.integrals.antiderivatives`).

    Returns
    -------
    Derivation

    Examples
    --------
    >>> d = derive("circle", forms="direct", routes=())
    >>> d.branches[1].F.route
    'numeric'
    """
    if isinstance(curve, str):
        from symvib.shapes import shape

        curve = shape(curve).curve()
    elif not isinstance(curve, Curve) and hasattr(curve, "curve"):
        curve = curve.curve()
    if not isinstance(curve, Curve):
        raise TypeError(f"derive() needs a Curve, a Shape or a shape name, not {type(curve).__name__}")
    c = curve
    tidy = _form_maker(forms)
    A_sym, B_sym = coefficients(c.xp, c.zp, c.h, c.hp, c.alphap, forms=forms)
    branches = {}
    # Every route on both branches (their integrands differ in the sign of mu, and a route may
    # find one and not the other; the derivation notebooks show each attempt), side by side.
    found = antiderivatives(c, seconds=seconds, routes=routes, total=total, check=check)
    for s in (1, -1):
        F = found[s]
        A = tidy(A_sym.subs(sigma, s))
        B = tidy(B_sym.subs(sigma, s))
        w_ = sp.exp(-2 * s * mu * c.alpha) * (C - 2 * g * F.expr)
        branches[s] = Branch(s=s, A=A, B=B, F=F, w=w_, qdot2=w_ / c.h**2)
    return Derivation(curve=c, branches=branches, A=A_sym, B=B_sym)
