"""Eq. 1 from first principles (:mod:`symvib.symbolic.mechanics`: sympy.physics.mechanics, Kane's
method) against ``derive`` for every catalogue curve, on every branch, at 30 digits; a friction
force with the wrong sign, or the wrong branch, is caught.  ``derivations/mechanics.ipynb`` shows
the same derivation step by step.
"""
from __future__ import annotations

from functools import cache

import pytest
import sympy as sp

from symvib.shapes import CATALOGUE
from symvib.symbolic.derive import derive
from symvib.symbolic.mechanics import BRANCHES, agrees, check_eq1, first_principles, on_branch
from symvib.symbolic.symbols import g


@cache
def _derived(name):
    # eq. 1 does not depend on F_sigma: the numeric route stands in at once (no integration budgets).
    return derive(CATALOGUE[name].curve(), routes=())


@pytest.mark.parametrize("name", sorted(CATALOGUE))
def test_kane_gives_eq1_for_every_branch(name):
    assert check_eq1(CATALOGUE[name].curve()) == dict.fromkeys(BRANCHES, True), name


@pytest.mark.parametrize("name", sorted(CATALOGUE))
def test_normal_reaction_is_kappa_w_plus_g_cos_alpha(name):
    """Newton along the normal: N = kappa h^2 qdot^2 + g cos(alpha) (physics.md, eq. 1)."""
    c = _derived(name).curve
    _, N, _, _ = first_principles(c)
    assert agrees(N, c.kappa * c.h**2 * c.qdot**2 + g * sp.cos(c.alpha), c), name


def test_check_eq1_catches_friction_with_the_wrong_sign():
    assert check_eq1("cycloid", friction=+1) == dict.fromkeys(BRANCHES, False)


@pytest.mark.parametrize("name", ["parabola", "circle", "catenary"])
def test_a_wrong_friction_or_branch_is_caught(name):
    d = _derived(name)
    c = d.curve
    qddot, N, sign_v, abs_N = first_principles(c, friction=+1)    # friction pushing the particle on
    for s, n in BRANCHES:
        ours = -(d.eom(s, n).lhs - c.qddot)
        assert not agrees(on_branch(qddot, sign_v, abs_N, N, s, n), ours, c), (name, s, n)
    qddot, N, sign_v, abs_N = first_principles(c)
    ours = -(d.eom(1, 1).lhs - c.qddot)
    assert not agrees(on_branch(qddot, sign_v, abs_N, N, -1, 1), ours, c)   # v < 0 is not the v > 0 branch
    assert not agrees(on_branch(qddot, sign_v, abs_N, N, 1, -1), ours, c)   # nor is N < 0


def test_the_mechanics_notebook_asserts_every_catalogue_curve():
    import json
    from pathlib import Path

    path = Path(__file__).resolve().parent.parent / "derivations" / "mechanics.ipynb"
    source = "\n".join("".join(c["source"]) for c in json.loads(path.read_text(encoding="utf-8"))["cells"]
                       if c["cell_type"] == "code")
    for needed in ("KanesMethod", "dynamicsymbols", "ReferenceFrame", "Particle", "for name in CATALOGUE",
                   ".eom(", "assert "):
        assert needed in source, needed
