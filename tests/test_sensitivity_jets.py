"""The sensitivities' jets (symvib/codegen/jets.py): sign changes of N and the curve's parameters.

Each jets kernel is held against SymPy's own derivatives of the curve's ``x(q), z(q)`` at 30 digits
(curvature and tangent angle rebuilt here from ``x, z``, not taken from the curve's forms); every
derivative of a run with a sign change of ``N``, or with respect to a curve parameter, against a
Richardson-extrapolated step study of central differences of the engine's own runs (as
tests/test_sensitivity.py does), to 1e-7.
"""
import math
import random
import subprocess
import sys
import warnings
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import sympy as sp

import symvib
from symvib import provenance, simulate
from symvib.codegen import jets as codegen_jets
from symvib.kernelformat import verify_text
from symvib.numeric import jet_kernels, sensitivity
from symvib.numeric.events import EventKind
from symvib.numeric.scene import resolve_scene, scene_from_dict
from symvib.numeric.sensitivity import sensitivities
from symvib.numeric.sensitivity_curve import parameter_value, resolve_wrt, with_parameters
from symvib.numeric.sensitivity_normal import normal_sign_change_tangent
from symvib.shapes import CATALOGUE, Shape
from symvib.symbolic.identity import sample_points
from symvib.symbolic.symbols import mu as MU

ROOT = Path(__file__).resolve().parents[1]
GENERATED = ROOT / "generated"
TOL = 1e-7
HALVINGS = 6
FIRST_STEP = 1e-3
#: Agreement of a float kernel with its 30-digit value, relative to the larger of the two and the
#: kernel's typical size at the sample points.
KERNEL_RTOL = 1e-10
#: Where a kernel's entry is 0, the rounding it may show, relative to the kernel's largest entry.
ROUNDING = 1e-4

CIRCLE_N = {"curve": {"shape": "circle"}, "parameters": {"R": 0.5},
            "physics": {"alpha0": 0.02, "restitution": 1.0}, "initial": {"q": 0.0, "qdot": 11.0},
            "limiters": {"right": 2.5}}
HUMP = {   # over a crest where N < 0 (two sign changes, curvature not constant: kappa' counts), then a valley
    "curve": {"name": "jets-hump", "z": "a*(1 - cos(x/b))"}, "parameters": {"a": 0.3, "b": 0.2},
    "physics": {"mu": 0.05, "restitution": 0.7}, "limiters": {"left": -1.5, "right": 1.5},
    "initial": {"q": 0.0, "qdot": 4.0}}
USER_TWO = {   # two parameters, two limiters, numeric F_sigma: dF_s'/da integrated by the module's quadrature
    "curve": {"name": "jets-sine", "z": "a*(1 - cos(x/b))", "closed_form": "never"},
    "parameters": {"a": 0.3, "b": 0.2}, "physics": {"mu": 0.08, "restitution": 0.6},
    "limiters": {"left": -0.25, "right": 0.3}, "initial": {"q": 0.0, "qdot": 4.0}}
USER_ELLIPSE = {   # parametric: the tangent angle itself moves with the parameters
    "curve": {"name": "jets-ellipse", "q": "u", "x": "a*sin(u)", "z": "-b*cos(u)", "domain": ["-pi/2", "pi/2"]},
    "parameters": {"a": 1.0, "b": 0.6}, "physics": {"mu": 0.06, "restitution": 0.75},
    "limiters": {"left": -0.9, "right": 1.0}, "initial": {"q": 0.2, "qdot": 4.5}}


# --- the kernels against SymPy ---------------------------------------------------------------


def _independent(curve):
    """What each jets kernel should return, rebuilt from ``x(q), z(q)`` alone (SymPy)."""
    q = curve.q
    x, z = curve.x, curve.z
    xp, zp = sp.diff(x, q), sp.diff(z, q)
    xpp, zpp = sp.diff(xp, q), sp.diff(zp, q)
    h = sp.sqrt(xp ** 2 + zp ** 2)
    dalpha = (xp * zpp - zp * xpp) / h ** 2
    kappa = dalpha / h
    out = {"jet3": [sp.diff(x, q, 3), sp.diff(z, q, 3), sp.diff(kappa, q)]}
    for j, a in enumerate(curve.params):
        xa, za = sp.diff(xp, a), sp.diff(zp, a)
        alpha_a = (xp * za - zp * xa) / h ** 2      # d atan2(z', x') / da
        out[f"param_jet_{j}"] = [sp.diff(x, a), sp.diff(z, a), xa, za, sp.diff(xpp, a), sp.diff(zpp, a), alpha_a,
                                 sp.diff(dalpha, a), sp.diff(h, a), sp.diff(sp.diff(h, q), a), sp.diff(kappa, a)]
        for s, b in ((1, "p"), (-1, "m")):
            E = sp.exp(2 * s * MU * curve.alpha)
            out[f"dF_{b}_param_{j}"] = [E * (2 * s * MU * alpha_a * (zp + s * MU * xp) + za + s * MU * xa)]
    return out


def _check_jets(curve, module, values, points=6, seed=0):
    rng = random.Random(seed)
    expected = _independent(curve)
    qs = sample_points(curve, points, seed=seed, values={p: sp.Float(v, 30) for p, v in values.items()})
    args = [float(values[p]) for p in curve.params]
    mu_value = 0.1 + 0.3 * rng.random()
    checked = 0
    for fname, exprs in expected.items():
        fn = getattr(module, fname)
        takes_mu = "mu" in module.SIGNATURES[fname]
        got = np.array([np.atleast_1d(fn(float(qv), *(([mu_value] if takes_mu else []) + args))).ravel()
                        for qv in qs])
        subs = {p: sp.Float(v, 30) for p, v in values.items()}
        subs[MU] = sp.Float(mu_value, 30)
        want = np.array([[float(sp.N(e.subs({**subs, curve.q: sp.Float(qv, 30)}), 30)) for e in exprs]
                         for qv in qs])
        # relative to each value and its column's size; a column that is 0 (alpha of the parabola does not
        # move with p) to rounding of the kernel's largest entry
        size = np.maximum(np.max(np.abs(want), axis=0), ROUNDING * np.max(np.abs(want)))
        assert np.all(np.abs(got - want) <= KERNEL_RTOL * np.maximum(np.abs(want), size)), (fname, got, want)
        checked += 1
    return checked


@pytest.mark.parametrize("name", sorted(CATALOGUE))
def test_every_catalogue_jets_kernel_is_sympy_s_derivative_at_30_digits(name):
    shape = CATALOGUE[name]
    curve = shape.curve()
    values = {p: 0.5 + 0.5 * random.Random(k).random() for k, p in enumerate(curve.params)}
    assert _check_jets(curve, jet_kernels.load_jets(name), values) == 1 + 3 * len(curve.params)


def test_a_user_curve_s_jets_with_two_parameters_are_sympy_s_derivatives(tmp_path, monkeypatch):
    monkeypatch.setenv("SYMVIB_CACHE", str(tmp_path))
    from symvib.prepare import load_jets

    scene = scene_from_dict(USER_ELLIPSE)
    module = load_jets(scene.shape)
    assert module.PARAM_JETS == {"a": 0, "b": 1}
    curve = scene.shape.curve()
    assert _check_jets(curve, module, dict(zip(curve.params, (1.3, 0.7)))) == 7
    assert len(list(tmp_path.glob("jets_ellipse_*_jets.py"))) == 1       # cached beside the kernels


# --- the committed modules, their hash and the one command -------------------------------------


def test_jets_generation_is_deterministic_and_the_committed_ones_are_current(tmp_path):
    a = codegen_jets.write_jets("cycloid", tmp_path / "a")
    b = codegen_jets.write_jets("cycloid", tmp_path / "b")
    assert a.read_bytes() == b.read_bytes()
    committed = GENERATED / "jets" / "cycloid.py"
    if jet_kernels.load_jets("cycloid").SYMPY_VERSION == sp.__version__:
        assert a.read_bytes() == committed.read_bytes(), "generated/jets differs from a fresh generation"
    assert codegen_jets.stale_jets(GENERATED) == []


def test_the_jets_hash_is_apart_from_the_kernel_modules_hash():
    source = CATALOGUE["circle"].source()
    assert provenance.jets_hash(source) != provenance.input_hash(source)
    assert "codegen/jets.py" not in provenance.GENERATOR_SOURCES      # generated/*.py stay as they are


def test_an_edited_or_missing_jets_module_is_found_by_generate_check(tmp_path):
    import shutil

    copy = tmp_path / "generated"
    shutil.copytree(GENERATED, copy)
    path = copy / "jets" / "circle.py"
    path.write_text(path.read_text().replace("numpy.sin(q)", "numpy.sin(q)*1.0000001", 1))
    (copy / "jets" / "ellipse.py").unlink()
    problems = "\n".join(codegen_jets.stale_jets(copy))
    assert "circle.py: edited by hand" in problems and "ellipse.py: missing" in problems
    out = subprocess.run([sys.executable, "-m", "symvib.cli", "generate", "--check", "--out", str(copy)],
                         capture_output=True, text=True, cwd=ROOT)
    assert out.returncode == 1 and "jets" in out.stdout


def test_a_hostile_curve_name_never_reaches_the_jets_source_or_its_file_name(tmp_path, monkeypatch):
    monkeypatch.setenv("SYMVIB_CACHE", str(tmp_path))
    from symvib.prepare import load_jets

    hostile = 'x"""\nimport os; os.system("echo owned") #/../../evil'
    shape = Shape(name=hostile, kind="graph", q="x", z="c*x**2", params={"c": "positive"})
    text = codegen_jets.jets_text(shape)
    verify_text(text, "hostile.py")
    assert "import os" not in text.split('"""', 2)[2].split("NAME = ", 1)[0]   # not as code before NAME
    assert "\nimport os" not in text
    module = load_jets(shape)
    assert module.NAME == hostile and module.PARAM_JETS == {"c": 0}
    files = [p.name for p in tmp_path.iterdir()]
    assert len(files) == 1 and files[0].endswith("_jets.py") and all(ch not in files[0] for ch in '"/ ;\n')


def test_a_plain_run_never_loads_the_jets():
    code = ("import sys, symvib\n"
            "r = symvib.simulate('paper-circle-7')\n"
            "r.sensitivities(('mu', 'k'))\n"       # no sign change of N, no curve parameter: no jets either
            "print(sorted(m for m in sys.modules if 'jets' in m))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"


# --- step studies ----------------------------------------------------------------------------------


def _observed(scene, n_events):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            r = simulate(scene, samples=False)
        except Exception:   # noqa: BLE001 - a perturbed value the scene refuses: no estimate at that step
            return None
    if len(r.events) < n_events:
        return None
    return (np.array([e.t for e in r.events[:n_events]]), np.array([e.q for e in r.events[:n_events]]),
            r.energy_budget.friction_work)


def _step_study(scene, target, n_events):
    """Richardson-extrapolated central differences of (event times, positions, friction work)."""
    x = parameter_value(scene, target)
    name = target[2]
    scale = {"mu": max(scene.mu, 0.01), "k": 1.0, "qdot0": max(abs(scene.qdot0), 0.1)}.get(name, 1.0)
    if target[1] == "curve":
        scale = abs(x)
    steps = [FIRST_STEP * scale / 2 ** j for j in range(HALVINGS + 1)]

    def central(d):
        plus = _observed(with_parameters(scene, [target], [x + d]), n_events)
        minus = _observed(with_parameters(scene, [target], [x - d]), n_events)
        if plus is None or minus is None:
            return None
        return [(a - b) / (2 * d) for a, b in zip(plus, minus)]

    D = [central(d) for d in steps]
    return [[(4 * f - c) / 3 for c, f in zip(coarse, fine)]
            for coarse, fine in zip(D, D[1:]) if coarse is not None and fine is not None]


def assert_matches(scene, wrt):
    """Every event's time and position, and the friction work, against the step study (1e-7)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = simulate(scene)
    sens = sensitivities(res, wrt=wrt)
    assert not any(sens.reasons), sens.reasons
    n = len(sens.events)
    final = sens.final["friction_work"]
    final_floor = max(1e-4 * np.nanmax(np.abs(final)), 1e-5) if np.any(np.isfinite(final)) else None
    for j, target in enumerate(resolve_wrt(scene, wrt)):
        study = _step_study(scene, target, n)
        assert study, f"{target}: every perturbed run changed its events"
        for which, a in enumerate((sens.t[:, j], sens.q[:, j])):
            floor = max(1e-4 * np.max(np.abs(a)), 1e-5)   # a derivative about 0: the column's size
            for i in range(n):
                err = min(abs(est[which][i] - a[i]) for est in study)
                assert err <= TOL * max(abs(a[i]), floor), (target, ("t", "q")[which], i, a[i],
                                                             [est[which][i] for est in study])
        if final_floor is not None:
            err = min(abs(est[2] - final[j]) for est in study)
            assert err <= TOL * max(abs(final[j]), final_floor), (target, "friction_work", final[j],
                                                                  [est[2] for est in study])
    return res, sens


def test_every_event_after_sign_changes_of_n_matches_a_step_study():
    scene = scene_from_dict(CIRCLE_N)
    res, sens = assert_matches(scene, ("mu", "qdot0", "right"))
    kinds = [e.kind for e in res.events]
    first = kinds.index(EventKind.NORMAL_SIGN_CHANGE)
    assert kinds.count(EventKind.NORMAL_SIGN_CHANGE) >= 5 and len(kinds) > first + 20
    assert np.all(np.isfinite(sens.t)) and np.all(np.isfinite(sens.final["t_final"]))


def test_a_user_curve_s_sign_changes_of_n_with_varying_curvature_match_a_step_study():
    res, _ = assert_matches(scene_from_dict(HUMP), ("mu", "qdot0", "right"))
    kinds = [e.kind for e in res.events]
    assert kinds[:3] == [EventKind.NORMAL_SIGN_CHANGE] * 2 + [EventKind.IMPACT] and len(kinds) > 10


@pytest.mark.slow
def test_a_user_curve_s_parameters_through_sign_changes_of_n_match_a_step_study():
    assert_matches(scene_from_dict(HUMP), ("a", "b"))


def test_the_circle_s_radius_through_sign_changes_of_n_matches_a_step_study():
    assert_matches(scene_from_dict(CIRCLE_N), ("R", "mu"))


def test_the_paper_parabola_s_p_matches_a_step_study():
    res, sens = assert_matches(resolve_scene("paper-parabola").replace(k=0.8), ("p", "mu", "k"))
    assert sens.wrt == ("p", "mu", "k") and np.all(np.isfinite(sens.final["friction_work"]))


@pytest.mark.slow
@pytest.mark.parametrize("data", [USER_TWO, USER_ELLIPSE], ids=["sine, numeric F", "parametric ellipse"])
def test_a_user_curve_s_two_parameters_match_a_step_study(data):
    scene = scene_from_dict(data)
    res, _ = assert_matches(scene, ("a", "b", "left", "mu"))
    impacts = {e.q for e in res.events if e.kind is EventKind.IMPACT}
    assert impacts == {scene.left, scene.right}       # both limiters are hit


@pytest.mark.slow
def test_sampled_positions_move_with_the_curve_s_parameter():
    """x, z and the arc length at fixed times: the curve itself moves with its parameter too."""
    from symvib.numeric.sample_sensitivity import sample_positions, sample_sensitivities

    scene = scene_from_dict(USER_ELLIPSE)
    times = np.array([0.05, 0.3, 0.7])
    res = simulate(scene)
    for coords in ("xz", "s"):
        exact = sample_sensitivities(res, times, ("b",), coords).derivatives[:, :, 0]
        target = resolve_wrt(scene, ("b",))[0]
        est = []
        for d in (1e-4, 5e-5):
            plus, minus = (sample_positions(simulate(with_parameters(scene, [target], [0.6 + e])), times, coords)
                           for e in (d, -d))
            est.append((plus - minus) / (2 * d))
        rich = (4 * est[1] - est[0]) / 3
        assert np.allclose(exact, rich, rtol=1e-6, atol=1e-9), (coords, exact, rich)


# --- a tangential zero of N, and names -----------------------------------------------------------


def test_a_tangential_zero_of_n_has_no_derivative():
    """dN/dq = 0 along the trajectory (kappa' = 0, kappa = 0, alpha' = 0 here): no number."""
    flat = SimpleNamespace(alpha=lambda q: 0.0, dalpha=lambda q: 0.0, kappa=lambda q: 0.0, dkappa=lambda q: 0.0,
                           mu=0.1, g=9.81, scale=1.0, Dmu=np.array([1.0]),
                           geometry_dp=lambda what, q: np.zeros((1, 1)))
    iv = SimpleNamespace(q_e=0.3, s=1, G_e=2.0, f_e=0.0, dG_fixed_q_end=lambda: np.array([0.5]))
    assert normal_sign_change_tangent(flat, iv) is None
    flat.kappa, iv.f_e = (lambda q: 1.0), 1.0
    assert normal_sign_change_tangent(flat, iv) is not None


def test_a_tangential_zero_of_n_in_a_run_says_why_for_it_and_after(monkeypatch):
    monkeypatch.setattr(sensitivity, "normal_sign_change_tangent", lambda c, iv: None)
    res = simulate(scene_from_dict(CIRCLE_N))
    sens = sensitivities(res, wrt=("mu",))
    first = [e.kind for e in res.events].index(EventKind.NORMAL_SIGN_CHANGE)
    assert not any(sens.reasons[:first]) and "tangential zero of the normal force" in sens.reasons[first]
    assert all(sens.reasons[first + 1:]) and np.all(np.isnan(sens.t[first:]))


def test_a_user_curve_s_missing_jets_where_nothing_can_make_them_is_a_reason_not_a_crash(tmp_path, monkeypatch):
    from symvib.prepare import prepare

    scene = scene_from_dict(HUMP)
    res, prepared = simulate(scene), prepare(scene)
    monkeypatch.setenv("SYMVIB_CACHE", str(tmp_path))          # an empty cache, and no generator
    monkeypatch.setattr(jet_kernels, "_GENERATOR", [])
    monkeypatch.setattr(jet_kernels, "_LOADED", {})
    sens = sensitivities(res, wrt=("mu",), prepared=prepared)
    assert sens.reasons[0].startswith("the curve's jets (kappa') are not available here")
    assert np.all(np.isnan(sens.t))


AMBIGUOUS = {"curve": {"name": "jets-ambiguous", "z": "right*x**2"}, "parameters": {"right": 0.5},
             "physics": {"mu": 0.1, "restitution": 0.8}, "limiters": {"right": 0.4},
             "initial": {"q": 0.1, "qdot": 1.5}}


def test_a_name_of_both_a_scene_and_a_curve_parameter_is_refused_and_dotted_names_decide():
    scene = scene_from_dict(AMBIGUOUS)
    with pytest.raises(ValueError, match="wrt: 'right' is ambiguous.*parameters.right.*limiters.right"):
        resolve_wrt(scene, ("right",))
    assert resolve_wrt(scene, ("parameters.right", "limiters.right")) == (
        ("parameters.right", "curve", "right"), ("limiters.right", "scene", "right"))
    with pytest.raises(ValueError, match="free: 'right' is ambiguous"):
        symvib.fit(scene, [0.2, 0.5], free=("right",))


def test_unknown_curve_parameter_names_are_refused_naming_wrt():
    res = simulate("paper-parabola")
    with pytest.raises(ValueError, match="wrt: 'R' is not a list of distinct parameters from .*p"):
        sensitivities(res, wrt=("R",))
    with pytest.raises(ValueError, match="distinct"):
        sensitivities(res, wrt=("p", "parameters.p"))


# --- the fit ----------------------------------------------------------------------------------------


def test_the_fit_takes_a_curve_parameter_as_free():
    truth = resolve_scene("paper-parabola").replace(mu=0.03, k=0.8, params={"p": 1.1})
    times = [e.t for e in simulate(truth).events if e.kind is EventKind.IMPACT][:6]
    start = truth.replace(mu=0.04, params={"p": 1.0})
    fit = symvib.fit(start, times, free=("mu", "p"))
    assert fit.status in ("converged", "no_error_estimate"), fit.message
    assert fit.estimates["mu"] == pytest.approx(0.03, rel=1e-6)
    assert fit.estimates["p"] == pytest.approx(1.1, rel=1e-6)
    assert math.isfinite(fit.stderr["p"]) and fit.scene.param_dict["p"] == pytest.approx(1.1, rel=1e-6)
