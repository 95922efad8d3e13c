"""The mechanics the engine applies, each law once (physics.md).

Every function takes floats, the curve's :class:`~symvib.numeric.engine.state.Kernels`
``K`` and its parameter values ``cp``; the loop (:mod:`symvib.numeric.engine.loop`)
calls them and never restates them.  Changing the impact law is an edit to
:func:`impact`; the rest test is :func:`rest`; the Zeno series :func:`zeno_series`.

Examples
--------
>>> impact(2.0, 4.0, 0.5, 2.0)   # qdot = 2, w = 4, k = 0.5, m = 2: qdot, w after; energy lost
(-1.0, 1.0, 3.0)
>>> side_at(0.5, True, -0.5, True, 0.5), side_at(0.1, True, -0.5, True, 0.5)
(1, 0)
"""
from __future__ import annotations

import math

from symvib.numeric.layout import EventCode, StatusCode

__all__ = ["Fs", "dFs", "ddFs", "dF_edge", "node", "energy", "qdot_of", "finite_state", "nsign_of", "impact", "side_at",
           "rest", "rest_outcome", "zeno_series", "CONE_RTOL", "ZENO_W", "EPS"]

#: Unit roundoff of a double.
EPS = 2.220446049250313e-16
#: Relative tolerance of the arrest test |tan alpha| <= mu_s at a turning point.
CONE_RTOL = 1e-9
#: Absolute slack of the arrest test, a few rounding errors of a sine of order 1.
CONE_ATOL = 4.0 * EPS
#: A Zeno accumulation is summed analytically once w at an impact is below
#: ZENO_W * g * (a length of the curve): the local model is then exact to rounding.
ZENO_W = 1e-10
#: 4-point Gauss-Legendre nodes and weights of :func:`dF_edge`.
EDGE_X = (-0.8611363115940526, -0.33998104358485626, 0.33998104358485626, 0.8611363115940526)
EDGE_W = (0.34785484513745385, 0.6521451548625461, 0.6521451548625461, 0.34785484513745385)
#: ``F_s'`` is taken next to a critical point (:func:`dF_edge`) where it is below this share of the
#: size of its terms ``exp(2 s mu alpha) h (1 + mu)``: there its direct value has lost more than
#: ``eps / EDGE_SHARE`` of its relative accuracy.
EDGE_SHARE = 1e-4
#: Farthest a critical point may be, in units of q_scale, for :func:`dF_edge` (its 4-point rule
#: then errs by about ``EDGE_REACH^8`` relative).
EDGE_REACH = 0.01
#: What :func:`rest` finds: the particle slides on, is arrested, or rests on a limiter.
SLIDE, ARREST, REST_ON_LIMITER = 0, 1, 2


def Fs(s, q, mu, K, cp):
    """``F_s(q)``, the phase-trajectory function of branch ``s`` (physics.md, eq. 2)."""
    if s > 0:
        return K.F_p(q, mu, *cp)
    return K.F_m(q, mu, *cp)


def dFs(s, q, mu, K, cp):
    """``F_s'(q) = exp(2 s mu alpha) (z' + s mu x')``."""
    if s > 0:
        return K.dF_p(q, mu, *cp)
    return K.dF_m(q, mu, *cp)


def ddFs(s, q, mu, K, cp):
    """``F_s''(q)``."""
    if s > 0:
        return K.ddF_p(q, mu, *cp)
    return K.ddF_m(q, mu, *cp)


def dF_edge(s, qc, off, mu, K, cp):
    """``F_s'(qc + off)`` next to a critical point ``qc`` of branch ``s`` (``F_s'(qc) = 0``, the
    friction-cone edge ``tan alpha = -s mu``) as ``Integral_0^off F_s''(qc + u) du`` (physics.md,
    "Accuracy").

    ``F_s' = exp(2 s mu alpha) (z' + s mu x')`` is there a difference of two terms far larger
    than itself, so evaluated directly it carries their rounding, about ``eps h`` instead of
    ``eps |F_s'|``; the integral of the smooth ``F_s''`` over the short ``[0, off]`` (4-point
    Gauss-Legendre: exact to ``off^8``) keeps the relative accuracy, and is linear in
    ``off`` as the motion about the edge is.  The caller gives ``off`` as a difference of
    nearby numbers (``(e - qc) + d xi``), not as ``q - qc``: ``q`` itself is rounded to an
    ulp of ``|q|``, which next to the edge can be a large part of ``off``.
    """
    total = 0.0
    for j in range(4):
        total += EDGE_W[j] * ddFs(s, qc + 0.5 * off * (EDGE_X[j] + 1.0), mu, K, cp)
    return 0.5 * off * total


def node(s, q, mu, K, cp):
    """``(F_s', h, exp(s mu alpha), kappa, cos alpha)`` at ``q``: one quadrature node."""
    if s > 0:
        return K.node_p(q, mu, *cp)
    return K.node_m(q, mu, *cp)


def energy(q, w, m, g, K, cp):
    """Mechanical energy ``m (w / 2 + g z)``, with ``w = (h qdot)^2`` the squared speed."""
    return m * (0.5 * w + g * K.z(q, *cp))


def qdot_of(q, w, sigma, K, cp):
    """The generalized velocity ``qdot = sigma sqrt(w) / h`` moving in direction ``sigma``."""
    return sigma * math.sqrt(max(w, 0.0)) / K.h(q, *cp)


def finite_state(t, q, w, Wf, Wimp):
    """Whether the run's state and energy sums are all finite numbers."""
    return (math.isfinite(t) and math.isfinite(q) and math.isfinite(w) and math.isfinite(Wf)
            and math.isfinite(Wimp))


def nsign_of(q, w, g, K, cp):
    """The sign of the normal force ``N = kappa w + g cos alpha`` (physics.md, eq. 1);
    where ``N = 0`` exactly, the sign of ``x'`` (the side gravity pulls to)."""
    n = K.N_w(q, w, g, *cp)
    if n == 0.0:
        n = K.dx(q, *cp)
    return 1 if n >= 0.0 else -1


def impact(qdot, w, k, m):
    """Newton's impact law at a limiter (physics.md, "Events" 1): ``v -> -k v``.

    Returns the generalized velocity after the impact, ``-k qdot``, the squared
    speed after it, ``k^2 w``, and the kinetic energy the impact takes,
    ``m (1 - k^2) w / 2``.  The direction reverses (the caller flips ``sigma``).
    """
    return -k * qdot, k * k * w, 0.5 * m * (1.0 - k * k) * w


def side_at(q, has_left, left, has_right, right):
    """+1 on the right limiter, -1 on the left one, 0 elsewhere."""
    if has_right and q == right:
        return 1
    if has_left and q == left:
        return -1
    return 0


def rest(q, side, mu_s, K, cp):
    """The rest test at ``q`` with zero speed (physics.md, "Events" 2), with the static friction
    coefficient ``mu_s`` (``Setup.mu_s``, ``>= mu``; the scene's ``mu`` when it gives none).

    Returns ``(what, direction)``: :data:`REST_ON_LIMITER` where gravity's pull
    along the curve pushes into the limiter the particle touches (``side``),
    :data:`ARREST` where static friction holds it (``|tan alpha| <= mu_s``, within
    :data:`CONE_RTOL`), else :data:`SLIDE` and the direction it slides to (the
    motion after it is the sliding one, with ``mu``).
    """
    hh = K.h(q, *cp)
    sin = K.dz(q, *cp) / hh
    cos = K.dx(q, *cp) / hh
    pull = -sin
    if side != 0 and pull * side > 0.0:
        return REST_ON_LIMITER, 0
    if abs(sin) <= mu_s * abs(cos) * (1.0 + CONE_RTOL) + CONE_ATOL:
        return ARREST, 0
    return SLIDE, (1 if pull > 0.0 else -1)


def rest_outcome(what):
    """The event and the status of a rest found by :func:`rest` (``what`` not SLIDE)."""
    if what == ARREST:
        return EventCode.ARREST, StatusCode.ARRESTED
    return EventCode.REST_ON_LIMITER, StatusCode.RESTING_ON_LIMITER


def zeno_series(q, w_before, sigma, g, mu, k, m, scale, K, cp):
    """The remaining bounces at a limiter summed as a geometric series (physics.md, "Events" 3).

    Just after an impact of squared speed ``w_before``, moving ``sigma`` away from
    the limiter: when gravity pushes into the limiter outside the friction cone
    (``a_down > 0``) and the bounce is below :data:`ZENO_W`, each bounce is a
    flight up against ``a_up`` and back down with ``a_down`` on a locally straight
    curve, so successive speeds shrink by ``sqrt(k^2 a_down / a_up)``.

    Returns ``(applies, ratio, remaining, W_impacts, W_friction)``: whether the
    series applies, the speed ratio, the time it takes, and the energy the
    impacts and the friction take over it.
    """
    hh = K.h(q, *cp)
    sin = K.dz(q, *cp) / hh
    cos = K.dx(q, *cp) / hh
    away = float(sigma)
    a_up = g * (away * sin + mu * abs(cos))
    a_down = g * (away * sin - mu * abs(cos))
    if a_down > 0.0 and k > 0.0 and w_before < ZENO_W * g * hh * scale:
        lam_w = k * k * a_down / a_up
        if lam_w < 1.0:
            ratio = math.sqrt(lam_w)
            v_after = k * math.sqrt(w_before)
            remaining = v_after * (1.0 / a_up + 1.0 / math.sqrt(a_up * a_down)) / (1.0 - ratio)
            kinetic = 0.5 * m * k * k * w_before
            w_imp = 0.5 * m * (1.0 - k * k) * lam_w * w_before / (1.0 - lam_w)
            return True, ratio, remaining, w_imp, kinetic - w_imp
    return False, 0.0, 0.0, 0.0, 0.0
