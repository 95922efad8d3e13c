"""Samples and figures of a run (issue 16): intervals between events, the exact energy stack,
arc length, density, and every figure labelled, captioned and readable."""
import math
import re

import matplotlib
import mpmath
import numpy as np
import pytest

from symvib import simulate
from symvib.numeric import driver, run_samples
from symvib.numeric.events import EventKind
from symvib.numeric.figures import FIGURE_NAMES, equilibrium_arcs, run_figures
from symvib.numeric.kernels import load
from symvib.numeric.scene import resolve_scene
from symvib.paper.report import HIGH_K, LOW_K, PAPER_FIGURES, SCENES

matplotlib.use("Agg")

#: Every paper scene with k = 1 and k = 0.8.
RUNS = [(name, k) for name, _ in SCENES for k in (HIGH_K, LOW_K)]
#: Relative tolerance of the energy stack (the issue's requirement).
STACK_RTOL = 1e-12


def _run(name, k, **kw):
    return simulate(resolve_scene(name).replace(k=k), backend="python", **kw)


@pytest.fixture(scope="module")
def runs():
    return {(name, k): _run(name, k) for name, k in RUNS}


# --- samples ---------------------------------------------------------------------------------------

@pytest.mark.parametrize("name, k", RUNS)
def test_sample_intervals_equal_the_event_intervals(runs, name, k):
    # Each event of a paper scene ends one motion interval: interval m runs from event m-1
    # (or the start) to event m, and the samples' index says so (circle-7 had 14 for 13 events).
    r = runs[name, k]
    S = r.samples
    ids = np.unique(S.interval)
    assert list(ids) == list(range(len(r.events)))
    starts = [0.0] + [e.t for e in r.events[:-1]]
    for m, e in enumerate(r.events):
        sel = S.interval == m
        assert S.t[sel][0] == pytest.approx(starts[m], rel=1e-12, abs=1e-15)
        assert S.t[sel][-1] == pytest.approx(e.t, rel=1e-12)
        assert S.q[sel][-1] == pytest.approx(e.q, rel=1e-12, abs=1e-15)
        assert (np.diff(S.t[sel]) >= 0).all()


@pytest.mark.parametrize("name, k", RUNS)
def test_energy_stack_equals_E0_at_every_sample(runs, name, k):
    r = runs[name, k]
    S, b = r.samples, r.energy_budget
    stack = S.E + S.W_mu + S.W_impacts
    assert np.max(np.abs(stack - b.initial)) <= STACK_RTOL * b.initial
    # The cumulative columns end on the energy budget's own totals.
    assert S.W_mu[-1] == pytest.approx(b.friction_work, rel=1e-12)
    assert S.W_impacts[-1] == pytest.approx(b.impact_loss, rel=1e-12, abs=1e-15 * b.initial)
    assert (np.diff(S.W_mu) >= -1e-15 * b.initial).all() and (np.diff(S.W_impacts) >= 0).all()


@pytest.mark.parametrize("name", [name for name, _ in SCENES])
def test_an_impact_instant_holds_the_state_before_and_after(runs, name):
    # At an impact the interval that ends has the energy before it and not yet its loss; the
    # next starts with the energy after it (the event's) and the loss counted.
    r = runs[name, LOW_K]
    S = r.samples
    k, m = r.scene.k, r.scene.m
    impacts = [(i, e) for i, e in enumerate(r.events) if e.kind is EventKind.IMPACT]
    assert impacts
    for i, e in impacts:
        before, after = np.flatnonzero(S.interval == i)[-1], np.flatnonzero(S.interval == i + 1)[0]
        assert S.t[before] == S.t[after] or S.t[after] == pytest.approx(S.t[before], rel=1e-15)
        assert S.E[after] == pytest.approx(e.energy, rel=1e-12)
        w_before = S.v[before] ** 2
        assert S.W_impacts[after] - S.W_impacts[before] == pytest.approx(0.5 * m * (1 - k * k) * w_before,
                                                                         rel=1e-12)
        assert S.qdot[after] == pytest.approx(e.qdot_after, rel=1e-12)


def test_arc_length_agrees_with_an_independent_quadrature():
    # s(q) = Integral_{q0}^{q} h du: the circle's closed form R (q - q0), and mpmath's tanh-sinh
    # quadrature of h for the parabola in its tangent angle (h = p / cos^3).
    r = _run("paper-circle-7", HIGH_K)
    R = dict(r.scene.params)["R"]
    assert np.max(np.abs(r.samples.s - R * (r.samples.q - r.scene.q0))) < 1e-12
    r = _run("paper-parabola", LOW_K)
    S, p = r.samples, dict(r.scene.params)["p"]
    for i in np.linspace(0, len(S.t) - 1, 15).astype(int):
        with mpmath.workdps(30):
            ref = mpmath.quad(lambda u: p / mpmath.cos(u) ** 3, [r.scene.q0, S.q[i]])
        assert S.s[i] == pytest.approx(float(ref), abs=1e-12)
    assert (np.diff(S.path) >= 0).all() and S.path[-1] >= np.ptp(S.s)


def test_derived_columns_follow_their_definitions(runs):
    r = runs["paper-circle-7", HIGH_K]
    S, sc = r.samples, r.scene
    mod = load(sc.shape)
    cp = tuple(sc.param_values)
    assert np.allclose(S.x, mod.x(S.q, *cp), rtol=0, atol=1e-15)
    assert np.allclose(S.v, S.qdot * mod.h(S.q, *cp), rtol=1e-13)
    moving = S.v != 0  # at a turning point F_mu is the sliding friction's limit along the interval
    assert np.allclose(S.F_mu[moving], -np.sign(S.v[moving]) * sc.mu * np.abs(S.F_N[moving]), rtol=1e-13)
    assert np.allclose(np.abs(S.F_mu), sc.mu * np.abs(S.F_N), rtol=1e-13, atol=1e-15)
    assert np.allclose(S.P_mu, S.F_mu * S.v, rtol=1e-13, atol=1e-15)


def test_density_is_set_by_samples_per_interval():
    few = _run("paper-circle-3.8", HIGH_K, samples_per_interval=1).samples
    many = _run("paper-circle-3.8", HIGH_K, samples_per_interval=400).samples
    assert np.bincount(many.interval).min() >= 400 > np.bincount(few.interval).max()
    default = _run("paper-circle-3.8", HIGH_K).samples
    assert np.bincount(default.interval).min() >= driver.SAMPLES_PER_INTERVAL


def test_a_long_run_keeps_one_piece_per_interval_by_default(monkeypatch):
    """Samples grow linearly with the events, at fewer per interval past SAMPLE_BUDGET (issue 15:
    100,000 events with samples in seconds); an explicit density is kept."""
    full = _run("paper-circle-7", HIGH_K).samples
    monkeypatch.setattr(run_samples, "SAMPLE_BUDGET", 10)
    thin = _run("paper-circle-7", HIGH_K).samples
    asked = _run("paper-circle-7", HIGH_K, samples_per_interval=driver.SAMPLES_PER_INTERVAL).samples
    per_piece = 2 * driver.plain_nodes(driver.NODES) + 1
    assert np.bincount(thin.interval).max() < driver.SAMPLES_PER_INTERVAL <= np.bincount(full.interval).min()
    assert np.bincount(thin.interval).min() >= per_piece // 2
    assert len(asked.t) == len(full.t)
    assert np.array_equal(np.unique(thin.interval), np.unique(full.interval))


def test_too_many_samples_are_refused_with_the_field_named(monkeypatch):
    monkeypatch.setattr(run_samples, "MAX_SAMPLES", 100)
    result = _run("paper-circle-7", HIGH_K)
    assert result.samples is None
    assert "samples_per_interval" in result.error and "max_events" in result.error
    assert result.success  # the run itself is whole


@pytest.mark.parametrize("bad", [0, -3, 2.5, "many", True, 10**9])
def test_a_bad_samples_per_interval_is_a_clear_error(bad):
    with pytest.raises(ValueError, match="samples_per_interval"):
        _run("paper-circle-3.8", HIGH_K, samples_per_interval=bad)


@pytest.mark.slow  # compiles the sampler for numba
def test_numba_samples_equal_the_plain_ones():
    sc = resolve_scene("paper-circle-7").replace(k=LOW_K)
    a, b = simulate(sc, backend="python").samples, simulate(sc, backend="numba").samples
    for name in a.__dataclass_fields__:
        assert np.allclose(getattr(a, name), getattr(b, name), rtol=1e-12, atol=1e-14), name


@pytest.mark.parametrize("name, factor", [("paper-circle-7", 1.0), ("paper-cycloid", 2.0)])
def test_the_equilibrium_band_is_the_friction_cone(name, factor):
    # circle: alpha = phi, so |phi| <= alpha0; cycloid: alpha = phi / 2, so |phi| <= 2 alpha0.
    r = _run(name, HIGH_K, samples=False)
    (a, b), = equilibrium_arcs(r, -1.0, 1.0)
    edge = factor * math.atan(r.scene.mu)
    assert a == pytest.approx(-edge, rel=1e-12) and b == pytest.approx(edge, rel=1e-12)


def test_the_equilibrium_band_widens_to_the_static_friction_cone():
    # circle: alpha = phi, so the band is |phi| <= atan(mu_s) where static friction exceeds mu.
    scene = resolve_scene("paper-circle-7")
    mu_s = 3 * scene.mu
    r = simulate(scene.replace(mu_s=mu_s), backend="python", samples=True)
    (a, b), = equilibrium_arcs(r, -1.0, 1.0)
    assert a == pytest.approx(-math.atan(mu_s), rel=1e-12) and b == pytest.approx(math.atan(mu_s), rel=1e-12)
    figures = dict((n, (fig, caption)) for n, fig, caption in run_figures(r, only=("phase", "sketch")))
    for name, (fig, caption) in figures.items():
        labels = fig.axes[0].get_legend_handles_labels()[1]
        assert r"relative equilibrium $|\tan\alpha| \leq \mu_s$" in labels, (name, labels)
        assert "$\\mu_s$ = " in fig.axes[0].get_title()
        assert "|tan alpha| <= mu_s (static friction)" in caption, name
    plain = run_figures(_run("paper-circle-7", HIGH_K, samples=True), only=("phase",))[0]
    assert r"relative equilibrium $|\tan\alpha| \leq \mu$" in plain[1].axes[0].get_legend_handles_labels()[1]
    assert "mu_s" not in plain[2] and "mu_s" not in plain[1].axes[0].get_title()



def test_the_force_plan_of_a_start_held_by_mu_s_shows_the_whole_pull():
    # circle at rest at phi0 = 0.3, mu = 0.1 < tan 0.3 <= mu_s = 0.35: arrested at once, so static
    # friction balances the pull m g sin phi0 (with mu alone it could give at most mu F_N)
    from symvib.numeric.figures import _forces_at, _kernels

    scene = resolve_scene("paper-circle-7").replace(mu=0.1, mu_s=0.35, q0=0.3, qdot0=0.0, k=1.0)
    r = simulate(scene, backend="python")
    assert r.status.value == "arrested" and r.t_final == 0.0
    mod, cp = _kernels(r)
    _, _, v, normal, friction, label = _forces_at(r, mod, cp, None)
    assert v == 0.0 and normal == pytest.approx(scene.m * scene.g * math.cos(0.3), rel=1e-14)
    assert friction == pytest.approx(scene.m * scene.g * math.sin(0.3), rel=1e-14) and "static" in label
    assert abs(friction) > scene.mu * abs(normal)


# --- figures --------------------------------------------------------------------------------------

UNIT = re.compile(r"\[[^\]]+\]")


def _check_figure(name, fig, caption):
    ax = fig.axes[0]
    for label in (ax.get_xlabel(), ax.get_ylabel()):
        assert label and UNIT.search(label), f"{name}: axis label {label!r} has no unit in brackets"
    assert ax.get_title(), name
    texts = [t.get_text() for t in fig.texts]
    assert caption and caption in " ".join(t.replace("\n", " ") for t in texts), name
    # The legend lies outside the axes: it covers no data.
    legend = ax.get_legend()
    if legend is not None:
        fig.canvas.draw()
        lb, ab = legend.get_window_extent(), ax.get_window_extent()
        assert lb.x0 >= ab.x1 - 1, f"{name}: the legend overlaps the axes"


@pytest.mark.parametrize("name, k", RUNS)
def test_every_figure_has_units_a_title_and_a_caption(runs, name, k):
    r = runs[name, k]
    refs = PAPER_FIGURES[name]
    figures = run_figures(r, paper=refs)
    assert [n for n, _, _ in figures] == list(FIGURE_NAMES)
    for fig_name, fig, caption in figures:
        _check_figure(fig_name, fig, caption)
        if fig_name in refs:
            assert refs[fig_name] in fig.axes[0].get_title() and refs[fig_name] in caption


def test_figures_read_in_greyscale_and_label_their_limiters(runs):
    r = runs["paper-parabola", HIGH_K]
    figs = dict((n, f) for n, f, _ in run_figures(r, only=("phase", "F_N", "E", "Ep", "energy-time")))
    for name in ("phase", "F_N", "E"):
        ax = figs[name].axes[0]
        styles = {ln.get_label(): ln.get_linestyle() for ln in ax.get_lines() if "branch" in ln.get_label()}
        assert len(set(styles.values())) == 2, f"{name}: branches differ by colour only: {styles}"
        assert {"left limiter", "right limiter"} <= {t.get_text().strip() for t in ax.texts}
    # E(phi) numbers its intervals in time order; Ep has no branch legend.
    numbers = {t.get_text() for t in figs["E"].axes[0].texts}
    assert {str(i) for i in range(1, len(r.events) + 1)} <= numbers
    assert not any("branch" in t.get_text() for t in figs["Ep"].axes[0].get_legend().get_texts())
    # The energy stack's top is E0 (never above it).
    ax = figs["energy-time"].axes[0]
    top = max(p.get_paths()[0].vertices[:, 1].max() for p in ax.collections)
    assert top <= r.energy_budget.initial * (1 + STACK_RTOL)


def test_impacts_at_k1_are_drawn_on_the_limiter_line(runs):
    r = runs["paper-circle-7", HIGH_K]
    (_, fig, _), = run_figures(r, only=("phase",))
    ax = fig.axes[0]
    arrows = [a for a in ax.texts if getattr(a, "arrow_patch", None) is not None]
    impacts = [e for e in r.events if e.kind is EventKind.IMPACT]
    tips = sorted((a.xy[0], a.xy[1]) for a in arrows)
    assert len(arrows) == len(impacts)
    for e in impacts:
        assert (pytest.approx(r.scene.right), pytest.approx(e.qdot_after)) in tips


def test_sketch_and_force_plan_are_drawn_from_the_curve(runs):
    r = runs["paper-circle-7", HIGH_K]
    figs = dict((n, f) for n, f, _ in run_figures(r, only=("sketch", "forces")))
    curve = figs["sketch"].axes[0].get_lines()[0]
    x, z = curve.get_data()
    R = dict(r.scene.params)["R"]
    assert np.allclose(x ** 2 + (z - R) ** 2, R ** 2)  # the circle itself
    labels = " ".join(t.get_text() for t in figs["forces"].axes[0].get_legend().get_texts())
    assert f"{r.scene.m * r.scene.g:.4g} N" in labels and f"{abs(r.samples.F_N[0]):.4g} N" in labels
