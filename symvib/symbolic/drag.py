"""Quadratic air drag: eqs. 1 and 2 with a drag force ``-c v |v|`` (physics.md, "Air drag").

A drag force ``-c v |v|`` along the tangent, per unit mass ``-gamma sigma v**2`` with
``gamma = c / m`` (an inverse length), adds ``sigma gamma h`` to the coefficient of
``qdot**2`` in eq. 1.  Unlike friction it follows the sign of the velocity alone, so a
run with drag has four branches ``(sigma, n)`` (``sigma = sign(v)``, ``n = sign(N)``,
``s = sigma n``) where eq. 1 has two:

    qddot + (h'/h + s mu alpha' + sigma gamma h) qdot**2 + g (z' + s mu x') / h**2 = 0.

Eq. 2 stays linear in ``w = v**2``; only its integrating factor gains the arc length
``S(q) = Integral_{q_ref}^q h du``:

    w' + 2 (s mu alpha' + sigma gamma h) w = -2 g (z' + s mu x'),
    w(q) = exp(-Phi) [C - 2 g D(q)],   Phi = 2 s mu alpha + 2 sigma gamma S,
    D(q) = Integral exp(Phi) (z' + s mu x') dq.

At ``gamma = 0`` these are eqs. 1 and 2.  ``D`` has a closed form where ``S`` is
linear in the tangent angle (the circle: ``S = R phi``); elsewhere it is a quadrature.
:meth:`DragDerivation.check` substitutes eq. 2 back into eq. 1 on every branch;
:func:`symvib.symbolic.mechanics.check_eq1` (``gamma=``) compares eq. 1 with Kane's
method.  Like every symbolic step, the integrations run under budgets.

Examples
--------
>>> d = derive_drag("circle")
>>> d.eom(1, 1)
Eq(phiddot + phidot**2*(R*gamma_drag + mu) + g*(mu*cos(phi) + sin(phi))/R, 0)
>>> d.arc_length
R*phi
>>> d.check()
{(1, 1): 'symbolic', (1, -1): 'symbolic', (-1, 1): 'symbolic', (-1, -1): 'symbolic'}
"""
from __future__ import annotations

import numbers
from dataclasses import dataclass

import sympy as sp

from symvib.symbolic import budget
from symvib.symbolic.angle import reference_point
from symvib.symbolic.curve import Curve
from symvib.symbolic.derive import derive
from symvib.symbolic.identity import identity_holds, numeric_zero
from symvib.symbolic.symbols import C, g, mu

#: Quadratic air drag per unit mass, ``gamma = c / m`` (drag force ``-c v |v|``).  A distinctive
#: name, since curves may call their parameters ``gamma`` or ``c``.  It lives here, not in
#: :mod:`symvib.symbolic.symbols`, whose source is hashed into every generated kernel module
#: (:mod:`symvib.provenance`): no kernel uses drag yet.
gamma_drag = sp.Symbol("gamma_drag", nonnegative=True)

__all__ = ["gamma_drag", "DragBranch", "DragDerivation", "derive_drag", "arc_length", "BRANCHES", "ARC_SECONDS",
           "INTEGRAL_SECONDS", "MAX_SECONDS"]

#: The branches ``(sigma, n)``: sign of the velocity, sign of the normal force.
BRANCHES = ((1, 1), (1, -1), (-1, 1), (-1, -1))
#: Budget (seconds, a child process) of the symbolic arc length ``Integral h dq``.
ARC_SECONDS = 5.0
#: Budget (seconds, a child process) of one closed-form attempt at ``D`` (one branch).
INTEGRAL_SECONDS = 5.0
#: Largest budget a derivation takes (a day), as ``symvib derive --budget``.
MAX_SECONDS = 86_400.0
#: Ranges of the symbols a numeric identity check draws (``gamma`` in 1/length of the curve's scale).
CHECK_RANGES = {C: (1.0, 20.0), g: (1.0, 20.0), mu: (0.01, 0.5), gamma_drag: (0.0, 2.0)}


@dataclass(frozen=True)
class DragBranch:
    """One branch ``(sigma, n)`` of eqs. 1-2 with drag.

    Attributes
    ----------
    sigma, n, s : int
        Sign of the velocity, of the normal force, and ``s = sigma n`` (friction's sign).
    A, B : sympy.Expr
        Eq. 1 as ``qddot + A qdot**2 + B = 0``.
    Phi : sympy.Expr
        Exponent of the integrating factor, ``2 s mu alpha + 2 sigma gamma S``.
    integrand : sympy.Expr
        ``D' = exp(Phi) (z' + s mu x')``.
    D : sympy.Expr or None
        A closed form of ``D`` (checked by differentiation), or ``None`` (a quadrature).
    """

    sigma: int
    n: int
    s: int
    A: sp.Expr
    B: sp.Expr
    Phi: sp.Expr
    integrand: sp.Expr
    D: sp.Expr | None

    def w(self, D: sp.Expr | None = None) -> sp.Expr:
        """``w(q) = exp(-Phi) [C - 2 g D]`` (eq. 2 with drag), with ``D`` given or the closed form."""
        D = self.D if D is None else D
        if D is None:
            raise ValueError("this branch's D has no closed form: pass D (a function of q whose derivative "
                             "is the integrand)")
        return sp.exp(-self.Phi) * (C - 2 * g * D)


@dataclass(frozen=True)
class DragDerivation:
    """Eqs. 1-2 with quadratic drag for a curve (:func:`derive_drag`; immutable).

    Attributes
    ----------
    curve : Curve
    arc_length : sympy.Expr
        ``S(q)`` from the reference point, closed form or ``Integral``.
    branches : dict of (int, int) -> DragBranch
    """

    curve: Curve
    arc_length: sp.Expr
    branches: dict

    def eom(self, sigma_: int, n: int = 1) -> sp.Eq:
        """Eq. 1 with drag on the branch ``(sigma, n)``, as ``Eq(qddot + A qdot**2 + B, 0)``."""
        br = self.branches[(sigma_, n)]
        c = self.curve
        return sp.Eq(c.qddot + br.A * c.qdot**2 + br.B, 0)

    def check(self) -> dict:
        """Eq. 2 with drag substituted back into eq. 1, on each branch.

        ``qdot**2 = w / h**2`` with ``w = exp(-Phi) [C - 2 g D]`` gives
        ``qddot = (w / h**2)' / 2``; with ``S' = h`` and ``D' = integrand`` (``S`` and
        ``D`` kept as functions, so the check holds whether or not a closed form exists)
        ``qddot + A qdot**2 + B`` must vanish.  Returns ``{(sigma, n): "symbolic" |
        "numeric" | None}`` as :func:`symvib.symbolic.identity.identity_holds` does.
        """
        c = self.curve
        S_f, D_f = sp.Function("S")(c.q), sp.Function("D")(c.q)
        out = {}
        for key, br in self.branches.items():
            phi = 2 * br.s * mu * c.alpha + 2 * br.sigma * gamma_drag * S_f
            f = sp.exp(phi) * (c.zp + br.s * mu * c.xp)
            if sp.simplify(f.subs(S_f, self.arc_length) - br.integrand) != 0:
                out[key] = None     # the branch's integrand is not the one eq. 2 needs
                continue
            qdot2 = sp.exp(-phi) * (C - 2 * g * D_f) / c.h**2
            qddot = sp.diff(qdot2, c.q) / 2
            residual = (qddot + br.A * qdot2 + br.B).subs({sp.Derivative(S_f, c.q): c.h,
                                                           sp.Derivative(D_f, c.q): f})
            out[key] = _vanishes(sp.expand(residual * sp.exp(phi)), c, S_f, D_f)
        return out


def _vanishes(expr: sp.Expr, c: Curve, S_f, D_f) -> str | None:
    """:func:`identity_holds` for an expression in which ``S(q)``, ``D(q)`` stand as symbols."""
    S_v, D_v = sp.Symbol("S_value", real=True), sp.Symbol("D_value", real=True)
    expr = expr.subs({S_f: S_v, D_f: D_v})
    extra = dict(CHECK_RANGES)
    extra.update({S_v: (-1.0, 1.0), D_v: (-1.0, 1.0)})
    return identity_holds(expr, c, extra=extra)


def arc_length(curve: Curve, *, seconds: float = ARC_SECONDS) -> sp.Expr:
    """``S(q) = Integral_{q_ref}^q h du`` in closed form within ``seconds``, else as an ``Integral``.

    A closed form is accepted only when ``S' = h`` holds (at 30 digits at random points)
    and ``S(q_ref) = 0``.
    """
    q = curve.q
    q_ref = reference_point(curve)
    if q not in curve.h.free_symbols:   # a constant metric (the circle in its angle)
        return curve.h * (q - q_ref)
    u = sp.Dummy("u", real=True)
    if seconds <= 0:
        return sp.Integral(curve.h.subs(q, u), (u, q_ref, q))
    outcome = budget.run(budget._integrate_job, (sp.srepr(curve.h), q.name), seconds=seconds)
    if outcome.status == "ok" and not outcome.value.has(sp.Integral):
        S = _real_logs(outcome.value, q, q_ref)
        S = S - S.subs(q, q_ref)
        if not S.has(sp.I) and numeric_zero(sp.diff(S, q) - curve.h, curve):
            return S
    return sp.Integral(curve.h.subs(q, u), (u, q_ref, q))


def _real_logs(expr: sp.Expr, q: sp.Symbol, q_ref: sp.Expr) -> sp.Expr:
    """``log(a)`` written ``log(-a)`` where ``a < 0`` at ``q_ref`` (SymPy's antiderivatives of
    ``sqrt`` terms take logarithms of negative numbers; the ``i pi`` they carry is a constant)."""
    def real(a):
        try:
            negative = bool(a.subs(q, q_ref).subs({p: 1 for p in a.free_symbols - {q}}) < 0)
        except TypeError:
            return sp.log(a)
        return sp.log(-a) if negative else sp.log(a)
    return expr.replace(sp.log, real)


def _closed_D(integrand: sp.Expr, curve: Curve, seconds: float) -> sp.Expr | None:
    """A closed form of ``Integral integrand dq`` within ``seconds``, checked by differentiation."""
    if integrand.has(sp.Integral):
        return None
    outcome = budget.run(budget._integrate_job, (sp.srepr(integrand), curve.q.name), seconds=seconds)
    if outcome.status != "ok" or outcome.value.has(sp.Integral):
        return None
    D = budget.simplify(outcome.value)
    if numeric_zero(sp.diff(D, curve.q) - integrand, curve, extra=CHECK_RANGES):
        return D
    return None


def derive_drag(curve, *, seconds: float = INTEGRAL_SECONDS, arc_seconds: float = ARC_SECONDS,
                forms: str = "simplest") -> DragDerivation:
    """Derive eqs. 1 and 2 with quadratic drag ``gamma = c / m`` for ``curve`` (physics.md, "Air drag").

    Parameters
    ----------
    curve : Curve, Shape or str
        A curve, or the name of a catalogue shape.
    seconds : float
        Budget of each branch's closed-form attempt at ``D`` (0: none, quadrature only; at most
        :data:`MAX_SECONDS`).
    arc_seconds : float
        Budget of the arc length's closed-form attempt.
    forms : {"simplest", "direct"}
        How eq. 1's coefficients are written, as in :func:`symvib.symbolic.derive.derive`.

    Returns
    -------
    DragDerivation

    Raises
    ------
    ValueError
        Naming ``seconds`` or ``arc_seconds`` (not a number in ``[0, MAX_SECONDS]``), or a curve
        parameter called ``gamma_drag``.

    Examples
    --------
    >>> d = derive_drag("parabola", seconds=0)
    >>> d.branches[(1, 1)].D is None
    True
    >>> d.check()[(-1, 1)]
    'symbolic'
    """
    for name, value in (("seconds", seconds), ("arc_seconds", arc_seconds)):
        if isinstance(value, bool) or not isinstance(value, numbers.Real) or not 0 <= value <= MAX_SECONDS:
            raise ValueError(f"{name}: a number of seconds in [0, {MAX_SECONDS:g}] (0: no closed-form attempt), "
                             f"got {value!r:.80}")
    plain = derive(curve, routes=(), forms=forms)   # eq. 1 without drag (no routes: F_sigma is not needed)
    c = plain.curve                                   # (derive resolves a shape name and refuses a non-curve)
    if any(p.name == gamma_drag.name for p in c.params):
        raise ValueError(f"curve parameter {gamma_drag.name!r} is the drag's own symbol: rename it")
    S = arc_length(c, seconds=arc_seconds)
    branches = {}
    for sig, n in BRANCHES:
        s = sig * n
        A = plain.branch(sig, n).A + sig * gamma_drag * c.h
        B = plain.branch(sig, n).B
        Phi = 2 * s * mu * c.alpha + 2 * sig * gamma_drag * S
        f = sp.exp(Phi) * (c.zp + s * mu * c.xp)
        D = _closed_D(f, c, seconds) if seconds > 0 else None
        branches[(sig, n)] = DragBranch(sigma=sig, n=n, s=s, A=A, B=B, Phi=Phi, integrand=f, D=D)
    return DragDerivation(curve=c, arc_length=S, branches=branches)

