"""The compiled quadratures of exact sensitivities, as plain Python that numba compiles with a curve's
kernels (physics.md, "Sensitivities" 2, 5; the binding and the disk cache:
:mod:`symvib.numeric.sensitivity_compiled`).

The arithmetic is the NumPy path's (:mod:`symvib.numeric.sensitivity_batch`), node by node: the
same ``theta`` levels (``NODES`` nodes a panel, 1, 2, 4, ... panels), the same inner rule between
neighbouring nodes, the same anchors, the same convergence rules (``RTOL``, ``ACCEPT``,
``MAX_PANELS``, a non-finite level fails, the first interval that fails past ``BATCH_PANELS`` ends
the derivatives); only sums are taken in another order, so the two agree to rounding
(``tests/test_sensitivity_compiled.py``).  The curve's scalar kernels (``dF_s``, ``ddF_s``,
``alpha``, ``alpha'``, ``h``, ``h'``, ``x'``, ``z'``) are the compile-time constant :data:`SK`, inlined
as in the compiled engine (:mod:`symvib.numeric.engine.static`).

The pass over events that gives the tangents of positions and speeds (pass 3 of
:func:`symvib.numeric.sensitivity._slide`) is here too, for runs where no event needs the curve's
jets (:func:`event_tangents_kernel`: the Python loop's operations in its order, so its numbers bit
for bit).  There a whole slide is one call (:func:`slide_kernel`): the scalar pass over events of
:func:`symvib.numeric.sensitivity._plan` (the branch of each interval, ``w`` before each event; the
kernels at the events come from NumPy as the Python pass reads them), the integrals of
``dF_s'/dmu``, the pass over events and the time derivatives, the same operations in the same
order as the Python passes and the entries above, so the same numbers bit for bit, without the
Python between them (a fit differentiates about 40 runs, each in about a millisecond).

Examples
--------
>>> LEVELS, BATCH_LEVELS
(9, 5)
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from symvib.numeric.layout import EventCode
from symvib.numeric.sensitivity_batch import (
    BATCH_PANELS,
    DIFFERENCE_RTOL,
    EPS,
    FIRST_PANELS,
    MAX_PANELS,
    NEAR_END,
)

__all__ = ["SensitivityKernels", "SK", "event_tangents_kernel", "slide_kernel", "time_derivatives_kernel",
           "end_integrals_kernel", "LEVELS", "BATCH_LEVELS", "ENTRIES", "COMPILED", "INTERVAL_SCALARS"]

#: Levels of the time derivative's refinement (``FIRST_PANELS, 2 FIRST_PANELS, ..., MAX_PANELS`` panels).
LEVELS = int(round(math.log2(MAX_PANELS / FIRST_PANELS))) + 1
#: Of those, the levels evaluated before any interval's refinement may end the others' (up to ``BATCH_PANELS``).
BATCH_LEVELS = int(round(math.log2(min(BATCH_PANELS, MAX_PANELS) / FIRST_PANELS))) + 1
#: Floor of a magnitude that a difference of two levels is divided by (as the NumPy path's).
TINY = 1e-300
#: The compiled entry points, cached on disk per curve.
ENTRIES = ("time_derivatives_kernel", "end_integrals_kernel", "slide_kernel")
#: This module's functions that numba compiles (the entry points and what they call).
COMPILED = ("_f", "_f_df", "_f_dmu", "_df_dmu", "_nan_max", "_level", "_step", "_end_integral", "event_tangents_kernel",
            *ENTRIES)


class SensitivityKernels(NamedTuple):
    """The curve's scalar kernels the compiled quadratures call (each the generated ``*_scalar`` function)."""

    dF_p: object
    dF_m: object
    ddF_p: object
    ddF_m: object
    alpha: object
    dalpha: object
    h: object
    dh: object
    dx: object
    dz: object
    N: object


#: The compile-time constant of the curve's kernels; each curve's compiled copy of this module's
#: entry points has its own (:func:`symvib.numeric.sensitivity_compiled.quadratures`), and passes it
#: to the functions they call as ``K`` (whose numba type, named by the curve, then names their
#: compiled code apart from another curve's).
SK = None


# --- compiled (plain Python here; numba compiles copies with SK bound) -----------------------------
def _f_df(K, s, q, mu, cp):
    """``F_s'`` and ``F_s''`` at ``q`` on branch ``s``."""
    if s > 0:
        return K.dF_p(q, mu, *cp), K.ddF_p(q, mu, *cp)
    return K.dF_m(q, mu, *cp), K.ddF_m(q, mu, *cp)


def _f(K, s, q, mu, cp):
    """``F_s'`` at ``q`` on branch ``s``."""
    if s > 0:
        return K.dF_p(q, mu, *cp)
    return K.dF_m(q, mu, *cp)


def _f_dmu(K, s, q, mu, cp):
    """``F_s'`` and ``d F_s' / d mu`` at ``q`` from one evaluation of ``alpha``, ``x'``, ``z'`` and ``E``
    (``F_s'`` so written differs from the ``dF`` kernel's at rounding)."""
    alpha, dx = K.alpha(q, *cp), K.dx(q, *cp)
    E = math.exp(2 * s * mu * alpha)
    slope = K.dz(q, *cp) + s * mu * dx
    return E * slope, E * (2 * s * alpha * slope + s * dx)


def _df_dmu(K, s, q, mu, cp):
    """``d F_s' / d mu`` at fixed ``q`` (:meth:`symvib.numeric.sensitivity_curve.CurveFunctions.df_dmu`)."""
    return _f_dmu(K, s, q, mu, cp)[1]


def _nan_max(a, b):
    """``np.maximum(a, b)``: NaN if ``a`` is."""
    return a if (a > b or a != a) else b


def _level(K, m, k, ends, tangents, mu, g, Dmu, with_mu, cp, U, Dd, Wt, order, n_start, offsets, xg, wg, cur, mag):
    """The integral of interval ``m``'s time-derivative integrand and of its magnitude on level ``k``
    (``FIRST_PANELS << k`` panels) into ``cur`` and ``mag`` (shape (P,)):
    :func:`symvib.numeric.sensitivity_batch._level` for one interval."""
    s, q_a, q_e = ends[m, 0], ends[m, 1], ends[m, 2]
    delta = q_e - q_a
    length = abs(delta)
    sigma = 1.0 if delta > 0 else -1.0
    P = cur.shape[0]
    Dq_a, Dq_e = tangents[0, m], tangents[1, m]
    for p in range(P):
        cur[p] = 0.0
        mag[p] = 0.0
    n0, n1 = offsets[k], offsets[k + 1]
    for half in range(2):
        from_start = half == 0
        if from_start:
            lo, hi, anchor, D, G_c, f_c, DG_c = n0, n0 + n_start[k], q_a, delta, ends[m, 3], ends[m, 5], tangents[2, m]
        else:
            lo, hi, anchor, D, G_c, f_c, DG_c = n0 + n_start[k], n1, q_e, -delta, ends[m, 4], ends[m, 6], tangents[3, m]
        x_prev, acc_f, acc_df, acc_dp = 0.0, 0.0, 0.0, 0.0
        switch = False        # (f(q) - f(q_c) as that difference from here on: batch.switched)
        for j in range(lo, hi):
            i = n0 + order[j]
            u, d = U[i], Dd[i]
            x = u if from_start else d
            mid, hw = (x_prev + x) / 2, (x - x_prev) / 2
            sum_f, sum_df, sum_dp = 0.0, 0.0, 0.0
            for t in range(xg.shape[0]):
                qn = anchor + D * (mid + hw * xg[t])
                if switch and with_mu:
                    f, dp = _f_dmu(K, s, qn, mu, cp)
                    sum_dp += dp * wg[t]
                elif switch:
                    f = _f(K, s, qn, mu, cp)
                else:
                    f, df = _f_df(K, s, qn, mu, cp)
                    sum_df += df * wg[t]
                    if with_mu:
                        sum_dp += _df_dmu(K, s, qn, mu, cp) * wg[t]
                sum_f += f * wg[t]
            acc_f += hw * sum_f
            acc_df += hw * sum_df
            acc_dp += hw * sum_dp
            x_prev = x
            int_f, int_df, int_dp = D * acc_f, D * acc_df, D * acc_dp
            G = G_c - 2 * g * int_f
            q = q_a + delta * u if u <= 0.5 else q_e - delta * d
            f_q = _f(K, s, q, mu, cp)
            switch = switch or (x >= NEAR_END and abs(f_q - f_c) * DIFFERENCE_RTOL >= EPS * (abs(f_q) + abs(f_c)))
            if switch:
                int_df = f_q - f_c
            alpha, dalpha = K.alpha(q, *cp), K.dalpha(q, *cp)
            h, dh = K.h(q, *cp), K.dh(q, *cp)
            E = math.exp(2 * s * mu * alpha)
            w = G / E
            root = math.sqrt(w) if w >= 0 else math.nan
            signed = x if from_start else -x
            for p in range(P):
                Dq = (1 - u) * Dq_a[p] + u * Dq_e[p]
                dg = DG_c[p] - 2 * g * (int_df * Dq + f_c * (signed * (Dq_e[p] - Dq_a[p])))
                if with_mu:
                    dg -= 2 * g * (int_dp * Dmu[p])
                W = (dg - G * 2 * s * (alpha * Dmu[p] + mu * dalpha * Dq)) / E
                J = ((dh * Dq * length + (h * sigma) * (Dq_e[p] - Dq_a[p])) / root
                     - 0.5 * (h * length) * W / (w * root))
                cur[p] += Wt[i] * J
                mag[p] += Wt[i] * abs(J)


def _step(m, out, previous, cur, mag, best, best_gap, rtol):
    """A new level ``cur`` (its magnitude ``mag``) of interval ``m``: converged, it goes to ``out``;
    returns whether the interval refines on (``_Refinement.step`` of the NumPy path, for one interval)."""
    P = cur.shape[0]
    finite, gap, any_nan = True, -math.inf, False
    for p in range(P):
        if not math.isfinite(cur[p]):
            finite = False
        v = abs(cur[p] - previous[m, p]) / _nan_max(mag[p], TINY)
        if v != v:
            any_nan = True
        elif v > gap:
            gap = v
    if any_nan:               # (np.max: NaN if any is)
        gap = math.nan
    converged = finite and gap <= rtol
    better = finite and not converged and gap < best_gap[m]
    for p in range(P):       # (element by element: compiles faster than numba's array assignment)
        if converged:
            out[m, p] = cur[p]
        if better:
            best[m, p] = previous[m, p]
        previous[m, p] = cur[p]
    if better:
        best_gap[m] = gap
    if not finite:
        best_gap[m] = math.inf
    return finite and not converged


def time_derivatives_kernel(ends, tangents, mu, g, Dmu, with_mu, cp, U, Dd, Wt, order, n_start, offsets, xg, wg,
                            batch_levels, levels, rtol, accept):
    """:func:`symvib.numeric.sensitivity_batch.time_derivatives` of the intervals ``ends`` (shape (M, 7):
    ``s, q_a, q_e, G_a, G_e, f_a, f_e``) with the tangents ``tangents`` (shape (4, M, P): ``Dq_a, Dq_e,
    DG_a, DG_e``); the levels' nodes from :func:`level_tables`."""
    M, P = tangents.shape[1], tangents.shape[2]
    out, previous, best = np.empty((M, P)), np.empty((M, P)), np.empty((M, P))
    best_gap, refining = np.empty(M), np.empty(M, dtype=np.bool_)
    for m in range(M):
        best_gap[m] = math.inf
        for p in range(P):
            out[m, p] = math.nan
            best[m, p] = math.nan
    cur, mag = np.empty(P), np.empty(P)
    for m in range(M):           # the levels up to BATCH_PANELS: no interval's failure ends another's
        _level(SK, m, 0, ends, tangents, mu, g, Dmu, with_mu, cp, U, Dd, Wt, order, n_start, offsets, xg, wg, cur,
               mag)
        for p in range(P):
            previous[m, p] = cur[p]
        on = True
        k = 0
        while on and k + 1 < batch_levels:
            k += 1
            _level(SK, m, k, ends, tangents, mu, g, Dmu, with_mu, cp, U, Dd, Wt, order, n_start, offsets, xg, wg, cur,
                   mag)
            on = _step(m, out, previous, cur, mag, best, best_gap, rtol)
        refining[m] = on
    for m in range(M):           # the finer levels, in time order: the first failure ends the derivatives
        if not refining[m]:
            continue
        on, k = True, batch_levels - 1
        while k + 1 < levels and on:
            k += 1
            _level(SK, m, k, ends, tangents, mu, g, Dmu, with_mu, cp, U, Dd, Wt, order, n_start, offsets, xg, wg, cur,
                   mag)
            on = _step(m, out, previous, cur, mag, best, best_gap, rtol)
        finite = True
        for p in range(P):
            if on and best_gap[m] <= accept:
                out[m, p] = best[m, p]
            finite = finite and math.isfinite(out[m, p])
        if not finite:
            break
    return out


def end_integrals_kernel(s, anchor, D, first_pieces, max_pieces, mu, cp, xg, wg, rtol):
    """``Integral_{anchor}^{anchor + D} dF_s'/dmu dq`` of each interval (shape (M,)):
    :func:`symvib.numeric.sensitivity_batch.end_integrals`' refinement, one interval at a time."""
    M = anchor.shape[0]
    out = np.empty(M)
    for m in range(M):
        out[m] = _end_integral(SK, s, anchor[m], D[m], first_pieces, max_pieces, mu, cp, xg, wg, rtol)
    return out


def _end_integral(K, s, anchor, D, first_pieces, max_pieces, mu, cp, xg, wg, rtol):
    """``Integral_{anchor}^{anchor + D} dF_s'/dmu dq`` of one interval (:func:`end_integrals_kernel`)."""
    previous, pieces = np.nan, first_pieces
    while pieces <= max_pieces:
        acc, acc_abs, x_prev = 0.0, 0.0, 0.0
        for i in range(1, pieces + 1):
            x = i / pieces
            mid, hw = (x_prev + x) / 2, (x - x_prev) / 2
            total, total_abs = 0.0, 0.0
            for t in range(xg.shape[0]):
                v = _df_dmu(K, s, anchor + D * (mid + hw * xg[t]), mu, cp)
                total += v * wg[t]
                total_abs += abs(v) * wg[t]
            acc += hw * total
            acc_abs += hw * total_abs
            x_prev = x
        current, magnitude = D * acc, abs(D * acc_abs)
        if pieces > first_pieces and abs(current - previous) <= rtol * _nan_max(magnitude, TINY):
            return current
        previous = current
        pieces *= 2
    return previous


def slide_kernel(codes, q_at, at_values, w_a0, k, mu, g, m, cp, sigma_in, limiter, Dmu, Dk, Dq_a0, Dw_a0, with_mu,
                 first_pieces, max_pieces, integral_rtol, U, Dd, Wt, order, n_start, offsets, xg, wg, batch_levels,
                 levels, rtol, accept, chunk):
    """Passes 1 to 4 of :func:`symvib.numeric.sensitivity._slide` for ``n`` differentiable events (codes
    ``codes``, positions ``q_at[1:]`` after the start ``q_at[0]`` with ``w_a0``) without an event that needs the
    curve's jets, in one call: the scalar pass of :func:`symvib.numeric.sensitivity._plan` (its operations in
    its order; ``at_values``: its kernel values, NumPy's, rows ``alpha`` at the events then at the middles,
    ``alpha'``, ``F_+``, ``F_-`` (as ``alpha``), ``F_+'``, ``F_-'``, ``E_+``, ``E_-`` at the events), the integrals
    of :func:`end_integrals_kernel`, :func:`event_tangents_kernel` and :func:`time_derivatives_kernel` in chunks
    of ``chunk`` intervals (none after a chunk with a failure).  The same numbers as those, bit for bit.

    Returns the intervals' scalars (shape (n, 14): :data:`INTERVAL_SCALARS`, ``q_a, q_e, w_a``), whether an
    interval leads to each event, ``w`` before each, the rows and tail of :func:`event_tangents_kernel`, the
    time derivatives (shape (n, P); 0 where no interval leads to the event, NaN from a failure on) and the
    integrals of ``dF_s'/dp`` (shape (n, P)).
    """
    n, P = codes.shape[0], Dmu.shape[0]
    half = n + 1                     # (at_values' columns: the events and the start, then the middles)
    scalars = np.zeros((n, 14))
    moving = np.zeros(n, dtype=np.bool_)
    turning = np.zeros(n, dtype=np.bool_)
    is_impact = np.zeros(n, dtype=np.bool_)
    w_minus = np.zeros(n)
    k2 = k * k
    q_a, w_a = q_at[0], w_a0
    for j in range(n):               # 1. the path in scalars (_plan's loop)
        q_e = q_at[j + 1]
        kind = codes[j]
        turning[j] = kind == REVERSAL_CODE or kind == ARREST_CODE
        is_impact[j] = kind == IMPACT_CODE
        if q_e == q_a:
            w_minus[j] = w_a
        else:
            moving[j] = True
            sigma = 1.0 if q_e > q_a else -1.0
            F_row = 2 if sigma > 0 else 3
            G_a = w_a * math.exp(2 * sigma * mu * at_values[0, j])       # (_branch)
            G_mid = G_a - 2 * g * (at_values[F_row, half + j] - at_values[F_row, j])
            w_mid = G_mid / math.exp(2 * sigma * mu * at_values[0, half + j])
            mid_q = q_at[j] + (q_at[j + 1] - q_at[j]) / 2
            s = sigma if SK.N(mid_q, w_mid, g, *cp) >= 0 else -sigma
            F_row, f_row, E_row = (2, 4, 6) if s > 0 else (3, 5, 7)
            E_a = math.exp(2 * s * mu * at_values[0, j])
            G_a = w_a * E_a
            G_e = 0.0 if turning[j] else G_a - 2 * g * (at_values[F_row, j + 1] - at_values[F_row, j])
            E_e = at_values[E_row, j + 1]
            row = scalars[j]
            row[0], row[1], row[2], row[3], row[4] = s, E_a, G_a, at_values[0, j], at_values[1, j]
            row[5], row[6], row[7], row[8], row[9] = at_values[f_row, j], at_values[f_row, j + 1], G_e, \
                at_values[0, j + 1], at_values[1, j + 1]
            row[10], row[11], row[12], row[13] = E_e, q_a, q_e, w_a
            w_minus[j] = 0.0 if turning[j] else G_e / E_e
        q_a, w_a = q_e, (k2 * w_minus[j] if is_impact[j] else w_minus[j])
    I_p_e = np.zeros((n, P))
    if with_mu:                      # 2. the integrals of dF_s'/dp over whole intervals
        for j in range(n):
            if moving[j]:
                value = _end_integral(SK, scalars[j, 0], scalars[j, 11], scalars[j, 12] - scalars[j, 11],
                                      first_pieces, max_pieces, mu, cp, xg, wg, integral_rtol)
                for p in range(P):
                    I_p_e[j, p] = value * Dmu[p]
    rows, tail = event_tangents_kernel(is_impact, turning, moving, sigma_in, w_minus, scalars, I_p_e, limiter, mu,
                                       g, k, m, Dmu, Dk, Dq_a0, Dw_a0)        # 3.
    dT = np.zeros((n, P))            # 4. the time derivatives, chunk by chunk
    for lo in range(0, n, chunk):
        hi = min(lo + chunk, n)
        M = 0
        for j in range(lo, hi):
            if moving[j]:
                M += 1
        if M > 0:
            ends, tangents, index = np.empty((M, 7)), np.empty((4, M, P)), np.empty(M, dtype=np.int64)
            i = 0
            for j in range(lo, hi):
                if moving[j]:
                    index[i] = j
                    for c in range(7):
                        ends[i, c] = scalars[j, ENDS_COLUMNS[c]]
                    for t in range(4):
                        for p in range(P):
                            tangents[t, i, p] = rows[TANGENT_ROWS[t], j, p]
                    i += 1
            out = time_derivatives_kernel(ends, tangents, mu, g, Dmu, with_mu, cp, U, Dd, Wt, order, n_start,
                                          offsets, xg, wg, batch_levels, levels, rtol, accept)
            for i in range(M):
                for p in range(P):
                    dT[index[i], p] = out[i, p]
        finite = True
        for j in range(lo, hi):
            for p in range(P):
                if not math.isfinite(dT[j, p]):
                    finite = False
        if not finite:
            break
    return scalars, moving, w_minus, rows, tail, dT, I_p_e


#: Columns of the interval scalars :func:`event_tangents_kernel` reads (each interval's, from :func:`_plan`).
INTERVAL_SCALARS = ("s", "E_a", "G_a", "alpha_a", "dalpha_a", "f_a", "f_e", "G_e", "alpha_e", "dalpha_e", "E_e")
#: Event codes :func:`event_tangents_kernel` and :func:`slide_kernel` read (:class:`symvib.numeric.layout.EventCode`).
IMPACT_CODE = EventCode.IMPACT.value
REVERSAL_CODE, ARREST_CODE = EventCode.REVERSAL.value, EventCode.ARREST.value
#: Columns ``s, q_a, q_e, G_a, G_e, f_a, f_e`` of the interval scalars, and the rows ``Dq_a, Dq_e, DG_a, DG_e`` of
#: :func:`event_tangents_kernel`'s, that :func:`time_derivatives_kernel` reads (:func:`slide_kernel`).
ENDS_COLUMNS, TANGENT_ROWS = (0, 11, 12, 2, 7, 5, 6), (0, 4, 2, 5)


def event_tangents_kernel(is_impact, turning, moving, sigma_in, w_minus, scalars, I_p_e, limiter, mu, g, k, m, Dmu,
                          Dk, Dq_a0, Dw_a0):
    """Pass 3 of :func:`symvib.numeric.sensitivity._slide` (the tangents of the events' positions and speeds,
    event by event) for events without a sign change of ``N`` or a lift-off, and without curve parameters:
    the same operations in the same order as :meth:`~symvib.numeric.sensitivity_interval.Interval.set_start`,
    ``set_end``, ``end_state`` and the loop's own (one row per event; ``moving``: an interval leads to it,
    whose :data:`INTERVAL_SCALARS` are ``scalars``' row; ``limiter``: ``D(limiter)`` where it ends on one).

    Returns the rows ``Dq_a, Dw_a, DG_a, A, Dq_e, DG_e, Dv_minus, Dv_plus`` (shape (8, n, P)) and the
    tangents of the impact loss and of ``w`` after the last event (shape (2, P)).
    """
    n, P = scalars.shape[0], Dmu.shape[0]
    rows = np.zeros((8, n, P))
    tail = np.zeros((2, P))
    Dq_a, Dw_a, Dw_minus = np.empty(P), np.empty(P), np.empty(P)
    for p in range(P):      # (element by element here: compiles faster than numba's array assignment)
        Dq_a[p], Dw_a[p] = Dq_a0[p], Dw_a0[p]
    for j in range(n):
        Dq_e = rows[4, j]
        for p in range(P):
            rows[0, j, p], rows[1, j, p] = Dq_a[p], Dw_a[p]
            Dw_minus[p] = 0.0
        if not moving[j]:                   # (a rest test at the start: no motion in between)
            for p in range(P):
                Dq_e[p], Dw_minus[p] = Dq_a[p], Dw_a[p]
        else:
            s, E_a, G_a, alpha_a, dalpha_a = scalars[j, 0], scalars[j, 1], scalars[j, 2], scalars[j, 3], scalars[j, 4]
            f_a, f_e, G_e, alpha_e, dalpha_e, E_e = (scalars[j, 5], scalars[j, 6], scalars[j, 7], scalars[j, 8],
                                                     scalars[j, 9], scalars[j, 10])
            for p in range(P):           # Interval.set_start
                moved = alpha_a * Dmu[p] + mu * dalpha_a * Dq_a[p]
                rows[2, j, p] = Dw_a[p] * E_a + G_a * 2 * s * moved
                rows[3, j, p] = rows[2, j, p] + 2 * g * f_a * Dq_a[p]
            for p in range(P):
                fixed_q = rows[3, j, p] - 2 * g * I_p_e[j, p]          # Interval.dG_fixed_q_end
                if turning[j]:
                    Dq_e[p] = fixed_q / (2 * g * f_e)
                else:
                    Dq_e[p] = limiter[j, p]
                    rows[5, j, p] = fixed_q - 2 * g * f_e * Dq_e[p]      # Interval.set_end
                    moved = alpha_e * Dmu[p] + mu * dalpha_e * Dq_e[p]   # Interval.end_state
                    Dw_minus[p] = (rows[5, j, p] - G_e * 2 * s * moved) / E_e
        root = math.sqrt(w_minus[j]) if w_minus[j] > 0 else 0.0
        v_minus = sigma_in[j] * math.sqrt(max(w_minus[j], 0.0))
        for p in range(P):
            Dv_minus = sigma_in[j] * Dw_minus[p] / (2 * root) if w_minus[j] > 0 else 0.0
            rows[6, j, p] = Dv_minus
            if is_impact[j]:
                Dw_a[p] = 2 * k * Dk[p] * w_minus[j] + k * k * Dw_minus[p]        # (w after the event)
                rows[7, j, p] = -(Dk[p] * v_minus + k * Dv_minus)
                tail[0, p] = tail[0, p] + m / 2 * (-2 * k * Dk[p] * w_minus[j] + (1 - k * k) * Dw_minus[p])
            else:
                Dw_a[p] = Dw_minus[p]
                rows[7, j, p] = 0.0 if turning[j] else Dv_minus
            Dq_a[p] = Dq_e[p]
    for p in range(P):
        tail[1, p] = Dw_a[p]
    return rows, tail
