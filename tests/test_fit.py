"""Fitting parameters to observed event times (symvib/numeric/fit.py, symvib.fit, symvib fit)."""
import re
import subprocess
import sys
import warnings

import numpy as np
import pytest
from readme_blocks import run_section

import symvib
from symvib.numeric.driver import simulate
from symvib.numeric.fit import fit, observed_events, read_events
from symvib.numeric.scene import resolve_scene, scene_from_dict
from symvib.paths import UserPathError

TRUTH = resolve_scene("paper-parabola").replace(mu=0.03, k=0.8)


def impact_times(scene, n):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        events = simulate(scene, samples=False).events
    return [e.t for e in events if e.kind.value == "impact"][:n]


def test_noise_free_impacts_give_back_mu_and_k_from_a_start_that_makes_fewer_of_them():
    times = impact_times(TRUTH, 6)
    start = TRUTH.replace(mu=0.05, k=0.7)
    assert len(impact_times(start, 6)) < 6          # the start makes fewer impacts than observed
    result = fit(start, observed_events(times, kinds=["impact"] * 6), free=("mu", "k"))
    assert result.status == "converged"
    assert result.estimates["mu"] == pytest.approx(0.03, rel=1e-9)
    assert result.estimates["k"] == pytest.approx(0.8, rel=1e-9)
    assert result.matched == 6 and np.max(np.abs(result.residuals)) < 1e-10


def test_a_scene_with_static_friction_fits_mu_as_without_it():
    # mu_s = 0.06 given (the fit's default bounds keep mu in [0, mu_s]: beyond it the scene is refused);
    # the impacts, which slide, do not see mu_s and give mu back as without it
    truth = TRUTH.replace(mu_s=0.06)
    times = impact_times(truth, 6)
    assert times == impact_times(TRUTH, 6)                  # sliding does not see mu_s
    result = fit(truth.replace(mu=0.055, k=0.7), observed_events(times, kinds=["impact"] * 6), free=("mu", "k"))
    assert result.status == "converged" and result.estimates["mu"] == pytest.approx(0.03, rel=1e-9)


def test_a_fit_at_its_minimum_stops_without_trying_steps_shorter_than_xtol():
    # Near the minimum, a step within xtol that does not lower the cost ends the fit: a larger lambda
    # would only shorten it (before, lambda climbed towards its cap, a forward run per factor 10).
    times = np.array(impact_times(TRUTH, 6)) + np.random.default_rng(3).normal(0.0, 1e-3, 6)
    trials = []

    def run(scene):
        trials.append((scene.mu, scene.k))
        return simulate(scene, samples=False)

    result = fit(TRUTH.replace(mu=0.04, k=0.75), observed_events(times, kinds=["impact"] * 6), free=("mu", "k"),
                 weights=np.full(6, 1e3), run=run)
    assert result.status == "converged", result.message
    best = np.array([result.estimates["mu"], result.estimates["k"]])
    near = [t for t in trials if np.all(np.abs(np.array(t) - best) <= 1e-10 * (np.abs(best) + 1e-10))]
    assert 1 <= len(near) <= 2, near           # the minimum itself, and at most one trial beside it


def test_noisy_impacts_give_estimates_within_their_standard_errors_and_errors_that_match_the_spread():
    # 1 ms of noise on 6 impact times; over 12 noise draws the estimates scatter as their reported
    # standard errors say (within the sampling error of 12 draws) and cover the truth.
    times = np.array(impact_times(TRUTH, 6))
    rng = np.random.default_rng(7)
    estimates, errors = [], []
    for _ in range(12):
        noisy = times + rng.normal(0.0, 1e-3, len(times))
        result = fit(TRUTH.replace(mu=0.04, k=0.75), observed_events(noisy, kinds=["impact"] * 6),
                     free=("mu", "k"), weights=np.full(6, 1e3))
        assert result.status == "converged", result.message
        estimates.append([result.estimates["mu"], result.estimates["k"]])
        errors.append([result.stderr["mu"], result.stderr["k"]])
    estimates, errors = np.array(estimates), np.array(errors)
    spread, reported = estimates.std(axis=0, ddof=1), errors.mean(axis=0)
    assert np.all(spread / reported > 0.5) and np.all(spread / reported < 1.7), (spread, reported)
    assert np.all(np.abs(estimates.mean(axis=0) - [0.03, 0.8]) < 3 * reported / np.sqrt(12) + 1e-12)


def test_two_impacts_fix_mu_and_qdot0_but_say_how_strongly_they_correlate():
    times = impact_times(TRUTH, 2)
    start = TRUTH.replace(mu=0.05, qdot0=6.5)
    result = fit(start, observed_events(times, kinds=["impact"] * 2), free=("mu", "qdot0"))
    assert result.status == "no_error_estimate"      # as many observations as parameters, no sigma
    assert result.estimates["qdot0"] == pytest.approx(7.0, rel=1e-9)
    assert 0.9 < result.correlation[0, 1] < 1.0
    with_sigma = fit(start, observed_events(times, kinds=["impact"] * 2), free=("mu", "qdot0"),
                     weights=[1e3, 1e3])
    assert with_sigma.status == "converged" and with_sigma.stderr["mu"] > 0.1 * with_sigma.estimates["mu"]


def test_a_parameter_the_data_do_not_see_is_named_not_identified():
    # Only the first impact (at the right limiter), time and position: the left limiter plays no part.
    first = simulate(TRUTH, samples=False).events[0]
    observed = observed_events([first.t], kinds=["impact"], q=[first.q])
    result = fit(TRUTH.replace(mu=0.035), observed, free=("mu", "left"))
    assert result.status == "not_identified"
    assert "left" in result.message


@pytest.mark.slow
def test_a_user_curve_s_mu_k_and_qdot0_come_back_from_its_event_times():
    # Impacts, reversals and the arrest (a video gives them all), three free parameters.
    truth = scene_from_dict({"curve": {"name": "fit-quartic", "z": "x**2/2 + x**4/4"},
                             "physics": {"mu": 0.05, "restitution": 0.8},
                             "limiters": {"left": -0.6, "right": 0.5}, "initial": {"q": -0.3, "qdot": 4.0}})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        events = symvib.simulate(truth, samples=False).events
    observed = observed_events([e.t for e in events], kinds=[e.kind.value for e in events])
    result = symvib.fit(truth.replace(mu=0.06, k=0.75, qdot0=3.8), observed, free=("mu", "k", "qdot0"))
    assert result.status == "converged", result.message
    assert result.matched == len(events)
    for name, value in (("mu", 0.05), ("k", 0.8), ("qdot0", 4.0)):
        assert result.estimates[name] == pytest.approx(value, rel=1e-8)


@pytest.mark.parametrize("kwargs, match", [
    ({"t": [0.3, 0.2]}, "observed.t: the times must be ascending"),
    ({"t": [0.1, float("nan")]}, "observed.t: time 2 is not a finite number"),
    ({"t": []}, "observed.t: no event times"),
    ({"t": [0.1, 0.2], "kinds": ["impact", "bounce"]}, "observed.kind: event 2 is 'bounce'"),
    ({"t": [0.1, 0.2], "kinds": ["impact"]}, "observed.kind: 1 kinds for 2 times"),
    ({"t": [0.1, 0.2], "q": [0.1]}, "observed.q"),
])
def test_bad_observations_are_refused_naming_the_field(kwargs, match):
    with pytest.raises(ValueError, match=match):
        observed_events(kwargs["t"], kwargs.get("kinds"), kwargs.get("q"))


def test_bad_fits_are_refused_naming_the_cause():
    one = observed_events([0.17], kinds=["impact"])
    with pytest.raises(ValueError, match="free: 2 parameters from 1 observations"):
        fit(TRUTH, one, free=("mu", "k"))
    with pytest.raises(ValueError, match="free: .* must be distinct names"):
        fit(TRUTH, one, free=("nu",))
    no_limiters = TRUTH.replace(left=None, right=None)
    with pytest.raises(ValueError, match="observed.kind: impacts observed, but the scene has no limiter"):
        fit(no_limiters, observed_events([0.1, 0.2], kinds=["impact"] * 2), free=("mu",))
    with pytest.raises(ValueError, match="weights: one positive finite"):
        fit(TRUTH, observed_events([0.1, 0.2]), free=("mu",), weights=[1.0, -1.0])
    with pytest.raises(ValueError, match="outside the bounds"):
        fit(TRUTH.replace(k=0.8), observed_events([0.1, 0.2]), free=("k",), bounds={"k": (0.9, 1.0)})


def test_an_events_file_is_read_as_data_and_its_errors_name_the_row(tmp_path):
    good = tmp_path / "events.csv"
    good.write_text("t,kind,q\n0.1,impact,0.78\n\n0.4,reversal,-0.2\n", encoding="utf-8")
    observed = read_events(good)
    assert observed.t.tolist() == [0.1, 0.4] and observed.kinds == ("impact", "reversal")
    assert observed.q.tolist() == [0.78, -0.2]
    for text, match in (("time,kind\n0.1,impact\n", "needs a column t"),
                        ("t\n__import__('os').system('true')\n", "row 2, column t: .* is not a number"),
                        ("t,kind\n0.1\n", "row 2 has 1 cells for 2 columns"),
                        ("", "empty")):
        bad = tmp_path / "bad.csv"
        bad.write_text(text, encoding="utf-8")
        with pytest.raises(ValueError, match=match):
            read_events(bad)


def test_symvib_fit_on_the_command_line_prints_the_estimates_and_writes_the_residual_figure(tmp_path):
    times = impact_times(TRUTH, 6)
    data = tmp_path / "impacts.csv"
    data.write_text("t,kind\n" + "".join(f"{t!r},impact\n" for t in times), encoding="utf-8")
    out = subprocess.run([sys.executable, "-m", "symvib.cli", "fit", "paper-parabola", str(data), "--free", "mu,k",
                          "--plot", str(tmp_path / "res.png")], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    assert "mu     = 0.03" in out.stdout and "k      = 0.8" in out.stdout
    assert (tmp_path / "res.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    bad = subprocess.run([sys.executable, "-m", "symvib.cli", "fit", "paper-parabola", str(data), "--free", "mu,nu"],
                         capture_output=True, text=True, timeout=600)
    assert bad.returncode == 2 and "free" in bad.stderr


def test_the_readme_s_fit_example_gives_back_mu_and_k(capsys):
    namespace = run_section("## Fit", "readme_fit")
    assert namespace["fit"].estimates["mu"] == pytest.approx(0.03, rel=1e-9)
    assert "k      = 0.8" in capsys.readouterr().out


@pytest.mark.slow
def test_95_percent_intervals_cover_the_truth_90_to_99_percent_of_the_time():
    # 200 synthetic data sets (6 impact times, 1 ms Gaussian noise, the noise known): the interval
    # estimate +- 1.96 standard errors must contain the true mu and k in 90-99 % of them.
    times = np.array(impact_times(TRUTH, 6))
    rng = np.random.default_rng(2026)
    hits = np.zeros(2)
    runs = 200
    for _ in range(runs):
        noisy = times + rng.normal(0.0, 1e-3, len(times))
        result = fit(TRUTH, observed_events(noisy, kinds=["impact"] * 6),     # (the start does not matter
                     free=("mu", "k"), weights=np.full(6, 1e3))               # here: the interval does)
        assert result.status == "converged", result.message
        for j, (name, true) in enumerate((("mu", 0.03), ("k", 0.8))):
            hits[j] += abs(result.estimates[name] - true) <= 1.96 * result.stderr[name]
    coverage = hits / runs
    assert np.all((coverage >= 0.90) & (coverage <= 0.99)), coverage


OBSERVED = observed_events([0.1, 0.2, 0.3])


@pytest.mark.parametrize("kwargs, match", [
    ({"free": "mu"}, r"free: a sequence of names .* got 'mu'"),
    ({"free": None}, "free: a sequence of names"),
    ({"free": 5}, "free: a sequence of names"),
    ({"free": [1]}, "free: .* must be distinct names"),
    ({"free": ("mu_s",)}, r"free: \('mu_s',\) must be distinct names from mu, k"),   # static friction: not fitted
    ({"free": ("__import__('os')",)}, "free: .* must be distinct names"),
    ({"bounds": {"muu": (0, 1)}}, "bounds: 'muu' is not a parameter"),
    ({"bounds": {"mu": 5}}, r"bounds.mu: a pair \(low, high\) of numbers, got 5"),
    ({"bounds": {"mu": ("a", "b")}}, "bounds.mu: a pair"),
    ({"bounds": {"mu": (1, 2, 3)}}, "bounds.mu: a pair"),
    ({"bounds": {"mu": (1, 0)}}, "bounds.mu: low <= high"),
    ({"bounds": {"mu": (float("nan"), 1)}}, "bounds.mu: low <= high, neither NaN"),
    ({"bounds": [(0, 1)]}, "bounds: a dict of parameter"),
    ({"bounds": {"mu": (-1, 1)}}, r"bounds.mu: \(-1, 1\) reaches beyond the values the scene allows, \[0, inf\]"),
    ({"free": ("k",), "bounds": {"k": (0, 5)}}, r"bounds.k: .* \[0, 1\]"),
    ({"free": ("q0",), "bounds": {"q0": (-10, 10)}}, r"bounds.q0: .* reaches beyond"),
    ({"scene": TRUTH.replace(mu_s=0.04), "bounds": {"mu": (0, 1)}}, r"bounds.mu: .* \[0, 0.04\]"),
    ({"weights": "abc"}, "weights: one positive finite 1/sigma per observation"),
    ({"weights": [1, float("inf"), 1]}, "weights: one positive finite"),
    ({"weights": [1, 1]}, "weights: one positive finite"),
    ({"max_iterations": -1}, "max_iterations: a whole number of at least 1"),
    ({"max_iterations": 0}, "max_iterations: a whole number"),
    ({"max_iterations": "5"}, "max_iterations: a whole number"),
    ({"max_iterations": float("nan")}, "max_iterations: a whole number"),
    ({"max_iterations": True}, "max_iterations: a whole number"),
    ({"xtol": -1}, "xtol: a positive finite number"),
    ({"xtol": float("nan")}, "xtol: a positive finite number"),
    ({"xtol": "1e-3"}, "xtol: a positive finite number"),
    ({"observed": [0.1, 0.2]}, "observed: events .* or samples .* got list"),
    ({"observed": None}, "observed: events"),
    ({"scene": "paper-parabola"}, "scene: a Scene"),
])
def test_hostile_fit_arguments_are_refused_naming_the_argument(kwargs, match):
    args = {"scene": TRUTH, "observed": OBSERVED, "free": ("mu",)} | kwargs
    with pytest.raises(ValueError, match=match):
        fit(args.pop("scene"), args.pop("observed"), **args)


@pytest.mark.parametrize("kinds, match", [
    ("impact", r"observed.kind: one kind per time \(a list such as \['impact'\]\), not a string"),
    ([None], "observed.kind: event 1 is 'none'"),
])
def test_kinds_that_are_not_a_list_of_kinds_are_refused(kinds, match):
    with pytest.raises(ValueError, match=match):
        observed_events([0.1], kinds=kinds)


@pytest.mark.parametrize("args, match", [
    (["--sigma", "nan"], "--sigma: must be a positive number"),
    (["--sigma", "-1"], "--sigma: must be a positive number"),
    (["--sigma", "inf"], "--sigma: must be a positive number"),
    (["--sigma", "abc"], "invalid float value"),
    (["--free", ","], r"free: \(\) must be distinct names"),
    (["--free", "mu,mu"], "free: .* must be distinct names"),
    (["--free", "__import__"], "free: .* must be distinct names"),
    (["--plot", "{data}"], "the --plot file is a PNG figure"),
    (["--plot", "{folder}/"], "is a directory; the --plot file must be a file name"),
    (["--plot", "{folder}/figure"], "the --plot file is a PNG figure"),
    (["--plot", "{folder}/scene.toml"], "the --plot file is a PNG figure"),
    (["--plot", "/dev/null"], "is not a regular file"),
    (["--plot", "{png_data}"], "--plot would overwrite the data file"),
])
def test_hostile_fit_command_lines_are_one_line_errors_before_the_fit(args, match, tmp_path, capsys):
    from symvib.cli import main

    data = tmp_path / "impacts.csv"
    data.write_text("t,kind\n0.3,impact\n0.9,impact\n", encoding="utf-8")
    png_data = tmp_path / "impacts.png"
    png_data.write_text(data.read_text(encoding="utf-8"), encoding="utf-8")
    names = {"data": str(data), "folder": str(tmp_path), "png_data": str(png_data)}
    given = png_data if "{png_data}" in args else data
    args = [a.format(**names) for a in args]
    try:
        code = main(["fit", "paper-parabola", str(given), *args])
    except SystemExit as exc:                                  # argparse's own errors
        code = exc.code
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert code == 2 and "estimates" not in captured.out and "Traceback" not in captured.err
    assert re.search(match, err[-1]), err
    assert png_data.read_text(encoding="utf-8").startswith("t,kind") and not list(tmp_path.glob("*.png"))[1:]


@pytest.mark.parametrize("text, match", [
    ('t,q\n"' + "1" * 200_000 + '",0\n', "row 2: not comma-separated values"),   # csv.Error: was a traceback
    ('t,q\n0.1,"0', "row 2: not comma-separated values"),
    ("\ufefft,kind\r\n0.1,bounce\r\n", "observed.kind: event 1 is 'bounce'"),
    ("t,q\n0.1,nan\n", "row 2, column q: 'nan' is not a finite number"),
])
def test_hostile_data_files_through_the_cli_are_one_line_errors(text, match, tmp_path, capsys):
    from symvib.cli import main

    data = tmp_path / "data.csv"
    data.write_text(text, encoding="utf-8")
    assert main(["fit", "paper-parabola", str(data)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and re.search(match, err) and str(data) in err and len(err) < 1000, err


def test_the_residual_figure_is_never_written_through_a_link(tmp_path):
    result = fit(TRUTH, observed_events(impact_times(TRUTH, 3), kinds=["impact"] * 3), free=("mu",))
    victim = tmp_path / "victim.txt"
    victim.write_text("keep me", encoding="utf-8")
    link = tmp_path / "res.png"
    link.symlink_to(victim)
    with pytest.raises(UserPathError, match="is a symbolic link; symvib never writes through one"):
        result.plot(link)                                    # (was: written through the link)
    assert victim.read_text(encoding="utf-8") == "keep me" and link.is_symlink()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["res.png", "victim.txt"]   # no temporary left
    result.plot(tmp_path / "plain.png")
    assert (tmp_path / "plain.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_an_estimate_held_on_its_bound_says_so():
    # the data come from mu = 0.05, but the scene's static friction mu_s = 0.04 bounds mu (mu <= mu_s)
    obs = observed_events(impact_times(TRUTH.replace(mu=0.05), 5), kinds=["impact"] * 5)
    result = fit(TRUTH.replace(mu=0.03, mu_s=0.04), obs, free=("mu",))
    assert result.estimates["mu"] == 0.04 and "mu = 0.04 is at its bound (high)" in result.message
    free = fit(TRUTH.replace(mu=0.03), obs, free=("mu",))
    assert free.estimates["mu"] == pytest.approx(0.05, rel=1e-8) and "bound" not in free.message


FLYING = {"name": "fit-bounces", "curve": {"shape": "circle"}, "parameters": {"R": 1.0},
          "physics": {"mu": 0.1, "restitution": 0.8, "contact": "unilateral", "restitution_curve": 0.3},
          "initial": {"q": 0.0, "qdot": 7.0}}


def test_lift_off_and_landing_times_fit_a_ball_in_a_bowl():
    # what a microphone hears of a ball in a bowl: it lifts off, lands and bounces (physics.md,
    # "Sensitivities" 10 differentiates them); 1e-5 s of noise
    truth = scene_from_dict(FLYING)
    events = [e for e in simulate(truth, samples=False).events if e.kind.value in ("lift_off", "landing")][:8]
    rng = np.random.default_rng(27)
    obs = observed_events(np.array([e.t for e in events]) + rng.normal(0, 1e-5, len(events)),
                          kinds=[e.kind.value for e in events])
    result = fit(truth.replace(mu=0.12, qdot0=7.1), obs, free=("mu", "qdot0"), weights=np.full(len(events), 1e5))
    assert result.status == "converged", result.message
    for name, value in (("mu", 0.1), ("qdot0", 7.0)):
        assert abs(result.estimates[name] - value) <= 4 * result.stderr[name], (name, result.estimates, result.stderr)


def test_flights_observed_on_a_bilateral_scene_are_refused_naming_the_kind():
    obs = observed_events([0.5, 1.2], kinds=["lift_off", "landing"])
    with pytest.raises(ValueError, match=r"observed.kind: landing and lift_off observed, but the scene's contact is "
                                         r"bilateral .*physics.contact"):
        fit(scene_from_dict({**FLYING, "physics": {"mu": 0.1, "restitution": 0.8}}), obs, free=("mu",))


def test_a_fit_whose_every_trial_run_fails_says_so_instead_of_converged():
    # the numeric fit's own run refuses a user curve's parameter values that were never prepared: every
    # trial step fails, and the fit must not call the start a minimum (it was "converged")
    scene = scene_from_dict({"curve": {"z": "a*(1 - cos(x/b))", "name": "fit-unprepared"},
                             "parameters": {"a": 0.3, "b": 0.2}, "physics": {"mu": 0.05, "restitution": 0.7},
                             "limiters": {"left": -0.3, "right": 0.3}, "initial": {"q": 0.0, "qdot": 4.0}})
    times = [e.t for e in symvib.simulate(scene, samples=False).events if e.kind.value == "impact"][:4]
    assert len(times) >= 2
    result = fit(scene.replace(qdot0=4.2), observed_events(times, kinds=["impact"] * len(times)), free=("qdot0", "a"))
    assert result.status == "runs_failed", result.message
    assert "not prepared" in result.message and result.estimates["qdot0"] == 4.2


def test_a_minimum_far_worse_than_the_weights_allow_is_a_poor_fit_not_converged(monkeypatch):
    # Without the continuation (all 20 impacts at once) this start settles in a local minimum
    # (mu 0.004, k 0.96 for 0.01, 0.95) whose residuals are hundreds of sigmas: it said "converged".
    from symvib.numeric import fit as fitmod

    truth = resolve_scene("paper-parabola").replace(mu=0.01, k=0.95)
    impacts = [e.t for e in simulate(truth, samples=False).events if e.kind.value == "impact"][:20]
    noisy = np.array(impacts) + np.random.default_rng(26).normal(0, 1e-3, 20)
    start = truth.replace(mu=0.012, k=0.9, qdot0=7.5, right=0.75)
    free, w = ("mu", "k", "qdot0", "right"), np.full(20, 1e3)
    good = fit(start, observed_events(noisy, kinds=["impact"] * 20), free, weights=w)
    assert good.status == "converged" and 2 * good.cost / (20 - 4) < fitmod.POOR_FIT
    monkeypatch.setattr(fitmod, "_stages", lambda n_obs, n_free: [n_obs])
    local = fit(start, observed_events(noisy, kinds=["impact"] * 20), free, weights=w)
    assert local.status == "poor_fit" and abs(local.estimates["mu"] - 0.01) > 1e-3
    assert "chi^2 / (m - n) = " in local.message and "another start" in local.message
