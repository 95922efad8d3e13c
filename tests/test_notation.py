"""The paper's notation (symvib.symbolic.notation): printed forms equal the derivation.

Each printed equation is checked three ways against ``derive``: its SymPy form on each
branch (``PM = +-1``, ``alpha0 = atan(mu)``), the plain text read back by ``parse_text``,
both at 30 digits at random points; and the printed signs are the paper's (a form with
the branch signs swapped is caught).
"""
from __future__ import annotations

from functools import cache

import pytest
import sympy as sp

from symvib.symbolic import notation
from symvib.symbolic.derive import derive
from symvib.symbolic.identity import numeric_zero
from symvib.symbolic.symbols import C, g, mu

#: Ranges of the physics symbols at the random points.
EXTRA = {mu: (0.01, 0.5), g: (1.0, 20.0), C: (5.0, 50.0)}
#: Shapes whose equations are printed: the paper's three and two graphs.
SHAPES = ("circle", "parabola", "cycloid", "parabola-x", "quartic")


#: Shapes whose F_+- has no closed form: derived on the numeric route at once (no budgets to wait for).
NUMERIC_F = ("quartic",)


@cache
def _derived(name):
    return derive(name, routes=()) if name in NUMERIC_F else derive(name)


def _equal(a, b, curve) -> bool:
    """``a == b`` at 30 digits at random points of the curve and the physics."""
    qd = curve.qdot
    return numeric_zero(a - b, curve, extra={**EXTRA, qd: (-3.0, 3.0)}, points=4)


@pytest.mark.parametrize("name", SHAPES)
@pytest.mark.parametrize("angle", (True, False), ids=("tg-alpha0", "mu"))
def test_printed_eom_is_the_derived_one_on_both_branches(name, angle):
    d = _derived(name)
    form = notation.eom(d, angle=angle)
    for s in (1, -1):
        assert _equal(form.branch(s), d.eom(s).lhs, d.curve), (name, s, form.text)
    assert not _equal(form.branch(1), d.eom(-1).lhs, d.curve)   # the branches differ


@pytest.mark.parametrize("name", [n for n in SHAPES if n not in NUMERIC_F])
def test_printed_phase_trajectory_is_the_derived_one(name):
    d = _derived(name)
    form = notation.phase(d)
    assert form.lhs == d.curve.qdot**2
    for s in (1, -1):
        assert _equal(form.branch(s), d.phase(s).lhs - d.phase(s).rhs, d.curve), (name, s, form.text)


@pytest.mark.parametrize("name", [n for n in SHAPES if n not in NUMERIC_F])
@pytest.mark.parametrize("which", ("eom", "phase"))
def test_plain_text_parses_back_to_the_derived_equation(name, which):
    d = _derived(name)
    form = getattr(notation, which)(d)
    lhs, rhs = notation.parse_text(form.text, d.curve)
    derived = {s: (d.eom(s).lhs if which == "eom" else d.phase(s).lhs - d.phase(s).rhs) for s in (1, -1)}
    for s in (1, -1):
        back = (lhs - rhs).subs(notation.PM, s).subs(notation.ALPHA0, sp.atan(mu))
        assert _equal(back, derived[s], d.curve), (name, s, form.text)
    # The test can fail: the same text with the branch signs swapped is the other branch.
    swapped = form.text.translate(str.maketrans({"±": "∓", "∓": "±"}))
    lhs, rhs = notation.parse_text(swapped, d.curve)
    back = (lhs - rhs).subs(notation.PM, 1).subs(notation.ALPHA0, sp.atan(mu))
    assert not _equal(back, derived[1], d.curve)
    assert _equal(back, derived[-1], d.curve)


def test_circle_in_the_papers_words():
    """Eqs. (7) and the corrected (8): tg alpha0, cos(phi +- alpha0), the upper/lower signs."""
    d = _derived("circle")
    eq7, eq8 = notation.eom(d), notation.phase(d)
    assert "tg(alpha0)" in eq8.text and "±" in eq8.text and "∓" in eq8.text
    assert "sin(phi ± alpha0)" in eq7.text and "cos(phi ± alpha0)" in eq8.text
    assert "exp(∓2*phi*tg(alpha0))" in eq8.text
    assert "mu" not in eq7.text + eq8.text
    assert r"\operatorname{tg}" in eq8.latex and r"\pm" in eq8.latex and r"\mp" in eq8.latex
    assert eq8.latex.startswith(r"\dot{\varphi}^{2} = ") and eq7.latex.startswith(r"\ddot{\varphi}")
    assert r"- \pm" not in eq8.latex and "+ ±" not in eq8.text


def test_paper_expr_folds_the_branch_and_keeps_mu_when_asked():
    phi = sp.Symbol("phi", real=True)
    a0, PM = notation.ALPHA0, notation.PM
    assert notation.paper_expr(sp.sin(phi) + mu * sp.cos(phi)) == sp.sin(phi + PM * a0) / sp.cos(a0)
    assert notation.paper_expr(sp.cos(phi) - mu * sp.sin(phi)) == sp.cos(phi + PM * a0) / sp.cos(a0)
    assert notation.paper_expr(mu * phi, angle=False) == PM * mu * phi
    assert notation.paper_expr(sp.exp(-2 * mu * phi)) == sp.exp(-2 * PM * phi * sp.tan(a0))


def test_a_quadrature_is_printed_as_F_pm():
    form = notation.phase(_derived("quartic"))
    assert "F_±" in form.text and r"F_{\pm}" in form.latex and "Integral" not in form.text
    assert form.rhs.has(sp.Integral)       # the form itself keeps the quadrature


def test_markdown_and_bad_text():
    d = _derived("circle")
    text = notation.markdown(d)
    assert r"\operatorname{tg}" in text and text.count("$$") == 4
    with pytest.raises(ValueError, match="one '='"):
        notation.parse_text("phidot^2", d.curve)
    with pytest.raises(ValueError, match="side 2"):
        notation.parse_text("phidot^2 = __import__('os')", d.curve)
