"""The paper's printed equations, audited against the derivation.

Every equation the paper prints for the general curve (eqs. 1-2) and for the
parabola, cycloid and circle (eqs. 3-8 and the energy expressions ``F_N``,
``P_mu``, ``Ek``, ``Ep``, ``E``) is transcribed here, as printed, and compared
with :func:`symvib.symbolic.derive.derive`.  The paper's ``+-`` is the symbol ``pm``
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

from symvib.symbolic.curve import CHECK_DIGITS, identity_holds, sample_points
from symvib.symbolic.derive import coefficients, derive, pm_latex
from symvib.symbolic.symbols import C, g, m, mu, sigma

__all__ = ["Printed", "Verdict", "PRINTED", "audit", "derivation", "errata_markdown"]

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
    terms of ``qdot`` before the trajectory is inserted.
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


@dataclass(frozen=True)
class Verdict:
    """The outcome of comparing one printed equation with the derivation."""

    key: str
    shape: str
    label: str
    matches: bool
    how: str
    evidence: str
    printed_tex: str
    corrected_tex: str


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


def _entries():
    P = []
    add = lambda *a, **k: P.append(Printed(*a, **k))  # noqa: E731
    # Parabola, q = phi (tangent angle).
    add("eq3", "parabola", "(3)", "eom", "equation of motion",
        r"\ddot\phi + (3tg\phi \pm \mu)\dot\phi^2 + \frac{g\cos^3\phi}{p}(\sin\phi \pm \mu\cos\phi) = 0",
        lambda c: c.qddot + (3 * sp.tan(c.q) + pm * mu) * c.qdot**2
        + g * sp.cos(c.q) ** 3 / _par(c, "p") * (sp.sin(c.q) + pm * mu * sp.cos(c.q)))
    add("eq4", "parabola", "(4)", "phase", "phase trajectory",
        r"\dot\phi^2 = \cos^6\phi\left(-\frac{g}{p\cos^2\phi} + Ce^{\mp 2\mu\phi}\right)",
        lambda c: sp.cos(c.q) ** 6 * _parabola_W(c))
    add("parabola.F_N", "parabola", "F_N", "energy", "F_N",
        r"F_{N,i} = mg\cos\phi + mp\cos^3\phi\left(-\frac{g}{p\cos^2\phi} + C_ie^{\mp 2\mu\phi}\right)",
        lambda c: m * g * sp.cos(c.q) + m * _par(c, "p") * sp.cos(c.q) ** 3 * _parabola_W(c))
    add("parabola.P_mu", "parabola", "P_mu", "energy", "P_mu",
        r"P_{\mu,i} = -\mu m p\left(g\cos\varphi + p\cos^3\varphi(\ldots)\right)\sqrt{-\frac{g}{p\cos^2"
        r"\varphi} + C_ie^{\mp 2\mu\varphi}}",
        lambda c: -mu * m * _par(c, "p") * (g * sp.cos(c.q) + _par(c, "p") * sp.cos(c.q) ** 3 * _parabola_W(c))
        * sp.sqrt(_parabola_W(c)),
        formula=lambda c: -mu * m * (g * sp.cos(c.q) + _par(c, "p") * c.qdot**2 / sp.cos(c.q) ** 3)
        * _par(c, "p") / sp.cos(c.q) ** 3 * c.qdot)
    add("parabola.Ek", "parabola", "Ek", "energy", "Ek",
        r"Ek_i = \frac12 mp^2\left(-\frac{g}{p\cos^2\phi} + C_ie^{\mp 2\mu\phi}\right)",
        lambda c: m * _par(c, "p") ** 2 * _parabola_W(c) / 2,
        formula=lambda c: m * _par(c, "p") ** 2 / sp.cos(c.q) ** 6 * c.qdot**2 / 2)
    add("parabola.Ep", "parabola", "Ep", "energy", "Ep",
        r"Ep_i = \frac12\frac{mgp}{\cos^2\phi}",
        lambda c: m * g * _par(c, "p") / (2 * sp.cos(c.q) ** 2))
    add("parabola.E", "parabola", "E", "energy", "E",
        r"E_i = \frac12 mp^2\left(-\frac{g}{p\cos^2\phi} + C_ie^{\mp 2\mu\phi}\right) + \frac12\frac{mgp}{\cos^2\phi}",
        lambda c: m * _par(c, "p") ** 2 * _parabola_W(c) / 2 + m * g * _par(c, "p") / (2 * sp.cos(c.q) ** 2))
    # Cycloid, q = phi (rolling angle).
    add("eq5", "cycloid", "(5)", "eom", "equation of motion",
        r"\ddot\phi - \dot\phi^2\left(\frac12 tg\frac\phi2 \mp \mu\right) + \left(tg\frac\phi2 \pm \mu\right)"
        r"\frac{g}{2R} = 0",
        lambda c: c.qddot - c.qdot**2 * (sp.tan(c.q / 2) / 2 - pm * mu)
        + (sp.tan(c.q / 2) + pm * mu) * g / (2 * _par(c, "R")))
    add("eq6", "cycloid", "(6)", "phase", "phase trajectory",
        r"\dot\phi^2 = -\frac{g/2R}{1+4\mu^2}\frac{1}{\cos^2\frac\phi2}\left[(\pm 3\mu)\sin\phi - (1-2\mu^2)"
        r"\cos\phi + \frac{1+4\mu^2}{2} + Ce^{\mp 2\mu\phi}\right]",
        _cycloid_Y, note="unnumbered in the text; the paper cites it as (6)")
    add("cycloid.F_N", "cycloid", "F_N", "energy", "F_N",
        r"F_{N,i} = mg\cos\frac\phi2 + m2R\cos\frac\phi2\,\dot\phi_i^2(\phi)\ \text{(eq. 6 inserted)}",
        lambda c: m * g * sp.cos(c.q / 2) + m * 2 * _par(c, "R") * sp.cos(c.q / 2) * _cycloid_Y(c),
        formula=lambda c: m * g * sp.cos(c.q / 2) + m * 2 * _par(c, "R") * sp.cos(c.q / 2) * c.qdot**2)
    add("cycloid.P_mu", "cycloid", "P_mu", "energy", "P_mu",
        r"P_{\mu,i} = -\mu F_{N,i}\,2R\cos\frac\phi2\,\sqrt{\dot\phi_i^2(\phi)}",
        lambda c: -mu * (m * g * sp.cos(c.q / 2) + m * 2 * _par(c, "R") * sp.cos(c.q / 2) * _cycloid_Y(c))
        * 2 * _par(c, "R") * sp.cos(c.q / 2) * sp.sqrt(_cycloid_Y(c)),
        formula=lambda c: -mu * (m * g * sp.cos(c.q / 2) + m * 2 * _par(c, "R") * sp.cos(c.q / 2) * c.qdot**2)
        * 2 * _par(c, "R") * sp.cos(c.q / 2) * c.qdot)
    add("cycloid.Ek", "cycloid", "Ek", "energy", "Ek",
        r"Ek_i = 2mR^2\cos^2\frac\phi2\,\dot\phi_i^2(\phi)",
        lambda c: 2 * m * _par(c, "R") ** 2 * sp.cos(c.q / 2) ** 2 * _cycloid_Y(c),
        formula=lambda c: 2 * m * _par(c, "R") ** 2 * sp.cos(c.q / 2) ** 2 * c.qdot**2)
    add("cycloid.Ep", "cycloid", "Ep", "energy", "Ep", r"Ep_i = mgR(1 - \cos\phi)",
        lambda c: m * g * _par(c, "R") * (1 - sp.cos(c.q)))
    add("cycloid.E", "cycloid", "E", "energy", "E",
        r"E_i = 2mR^2\cos^2\frac\phi2\,\dot\phi_i^2(\phi) + mgR(1-\cos\phi)",
        lambda c: 2 * m * _par(c, "R") ** 2 * sp.cos(c.q / 2) ** 2 * _cycloid_Y(c)
        + m * g * _par(c, "R") * (1 - sp.cos(c.q)),
        note="the printed second term is garbled in the source; read as Ek + Ep")
    # Circle, q = phi.
    add("eq7", "circle", "(7)", "eom", "equation of motion",
        r"\ddot\phi \pm \dot\phi^2 tg\alpha_0 + \frac{g}{R\cos\alpha_0}\sin(\phi \pm \alpha_0) = 0",
        lambda c: c.qddot + pm * c.qdot**2 * mu
        + g / (_par(c, "R") * sp.cos(sp.atan(mu))) * sp.sin(c.q + pm * sp.atan(mu)))
    add("eq8", "circle", "(8)", "phase", "phase trajectory",
        r"\dot\phi^2 = \frac{2g}{(1+4tg^2\alpha_0)R\cos\alpha_0}\left[\cos(\phi\pm\alpha_0) - 2tg\alpha_0\sin("
        r"\phi\pm\alpha_0)\right] + Ce^{\mp 2\phi tg\alpha_0}",
        _circle_Z)
    add("circle.F_N", "circle", "F_N", "energy", "F_N",
        r"F_{N,i} = mg\cos\varphi + mR\,\dot\varphi_i^2(\varphi)\ \text{(eq. 8 inserted)}",
        lambda c: m * g * sp.cos(c.q) + m * _par(c, "R") * _circle_Z(c),
        formula=lambda c: m * g * sp.cos(c.q) + m * _par(c, "R") * c.qdot**2)
    add("circle.P_mu", "circle", "P_mu", "energy", "P_mu",
        r"P_{\mu,i} = -\mu F_{N,i}R\dot\varphi = -\mu F_{N,i}R\left\{-\sqrt{\dot\varphi_i^2(\varphi)}\right\}",
        lambda c: -mu * (m * g * sp.cos(c.q) + m * _par(c, "R") * _circle_Z(c)) * _par(c, "R")
        * (-sp.sqrt(_circle_Z(c))),
        formula=lambda c: -mu * (m * g * sp.cos(c.q) + m * _par(c, "R") * c.qdot**2) * _par(c, "R") * c.qdot)
    add("circle.Ek", "circle", "Ek", "energy", "Ek", r"Ek_i = \frac12 mR^2\dot\varphi_i^2(\varphi)",
        lambda c: m * _par(c, "R") ** 2 * _circle_Z(c) / 2,
        formula=lambda c: m * _par(c, "R") ** 2 * c.qdot**2 / 2)
    add("circle.Ep", "circle", "Ep", "energy", "Ep", r"Ep_i = mgR(1-\cos\varphi)",
        lambda c: m * g * _par(c, "R") * (1 - sp.cos(c.q)))
    add("circle.E", "circle", "E", "energy", "E",
        r"E_i = \frac12 mR^2\dot\varphi_i^2(\varphi) + mgR(1-\cos\phi)",
        lambda c: m * _par(c, "R") ** 2 * _circle_Z(c) / 2 + m * g * _par(c, "R") * (1 - sp.cos(c.q)))
    return tuple(P)


#: Every printed equation of the three curves, in the paper's order.
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
                   d.latex()["eom"])


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
    return Verdict(entry.key, entry.shape, entry.label, ok, how, evidence, entry.tex, d.latex()["phase"])


def _sample_residual(entry, d, s):
    c = d.curve
    br = d.branches[s]
    W = entry.build(c).subs(pm, s)
    res = _residual_in(W, br.A, br.B, c.q)
    subs = {c.q: sp.Rational(1, 3), mu: sp.Rational(1, 20), g: sp.Rational(981, 100), C: 2,
            **{p: sp.Rational(1, 2) for p in c.params}}
    return f"{float(sp.N(res.subs(subs), CHECK_DIGITS)):.3g}"


def _judge_energy(entry, d) -> Verdict:
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
    else:
        how, evidence = "differs", "; ".join(notes)
        if formula_note:
            evidence += "; " + formula_note
    return Verdict(entry.key, entry.shape, entry.label, ok, how, evidence, entry.tex, d.latex()[quantity])


def _judge_formula(entry, d) -> str:
    """Whether the printed energy in terms of ``qdot`` (before inserting a trajectory) is right."""
    if entry.formula is None:
        return ""
    c = d.curve
    # For qdot > 0 and F_N > 0 the absolute values of the derived P_mu drop out.
    derived = d.energies[entry.quantity].replace(sp.Abs, lambda a: a)
    diff = entry.formula(c) - derived
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


def _general_entries():
    """Eqs. (1) and (2): checked for an arbitrary curve with undefined functions."""
    q = sp.Symbol("x", real=True)
    f = sp.Function("f")
    fp, fpp = sp.diff(f(q), q), sp.diff(f(q), q, 2)
    h = sp.sqrt(1 + fp**2)
    alphap = fpp / (1 + fp**2)
    A, B = coefficients(sp.Integer(1), fp, h, sp.diff(h, q), alphap)
    verdicts = []
    # Eq. (1): sddot + g sin(alpha) +- mu (v^2/R_k + g cos(alpha)) = 0 with s(q), v = h qdot.
    Q = sp.Function("Q")  # a general parametrization X(q), Z(q)
    u = sp.Symbol("q", real=True)
    X, Z = sp.Function("X")(u), sp.Function("Z")(u)
    Xp, Zp = sp.diff(X, u), sp.diff(Z, u)
    H = sp.sqrt(Xp**2 + Zp**2)
    Ap_ = (Xp * sp.diff(Zp, u) - Zp * sp.diff(Xp, u)) / H**2
    qd, qdd = sp.symbols("qdot qddot", real=True)
    ok1 = True
    for s in (1, -1):
        sdd = H * qdd + sp.diff(H, u) * qd**2
        printed = sdd + g * Zp / H + s * mu * (H**2 * qd**2 * Ap_ / H + g * Xp / H)
        Ag, Bg = coefficients(Xp, Zp, H, sp.diff(H, u), Ap_)
        derived = qdd + Ag.subs(sigma, s) * qd**2 + Bg.subs(sigma, s)
        ok1 &= sp.simplify(printed / H - derived) == 0
    del Q
    verdicts.append(Verdict(
        "eq1", "general", "(1)", ok1, "identical" if ok1 else "differs",
        "with s' = h q', v = h qdot, 1/R_k = kappa = alpha'/h, divided by h it is the derived "
        "qddot + A qdot^2 + B = 0 for an arbitrary parametrization X(q), Z(q)",
        r"\ddot s + g\sin\alpha \pm \mu\left(\frac{v^2}{R_k} + g\cos\alpha\right) = 0",
        r"\ddot q + \left(\frac{h'}{h} \pm \mu\alpha'\right)\dot q^2 + \frac{g(z' \pm \mu x')}{h^2} = 0"))
    # Eq. (2): the graph form of the phase trajectory, with unevaluated integrals.
    ok2 = True
    for s in (1, -1):
        P = 2 / h * (sp.diff(h, q) + s * mu * fpp / h)
        I1 = sp.Integral(P, q)
        Xsq = sp.exp(-I1) * (-2 * g * sp.Integral((fp + s * mu) / (1 + fp**2) * sp.exp(I1), q) + C)
        res = sp.diff(Xsq, q) / 2 + A.subs(sigma, s) * Xsq + B.subs(sigma, s)
        ok2 &= sp.simplify(res) == 0
    verdicts.append(Verdict(
        "eq2", "general", "(2)", ok2, "identical" if ok2 else "differs",
        "for a graph z = f(x) with f undefined, the printed xdot^2(x) (integrals left unevaluated) "
        "solves the derived equation of motion xddot + A xdot^2 + B = 0 identically",
        r"\dot x^2 = e^{-\int\frac{2}{\sqrt{1+z'^2}}\left[\frac{d}{dx}\sqrt{1+z'^2} \pm \mu\frac{z''}{"
        r"\sqrt{1+z'^2}}\right]dx}"
        r"\left[-2g\int\frac{z' \pm \mu}{1+z'^2}e^{\int\ldots dx}dx + C\right]",
        r"w(q) = e^{-2\sigma\mu\alpha}\left[C - 2gF_\sigma(q)\right],\ F_\sigma = \int e^{2\sigma\mu\alpha}(z'"
        r" + \sigma\mu x')\,dq"))
    return verdicts


def audit(shapes=("parabola", "cycloid", "circle"), *, general: bool = True) -> tuple:
    """Compare every printed equation with the derivation; one :class:`Verdict` each.

    Eqs. (1)-(2) come first (general curve; left out with ``general=False``),
    then each shape's entries in the paper's order.
    """
    verdicts = list(_general_entries()) if general else []
    judges = {"eom": _judge_eom, "phase": _judge_phase, "energy": _judge_energy}
    for entry in PRINTED:
        if entry.shape in shapes:
            verdicts.append(judges[entry.kind](entry, derivation(entry.shape)))
    return tuple(verdicts)


#: What each known erratum amounts to, in words (keyed by verdict key).
EXPLANATIONS = {
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


def errata_markdown(verdicts=None) -> str:
    """The errata table (Markdown): printed form, corrected form, evidence."""
    verdicts = audit() if verdicts is None else verdicts
    lines = [
        "# Errata of the paper's printed equations",
        "",
        "Generated by `python -m symvib.symbolic.audit` from `symvib/symbolic/audit.py`, which transcribes every",
        "printed equation and compares it with `symvib.symbolic.derive` (tests: `tests/test_audit.py`).",
        "Equal up to a rescaled integration constant or a shifted potential-energy level counts",
        "as equal. Upper signs are for `v > 0`; `tg alpha0 = mu`.",
        "",
        "| eq. | curve | verdict | note |",
        "| --- | --- | --- | --- |",
    ]
    for v in verdicts:
        note = v.how if v.matches else _first_sentence(EXPLANATIONS.get(v.key, v.evidence))
        note = note.replace("|", "\\|")  # |F_N| in a table cell
        lines.append(f"| {v.label} | {v.shape} | {'matches' if v.matches else '**differs**'} | {note} |")
    lines += ["", "## The equations that differ", ""]
    for v in verdicts:
        if v.matches:
            continue
        lines += [
            f"### {v.shape} {v.label}", "",
            "Printed:", "", f"$${v.printed_tex}$$", "",
            "Derived (corrected):", "", f"$${v.corrected_tex}$$", "",
            f"Evidence: {v.evidence}.", "",
        ]
        if v.key in EXPLANATIONS:
            lines += [EXPLANATIONS[v.key], ""]
    return "\n".join(lines)


if __name__ == "__main__":  # pragma: no cover - writes docs/errata.md
    import sys

    text = errata_markdown()
    if len(sys.argv) > 1:
        with open(sys.argv[1], "w", encoding="utf-8") as fh:
            fh.write(text + "\n")
    else:
        print(text)
