"""Gauss-Legendre rules and their integration matrices at high precision (mpmath).

The driver rebuilds ``G = C - 2 g F`` at the Gauss nodes of a panel by
cumulative integration (:mod:`symvib.numeric.quadrature`). Next to a turning point the
panel is weighted, ``G(x_j) = Integral_{-1}^{x_j} (x + 1) G'(x) dx``, and the
first rows of that matrix are small (about ``(x_1 + 1)^2 / 2``, 1e-5 for 16
nodes) while their entries alternate in sign. A matrix computed in double
precision (Vandermonde solve, :func:`numpy.polynomial.legendre.legint`) carries
absolute errors of about one ulp of ``O(1)``, which is a relative error of
1e-11 in ``G`` at the first node; summed over a long run of turning points it
biased the event times by 3e-15 per interval (1e-13 over 30 intervals). Here
every entry is computed at ``DPS`` digits and rounded once, so each is the
double nearest to its exact value; with them the times agree with the 30-digit
reference to the rounding floor (``tests/test_quadrature.py``).

For ``n`` nodes ``x_i`` and weights ``w_i`` (the roots of ``P_n`` by Newton's
method from Tricomi's estimate), the Lagrange basis is, by the exactness of
the rule for degree ``2n - 1``,

    l_i(x) = w_i sum_{k<n} (2k + 1)/2 P_k(x_i) P_k(x),

and ``Integral_{-1}^{y} P_k = (P_{k+1}(y) - P_{k-1}(y)) / (2k + 1)`` (``y + 1``
for ``k = 0``), ``(x + 1) P_k = ((k + 1) P_{k+1} + k P_{k-1}) / (2k + 1) + P_k``.

The rules the project uses are tabulated in ``generated/gauss_rules.py``
(written by ``symvib generate`` through :mod:`symvib.codegen.gauss`, checked by
``symvib generate --check``), so running the driver needs no mpmath; other node
counts :func:`symvib.numeric.quadrature.rule` computes here on first use (mpmath,
imported only then, ships with SymPy; this module needs no SymPy).

Examples
--------
>>> x, w, S, SW = rule_mp(3)
>>> x[1], round(w[1] * 9, 15)             # nodes 0, +-sqrt(3/5); weights 5/9, 8/9
(0.0, 8.0)
>>> round(sum(S[2]), 15) == round(x[2] + 1, 15)  # integral of 1 from -1 to x_3
True
"""
from __future__ import annotations

__all__ = ["rule_mp", "MAX_NODES", "DPS"]

#: Largest node count a rule may have (64 takes about 5 s to compute).
MAX_NODES = 64
#: Working digits: every entry is exact to far below half an ulp before rounding.
DPS = 40


def _legendre(n: int, x) -> list:
    """``[P_0(x), ..., P_n(x)]`` by the three-term recurrence."""
    import mpmath

    out = [mpmath.mpf(1), x]
    for m in range(1, n):
        out.append(((2 * m + 1) * x * out[m] - m * out[m - 1]) / (m + 1))
    return out[: n + 1]


def rule_mp(n: int) -> tuple:
    """Nodes, weights, ``S`` and ``SW`` of the ``n``-point rule, each entry correctly rounded.

    Returns
    -------
    x, w : list of float
        Ascending nodes on ``[-1, 1]`` and weights.
    S, SW : list of list of float
        ``S[j][i] = Integral_{-1}^{x_j} l_i``, ``SW[j][i] = Integral_{-1}^{x_j} (x + 1) l_i``.
    """
    import mpmath  # (only here: the driver reads the tabulated rules and needs no mpmath)

    if not isinstance(n, int) or not 1 <= n <= MAX_NODES:
        raise ValueError(f"nodes: must be an integer in [1, {MAX_NODES}], got {n!r}")
    with mpmath.workdps(DPS + 10):
        eps = mpmath.mpf(10) ** (-DPS - 5)
        xs = []
        for i in range(1, n + 1):
            x = mpmath.cos(mpmath.pi * (i - mpmath.mpf(1) / 4) / (n + mpmath.mpf(1) / 2))
            for _ in range(100):
                p = _legendre(n, x)
                dp = n * (x * p[n] - p[n - 1]) / (x * x - 1)
                step = p[n] / dp
                x -= step
                if abs(step) < eps:
                    break
            xs.append(x)
        xs.sort()
        # The rule is symmetric: mirror the upper half (the middle node of an odd
        # rule is 0 exactly, where Newton's method stops at about 1e-100).
        for i in range(n // 2):
            xs[i] = -xs[n - 1 - i]
        if n % 2:
            xs[n // 2] = mpmath.mpf(0)
        ws = []
        for x in xs:
            p = _legendre(n, x)
            dp = n * (x * p[n] - p[n - 1]) / (x * x - 1)
            ws.append(2 / ((1 - x * x) * dp * dp))
        P = [_legendre(n + 1, x) for x in xs]

        def integral(k, j):  # Integral_{-1}^{x_j} P_k
            if k == 0:
                return xs[j] + 1
            return (P[j][k + 1] - P[j][k - 1]) / (2 * k + 1)

        I = [[integral(k, j) for k in range(n + 1)] for j in range(n)]
        J = [[((k + 1) * I[j][k + 1] + (k * I[j][k - 1] if k else 0)) / (2 * k + 1) + I[j][k]
              for k in range(n)] for j in range(n)]
        S = [[0.0] * n for _ in range(n)]
        SW = [[0.0] * n for _ in range(n)]
        for i in range(n):
            c = [ws[i] * (2 * k + 1) / 2 * P[i][k] for k in range(n)]
            for j in range(n):
                S[j][i] = float(mpmath.fsum(c[k] * I[j][k] for k in range(n)))
                SW[j][i] = float(mpmath.fsum(c[k] * J[j][k] for k in range(n)))
        return [float(x) for x in xs], [float(w) for w in ws], S, SW
