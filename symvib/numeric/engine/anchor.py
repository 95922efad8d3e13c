"""``G`` from a nearby anchor: the phase trajectory where ``C - 2 g F_s(q)`` cancels (physics.md, "Accuracy").

The closed form ``G(q) = C - 2 g F_s(q)`` (physics.md, eq. 2) carries the rounding of
``C`` and ``F_s``, about ``eps (|C| + 2 g |F_s|)``: where ``G`` itself is far smaller (a
start at rest, a particle that nearly stops, motion next to the friction-cone edge),
that is a large relative error of ``G``, hence of a turning point and of the time
spent near it.  Here ``G`` is carried instead from a point where it is known (the
start of the interval, where ``G = w exp(2 s mu alpha)``) by integrating ``G' = -2 g
F_s'`` (:func:`anchored_G`), which errs by ``eps`` of what it integrates; and next to a
critical point of ``F_s`` (the cone edge, where ``F_s'`` is itself a cancelling
difference) ``F_s'`` is taken as the integral of ``F_s''`` from there
(:func:`dF_best`, :func:`~symvib.numeric.engine.laws.dF_edge`).

Examples
--------
>>> import numpy as np
>>> roots = np.array([[0.5, 2.0], [0.0, 0.0]]); count = np.array([2, 0])
>>> float(crit_near(roots, count, 1, 0.6, 0.2)), float(crit_near(roots, count, 1, 1.0, 0.2))
(0.5, nan)
"""
from __future__ import annotations

import math

import numpy as np

from symvib.numeric.engine.laws import EDGE_REACH, EDGE_SHARE, EPS, dF_edge, dFs, node
from symvib.numeric.engine.roots import ROOT_MAXITER, ROOT_RTOL

__all__ = ["crit_near", "dF_best", "anchored_G", "root_anchored", "PANEL_Q", "ANCHOR_RTOL", "ANCHOR_NARROWEST",
           "ANCHOR_TRIES"]

#: Widest quadrature panel, in units of the curve's q_scale (here and in the time quadrature).
PANEL_Q = 1.0
#: :func:`root_anchored` stops where ``|G|`` is below this many rounding errors of the anchor's ``G``.
ROOT_NOISE = 4.0
#: Doubles :func:`root_anchored` steps back towards the anchor to stand where ``G >= 0``.
ROOT_STEPS_BACK = 8


def crit_near(roots, count, s, x, reach):
    """The known critical point of branch ``s`` nearest ``x``, if it is within ``reach`` (nan otherwise)."""
    row = 0 if s > 0 else 1
    best = math.nan
    dist = reach
    for i in range(count[row]):
        d = abs(roots[row, i] - x)
        if d <= dist:
            best = roots[row, i]
            dist = d
    return best


def dF_best(s, base, u, S, K, cp, roots, count):
    """``F_s'`` at ``base + u``: its kernel, or :func:`~symvib.numeric.engine.laws.dF_edge` where that
    has lost its relative accuracy next to a known critical point (as the time quadrature takes it)."""
    mu = S.mu
    x = base + u
    qc = crit_near(roots, count, s, x, EDGE_REACH * S.scale)
    if qc != qc:
        return dFs(s, x, mu, K, cp)  # no edge near: the kernel (cheaper than the node's)
    dF, hh, ex, _, _ = node(s, x, mu, K, cp)
    if abs(dF) < EDGE_SHARE * ex * ex * hh * (1.0 + mu):
        return dF_edge(s, qc, (base - qc) + u, mu, K, cp)
    return dF


def anchored_G(x, qa, Ga, s, S, K, cp, X, Wt, roots, count):
    """``G(x) = G(qa) - 2 g Integral_qa^x F_s'``: ``G`` from a nearby anchor, by Gauss-Legendre panels
    of at most ``PANEL_Q`` q_scale, free of the cancellation of ``C - 2 g F_s(x)`` where ``G`` is
    small next to ``F_s`` (physics.md, "Accuracy"); ``X, Wt``: the nodes and weights of a Gauss-Legendre
    rule (``Rules.Xp, Rules.Wp``).

    Error control: each panel is checked against its two halves (:func:`_agrees`); one that
    disagrees (``F_s'`` varying on a length below the panel's: next to a pole) is walked in halved and
    doubled panels (:func:`_walked`).  Where every panel agrees the sum is the plain rule's, to the bit.
    """
    L = x - qa
    if L == 0.0:
        return Ga
    parts = max(1, int(math.ceil(abs(L) / (PANEL_Q * S.scale))))
    step = L / parts
    total = 0.0
    walked = 0.0   # the integral over the parts that were walked
    for jp in range(parts):
        before = total
        for j in range(len(X)):
            total += Wt[j] * dF_best(s, qa, (jp + 0.5 * (X[j] + 1.0)) * step, S, K, cp, roots, count)
        halves, size = _halves(s, qa, jp * step, step, S, K, cp, X, Wt, roots, count)
        if not _agrees(total - before, halves, size):
            total = before
            walked += _walked(s, qa, jp * step, step, S, K, cp, X, Wt, roots, count)
    return Ga - S.g * step * total - 2.0 * S.g * walked


#: :func:`anchored_G`'s check: a panel agrees with its two halves when their sums differ by at most this
#: share of the sum of ``|F_s'|`` (the rounding of a sum of a few dozen terms is far below it; a panel
#: whose integrand varies on a length below its own is far above it).
ANCHOR_RTOL = 64.0 * EPS
#: Narrowest panel of :func:`_walked`, as a share of its part: taken as it is.
ANCHOR_NARROWEST = 2.0 ** -30
#: Most panels :func:`_walked` tries in one part (then the rest of the part is one panel).
ANCHOR_TRIES = 400


def _panel_sum(s, qa, u0, width, S, K, cp, X, Wt, roots, count):
    """``(sum_j Wt_j F_s'(qa + u0 + width (X_j + 1) / 2), the same of |F_s'|)`` (the panel's integral is
    ``width / 2`` times the first)."""
    total = 0.0
    size = 0.0
    for j in range(len(X)):
        v = dF_best(s, qa, u0 + 0.5 * (X[j] + 1.0) * width, S, K, cp, roots, count)
        total += Wt[j] * v
        size += Wt[j] * abs(v)
    return total, size


def _halves(s, qa, u0, width, S, K, cp, X, Wt, roots, count):
    """``(left + right, their sums of |F_s'|)``: :func:`_panel_sum` of the panel's two halves."""
    left, size = _panel_sum(s, qa, u0, 0.5 * width, S, K, cp, X, Wt, roots, count)
    right, size_r = _panel_sum(s, qa, u0 + 0.5 * width, 0.5 * width, S, K, cp, X, Wt, roots, count)
    return left + right, size + size_r


def _agrees(full, halves, size):
    """Whether a panel's rule sum ``full`` agrees with its halves' ``halves`` (sum of ``|F_s'|``: ``size``)
    within :data:`ANCHOR_RTOL` (a non-finite sum agrees: the caller's result says it is not finite)."""
    gap = abs(full - 0.5 * halves)
    if not math.isfinite(gap):
        return True
    return gap <= ANCHOR_RTOL * 0.5 * size


def _walked(s, qa, u0, step, S, K, cp, X, Wt, roots, count):
    """``Integral F_s'`` over ``[qa + u0, qa + u0 + step]`` by panels halved where they disagree with their
    halves and doubled after they agree (each accepted panel counted by its halves)."""
    done = 0.0
    width = 0.5
    tries = 0
    out = 0.0
    while done < 1.0 and tries < ANCHOR_TRIES:
        tries += 1
        width = min(width, 1.0 - done)
        w = width * step
        u = u0 + done * step
        full, _ = _panel_sum(s, qa, u, w, S, K, cp, X, Wt, roots, count)
        halves, size = _halves(s, qa, u, w, S, K, cp, X, Wt, roots, count)
        if width <= ANCHOR_NARROWEST or _agrees(full, halves, size):
            out += 0.25 * w * halves
            done += width
            width = min(1.0, 2.0 * width)
        else:
            width = 0.5 * width
    if done < 1.0:   # (the budget spent: the rest of the part as one panel)
        rest, _ = _panel_sum(s, qa, u0 + done * step, (1.0 - done) * step, S, K, cp, X, Wt, roots, count)
        out += 0.5 * (1.0 - done) * step * rest
    return out


def root_anchored(qa, Ga, b, Gb, x, s, S, K, cp, X, Wt, roots, count):
    """The root of :func:`anchored_G` (anchored at ``qa``, where ``G = Ga > 0``) between ``qa``
    and ``b`` (``G(b) = Gb < 0``): Newton's method on ``G' = -2 g F_s'`` (:func:`dF_best`) from
    ``x`` (the closed form's root: off by its rounding only, so a step or two), kept in the
    bracket by bisection (as :func:`symvib.numeric.engine.roots.root_G`); ``X, Wt`` as for
    :func:`anchored_G`.

    Returns ``(root, G there)``: the last double before the root (where ``G >= 0``) and ``G`` there.
    A double is a coarse place for a root where the motion is short (next to the cone edge, or a
    bounce of 1e-13 at a limiter): the caller keeps ``G`` there, so that the interval ends on a
    consistent state, and adds the time of the last stretch to the root,
    :func:`symvib.numeric.engine.timing.tail_time` (a microsecond at 1e-10 from the edge).
    """
    g2 = 2.0 * S.g
    lo, hi = b, qa  # G(lo) < 0 < G(hi)
    if not (min(qa, b) < x < max(qa, b)):
        x = qa + (b - qa) * Ga / (Ga - Gb)
    if not (min(qa, b) < x < max(qa, b)):
        x = 0.5 * (qa + b)
    f_hi = Ga
    for _ in range(ROOT_MAXITER):
        fx = anchored_G(x, qa, Ga, s, S, K, cp, X, Wt, roots, count)
        if fx < 0.0:
            lo = x
        else:
            hi, f_hi = x, fx
        if abs(fx) <= ROOT_NOISE * EPS * Ga:
            break  # G is 0 to the rounding of its integral from the anchor
        dfx = -g2 * dF_best(s, x, 0.0, S, K, cp, roots, count)
        new = x - fx / dfx if dfx != 0.0 else math.nan
        if not (min(lo, hi) < new < max(lo, hi)):
            new = 0.5 * (lo + hi)
        if abs(new - x) <= ROOT_RTOL * abs(x):
            x = new  # converged: the root is within a rounding error of the step
            fx = anchored_G(x, qa, Ga, s, S, K, cp, X, Wt, roots, count)
            break
        if abs(hi - lo) <= ROOT_RTOL * abs(x):
            x, fx = hi, f_hi
            break
        x = new
    # The double on the near side of the root (where G >= 0), and G there: a step back if needed.
    for _ in range(ROOT_STEPS_BACK):
        if fx >= 0.0:
            return x, fx
        x = np.nextafter(x, qa)
        fx = anchored_G(x, qa, Ga, s, S, K, cp, X, Wt, roots, count)
    return x, max(fx, 0.0)
