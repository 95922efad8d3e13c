"""The paper's printed equations, audited against the derivation.

Every equation the paper prints for the general curve (eqs. 1-2) and for the
parabola, cycloid and circle (eqs. 3-8 and the energy expressions ``F_N``,
``P_mu``, ``Ek``, ``Ep``, ``E``) is transcribed here, as printed, and compared
with :func:`symvib.symbolic.derive.derive`.  Beside each transcription is the
seed's own text (:mod:`symvib.paper.seed`); :func:`seed_differences` reads
it into SymPy and reports where the transcription differs from it beyond the
declared OCR noise.  A differing equation is a *root* error or *inherits* the
error of a printed equation it inserts or solves (:attr:`Verdict.origin`).  The paper's ``+-`` is the symbol ``pm``
(upper sign ``+1`` for ``v > 0``); ``tg alpha0`` is ``mu``.

Equal up to a rescaled (or shifted) integration constant and a shifted
potential-energy level counts as equal:

* an equation of motion matches when, divided by its ``qddot`` coefficient, it
  is the derived one (difference simplified to zero);
* a phase trajectory ``qdot**2 = W(q; C)`` matches when it solves the derived
  equation of motion for every ``C`` (``W'/2 + A W + B = 0``): the solutions
  form a one-parameter family, so it is then the derived one with ``C``
  rescaled and shifted;
* an energy expression with ``C`` matches when some ``C'`` makes the derived
  expression equal to it at every point (``C'`` solved at one point at 30
  digits, equality checked at others); ``Ep`` matches up to a constant.

Examples
--------
>>> verdicts = {v.key: v for v in audit()}
>>> verdicts["eq5"].matches, verdicts["eq3"].matches
(False, True)
"""
from __future__ import annotations

import random
import re
from dataclasses import dataclass
from functools import cache

import mpmath
import sympy as sp

from symvib.paper.seed import OCR_EDITS, SEED_TEXT
from symvib.shapes import shape
from symvib.symbolic.derive import coefficients, derive, pm_latex
from symvib.symbolic.identity import CHECK_DIGITS, identity_holds, sample_points
from symvib.symbolic.symbols import C, g, m, mu, sigma

__all__ = ["Printed", "Verdict", "PRINTED", "GENERAL", "audit", "derivation", "errata_markdown", "seed_differences",
           "seed_names"]

pm = sp.Symbol("pm")
#: Points at which numeric comparisons are made.
AUDIT_POINTS = 5
#: Relative tolerance of the numeric comparisons at 30 digits.
AUDIT_TOLERANCE = mpmath.mpf("1e-20")


@dataclass(frozen=True)
class Printed:
    """One printed equation: where it is, what it says, and its transcription.

    ``build(c)`` returns the printed expression in the symbols of curve ``c``
    and ``pm``: for ``kind="eom"`` the left side of ``... = 0``; for
    ``"phase"`` the right side of ``qdot**2 = ...``; for ``"energy"`` the
    expression (``qdot**2`` replaced by the printed phase trajectory, as the
    paper does).  ``formula(c)``, where the paper prints one, is the energy in
    terms of ``qdot`` before the trajectory is inserted (for ``P_mu``,
    ``formula(c, F_N)`` takes the normal force; by default the printed one).
    ``speed`` is the sign the paper gives ``qdot = speed * sqrt(qdot**2)`` where
    it inserts the trajectory, and ``inputs`` are the keys of the printed
    equations it inserts (whose errors it inherits).

    ``seed_text`` is the seed's own text of the equation (an exact substring of
    the seed file, :mod:`symvib.paper.seed`), ``ocr`` the differences
    between it and the transcription that are declared OCR noise, and
    ``sides`` the sides of its chain ``a = b = c`` that hold ``build`` and
    ``formula`` (``None``: not printed).  For the general curve (eqs. 1-2)
    ``c`` is :data:`GENERAL`.
    """

    key: str
    shape: str
    label: str
    kind: str
    quantity: str
    tex: str
    build: object
    note: str = ""
    formula: object = None
    seed_text: str = ""
    ocr: tuple = ()
    sides: tuple = (-1, None)
    inputs: tuple = ()
    speed: int = 1


@dataclass(frozen=True)
class Verdict:
    """The outcome of comparing one printed equation with the derivation.

    ``root`` is True for an error of its own; ``inherited`` lists the labels of
    the printed equations whose errors it carries (it inserts them, or it
    solves a wrong printed equation of motion).
    """

    key: str
    shape: str
    label: str
    matches: bool
    how: str
    evidence: str
    printed_tex: str
    corrected_tex: str
    root: bool = False
    inherited: tuple = ()

    @property
    def origin(self) -> str:
        """``"root"``, ``"inherited from eq. (5)"``, ``"root; also inherits eq. (8)"`` or ``""`` (matches)."""
        if self.matches:
            return ""
        names = " and ".join(_eq_name(x) for x in self.inherited)
        if self.root:
            return "root" + (f"; also inherits {names}" if names else "")
        return f"inherited from {names}"


def _eq_name(label: str) -> str:
    return f"eq. {label}" if label.startswith("(") else f"the printed {label}"


class _General:
    """The symbols of eqs. (1)-(2) for a general curve: arc ``s``, tangent angle ``alpha``, graph ``z = f(x)``."""

    sddot, alpha, v, R_k = sp.symbols("sddot alpha v R_k", real=True)
    x = sp.Symbol("x", real=True)
    f = sp.Function("f")


#: The "curve" the general entries are built on.
GENERAL = _General()


def _par(c, name):
    return next(p for p in c.params if p.name == name)


# --- transcriptions --------------------------------------------------------------------
def _parabola_W(c):
    phi = c.q
    p = _par(c, "p")
    return -g / (p * sp.cos(phi) ** 2) + C * sp.exp(-pm * 2 * mu * phi)


def _cycloid_Y(c):
    phi = c.q
    R = _par(c, "R")
    bracket = (pm * 3 * mu * sp.sin(phi) - (1 - 2 * mu**2) * sp.cos(phi) + (1 + 4 * mu**2) / 2
               + C * sp.exp(-pm * 2 * mu * phi))
    return -(g / (2 * R)) / (1 + 4 * mu**2) / sp.cos(phi / 2) ** 2 * bracket


def _circle_Z(c):
    phi = c.q
    R = _par(c, "R")
    a0 = sp.atan(mu)
    return (2 * g / ((1 + 4 * mu**2) * R * sp.cos(a0))
            * (sp.cos(phi + pm * a0) - 2 * mu * sp.sin(phi + pm * a0)) + C * sp.exp(-pm * 2 * phi * mu))


# The printed normal forces in terms of qdot (the P_mu entries insert them).
def _parabola_FN(c):
    return m * g * sp.cos(c.q) + m * _par(c, "p") * c.qdot**2 / sp.cos(c.q) ** 3


def _cycloid_FN(c):
    return m * g * sp.cos(c.q / 2) + m * 2 * _par(c, "R") * sp.cos(c.q / 2) * c.qdot**2


def _circle_FN(c):
    return m * g * sp.cos(c.q) + m * _par(c, "R") * c.qdot**2


def _eq2(c):
    """Eq. (2) as printed: the exponential inside the integral is e^{-int ...} as outside."""
    x, f = c.x, c.f
    fp, fpp = sp.diff(f(x), x), sp.diff(f(x), x, 2)
    h = sp.sqrt(1 + fp**2)
    inner = sp.Integral(2 / h * (sp.diff(h, x) + pm * mu * fpp / h), x)
    return sp.exp(-inner) * (-2 * g * sp.Integral(1 / (1 + fp**2) * (fp + pm * mu) * sp.exp(-inner), x) + C)


def _entries():
    P = []

    def add(key, *a, **k):
        P.append(Printed(key, *a, seed_text=SEED_TEXT[key], ocr=OCR_EDITS.get(key, ()), **k))

    # General curve (eqs. 1-2): see _judge_general.
    add("eq1", "general", "(1)", "eom", "equation of motion",
        r"\ddot s + g\sin\alpha \pm \mu\left(\frac{v^2}{R_k} + g\cos\alpha\right) = 0",
        lambda c: c.sddot + g * sp.sin(c.alpha) + pm * mu * (c.v**2 / c.R_k + g * sp.cos(c.alpha)),
        sides=(0, None))
    add("eq2", "general", "(2)", "phase", "phase trajectory",
        r"\dot x^2 = e^{-\int\frac{2}{\sqrt{1+z'^2}}\left[\frac{d}{dx}\sqrt{1+z'^2} \pm \mu\frac{z''}{"
        r"\sqrt{1+z'^2}}\right]dx}"
        r"\left[-2g\int\frac{z' \pm \mu}{1+z'^2}e^{-\int\ldots dx}dx + C\right]",
        _eq2)
    # Parabola, q = phi (tangent angle).
    add("eq3", "parabola", "(3)", "eom", "equation of motion",
        r"\ddot\phi + (3tg\phi \pm \mu)\dot\phi^2 + \frac{g\cos^3\phi}{p}(\sin\phi \pm \mu\cos\phi) = 0",
        lambda c: c.qddot + (3 * sp.tan(c.q) + pm * mu) * c.qdot**2
        + g * sp.cos(c.q) ** 3 / _par(c, "p") * (sp.sin(c.q) + pm * mu * sp.cos(c.q)), sides=(0, None))
    add("eq4", "parabola", "(4)", "phase", "phase trajectory",
        r"\dot\phi^2 = \cos^6\phi\left(-\frac{g}{p\cos^2\phi} + Ce^{\mp 2\mu\phi}\right)",
        lambda c: sp.cos(c.q) ** 6 * _parabola_W(c))
    add("parabola.F_N", "parabola", "F_N", "energy", "F_N",
        r"F_{N,i} = mg\cos\phi + mp\cos^3\phi\left(-\frac{g}{p\cos^2\phi} + C_ie^{\mp 2\mu\phi}\right)",
        lambda c: m * g * sp.cos(c.q) + m * _par(c, "p") * sp.cos(c.q) ** 3 * _parabola_W(c),
        formula=_parabola_FN, inputs=("eq4",))
    add("parabola.P_mu", "parabola", "P_mu", "energy", "P_mu",
        r"P_{\mu,i} = -\mu F_{N,i}\frac{p}{\cos^3\varphi}\dot\varphi = -\mu m p\left(g\cos\varphi + p\cos^3\varphi"
        r"(\ldots)\right)\sqrt{-\frac{g}{p\cos^2\varphi} + C_ie^{\mp 2\mu\varphi}}",
        lambda c: -mu * m * _par(c, "p") * (g * sp.cos(c.q) + _par(c, "p") * sp.cos(c.q) ** 3 * _parabola_W(c))
        * sp.sqrt(_parabola_W(c)),
        formula=lambda c, F_N=None: -mu * (_parabola_FN(c) if F_N is None else F_N)
        * _par(c, "p") / sp.cos(c.q) ** 3 * c.qdot,
        sides=(-1, 2), inputs=("parabola.F_N", "eq4"))
    add("parabola.Ek", "parabola", "Ek", "energy", "Ek",
        r"Ek_i = \frac12 m\frac{p^2}{\cos^6\phi}\dot\phi_i^2 = \frac12 mp^2\left(-\frac{g}{p\cos^2\phi} + "
        r"C_ie^{\mp 2\mu\phi}\right)",
        lambda c: m * _par(c, "p") ** 2 * _parabola_W(c) / 2,
        formula=lambda c: m * _par(c, "p") ** 2 / sp.cos(c.q) ** 6 * c.qdot**2 / 2, sides=(-1, 2), inputs=("eq4",))
    add("parabola.Ep", "parabola", "Ep", "energy", "Ep",
        r"Ep_i = \frac12\frac{mgp}{\cos^2\phi}",
        lambda c: m * g * _par(c, "p") / (2 * sp.cos(c.q) ** 2))
    add("parabola.E", "parabola", "E", "energy", "E",
        r"E_i = \frac12 mp^2\left(-\frac{g}{p\cos^2\phi} + C_ie^{\mp 2\mu\phi}\right) + \frac12\frac{mgp}{\cos^2\phi}",
        lambda c: m * _par(c, "p") ** 2 * _parabola_W(c) / 2 + m * g * _par(c, "p") / (2 * sp.cos(c.q) ** 2),
        formula=lambda c: m * _par(c, "p") ** 2 / sp.cos(c.q) ** 6 * c.qdot**2 / 2
        + m * g * _par(c, "p") / (2 * sp.cos(c.q) ** 2), inputs=("eq4",))
    # Cycloid, q = phi (rolling angle).
    add("eq5", "cycloid", "(5)", "eom", "equation of motion",
        r"\ddot\phi - \dot\phi^2\left(\frac12 tg\frac\phi2 \mp \mu\right) + \left(tg\frac\phi2 \pm \mu\right)"
        r"\frac{g}{2R} = 0",
        lambda c: c.qddot - c.qdot**2 * (sp.tan(c.q / 2) / 2 - pm * mu)
        + (sp.tan(c.q / 2) + pm * mu) * g / (2 * _par(c, "R")), sides=(0, None))
    add("eq6", "cycloid", "(6)", "phase", "phase trajectory",
        r"\dot\phi^2 = -\frac{g/2R}{1+4\mu^2}\frac{1}{\cos^2\frac\phi2}\left[(\pm 3\mu)\sin\phi - (1-2\mu^2)"
        r"\cos\phi + \frac{1+4\mu^2}{2} + Ce^{\mp 2\mu\phi}\right]",
        _cycloid_Y, note="unnumbered in the text; the paper cites it as (6)")
    add("cycloid.F_N", "cycloid", "F_N", "energy", "F_N",
        r"F_{N,i} = mg\cos\frac\phi2 + m2R\cos\frac\phi2\,\dot\phi_i^2(\phi)\ \text{(eq. 6 inserted)}",
        lambda c: m * g * sp.cos(c.q / 2) + m * 2 * _par(c, "R") * sp.cos(c.q / 2) * _cycloid_Y(c),
        formula=_cycloid_FN, inputs=("eq6",))
    add("cycloid.P_mu", "cycloid", "P_mu", "energy", "P_mu",
        r"P_{\mu,i} = -\mu F_{N,i}\,2R\cos\frac\phi2\,\dot\phi = -\mu F_{N,i}\,2R\cos\frac\phi2\,"
        r"\sqrt{\dot\phi_i^2(\phi)}",
        lambda c: -mu * (m * g * sp.cos(c.q / 2) + m * 2 * _par(c, "R") * sp.cos(c.q / 2) * _cycloid_Y(c))
        * 2 * _par(c, "R") * sp.cos(c.q / 2) * sp.sqrt(_cycloid_Y(c)),
        formula=lambda c, F_N=None: -mu * (_cycloid_FN(c) if F_N is None else F_N)
        * 2 * _par(c, "R") * sp.cos(c.q / 2) * c.qdot,
        sides=(-1, 1), inputs=("cycloid.F_N", "eq6"))
    add("cycloid.Ek", "cycloid", "Ek", "energy", "Ek",
        r"Ek_i = 2mR^2\cos^2\frac\phi2\,\dot\phi_i^2(\phi)",
        lambda c: 2 * m * _par(c, "R") ** 2 * sp.cos(c.q / 2) ** 2 * _cycloid_Y(c),
        formula=lambda c: 2 * m * _par(c, "R") ** 2 * sp.cos(c.q / 2) ** 2 * c.qdot**2,
        sides=(-1, 1), inputs=("eq6",))
    add("cycloid.Ep", "cycloid", "Ep", "energy", "Ep", r"Ep_i = mgR(1 - \cos\phi)",
        lambda c: m * g * _par(c, "R") * (1 - sp.cos(c.q)))
    add("cycloid.E", "cycloid", "E", "energy", "E",
        r"E_i = 2mR^2\cos^2\frac\phi2\,\dot\phi_i^2(\phi) + mgR(1-\cos\phi)",
        lambda c: 2 * m * _par(c, "R") ** 2 * sp.cos(c.q / 2) ** 2 * _cycloid_Y(c)
        + m * g * _par(c, "R") * (1 - sp.cos(c.q)),
        formula=lambda c: 2 * m * _par(c, "R") ** 2 * sp.cos(c.q / 2) ** 2 * c.qdot**2
        + m * g * _par(c, "R") * (1 - sp.cos(c.q)),
        note="the printed second term is garbled in the source; read as Ek + Ep", inputs=("eq6",))
    # Circle, q = phi.
    add("eq7", "circle", "(7)", "eom", "equation of motion",
        r"\ddot\phi \pm \dot\phi^2 tg\alpha_0 + \frac{g}{R\cos\alpha_0}\sin(\phi \pm \alpha_0) = 0",
        lambda c: c.qddot + pm * c.qdot**2 * mu
        + g / (_par(c, "R") * sp.cos(sp.atan(mu))) * sp.sin(c.q + pm * sp.atan(mu)), sides=(0, None))
    add("eq8", "circle", "(8)", "phase", "phase trajectory",
        r"\dot\phi^2 = \frac{2g}{(1+4tg^2\alpha_0)R\cos\alpha_0}\left[\cos(\phi\pm\alpha_0) - 2tg\alpha_0\sin("
        r"\phi\pm\alpha_0)\right] + Ce^{\mp 2\phi tg\alpha_0}",
        _circle_Z)
    add("circle.F_N", "circle", "F_N", "energy", "F_N",
        r"F_{N,i} = mg\cos\varphi + mR\,\dot\varphi_i^2(\varphi)\ \text{(eq. 8 inserted)}",
        lambda c: m * g * sp.cos(c.q) + m * _par(c, "R") * _circle_Z(c),
        formula=_circle_FN, inputs=("eq8",))
    add("circle.P_mu", "circle", "P_mu", "energy", "P_mu",
        r"P_{\mu,i} = -\mu F_{N,i}R\dot\varphi = -\mu F_{N,i}R\left\{-\sqrt{\dot\varphi_i^2(\varphi)}\right\}",
        lambda c: -mu * (m * g * sp.cos(c.q) + m * _par(c, "R") * _circle_Z(c)) * _par(c, "R")
        * (-sp.sqrt(_circle_Z(c))),
        formula=lambda c, F_N=None: -mu * (_circle_FN(c) if F_N is None else F_N) * _par(c, "R") * c.qdot,
        sides=(-1, 1), inputs=("circle.F_N", "eq8"), speed=-1)
    add("circle.Ek", "circle", "Ek", "energy", "Ek", r"Ek_i = \frac12 mR^2\dot\varphi_i^2(\varphi)",
        lambda c: m * _par(c, "R") ** 2 * _circle_Z(c) / 2,
        formula=lambda c: m * _par(c, "R") ** 2 * c.qdot**2 / 2, sides=(-1, 1), inputs=("eq8",))
    add("circle.Ep", "circle", "Ep", "energy", "Ep", r"Ep_i = mgR(1-\cos\varphi)",
        lambda c: m * g * _par(c, "R") * (1 - sp.cos(c.q)))
    add("circle.E", "circle", "E", "energy", "E",
        r"E_i = \frac12 mR^2\dot\varphi_i^2(\varphi) + mgR(1-\cos\phi)",
        lambda c: m * _par(c, "R") ** 2 * _circle_Z(c) / 2 + m * g * _par(c, "R") * (1 - sp.cos(c.q)),
        formula=lambda c: m * _par(c, "R") ** 2 * c.qdot**2 / 2 + m * g * _par(c, "R") * (1 - sp.cos(c.q)),
        inputs=("eq8",))
    return tuple(P)


#: Every printed equation, in the paper's order: eqs. (1)-(2) for the general curve, then the three curves.
PRINTED = _entries()


# --- comparisons --------------------------------------------------------------------------
@cache
def derivation(name: str):
    """The :class:`~symvib.symbolic.derive.Derivation` of catalogue shape ``name``, derived once per process.

    The audit and the paper report (:mod:`symvib.paper`) share it, so the
    report does not derive a curve the audit already derived.

    Parameters
    ----------
    name : str
        A catalogue shape name (``"parabola"``, ``"cycloid"``, ``"circle"``, ...).

    Returns
    -------
    symvib.symbolic.derive.Derivation
    """
    return derive(name)


def _tex(d, e):
    names = d.curve.latex_names()
    names[pm] = r"\pm"
    return pm_latex(sp.latex(e, symbol_names=names))


def _split_eom(expr, c):
    """``(A, B)`` of ``qddot + A qdot**2 + B`` after dividing by the ``qddot`` coefficient."""
    e = sp.expand(expr)
    e = sp.expand(e / e.coeff(c.qddot))
    A = e.coeff(c.qdot, 2)
    return A, sp.expand(e - c.qddot - A * c.qdot**2)


def _zero(e, c):
    e = sp.simplify(e)
    if e == 0 or sp.simplify(e.rewrite(sp.tan)) == 0:
        return True
    return identity_holds(e, c, extra={mu: (0.01, 0.5), g: (1.0, 20.0)}, simplify=False) is not None


def _sign_name(s):
    return "upper sign (v > 0)" if s > 0 else "lower sign (v < 0)"


def _judge_eom(entry, d) -> Verdict:
    c = d.curve
    notes, ok = [], True
    for s in (1, -1):
        Ap, Bp = _split_eom(entry.build(c).subs(pm, s), c)
        br = d.branches[s]
        dA, dB = sp.simplify(Ap - br.A), Bp - br.B
        okA, okB = dA == 0 or _zero(dA, c), _zero(dB, c)
        ok &= okA and okB
        if not okA:
            notes.append(f"{_sign_name(s)}: the coefficient of ${_tex(d, c.qdot**2)}$ is off by "
                         f"${_tex(d, dA)}$ (printed minus derived)")
        if not okB:
            notes.append(f"{_sign_name(s)}: the free term is off by ${_tex(d, sp.simplify(dB))}$")
    if ok:
        how, evidence = "identical", "printed minus derived is 0 on both branches"
    else:
        how, evidence = "differs", "; ".join(notes)
    return Verdict(entry.key, entry.shape, entry.label, ok, how, evidence, entry.tex,
                   d.latex()["eom"], root=not ok)


def _residual_in(W, A, B, q):
    return sp.diff(W, q) / 2 + A * W + B


def _judge_phase(entry, d) -> Verdict:
    c = d.curve
    extra = {mu: (0.01, 0.5), g: (1.0, 20.0), C: (-5.0, 50.0)}
    results = {}
    for s in (1, -1):
        W = entry.build(c).subs(pm, s)
        br = d.branches[s]
        results[s] = identity_holds(_residual_in(W, br.A, br.B, c.q), c, extra=extra)
    ok = all(results.values())
    wrong = [_sign_name(s) for s in (1, -1) if not results[s]]
    if ok:
        how = "equal up to the integration constant"
        evidence = (f"solves the derived eq. of motion for every C on both branches "
                    f"({results[1]} check)")
    else:
        # Does it solve the paper's own printed equation of motion instead?
        own = next((e for e in PRINTED if e.shape == entry.shape and e.kind == "eom"), None)
        consistent = None
        if own is not None:
            consistent = True
            for s in (1, -1):
                Ap, Bp = _split_eom(own.build(c).subs(pm, s), c)
                W = entry.build(c).subs(pm, s)
                consistent &= identity_holds(_residual_in(W, Ap, Bp, c.q), c, extra=extra) is not None
        s_bad = 1 if not results[1] else -1
        value = _sample_residual(entry, d, s_bad)
        how = "differs"
        right = [_sign_name(s) for s in (1, -1) if results[s]]
        evidence = (f"{' and '.join(wrong)}: substituted into the derived eq. of motion it leaves a "
                    f"residual ({value} at phi = 1/3, mu = 1/20, g = 9.81, C = 2, parameters 1/2)")
        if right:
            evidence += f"; the {' and '.join(right)} is right"
        if consistent:
            evidence += f"; it does solve the printed eq. {own.label}, so it inherits that equation's error"
        return Verdict(entry.key, entry.shape, entry.label, ok, how, evidence, entry.tex, d.latex()["phase"],
                       root=not consistent, inherited=(own.label,) if consistent else ())
    return Verdict(entry.key, entry.shape, entry.label, ok, how, evidence, entry.tex, d.latex()["phase"])


def _sample_residual(entry, d, s):
    c = d.curve
    br = d.branches[s]
    W = entry.build(c).subs(pm, s)
    res = _residual_in(W, br.A, br.B, c.q)
    subs = {c.q: sp.Rational(1, 3), mu: sp.Rational(1, 20), g: sp.Rational(981, 100), C: 2,
            **{p: sp.Rational(1, 2) for p in c.params}}
    return f"{float(sp.N(res.subs(subs), CHECK_DIGITS)):.3g}"


def _judge_energy(entry, d, done=None) -> Verdict:
    """Printed energy vs derived: equal for some constant ``C'`` (and level shift for Ep, E)."""
    c = d.curve
    quantity = entry.quantity
    shift = quantity in ("Ep", "E")
    rng = random.Random(sum(map(ord, entry.key)))
    notes = []
    with mpmath.workdps(CHECK_DIGITS):
        for s in (1, -1):
            printed = entry.build(c).subs(pm, s)
            derived = d.energies_on_branch(s)[quantity]
            if not printed.has(C):
                if identity_holds(sp.diff(printed - derived, c.q), c) is None:
                    notes.append(f"{_sign_name(s)}: printed minus derived is not a constant")
                continue
            values = {mu: sp.Float(0.05 + 0.1 * rng.random(), CHECK_DIGITS),
                      g: sp.Float(9.81, CHECK_DIGITS), m: sp.Float(0.2, CHECK_DIGITS),
                      **{p: sp.Float(0.5 + rng.random(), CHECK_DIGITS) for p in c.params}}
            Cp = _feasible_C(entry, d, s, values)
            points = sample_points(c, AUDIT_POINTS, seed=5, margin=0.3,
                                   values={p: values[p] for p in c.params})
            pf = sp.lambdify([c.q], printed.subs(values).subs(C, Cp), "mpmath")
            Cd = sp.Symbol("Cd")
            dfun = sp.lambdify([c.q, Cd], derived.subs(values).subs(C, Cd), "mpmath")
            # Fit C' (and a level shift K for Ep, E) at the first points, compare at the rest.
            try:
                if shift:
                    Csol, K = mpmath.findroot(
                        [lambda x, k: dfun(points[0], x) + k - pf(points[0]),
                         lambda x, k: dfun(points[1], x) + k - pf(points[1])], (Cp, 0))
                else:
                    Csol, K = mpmath.findroot(lambda x: dfun(points[0], x) - pf(points[0]), Cp), 0
            except (ValueError, ZeroDivisionError):
                notes.append(f"{_sign_name(s)}: no integration constant makes the derived {quantity} "
                             "equal to it")
                continue
            rest = points[2:] if shift else points[1:]
            worst = max(abs(dfun(qv, Csol) + K - pf(qv)) / max(abs(pf(qv)), mpmath.mpf(1)) for qv in rest)
            if not worst < AUDIT_TOLERANCE:
                notes.append(f"{_sign_name(s)}: with the constant fitted, the derived {quantity} and the "
                             f"printed one still differ by {float(worst):.2g} (relative) elsewhere")
    ok = not notes
    formula_note = _judge_formula(entry, d)
    if ok:
        if not entry.build(c).has(C):
            how = ("identical" if sp.simplify(entry.build(c) - d.energies_on_branch(1)[quantity]) == 0
                   else "equal up to a shift of the potential-energy level")
        else:
            how = "equal up to the integration constant" + (" and the energy level" if shift else "")
        evidence = "matches the derived expression on both branches"
        return Verdict(entry.key, entry.shape, entry.label, ok, how, evidence, entry.tex, d.latex()[quantity])
    how, evidence = "differs", "; ".join(notes)
    if formula_note:
        evidence += "; " + formula_note
    done = done or {}
    inherited = tuple(done[k].label for k in entry.inputs if k in done and not done[k].matches)
    own = _own_form_holds(entry, d)
    evidence += ("; with the derived " + " and ".join(_eq_name(x) for x in inherited) + " inserted instead, "
                 + ("it is right" if own else "it is still wrong")) if inherited else ""
    return Verdict(entry.key, entry.shape, entry.label, ok, how, evidence, entry.tex, d.latex()[quantity],
                   root=not own, inherited=inherited)


def _own_form_holds(entry, d) -> bool:
    """Whether the printed energy is right once its inputs are the derived ones.

    The printed form in terms of ``qdot`` (``formula``; for ``P_mu`` with the
    derived ``F_N``), with ``qdot = speed * sqrt(qdot**2)`` of the derived
    trajectory inserted as the paper inserts its own, against the derived
    energy along each branch (``Ep`` and ``E`` up to a constant level).
    """
    c = d.curve
    extra = {mu: (0.01, 0.5), g: (1.0, 20.0), m: (0.1, 1.0), C: (1000.0, 2000.0)}
    for s in (1, -1):
        if entry.formula is None:
            printed = entry.build(c).subs(pm, s)
        else:
            printed = (entry.formula(c, d.energies["F_N"]) if entry.quantity == "P_mu" else entry.formula(c))
            printed = printed.subs(c.qdot, entry.speed * sp.sqrt(d.branches[s].qdot2))
        diff = printed - d.energies_on_branch(s)[entry.quantity]
        if entry.quantity in ("Ep", "E"):
            diff = sp.diff(diff, c.q)
        if identity_holds(diff, c, extra=extra, simplify=False) is None:
            return False
    return True


def _judge_formula(entry, d) -> str:
    """Whether the printed energy in terms of ``qdot`` (before inserting a trajectory) is right."""
    if entry.formula is None:
        return ""
    c = d.curve
    # For qdot > 0 and F_N > 0 the absolute values of the derived P_mu drop out.
    derived = d.energies[entry.quantity].replace(sp.Abs, lambda a: a)
    diff = entry.formula(c) - derived
    if entry.quantity in ("Ep", "E"):
        diff = sp.diff(diff, c.q)
    extra = {c.qdot: (0.5, 3.0), mu: (0.01, 0.5), g: (1.0, 20.0), m: (0.1, 1.0)}
    if identity_holds(diff, c, extra=extra) is not None:
        return (f"its form in terms of ${_tex(d, c.qdot)}$ is right (for ${_tex(d, c.qdot)} > 0$): "
                "the difference comes from the inserted phase trajectory")
    return (f"its form in terms of ${_tex(d, c.qdot)}$ is itself wrong: printed minus derived = "
            f"${_tex(d, sp.simplify(diff))}$ for ${_tex(d, c.qdot)} > 0$")


def _feasible_C(entry, d, s, values):
    """An integration constant making the printed qdot**2 positive on the central part of the domain."""
    phase = next(e for e in PRINTED if e.shape == entry.shape and e.kind == "phase")
    c = d.curve
    W = sp.lambdify([c.q, C], phase.build(c).subs(pm, s).subs(values), "mpmath")
    points = sample_points(c, AUDIT_POINTS, seed=5, margin=0.3, values={p: values[p] for p in c.params})
    for trial in (1, 10, 100, 1000, -1, -10, -100, -1000):
        if all(mpmath.re(W(qv, trial)) > 0 for qv in points):
            return sp.Integer(trial)
    return sp.Integer(1)


def _printed(key: str) -> Printed:
    return next(e for e in PRINTED if e.key == key)


def _general_entries():
    """Eqs. (1) and (2): checked for an arbitrary curve with undefined functions."""
    G = GENERAL
    verdicts = []
    # Eq. (1) with s(q), s' = H, v = H qdot, sin(alpha) = Z'/H, cos(alpha) = X'/H, 1/R_k = kappa = alpha'/H
    # for an arbitrary parametrization X(q), Z(q).
    u = sp.Symbol("q", real=True)
    X, Z = sp.Function("X")(u), sp.Function("Z")(u)
    Xp, Zp = sp.diff(X, u), sp.diff(Z, u)
    H = sp.sqrt(Xp**2 + Zp**2)
    Ap_ = (Xp * sp.diff(Zp, u) - Zp * sp.diff(Xp, u)) / H**2
    qd, qdd = sp.symbols("qdot qddot", real=True)
    eq1 = _printed("eq1")
    ok1 = True
    for s in (1, -1):
        printed = eq1.build(G).subs(pm, s).subs({sp.sin(G.alpha): Zp / H, sp.cos(G.alpha): Xp / H}).subs(
            {G.sddot: H * qdd + sp.diff(H, u) * qd**2, G.v: H * qd, G.R_k: H / Ap_})
        Ag, Bg = coefficients(Xp, Zp, H, sp.diff(H, u), Ap_)
        derived = qdd + Ag.subs(sigma, s) * qd**2 + Bg.subs(sigma, s)
        ok1 &= sp.simplify(printed / H - derived) == 0
    verdicts.append(Verdict(
        "eq1", "general", "(1)", ok1, "identical" if ok1 else "differs",
        "with s' = h q', v = h qdot, 1/R_k = kappa = alpha'/h, divided by h it is the derived "
        "qddot + A qdot^2 + B = 0 for an arbitrary parametrization X(q), Z(q)",
        eq1.tex,
        r"\ddot q + \left(\frac{h'}{h} \pm \mu\alpha'\right)\dot q^2 + \frac{g(z' \pm \mu x')}{h^2} = 0",
        root=not ok1))
    # Eq. (2): the graph form of the phase trajectory, with unevaluated integrals.
    x, f = G.x, G.f
    fp, fpp = sp.diff(f(x), x), sp.diff(f(x), x, 2)
    h = sp.sqrt(1 + fp**2)
    A, B = coefficients(sp.Integer(1), fp, h, sp.diff(h, x), fpp / (1 + fp**2))
    eq2 = _printed("eq2")

    def solves(W, s):
        # Expanded, exponentials combined and cancelled: zero exactly when it solves it (no simplify needed).
        res = sp.diff(W, x) / 2 + A.subs(sigma, s) * W + B.subs(sigma, s)
        return sp.cancel(sp.powsimp(sp.expand(res), combine="exp")) == 0

    ok2 = all(solves(eq2.build(G).subs(pm, s), s) for s in (1, -1))
    if ok2:
        evidence = ("for a graph z = f(x) with f undefined, the printed xdot^2(x) (integrals left unevaluated) "
                    "solves the derived equation of motion xddot + A xdot^2 + B = 0 identically")
    else:
        # The same with the exponential inside the integral e^{+int ...}: the sign is the error.
        fixed = eq2.build(G).replace(
            lambda e: isinstance(e, sp.Integral) and e.function.has(sp.exp),
            lambda e: sp.Integral(e.function.replace(sp.exp, lambda a: sp.exp(-a)), *e.limits))
        right = all(solves(fixed.subs(pm, s), s) for s in (1, -1))
        evidence = ("for a graph z = f(x) with f undefined, the printed xdot^2(x) (integrals left unevaluated) "
                    "does not solve the derived equation of motion xddot + A xdot^2 + B = 0: substituted, it "
                    "leaves g (z' +- mu)/(1 + z'^2) (1 - e^{-2 int P dx}), P the bracket of the exponent")
        if right:
            evidence += ("; with e^{+int ... dx} inside the integral (the integrating factor) it solves it "
                         "identically on both branches")
    verdicts.append(Verdict(
        "eq2", "general", "(2)", ok2, "identical" if ok2 else "differs", evidence, eq2.tex,
        r"\dot x^2 = e^{-\int P\,dx}\left[C - 2g\int\frac{z' \pm \mu}{1+z'^2}e^{+\int P\,dx}dx\right],\ "
        r"P = \frac{2}{\sqrt{1+z'^2}}\left[\frac{d}{dx}\sqrt{1+z'^2} \pm \mu\frac{z''}{\sqrt{1+z'^2}}\right]",
        root=not ok2))
    return verdicts


# --- the transcriptions against the seed's text ----------------------------------------------
#: Sampling ranges of the symbols when a transcription is compared with the seed's text.
SEED_RANGES = {"mu": (0.01, 0.5), "g": (1.0, 20.0), "m": (0.1, 1.0), "C": (-5.0, 50.0), "phi": (-0.6, 0.6),
               "phidot": (0.3, 3.0), "alpha": (-1.0, 1.0), "v": (0.1, 3.0), "R_k": (0.5, 3.0)}
#: Relative difference above which a transcription and the seed's text differ (30-digit evaluation).
SEED_TOLERANCE = 1e-18


def seed_names(entry: Printed, c=None, F_N=None) -> dict:
    """The name table the entry's seed text is read with (:func:`symvib.paper.seedtex.parse`).

    ``C_i`` (the constant of interval ``i``) is ``C``, ``\\dot\\phi_i`` is ``qdot``,
    ``alpha_0`` is ``atan(mu)``; ``F_{N,i}`` (in a ``P_mu``) is ``F_N`` when given.
    """
    base = {"g": g, "mu": mu, "pm": pm, "C": C, "C_i": C, "m": m}
    if entry.shape == "general":
        G = GENERAL
        fp = sp.diff(G.f(G.x), G.x)
        return base | {"ddot s": G.sddot, "alpha": G.alpha, "v": G.v, "R_k": G.R_k, "x": G.x, "z'": fp,
                       "z''": sp.diff(fp, G.x)}
    c = c if c is not None else shape(entry.shape).curve()
    names = base | {"phi": c.q, "dot phi": c.qdot, "dot phi_i": c.qdot, "ddot phi": c.qddot,
                    "alpha_0": sp.atan(mu)} | {p.name: p for p in c.params}
    if F_N is not None:
        names["F_N,i"] = F_N
    return names


def seed_differences(entry: Printed) -> list:
    """Where the transcription differs from the seed's text with the declared OCR edits applied.

    The seed's text is read into SymPy (:func:`symvib.paper.seedtex.read`):
    the side holding the printed expression is compared with ``build`` (for an
    equation of motion, left minus right side), and the side holding the form
    in terms of the velocity, where printed, with ``formula``.  Returns one
    message per difference (empty when they agree).
    """
    from symvib.paper import seedtex

    c = GENERAL if entry.shape == "general" else shape(entry.shape).curve()
    build_side, formula_side = entry.sides
    fn = _printed(f"{entry.shape}.F_N") if entry.quantity == "P_mu" else None
    roles = [("transcription", build_side, entry.build(c), fn.build(c) if fn else None)]
    if formula_side is not None:
        roles.append(("velocity form", formula_side, entry.formula(c), fn.formula(c) if fn else None))
    problems = []
    for role, side, mine, F_N in roles:
        names = seed_names(entry, c, F_N)
        try:
            if entry.kind == "eom":
                lhs, rhs = seedtex.read(entry.seed_text, entry.ocr, names, sides=(0, -1))
                seed = lhs - rhs
            else:
                (seed,) = seedtex.read(entry.seed_text, entry.ocr, names, sides=(side,))
        except seedtex.SeedTexError as exc:
            problems.append(f"{entry.key} ({role}): the seed text does not read: {exc}")
            continue
        where = _differ(mine, seed)
        if where:
            problems.append(f"{entry.key} ({role}): {where}")
    return problems


def _canonical(e):
    """``e`` with every integrand simplified (integrals compare structurally)."""
    return e.replace(lambda x: isinstance(x, sp.Integral),
                     lambda x: sp.Integral(sp.factor(sp.simplify(x.function)), *x.limits))


def _differ(mine, seed) -> str:
    """``""`` when the two expressions agree, else where they do not."""
    if mine.has(sp.Integral) or seed.has(sp.Integral):
        d = sp.simplify(_canonical(mine) - _canonical(seed))
        return "" if d == 0 else f"transcription minus seed = {d}"
    rng = random.Random(7)
    symbols = sorted((mine.free_symbols | seed.free_symbols) - {pm}, key=str)
    for _ in range(3):
        for s in (1, -1):
            vals = {pm: s}
            for sym in symbols:
                lo, hi = SEED_RANGES.get(sym.name, (0.5, 2.0))
                vals[sym] = sp.Float(lo + (hi - lo) * rng.random(), CHECK_DIGITS)
            a, b = (complex(e.evalf(CHECK_DIGITS, subs=vals)) for e in (mine, seed))
            if abs(a - b) > SEED_TOLERANCE * max(1.0, abs(a), abs(b)):
                at = ", ".join(f"{k} = {float(v):.4g}" for k, v in vals.items())
                return f"transcription {a:.10g} against seed {b:.10g} at {at}"
    return ""


def audit(shapes=("parabola", "cycloid", "circle"), *, general: bool = True) -> tuple:
    """Compare every printed equation with the derivation; one :class:`Verdict` each.

    Eqs. (1)-(2) come first (general curve; left out with ``general=False``),
    then each shape's entries in the paper's order.
    """
    verdicts = list(_general_entries()) if general else []
    done = {}
    for entry in PRINTED:
        if entry.shape in shapes:
            d = derivation(entry.shape)
            if entry.kind == "energy":
                done[entry.key] = _judge_energy(entry, d, done)
            else:
                done[entry.key] = (_judge_eom if entry.kind == "eom" else _judge_phase)(entry, d)
            verdicts.append(done[entry.key])
    return tuple(verdicts)


#: What each known erratum amounts to, in words (keyed by verdict key).
EXPLANATIONS = {
    "eq2": "The exponential inside the integral must be e^{+int P dx} (the integrating factor of the linear "
           "equation for xdot^2), not e^{-int P dx} as the seed prints it. With the printed sign eq. (2) does not "
           "solve eq. (1); the curves' eqs. (4), (6), (8) do not inherit it (eq. (4) is right).",
    "eq5": "The friction term of the velocity-squared coefficient is mu/2, not mu: on the cycloid "
           "alpha = phi/2, so s mu alpha' = s mu/2. The printed equation has the coefficient of a "
           "curve with alpha' = 1.",
    "eq6": "Eq. (6) solves the printed eq. (5), not the equation of motion: the exponent must be "
           "exp(-+ mu phi) and the bracket follows from F_s = R exp(s mu phi)[(2 s mu sin phi - "
           "(1 - mu^2) cos phi)/(1 + mu^2) + 1].",
    "cycloid.F_N": "The centripetal term is kappa w = R cos(phi/2) phidot^2 (radius of curvature "
                   "4 R cos(phi/2)), not 2 R cos(phi/2) phidot^2; it also inserts eq. (6).",
    "cycloid.P_mu": "Built from the printed F_N and eq. (6), both wrong; the form -mu F_N v is right.",
    "cycloid.Ek": "The form 2 m R^2 cos^2(phi/2) phidot^2 is right; it inserts the wrong eq. (6).",
    "cycloid.E": "Inherits eq. (6) through Ek.",
    "eq8": "The lower sign is wrong: the bracket must be cos(phi -+ alpha0) -+ 2 tg(alpha0) sin(phi -+ alpha0) "
           "(upper signs for v > 0), i.e. (1 - 2 mu^2) cos(phi) -+ 3 mu sin(phi) after dividing by cos(alpha0). "
           "The printed '- 2 tg(alpha0)' for both signs breaks the mirror symmetry phi -> -phi between "
           "the branches.",
    "circle.F_N": "The form m g cos(phi) + m R phidot^2 is right; it inserts eq. (8), wrong for v < 0.",
    "circle.Ek": "The form m R^2 phidot^2 / 2 is right; it inserts eq. (8), wrong for v < 0.",
    "circle.E": "Inherits eq. (8) through Ek.",
    "circle.P_mu": "The power of friction is -mu |F_N| R |phidot| <= 0; the printed form inserts "
                   "phidot = -sqrt(...), which makes it positive, and eq. (8), wrong for v < 0.",
}


def _first_sentence(text: str) -> str:
    """Up to the first full stop that ends a sentence (not the one of "eq. (6)" or "i.e.")."""
    return re.split(r"\.\s+(?=[A-Z])", text, maxsplit=1)[0].rstrip(".")


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def seed_cell(entry: Printed) -> str:
    """The seed's text of ``entry`` as a Markdown code span for a table cell (line breaks shown as ``↵``)."""
    text = " ↵ ".join(entry.seed_text.split("\n"))
    return f"`{_cell(text)}`"


def ocr_cell(entry: Printed) -> str:
    """The declared OCR differences of ``entry`` for a table cell (``none`` when there are none)."""
    if not entry.ocr:
        return "none"
    return "; ".join(f"`{_cell(e.seed)}` read as `{_cell(e.reading)}`: {_cell(e.reason)}" for e in entry.ocr)


def errata_rows(verdicts) -> list:
    """The rows of the errata table (Markdown), one per verdict: eq., curve, verdict, error, note."""
    rows = []
    for v in verdicts:
        note = v.how if v.matches else _first_sentence(EXPLANATIONS.get(v.key, v.evidence))
        verdict = "matches" if v.matches else "**differs**"
        rows.append(f"| {v.label} | {v.shape} | {verdict} | {v.origin or '-'} | {_cell(note)} |")
    return rows


def errata_markdown(verdicts=None, *, extra_rows=(), title="# Errata of the paper's printed equations") -> str:
    """The errata of the printed equations (Markdown): the table, each differing equation, each seed text.

    ``extra_rows`` are further table rows (already formatted: five cells),
    such as the reading of the circle's "alpha0 = 3" (:mod:`symvib.paper.errata`).
    """
    verdicts = audit() if verdicts is None else verdicts
    wrong = [v for v in verdicts if not v.matches]
    roots = [v for v in wrong if v.root]
    lines = [
        title,
        "",
        "Generated by `symvib.paper.errata.write_errata` (`python -m symvib.paper.errata docs/errata.md`) from",
        "`symvib/paper/audit.py`, which transcribes every printed equation and compares it with",
        "`symvib.symbolic.derive` (tests: `tests/test_audit.py`). Equal up to a rescaled integration constant",
        "or a shifted potential-energy level counts as equal. Upper signs are for `v > 0`; `tg alpha0 = mu`.",
        f"Of {len(verdicts)} printed equations {len(wrong)} differ: {len(roots)} by an error of their own "
        "(*root*), the others only because they insert or solve a wrong printed equation (*inherited*).",
        "",
        "| eq. | curve | verdict | error | note |",
        "| --- | --- | --- | --- | --- |",
        *errata_rows(verdicts),
        *extra_rows,
        "",
        "## The equations that differ",
        "",
    ]
    for v in wrong:
        lines += [
            f"### {v.shape} {v.label}: {v.origin}", "",
            "Printed:", "", f"$${v.printed_tex}$$", "",
            "Derived (corrected):", "", f"$${v.corrected_tex}$$", "",
            f"Evidence: {v.evidence}.", "",
        ]
        if v.key in EXPLANATIONS:
            lines += [EXPLANATIONS[v.key], ""]
    lines += [
        "## Each transcription beside the seed's text",
        "",
        "The seed's text is an exact substring of the paper's OCR text (`docs/seed/`; `↵` marks its line",
        "breaks). `tests/test_audit.py` reads it into SymPy (`symvib.paper.seedtex`: layout removed, the",
        "paper's `tg` read as `tan`, the declared OCR differences applied) and fails on any other difference",
        "from the transcription.",
        "",
        "| eq. | curve | transcription | seed text | declared OCR differences |",
        "| --- | --- | --- | --- | --- |",
    ]
    keys = {v.key for v in verdicts}
    for e in PRINTED:
        if e.key in keys:
            lines.append(f"| {e.label} | {e.shape} | ${_cell(' '.join(e.tex.split()))}$ | {seed_cell(e)} | "
                         f"{ocr_cell(e)} |")
    return "\n".join(lines)


if __name__ == "__main__":  # pragma: no cover - prints the errata of the equations (the whole document: errata)
    print(errata_markdown())
