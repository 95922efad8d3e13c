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

The rules the project uses are tabulated in ``generated/gauss_rules.json``
(written by ``symvib generate`` through :mod:`symvib.codegen.gauss`, checked by
``symvib generate --check``), so running the driver needs no mpmath; other node
counts :func:`symvib.numeric.quadrature.rule` computes here on first use (mpmath,
imported only then, ships with SymPy; this module needs no SymPy).  The table's
format is defined here, where its writer and its reader both find it
(:func:`table_text`, :func:`read_table`): data, not code, so a process reads it
with :func:`json.loads` in milliseconds, with no syntax tree to check and
nothing to execute (as a Python module it cost a third of a second of every
run's start-up).  Its first line holds the SHA-256 of the rest, so a table
edited by hand is refused; JSON writes each double as its shortest ``repr``,
which reads back to the same double, so the table is exact.

Examples
--------
>>> x, w, S, SW = rule_mp(3)
>>> x[1], round(w[1] * 9, 15)             # nodes 0, +-sqrt(3/5); weights 5/9, 8/9
(0.0, 8.0)
>>> round(sum(S[2]), 15) == round(x[2] + 1, 15)  # integral of 1 from -1 to x_3
True
"""
from __future__ import annotations

import hashlib
import json
import math

from symvib.kernelformat import KernelError

__all__ = ["rule_mp", "MAX_NODES", "DPS", "TABLE_FILE", "table_text", "read_table", "TableError"]

#: Largest node count a rule may have (64 takes about 5 s to compute).
MAX_NODES = 64
#: Working digits: every entry is exact to far below half an ulp before rounding.
DPS = 40
#: The table's file in the generated folder.
TABLE_FILE = "gauss_rules.json"
#: The table's first line up to the digest: ``{"body_sha256": "<hex of the rest of the file>",``.
TABLE_HEAD = '{"body_sha256": "'
#: What the table says of itself.
TABLE_ABOUT = ("Gauss-Legendre rules and integration matrices, correctly rounded (written by `symvib generate` "
               "from symvib.quadrature_rules.rule_mp; do not edit)")


class TableError(KernelError):
    """The Gauss-Legendre table is missing, edited by hand or malformed (``symvib generate`` rewrites it)."""


def table_text(rules: dict) -> str:
    """The text of the table file of ``rules`` (``n -> (x, w, S, SW)``, as :func:`rule_mp` returns).

    One JSON object: ``body_sha256`` on the first line (the SHA-256 of every line after it), then
    ``about``, ``dps`` and ``rules`` (``"n": {"x": [...], "w": [...], "S": [[...]], "SW": [[...]]}``,
    one matrix row per line).

    Examples
    --------
    >>> text = table_text({1: rule_mp(1)})
    >>> read_table(text, "t")[1][1]                  # the 1-point rule's weight
    (2.0,)
    """
    lines = [f' "about": {json.dumps(TABLE_ABOUT)},', f' "dps": {DPS},', ' "rules": {']
    for position, (n, (x, w, S, SW)) in enumerate(sorted(rules.items())):
        lines.append(f'  "{int(n)}": {{')
        lines.append(f'   "x": {json.dumps([float(v) for v in x])},')
        lines.append(f'   "w": {json.dumps([float(v) for v in w])},')
        for name, rows, end in (("S", S, ","), ("SW", SW, "")):
            lines.append(f'   "{name}": [')
            lines += [f'    {json.dumps([float(v) for v in row])}' + ("," if i < len(rows) - 1 else "")
                      for i, row in enumerate(rows)]
            lines.append(f'   ]{end}')
        lines.append("  }" + ("," if position < len(rules) - 1 else ""))
    lines.append(" }")
    lines.append("}")
    body = "\n".join(lines) + "\n"
    return TABLE_HEAD + hashlib.sha256(body.encode()).hexdigest() + '",\n' + body


def read_table(text: str, origin) -> dict:
    """The rules of a table file's ``text``: ``n -> (x, w, S, SW)`` as tuples of floats.

    Raises
    ------
    TableError
        Naming ``origin`` when the digest does not match the text (edited by hand or
        truncated), or the data are not ``n`` finite nodes, weights and ``n x n``
        matrices for each ``n``.
    """
    first, _, body = text.partition("\n")
    digest = first[len(TABLE_HEAD):-2] if first.startswith(TABLE_HEAD) and first.endswith('",') else None
    if digest is None or digest != hashlib.sha256(body.encode()).hexdigest():
        raise TableError(f"{origin}: the Gauss-Legendre table was edited by hand or is truncated (its body "
                         "digest does not match); run `symvib generate`")
    try:
        data = json.loads(text)
        rules = {}
        for key, entry in data["rules"].items():
            n = int(key)
            x, w = tuple(entry["x"]), tuple(entry["w"])
            S, SW = (tuple(tuple(row) for row in entry[m]) for m in ("S", "SW"))
            values = x + w + sum(S, ()) + sum(SW, ())
            if not (len(x) == len(w) == len(S) == len(SW) == n and all(len(r) == n for r in S + SW)
                    and all(isinstance(v, float) and math.isfinite(v) for v in values)):
                raise ValueError(f"rule {key} is not n finite nodes, weights and n x n matrices")
            rules[n] = (x, w, S, SW)
    except (ValueError, KeyError, TypeError, AttributeError) as err:
        raise TableError(f"{origin}: not a Gauss-Legendre table ({err}); run `symvib generate`") from None
    return rules


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
