"""A hand-written kernel of one curve, the speed anchor of ``bench_sweep.py``.

The paper's parabola ``x^2 = 2 p z`` in its tangent angle ``phi`` (``alpha = phi``),
in closed forms, with nothing generated and nothing general:

* ``x = p tan phi``, ``z = p tan^2 phi / 2``, ``h = p sec^3 phi``;
* ``F_s = (p/2) exp(2 s mu phi) sec^2 phi`` (its derivative is
  ``exp(2 s mu phi)(z' + s mu x')``, docs/physics.md), so the phase trajectory
  (paper eq. 2) is ``w = h^2 phidot^2 = C exp(-2 s mu phi) - g p sec^2 phi``;
* a reversal where ``w = 0`` past the edge of the friction cone ``tan phi = -s mu``
  (Illinois steps in a bracket), an arrest there when ``|tan phi| <= mu``,
  an impact at a limiter (``phidot -> -k phidot``);
* times ``t = integral h / sqrt(w) dphi`` by Gauss-Legendre, with ``phi = r + (b - r) v^2``
  at a reversal ``r`` (the square-root singularity removed), a reversal-to-reversal
  interval split at its middle.

It supports exactly the benchmark's scenes (start at ``phi0`` with ``phidot0 > 0``,
both limiters, ``N > 0``); ``bench_sweep.py`` checks its event counts and final
times against symvib's on every scene of the grid.
"""
from __future__ import annotations

import math

import numba
import numpy as np

#: Gauss-Legendre nodes per quadrature piece.
NODES = 32
_X, _W = np.polynomial.legendre.leggauss(NODES)
_V, _WV = 0.5 * (_X + 1.0), 0.5 * _W
#: Illinois steps of the reversal root at most (it converges in about 10).
ROOT_STEPS = 60
ARRESTED, MAX_EVENTS = 1, 4


@numba.njit(cache=False)
def _w(phi, C, s, mu, g, p):
    c = math.cos(phi)
    return C * math.exp(-2.0 * s * mu * phi) - g * p / (c * c)


@numba.njit(cache=False)
def _w_near(r, d, s, mu, g, p):
    """``w`` at ``r + d`` where ``w(r) = 0`` (a reversal), in differences from ``r`` (no cancellation)."""
    cr, cp = math.cos(r), math.cos(r + d)
    return g * p * (math.expm1(-2.0 * s * mu * d) / (cr * cr)
                    - math.sin(d) / (cp * cr) * (math.tan(r + d) + math.tan(r)))


@numba.njit(cache=False)
def _dw(phi, C, s, mu, g, p):
    c = math.cos(phi)
    return -2.0 * s * mu * C * math.exp(-2.0 * s * mu * phi) - 2.0 * g * p * math.tan(phi) / (c * c)


@numba.njit(cache=False)
def _half(e, m, exact, C, s, mu, g, p):
    """Time from the end ``e`` of an interval to its middle ``m``.

    With ``r`` the root of ``w`` at ``e`` (``exact``: a reversal) or just behind it (``w``
    extrapolated linearly; a slow start), ``phi = r + (m - r) v^2`` makes the integrand
    regular; otherwise plain Gauss-Legendre.
    """
    r = e
    if not exact:
        w, dw = _w(e, C, s, mu, g, p), _dw(e, C, s, mu, g, p)
        r = e - w / dw if dw != 0.0 else math.inf
        if not ((e - r) * (m - e) > 0.0 and abs(e - r) < abs(m - e)):
            r = math.nan  # no root of w near behind e: w is not small there
    total = 0.0
    if r == r:  # substituted
        v0 = math.sqrt((e - r) / (m - r))
        for i in range(NODES):
            v = v0 + (1.0 - v0) * _V[i]
            d = (m - r) * v * v
            phi = r + d
            c = math.cos(phi)
            w = _w_near(r, d, s, mu, g, p) if exact else _w(phi, C, s, mu, g, p)
            total += _WV[i] * (1.0 - v0) * 2.0 * v * abs(m - r) * p / (c * c * c) / math.sqrt(w)
        return total
    for i in range(NODES):
        phi = e + (m - e) * _V[i]
        c = math.cos(phi)
        total += _WV[i] * abs(m - e) * p / (c * c * c) / math.sqrt(_w(phi, C, s, mu, g, p))
    return total


@numba.njit(cache=False)
def _time(a, b, rev_a, rev_b, C, s, mu, g, p):
    """Time from ``a`` to ``b`` (``rev_*``: that end is a reversal), in two halves."""
    m = 0.5 * (a + b)
    return _half(a, m, rev_a, C, s, mu, g, p) + _half(b, m, rev_b, C, s, mu, g, p)


@numba.njit(cache=False)
def _G(x, phi, rev, C, s, mu, g, p):
    """``w`` at ``x`` (in differences from ``phi`` when ``phi`` is a reversal), sign of ``G``."""
    return _w_near(phi, x - phi, s, mu, g, p) if rev else _w(x, C, s, mu, g, p)


@numba.njit(cache=False)
def _reversal(lo, hi, phi, rev, C, s, mu, g, p):
    """The root of ``w`` between ``lo`` (w > 0) and ``hi`` (w <= 0): Illinois steps."""
    fa, fb = _G(lo, phi, rev, C, s, mu, g, p), _G(hi, phi, rev, C, s, mu, g, p)
    x = hi
    for _ in range(ROOT_STEPS):
        x = (lo * fb - hi * fa) / (fb - fa)
        fx = _G(x, phi, rev, C, s, mu, g, p)
        if fx > 0.0:
            lo, fa = x, fx
            fb *= 0.5
        else:
            hi, fb = x, fx
            fa *= 0.5
        if abs(hi - lo) <= 4e-16 * max(1.0, abs(x)):
            break
    return x


@numba.njit(cache=False)
def scene(phi0, phidot0, mu, k, left, right, g, p, max_events):
    """One scene to arrest: (status, events, impacts, t_final, phi_final)."""
    phi, phidot, s, t = phi0, phidot0, 1.0 if phidot0 > 0 else -1.0, 0.0
    rev, events, impacts = False, 0, 0
    while events < max_events:
        c = math.cos(phi)
        h, e = p / (c * c * c), math.exp(2.0 * s * mu * phi)
        C = (h * phidot) ** 2 * e + g * p * e / (c * c)
        limit = right if s > 0 else left
        if _w(limit, C, s, mu, g, p) > 0.0:
            t += _time(phi, limit, rev, False, C, s, mu, g, p)
            cl = math.cos(limit)
            phidot = -k * s * math.sqrt(_w(limit, C, s, mu, g, p)) * cl * cl * cl / p
            phi, s, rev = limit, -s, False
            impacts += 1
            events += 1
            continue
        edge = math.atan(-s * mu)
        lo = edge if (edge - phi) * s > 0 else phi
        r = _reversal(lo, limit, phi, rev, C, s, mu, g, p)
        t += _time(phi, r, rev, True, C, s, mu, g, p)
        events += 1
        phi, phidot, s, rev = r, 0.0, -s, True
        if abs(math.tan(r)) <= mu:
            return ARRESTED, events, impacts, t, phi
    return MAX_EVENTS, events, impacts, t, phi


@numba.njit(cache=False)
def sweep(phidot0, mu, k, left, right, g, p, phi0, max_events):
    """Every (phidot0[i], mu[i]) scene; columns: status, events, impacts, t_final, phi_final."""
    n = phidot0.shape[0]
    out = np.empty((n, 5))
    for i in range(n):
        status, events, impacts, t, phi = scene(phi0, phidot0[i], mu[i], k, left, right, g, p, max_events)
        out[i, 0], out[i, 1], out[i, 2], out[i, 3], out[i, 4] = status, events, impacts, t, phi
    return out
