"""Gauss-Legendre rules with cumulative integration for the driver (NumPy only).

A :class:`GaussRule` holds, for ``n`` Gauss-Legendre points on ``[-1, 1]``
(interior points: an integrand may be 0/0 at an end), the quadrature weights
(exact to degree ``2n - 1``), the cumulative-integration matrix ``S`` with
``(S @ f)[j] = Integral_{-1}^{x_j} f`` for the degree ``n - 1`` interpolant of
``f``, its weighted twin ``W`` with ``(W @ f)[j] = Integral_{-1}^{x_j} (x + 1) f``
(no loss of relative accuracy near ``x = -1``).  The cumulative form
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
from functools import cache

import numpy as np

from symvib.quadrature_rules import MAX_NODES, TABLE_FILE, read_table  # (no mpmath at import)

__all__ = ["GaussRule", "rule", "table", "MAX_NODES", "plain_nodes", "tail_rows"]


@dataclass(frozen=True)
class GaussRule:
    """Quadrature data for ``n`` Gauss-Legendre points on ``[-1, 1]`` (ascending)."""

    n: int
    x: np.ndarray
    weights: np.ndarray
    cumulative: np.ndarray
    cumulative_weighted: np.ndarray


@cache
def table() -> dict:
    """The tabulated rules, ``n -> (x, w, S, SW)``, read once from ``generated/gauss_rules.json``
    (:func:`symvib.quadrature_rules.read_table`: its digest and shapes checked).

    Examples
    --------
    >>> 16 in table()
    True
    """
    from symvib.numeric.kernels import KernelError, generated_dir

    path = generated_dir() / TABLE_FILE
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as err:
        raise KernelError(f"{path}: the Gauss-Legendre table cannot be read ({err.strerror}); "
                          "run `symvib generate`") from None
    return read_table(text, path)


@cache
def rule(n: int) -> GaussRule:
    """The :class:`GaussRule` with ``n`` nodes (cached; arrays read-only).

    Nodes, weights and both integration matrices are correctly rounded (see
    :mod:`symvib.quadrature_rules` for why the last ulp matters): read from the generated
    table (:func:`table`) for the tabulated ``n``, computed
    with mpmath on first use otherwise (:func:`symvib.quadrature_rules.rule_mp`).
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 1 <= n <= MAX_NODES:
        raise ValueError(f"nodes: must be an integer in [1, {MAX_NODES}], got {n!r}")
    n = int(n)
    data = table().get(n)
    if data is None:
        from symvib.quadrature_rules import rule_mp  # imports mpmath

        data = rule_mp(n)
    x, weights, cumulative, weighted = (np.array(a, dtype=float) for a in data)
    for a in (x, weights, cumulative, weighted):
        a.setflags(write=False)
    return GaussRule(n, x, weights, cumulative, weighted)


def plain_nodes(nodes: int) -> int:
    """Nodes of a panel that does not start on a root, for ``nodes`` on one that does.

    A panel that starts on a turning point (in the variable ``r``, ``q = q* -+ r^2``)
    has the interval's other end, possibly another turning point, at ``r = sqrt(L)``
    while it spans ``[0, sqrt(L/2)]``: the Bernstein ellipse of that branch point has
    ``rho = 3.4``, and ``nodes`` Gauss points leave an error of about ``rho^(-2 nodes)``.
    Every other panel is at least 2.6 of its half-widths from the nearest
    (virtual) root (3 for a panel in ``q``, 2.66 for the last of a graded run in
    ``r``), so ``rho >= 5.1`` and ``3/4`` of the nodes reach the same error
    (16 -> 12: ``5.1^-24 = 1e-17`` against ``3.4^-32 = 1e-17``).
    ``tests/test_quadrature.py`` checks 29 turning points against the
    30-digit reference to 2e-14 at 16 and at 32 nodes.

    Examples
    --------
    >>> plain_nodes(16), plain_nodes(12), plain_nodes(2)
    (12, 9, 2)
    """
    return max(1, -(-3 * nodes // 4))


def tail_rows(x, weights) -> np.ndarray:
    """Rows ``E_k`` with ``E_k @ f = a_k``, the Legendre coefficient of degree ``k`` of the interpolant
    of ``f`` at the Gauss-Legendre nodes ``x``, for ``k = n-1, n-2, n-3, n-4`` (``a_k = (2k + 1)/2
    sum_j w_j P_k(x_j) f_j``, exact for the interpolant by the rule's exactness to degree ``2n - 1``);
    degrees below 0 give zero rows.

    Examples
    --------
    >>> r = rule(6)
    >>> E = tail_rows(r.x, r.weights)
    >>> bool(abs(E[0] @ r.x ** 5 - 8 / 63) < 1e-15)        # x^5 = (8/63) P_5 + lower degrees
    True
    """
    n = len(x)
    out = np.zeros((4, n))
    for row in range(4):
        k = n - 1 - row
        if k >= 0:
            unit = np.zeros(k + 1)
            unit[k] = 1.0
            out[row] = (2 * k + 1) / 2 * np.asarray(weights) * np.polynomial.legendre.legval(np.asarray(x), unit)
    return out
