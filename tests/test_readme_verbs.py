"""The README's four verbs, each by its example: "Derive", "Generate", "Simulate" and "Sweep".

Each block runs as a reader would run it (``tests/readme_blocks.py``), and each test checks what the
block's comments claim, so an example that runs but says something false fails here.
"""
from pathlib import Path

import numpy as np
import pytest
from readme_blocks import python_blocks, run_section

from symvib import simulate
from symvib.numeric import kernels
from symvib.numeric.events import EventKind
from symvib.numeric.scene import resolve_scene

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("heading", ["## Derive", "## Generate", "## Simulate", "## Sweep"])
def test_each_verb_has_one_short_example(heading):
    blocks = python_blocks(heading)
    assert len(blocks) == 1 and len(blocks[0].splitlines()) <= 12


def test_derive_gives_the_circles_equations(capsys):
    import sympy

    namespace = run_section("## Derive", "readme_derive")
    assert "{1: 'symbolic', -1: 'symbolic'}" in capsys.readouterr().out   # eq. 2 solves eq. 1, both branches
    d, eom, phase = namespace["d"], namespace["eom"], namespace["phase"]
    s = {symbol.name: symbol for symbol in eom.free_symbols | phase.free_symbols}
    mu, g, R, phi = s["mu"], s["g"], s["R"], s["phi"]
    want = s["phiddot"] + mu * s["phidot"] ** 2 + g * (sympy.sin(phi) + mu * sympy.cos(phi)) / R
    assert sympy.simplify(eom.lhs - eom.rhs - want) == 0               # the circle's eq. 1, branch v > 0
    assert phase.lhs == s["phidot"] ** 2 and "C" in s                   # eq. 2: qdot^2 = P(phi), with its constant
    P = phase.rhs                                                         # branch v < 0: qddot = P'/2 solves eq. 1
    assert sympy.simplify(P.diff(phi) / 2 - mu * P + g * (sympy.sin(phi) - mu * sympy.cos(phi)) / R) == 0
    assert sympy.simplify(P.diff(phi) / 2 + mu * P + g * (sympy.sin(phi) + mu * sympy.cos(phi)) / R) != 0
    assert isinstance(namespace["latex"], dict) and "eom" in namespace["latex"]
    assert d.check() == {1: "symbolic", -1: "symbolic"}


def test_generate_writes_a_checked_module_whose_kernels_agree(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    namespace = run_section("## Generate", "readme_generate")
    path = Path(namespace["path"])
    assert path.resolve() == (tmp_path / "my-kernels" / "parabola.py").resolve()
    text = path.read_text(encoding="utf-8")
    kernels.check_text(text, path)                # body digest and the loader's whitelist: loadable as written
    written = {}
    exec(compile(text, str(path), "exec"), written)  # noqa: S102  (checked just above)
    assert "('q', 'p')" in capsys.readouterr().out
    k, h = namespace["k"], namespace["h"]
    assert written["SIGNATURES"]["h"] == k.SIGNATURES["h"] == ("q", "p")
    assert isinstance(h, np.ndarray) and h.shape == (2,)
    np.testing.assert_allclose(h, 1.0 / np.cos([0.0, 0.5]) ** 3, rtol=1e-14)   # h = p sec^3(phi) on the parabola
    np.testing.assert_allclose(written["h"](np.array([0.0, 0.5]), 1.0), h, rtol=1e-15)
    assert h[1] == pytest.approx(k.h_scalar(0.5, 1.0), rel=1e-15)


def test_simulate_runs_the_paper_parabola_to_arrest(capsys):
    namespace = run_section("## Simulate", "readme_simulate")
    result = namespace["result"]
    out = capsys.readouterr().out
    assert out.startswith("arrested\n") and result.success
    assert result.count(EventKind.IMPACT) == 10 and result.count(EventKind.REVERSAL) == 7
    assert result.events[-1].kind == EventKind.ARREST
    assert result.energy_budget.relative_residual < 1e-12
    assert result.event_table() in out


def test_sweep_counts_impacts_as_single_runs_do():
    namespace = run_section("## Sweep", "readme_sweep")
    impacts = namespace["res"].grid("impacts")
    assert impacts.shape == (4, 2)
    assert np.all(np.diff(impacts, axis=0) >= 0) and np.all(impacts[:, 0] >= impacts[:, 1])   # as the comment says
    base = resolve_scene("paper-parabola")
    for i, qdot in enumerate(np.linspace(3.0, 12.0, 4)):
        for j, mu in enumerate((0.05, 0.1)):
            one = simulate(base.replace(qdot0=qdot, mu=mu), backend="python")
            assert impacts[i, j] == one.count(EventKind.IMPACT), (qdot, mu)
