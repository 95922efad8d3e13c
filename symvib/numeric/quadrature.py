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

__all__ = ["GaussRule", "rule", "table", "MAX_NODES"]


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
