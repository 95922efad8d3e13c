"""The rule of a numeric ``F_sigma``: composite Gauss-Legendre with panels refined where they must be.

Where a curve's ``F_sigma`` has no closed form (physics.md, eq. 2), its
kernels ``F_p``/``F_m`` integrate ``F_s'`` from the module's ``Q_REF`` with this rule;
the code generator (:mod:`symvib.codegen.kernel_text`) writes it into the module, and a
run on a narrowed domain (:func:`symvib.numeric.prepared.kernel_view`) uses the same
rule from its own reference point.  Both wings read the constants here (ground floor:
no NumPy at import).

The rule, from ``q_ref`` to ``q`` with the widest panel ``width = PANEL * q_scale``:

1. ``[q_ref, q]`` is cut into ``max(1, ceil(|q - q_ref| / width))`` equal *pieces*.
2. Each piece is first integrated as one panel of :data:`NODES` Gauss-Legendre nodes;
   the panel's Legendre coefficients ``a_12 .. a_15`` of ``F_s'`` (from the same
   values, rows :func:`tail_rows`) estimate its error as the engine's time
   quadrature does for a kernel (``symvib.numeric.engine.timing.tail_error``, the
   cautious rule): ``t = max|a_15, a_14|``, ``r = sqrt(t / max|a_13, a_12|)``, error
   ``2 t r^9`` (half the decay ``r^(2 n)`` the rule earns; extrapolating the whole
   decay passed panels of narrow Gaussian wells that erred by up to 1e-4), ``2 t``
   where the tail does not decay (``r >= 1/2``).  A panel passes when that is at most :data:`TOL`
   of its integral of ``|F_s'|``, or when its tail does not decay and is below
   :data:`FLAT` of its mean ``|F_s'|`` (rounding of the values, not truncation:
   ``sin(q/b)`` far out, ``exp(-q^2/b^2)`` carry a rounding of their argument's
   size), or when its estimate is not finite (the values are not: the result
   says so).
3. A piece whose panel fails is walked from its start: panels of half the piece
   at first, each halved where it fails and doubled (up to the piece) after it
   passes, as the engine's time quadrature walks an interval; a panel narrower
   than :data:`NARROWEST` of the piece passes as it is.  A piece takes at most
   :data:`TRIES` panels; the rest of a piece that spent them is one panel (the
   fallback: the old rule's accuracy there).

On a smooth curve every piece passes at once, so the rule costs one panel of
:data:`NODES` values per piece (the rule before, plus the four coefficient sums);
a narrow feature (a Gaussian well of width ``b``, a sine track of period ``2 pi b``,
with ``q_scale = 1``) is refined to panels of about ``b/2`` where it is and nowhere
else.  What it is worth: ``F_s`` within a few rounding errors of the integral of
``|F_s'|`` (``tests/test_numeric_antiderivative.py``: Gaussian wells of ``b`` = 0.1 ..
0.02 and sine tracks with ``q_scale`` 1, against mpmath at 30 digits; physics.md,
"Accuracy", where the rule is told for users).

The generated modules carry no conditional and no comparison
(:data:`symvib.kernelformat.ALLOWED_NODES`): their walk decides with
``math.copysign`` (a step function that is 0 or 1 even for NaN) and loops over
``range(n)`` whose ``n`` is 0 or 1 where it would branch.  The narrowed view's
template (:mod:`symvib.numeric.prepared`) writes the same rule in plain Python,
and the tests hold the two to the same bits.

Examples
--------
>>> NODES, PANEL, TRIES
(16, 0.25, 1000)
>>> x, w, *rows = tail_rows()
>>> len(x), len(rows), abs(sum(w) - 2.0) < 1e-14
(16, 4, True)
"""
from __future__ import annotations

__all__ = ["NODES", "PANEL", "TOL", "FLAT", "UNRESOLVED", "TRIES", "NARROWEST", "TAIL_POWER", "tail_rows"]

#: Gauss-Legendre nodes per panel.
NODES = 16
#: Widest panel (a piece), in units of the curve's ``q_scale``.
PANEL = 0.25
#: A panel passes when its error estimate is at most this share of its integral of ``|F_s'|``.
TOL = 1e-15
#: A tail that does not decay and is below this share of the panel's mean ``|F_s'|`` is rounding.
FLAT = 1e-10
#: A ratio of successive Legendre coefficients at and above which the tail is taken as not decaying.
UNRESOLVED = 0.5
#: The power of that ratio in the error estimate: ``NODES // 2 + 1`` (half the decay the rule earns).
TAIL_POWER = NODES // 2 + 1
#: Most panels one piece may take (its first one included).
TRIES = 1000
#: Narrowest panel, as a share of its piece: it passes as it is.
NARROWEST = 2.0 ** -24


def tail_rows(n: int = NODES) -> tuple:
    """``(x, w, t1, t2, t3, t4)``: the ``n`` Gauss-Legendre nodes and weights on ``[-1, 1]`` and the
    rows that give the Legendre coefficients ``a_{n-1}, a_{n-2}, a_{n-3}, a_{n-4}`` of a function from
    its values at the nodes (``a_k = sum_j (2k + 1)/2 w_j P_k(x_j) f(x_j)``), each a tuple of floats."""
    import numpy as np
    from numpy.polynomial import legendre

    x, w = legendre.leggauss(n)
    rows = []
    for k in (n - 1, n - 2, n - 3, n - 4):
        unit = np.zeros(k + 1)
        unit[k] = 1.0
        rows.append(tuple(float(v) for v in (2 * k + 1) / 2 * w * legendre.legval(x, unit)))
    return (tuple(float(v) for v in x), tuple(float(v) for v in w), *rows)
