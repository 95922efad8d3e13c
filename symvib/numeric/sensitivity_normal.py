"""The derivative of a sign change of the normal force (physics.md, "Sensitivities" 8).

On a bilateral contact the normal force per unit mass ``N = kappa w + g cos(alpha)`` changes sign at
``q_N`` inside a motion and the branch ``s = sigma sign(N)`` flips there (physics.md, "Events" 3).
The event's position solves ``N(q, w(q; p); p) = 0``, so by the implicit function theorem

    Dq_N = -(dN/dp at fixed q) / (dN/dq along the trajectory),
    dN/dp = kappa (dw/dp) + w (dkappa/dp) - g sin(alpha) (dalpha/dp)     (at fixed q),
    dN/dq = kappa' w + kappa w' - g sin(alpha) alpha',   w' = -2 s mu alpha' w - 2 g (z' + s mu x'),

with ``w' `` from eq. 2 on the branch that ends there, and ``kappa'`` from the curve's jets
(:mod:`symvib.numeric.jet_kernels`: it needs the third derivatives of ``x, z``).  ``w`` is continuous
across the event and the next interval starts on the other branch, so ``Dw`` carries through
unchanged.  Where ``dN/dq = 0`` (``N`` touches 0 without crossing it: the trajectory grazes the
edge where the contact changes side) the event has no derivative, and this module says so.

Examples
--------
>>> TANGENTIAL_N
1e-08
"""
from __future__ import annotations

import math

__all__ = ["normal_sign_change_tangent", "TANGENTIAL_N", "TANGENTIAL_N_REASON"]

#: ``|dN/dq| q_scale`` below this fraction of ``|kappa w| + g`` is a tangential zero of ``N`` (no derivative):
#: an event position found to about 1e-12 of ``q_scale`` then moves by more than 1e-4 of it per unit change.
TANGENTIAL_N = 1e-8
#: The reason a tangential sign change of ``N`` gives in the table.
TANGENTIAL_N_REASON = ("a tangential zero of the normal force (dN/dq = 0 along the trajectory: N touches 0 "
                       "without crossing it); this event and the ones after it")


def normal_sign_change_tangent(c, iv):
    """``Dq_N`` (shape ``(P,)``) of the sign change of ``N`` that ends the interval ``iv``, or None when
    it is tangential (:data:`TANGENTIAL_N`).

    Parameters
    ----------
    c : symvib.numeric.sensitivity_curve.CurveFunctions
        The curve, with the parameters of ``wrt``.
    iv : symvib.numeric.sensitivity_interval.Interval
        The interval ending at the event (its end not a turning point).
    """
    q, s = iv.q_e, iv.s
    alpha, dalpha, kappa = float(c.alpha(q)), float(c.dalpha(q)), float(c.kappa(q))
    E = math.exp(2 * s * c.mu * alpha)
    w = iv.G_e / E
    alpha_p = c.geometry_dp("alpha", q)[0]
    # dw/dp at fixed q: w = G / E, with E = exp(2 s mu alpha) moving with mu and with alpha's own parameters
    w_p = (iv.dG_fixed_q_end() - iv.G_e * 2 * s * (alpha * c.Dmu + c.mu * alpha_p)) / E
    N_p = kappa * w_p + w * c.geometry_dp("kappa", q)[0] - c.g * math.sin(alpha) * alpha_p
    dw = -2 * s * c.mu * dalpha * w - 2 * c.g * iv.f_e / E
    dN = c.dkappa(q) * w + kappa * dw - c.g * math.sin(alpha) * dalpha
    if not abs(dN) * c.scale > TANGENTIAL_N * (abs(kappa * w) + c.g):
        return None
    return -N_p / dN
