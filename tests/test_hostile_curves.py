"""Hostile curves and options end in a result or one line naming the field (issue 29, items 8, 9, 11, 12).

Kinks are singular points (``symvib derive`` refuses them naming the point); a simplification
that SymPy cannot finish is bounded (the unsimplified, equal, expression stands); a numeric
``F_sigma`` whose quadrature would take millions of panels is refused up front naming
``curve.q_scale``; ``--budget`` must be a positive finite number; numba's warnings about an
engine it cannot cache never reach the user.
"""
from __future__ import annotations

import importlib
import subprocess
import sys
import threading
import warnings
import weakref
from types import SimpleNamespace

import pytest
import sympy as sp

from symvib.numeric import backends, driver
from symvib.numeric.scene import SceneError, scene_from_dict
from symvib.symbolic import budget

#: Hang guard (s) of a subprocess: far above the expected seconds.
HANG_GUARD = 120.0
#: Spent budgets of 5 ms in a simplifier that churns weak keys: each alarm fell in a callback with
#: a chance of about a quarter (5 of 20, before the alarm let callbacks be).
RUNS_INTO_CALLBACKS = 20


def _cli(*args, timeout=HANG_GUARD):
    return subprocess.run([sys.executable, "-m", "symvib.cli", *args], capture_output=True, text=True, timeout=timeout)


def _one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


@pytest.mark.parametrize(("z", "point"), [("abs(x)", "x = 0 "), ("sqrt((x - 1)**2)", "x = 1 "),
                                          ("abs(sin(x))", "x = 0 "), ("x**2 + abs(x + 2)", "x = -2 ")])
def test_derive_refuses_a_kink_naming_it(z, point):
    out = _cli("derive", "--z", z)
    assert out.returncode == 2
    line = _one_line(out.stderr)
    assert point in line and "corner" in line
    assert "DiracDelta" not in out.stdout + out.stderr


@pytest.mark.parametrize("command", (["derive", "parabola"], ["generate", "--z", "x**2", "--out", "unused"]))
@pytest.mark.parametrize("value", ("nan", "inf", "-inf", "-1", "0", "1e300"))
def test_budget_must_be_a_positive_number_of_seconds(tmp_path, command, value):
    out = _cli(*command, f"--budget={value}")
    assert out.returncode == 2
    assert _one_line(out.stderr).startswith(f"symvib {command[0]}: error: --budget: ")


@pytest.mark.parametrize("text", ("cos(1000000*x)", "cos(x/(1/1000000))", "cos(1000000*x)**2/1000000"))
def test_a_simplification_sympy_cannot_finish_leaves_its_input(text):
    x = sp.Symbol("x", real=True)
    expr = sp.diff(sp.sympify(text, locals={"x": x}), x) ** 2 + 1
    budget._HOPELESS.clear()
    assert budget.simplify(expr, seconds=0.5) == expr  # equal, unsimplified, in about half a second
    assert budget._HOPELESS  # and not tried again in this process


class _Key:
    """A weakly referenced key (instances of ``object`` itself are not)."""


class _Finalized:
    """An object with a finalizer of a few bytecodes."""

    def __del__(self):
        self.gone = [True] * 4


def _churn_weak_keys(expr):
    """A simplifier that never ends and spends much of its time in weak references' callbacks, as
    SymPy's caches do when their keys die."""
    keys = weakref.WeakKeyDictionary()
    while True:
        key = _Key()
        keys[key] = expr
        del key   # (its WeakKeyDictionary's callback runs here)


def _churn_finalizers(expr):
    """A simplifier that never ends and spends much of its time in finalizers."""
    while True:
        _Finalized()


@pytest.mark.parametrize("how", (_churn_weak_keys, _churn_finalizers))
def test_a_spent_simplify_budget_interrupts_no_callback(monkeypatch, how):
    """The budget's alarm used to raise inside a weak reference's callback or a finalizer when it
    fired there (on a quarter of these runs): Python printed "Exception ignored"
    (PytestUnraisableExceptionWarning in test runs) and the budget ran on until a repeated alarm
    landed elsewhere."""
    ignored = []
    monkeypatch.setattr(sys, "unraisablehook", ignored.append)
    x = sp.Symbol("x", real=True)
    for _ in range(RUNS_INTO_CALLBACKS):
        assert budget.simplify(sp.cos(x) + 1, seconds=0.005, how=how, remember=False) == sp.cos(x) + 1
    assert ignored == []


def test_simplify_in_a_worker_thread_is_bounded_too():
    """Off the main thread no alarm can interrupt SymPy: a child process does the work."""
    x = sp.Symbol("x", real=True)
    slow = sp.diff(sp.cos(1000001 * x), x) ** 2 + 1
    found = {}
    budget._HOPELESS.clear()
    worker = threading.Thread(target=lambda: found.update(
        fast=budget.simplify(sp.sin(x) ** 2 + sp.cos(x) ** 2), slow=budget.simplify(slow, seconds=0.5)))
    worker.start()
    worker.join(HANG_GUARD)
    assert found == {"fast": 1, "slow": slow}


@pytest.mark.parametrize("z", ("1e-6*cos(x/1e-6)", "cos(1000000*x)/1000000"))
def test_a_fast_oscillating_curve_is_built(z):
    """The curve's metric is simplified within budget.SIMPLIFY_SECONDS (it hung in _finish)."""
    code = f"from symvib.symbolic.curve import graph; c = graph({z!r}); print(c.kappa.has(sp.DiracDelta))"
    out = subprocess.run([sys.executable, "-c", "import sympy as sp; " + code], capture_output=True, text=True,
                         timeout=HANG_GUARD)
    assert out.returncode == 0 and out.stdout.strip() == "False", out.stderr


def _catenary(**changes):
    data = {"curve": {"shape": "catenary"}, "parameters": {"a": 1.0}, "physics": {"mu": 0.1, "restitution": 0.8},
            "limiters": {"left": -0.5, "right": 0.5}, "initial": {"q": 0.0, "qdot": 2.0}}
    for key, value in changes.items():
        section, name = key.split("__")
        data[section][name] = value
    return scene_from_dict(data)


def _numeric_module(scale):
    return SimpleNamespace(F_ROUTES={1: "numeric", -1: "numeric"}, PANEL=0.25, Q_REF=0.0,
                           q_scale_scalar=lambda *cp: scale)


@pytest.mark.parametrize(("scale", "scene"), [(1e-7, _catenary()), (1e-6, _catenary()),
                                              (1.0, _catenary(limiters__right=1e5)),
                                              (1e-3, _catenary(initial__q=-40.0, limiters__left=-50.0))])
def test_a_quadrature_of_millions_of_panels_is_refused_up_front(scale, scene):
    with pytest.raises(SceneError, match=r"^curve\.q_scale: .*MAX_F_PANELS"):
        driver.check_panels(scene, _numeric_module(scale), (1.0,))


def test_the_catalogue_catenary_runs_within_the_panel_bound():
    driver.check_panels(_catenary(), _numeric_module(1.0), (1.0,))
    assert driver.simulate(_catenary()).success


def test_numba_warnings_stay_quiet_and_an_uncacheable_engine_is_forgotten(tmp_path, monkeypatch):
    pytest.importorskip("numba")
    from numba.core.errors import NumbaWarning

    bind = importlib.import_module("symvib.numeric.engine.bind")  # the module (the package exports a function)
    markers = {entry: tmp_path / entry for entry in backends.COMPILED_ENTRIES}
    monkeypatch.setattr(bind, "compiled_marker", lambda mod, entry: markers[entry])
    for path in markers.values():
        path.touch()
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        with backends.quiet_compiler(object(), "numba"):
            warnings.warn("Cannot cache compiled function 'simulate_bound' as it uses dynamic globals",
                          NumbaWarning, stacklevel=1)
            warnings.warn("something else", UserWarning, stacklevel=1)
    assert [w.category for w in seen] == [UserWarning]
    assert not any(path.exists() for path in markers.values())


@pytest.mark.slow
def test_a_narrow_well_with_far_limiters_agrees_with_an_independent_integrator():
    # A Gaussian well 0.05 wide between limiters 30 widths out: its simplified curvature once
    # overflowed to inf/inf there, and the run ended non_finite on both engines.
    pytest.importorskip("scipy")
    from symvib import simulate
    from symvib.checks.accuracy import compare, reference_for

    data = {"curve": {"z": "-a*exp(-x**2/b**2)"}, "parameters": {"a": 0.1, "b": 0.05},
            "physics": {"mu": 0.1, "restitution": 0.8}, "limiters": {"left": -1.5, "right": 1.5},
            "initial": {"q": -1.4, "qdot": 3.0}, "run": {"t_max": 50.0, "max_events": 200}}
    scene = scene_from_dict(data)
    reference = reference_for(data)
    for backend in ("python", "numba"):
        result = simulate(scene, samples=False, backend=backend)
        assert result.success, (backend, result.status)
        verdict = compare(result, reference.run, scene=scene)
        assert verdict.verdict == "agree", (backend, verdict)
        assert [e.kind.value for e in result.events][-1] == "arrest"


@pytest.mark.slow
def test_an_interval_far_below_q_scale_that_misses_its_tolerance_names_q_scale_as_the_remedy():
    # The semicubical parabola at L = 1e-6 without a q_scale: its numeric F_sigma's panels are fractions
    # of a q_scale thousands of times the motion; the run says so, and declaring it is the cure.
    pytest.importorskip("scipy")
    from symvib import simulate
    from symvib.checks.accuracy import reference_for

    length = 1e-6
    data = {"curve": {"x": "q**3/L**2", "z": "q**2/L", "q": "q"}, "parameters": {"L": length},
            "physics": {"mu": 0.1, "restitution": 0.8}, "limiters": {"right": 2.0 * length},
            "initial": {"q": 0.5 * length, "qdot": 0.0}, "run": {"t_max": 10.0, "max_events": 50}}
    result = simulate(scene_from_dict(data), samples=False, backend="python")
    assert result.status.value == "tolerance_not_met" and "q_scale" in result.message, result.message
    data["curve"]["q_scale"] = "L"
    kind, t_ref = reference_for(data).run.events[0][:2]
    first = simulate(scene_from_dict(data), samples=False, backend="python").events[0]
    assert first.kind.value == kind == "normal_sign_change" and abs(first.t - t_ref) <= 1e-12 * t_ref, first
