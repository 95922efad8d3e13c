"""Gauss-Legendre rules with cumulative integration for the driver (NumPy only).

A :class:`ChebRule` holds, for ``n`` Gauss-Legendre points on ``[-1, 1]``
(interior points: an integrand may be 0/0 at an end), the quadrature weights
(exact to degree ``2n - 1``), the cumulative-integration matrix ``S`` with
``(S @ f)[j] = Integral_{-1}^{x_j} f`` for the degree ``n - 1`` interpolant of
``f``, its weighted twin ``W`` with ``(W @ f)[j] = Integral_{-1}^{x_j} (x + 1) f``
(no loss of relative accuracy near ``x = -1``), and the map from values to
Legendre coefficients.  The cumulative form
lets the driver rebuild ``G = C - 2 g F`` at the nodes from an anchor without
cancellation (its integrand ``G'`` is smooth); totals use the Gauss weights,
which converge twice as fast near the square-root singularity of the other
end of an interval.

Examples
--------
>>> import numpy as np
>>> r = rule(16)
>>> float(r.weights @ np.exp(r.x))            # Integral of exp over [-1, 1]
2.3504023872876028
>>> bool(abs((r.cumulative @ np.cos(r.x))[-1] - (np.sin(r.x[-1]) + np.sin(1))) < 1e-15)
True
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.polynomial import legendre as _leg

__all__ = ["ChebRule", "rule"]


@dataclass(frozen=True)
class ChebRule:
    """Quadrature data for ``n`` Gauss-Legendre points on ``[-1, 1]`` (ascending)."""

    n: int
    x: np.ndarray
    weights: np.ndarray
    cumulative: np.ndarray
    to_coeffs: np.ndarray
    cumulative_weighted: np.ndarray


@lru_cache(maxsize=None)
def rule(n: int) -> ChebRule:
    """The :class:`ChebRule` with ``n`` nodes (cached; arrays read-only)."""
    x, weights = _leg.leggauss(n)
    vander = _leg.legvander(x, n - 1)
    to_coeffs = np.linalg.solve(vander, np.eye(n))
    cumulative = np.empty((n, n))
    weighted = np.empty((n, n))
    for i in range(n):
        c = _leg.legint(to_coeffs[:, i], lbnd=-1)
        cumulative[:, i] = _leg.legval(x, c)
        cw = _leg.legint(_leg.legadd(_leg.legmulx(to_coeffs[:, i]), to_coeffs[:, i]), lbnd=-1)
        weighted[:, i] = _leg.legval(x, cw)
    for a in (x, weights, cumulative, to_coeffs, weighted):
        a.setflags(write=False)
    return ChebRule(n, x, weights, cumulative, to_coeffs, weighted)
