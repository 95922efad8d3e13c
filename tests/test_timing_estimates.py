"""The time quadrature's error model: the Bernstein ellipse through a singularity, and the tail
estimate built on it (symvib.numeric.engine.timing), against closed forms and exact integrals."""
from __future__ import annotations

import cmath
import math

import mpmath
import numpy as np
import pytest

from symvib.numeric.driver import tail_rows
from symvib.numeric.engine.timing import ellipse_ratio, tail_error, zero_ratio
from symvib.numeric.quadrature import rule


def ratio_by_joukowski(u: complex) -> float:
    """``1/rho`` from the definition: ``rho = |u + sqrt(u^2 - 1)|`` on the branch where it is >= 1."""
    w = cmath.sqrt(u * u - 1.0)
    return 1.0 / max(abs(u + w), abs(u - w))


@pytest.mark.parametrize("u, rho", [(2.0, 2.0 + math.sqrt(3.0)), (-5.0, 5.0 + math.sqrt(24.0)), (0.3, 1.0),
                                    (1j * 0.75, 0.75 + math.sqrt(1.5625))])
def test_ellipse_ratio_meets_closed_forms_on_the_axes(u, rho):
    assert ellipse_ratio(u.real if isinstance(u, complex) else u, u.imag if isinstance(u, complex) else 0.0) == \
        pytest.approx(1.0 / rho, rel=1e-14)


def test_ellipse_ratio_agrees_with_the_complex_definition_off_the_segment():
    rng = np.random.default_rng(7)
    for _ in range(2000):
        u = complex(rng.normal() * 10 ** rng.uniform(-1, 2), rng.normal() * 10 ** rng.uniform(-3, 2))
        expected = ratio_by_joukowski(u)
        assert ellipse_ratio(u.real, u.imag) == pytest.approx(expected, rel=1e-9, abs=1e-15), u


@pytest.mark.parametrize("zeros", [(0.4 + 0.3j, 0.4 - 0.3j), (1.7, -2.5), (-1.2 + 0.05j, -1.2 - 0.05j)])
def test_zero_ratio_finds_the_nearer_zero_of_the_local_quadratic(zeros):
    """``G = a (z - z1)(z - z2)`` on a panel ``[c - hw, c + hw]``: the larger ``1/rho`` of the two zeros."""
    z1, z2 = (complex(z) for z in zeros)
    a, c, hw, x = 3.0, 0.2, 0.8, 0.5
    G = (a * (x - z1) * (x - z2)).real
    G1 = (a * (2 * x - z1 - z2)).real
    G2 = 2.0 * a
    expected = max(ratio_by_joukowski((z1 - c) / hw), ratio_by_joukowski((z2 - c) / hw))
    assert zero_ratio(x, G, G1, G2, c, hw) == pytest.approx(expected, rel=1e-12)


def test_zero_ratio_of_a_linear_model_is_its_one_zero():
    # G = 2 (z - 1.9): zero at 1.9, panel [-1, 1]
    assert zero_ratio(0.0, -3.8, 2.0, 0.0, 0.0, 1.0) == pytest.approx(1.0 / (1.9 + math.sqrt(1.9 ** 2 - 1)), rel=1e-14)


@pytest.mark.parametrize("x0", [1.05, 1.3, 2.0, 4.0, -1.5])
def test_tail_estimate_bounds_the_error_where_the_zero_of_G_explains_the_decay(x0):
    """The time integrand ``1/sqrt(G)``, ``G = s (x - x0)`` with a turning point beyond the panel:
    the estimate (trusting the zero's ellipse) is at least the true error of the 12-node rule."""
    mpmath.mp.dps = 30
    r = rule(12)
    sign = 1.0 if x0 < -1 else -1.0
    G = sign * (r.x - x0)
    f = 1.0 / np.sqrt(G)
    c = tail_rows(r.x, r.weights) @ f
    exact = float(mpmath.quad(lambda x: 1 / mpmath.sqrt(sign * (x - x0)), [-1, 1]))
    err = abs(float(r.weights @ f) - exact)
    j = int(np.argmin(G))
    r_geom = zero_ratio(float(r.x[j]), float(G[j]), sign, 0.0, 0.0, 1.0)
    est = tail_error(c[0], c[1], c[2], c[3], 12, False, r_geom, 0.0)
    assert est >= err or err < 4e-16 * abs(exact)
