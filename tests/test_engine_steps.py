"""Each step of the engine's run alone, against the law it applies written out (physics.md, "Events", "Time").

The run (:func:`symvib.numeric.engine.loop.run`) is a loop over named steps on one
:class:`~symvib.numeric.engine.state.RunState`; here each step gets a state made by hand and
its result is held against the formula, not against another run:

* the impact law (physics.md, "Events" 1): ``w -> k^2 w``, the direction flips, ``(1 - k^2) m w / 2``
  lost, ``qdot -> -k qdot``;
* the departure: the branch ``s = sigma sign(N)``, flipped after ``N = 0``, and the time from a
  turning point added;
* a turning point's rest test (2): arrest iff ``|tan alpha| <= mu``, else a reversal down the slope,
  and rest on a limiter that gravity pushes the particle into;
* the time of an interval against a closed form: on the cycloid without friction the motion is
  harmonic in the arc length (the tautochrone), so from the lowest point to the turning point it
  takes ``pi sqrt(R / g)`` whatever the speed;
* the stop at ``t_max`` inside an interval (status ``T_MAX``, ``t = t_max`` exactly).

On the paper's parabola in its tangent angle ``phi`` (``x = p tan phi``, ``z = p tan^2 phi / 2``,
``h = p / cos^3 phi``, ``alpha = phi``), on the plain engine (the compiled one runs the same code).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from symvib.numeric.driver import NODES, rules, scene_row
from symvib.numeric.engine.bind import kernel_functions
from symvib.numeric.engine.loop import (
    after_impact,
    arrive,
    depart,
    finish,
    impact_step,
    interval,
    run,
    run_arrays,
    run_on,
    start,
    stop_at_t_max,
    turning_point,
)
from symvib.numeric.engine.scan import CRIT_STEP, End, map_new, scratch
from symvib.numeric.engine.state import NO_EVENT, Interval, Kernels, RunState
from symvib.numeric.engine.timing import QUAD_OK, WORK_ROWS
from symvib.numeric.kernels import load
from symvib.numeric.layout import EventCode, StatusCode
from symvib.numeric.scene import scene_from_dict

P, G, M = 1.0, 9.81, 0.2
LEFT, RIGHT = -math.pi / 6, math.pi / 4


def parabola(mu=0.05, k=0.8, limiters=True):
    """The paper parabola's kernels, parameters and scene constants (``Setup``)."""
    from symvib.numeric.engine.loop import setup_of

    scene = scene_from_dict({"curve": {"shape": "parabola"}, "parameters": {"p": P},
                             "physics": {"g": G, "m": M, "mu": mu, "restitution": k},
                             **({"limiters": {"left": LEFT, "right": RIGHT}} if limiters else {}),
                             "initial": {"q": 0.0, "qdot": 3.0}})
    K = Kernels(*kernel_functions(load("parabola")))
    cp = (P,)
    return K, cp, setup_of(scene_row(scene), K, cp), scene


def h(phi):
    return P / math.cos(phi) ** 3


def z(phi):
    return P * math.tan(phi) ** 2 / 2


def state(q, w, sigma, **kw):
    """A running state at ``q`` with squared speed ``w`` moving ``sigma`` (the rest as given, else 0)."""
    fields = dict(t=1.0, q=q, w=w, sigma=sigma, side=0, nsign=1, flip=False, impact_next=False, tail_next=0.0,
                  W_friction=0.0, W_impacts=0.0, t_err=0.0, status=StatusCode.RUNNING)
    fields.update(kw)
    return RunState(**fields)


# --- events 1: the impact ---------------------------------------------------------------------------
@pytest.mark.parametrize("k", [0.8, 1.0, 0.3])
def test_the_impact_step_is_newtons_impact_law(k):
    K, cp, S, _ = parabola(k=k)
    w = 3.0
    x = state(RIGHT, w, 1, impact_next=True, W_friction=0.1, W_impacts=0.2, t_err=1e-15)
    after, ev = impact_step(x, S, K, cp)
    assert after.w == k * k * w  # w -> k^2 w
    assert after.sigma == -1 and after.side == 1  # the direction flips; the particle is on the right limiter
    assert not after.impact_next
    assert after.W_impacts == 0.2 + 0.5 * M * (1.0 - k * k) * w  # (1 - k^2) m w / 2 lost
    assert (after.t, after.q, after.W_friction, after.t_err) == (x.t, x.q, x.W_friction, x.t_err)
    assert ev.kind == EventCode.IMPACT and (ev.t, ev.q) == (x.t, RIGHT)
    assert ev.before == pytest.approx(math.sqrt(w) / h(RIGHT), rel=1e-14)  # qdot = sigma sqrt(w) / h
    assert ev.after == -k * ev.before  # qdot -> -k qdot
    assert ev.energy == pytest.approx(M * (0.5 * k * k * w + G * z(RIGHT)), rel=1e-14)


def test_a_plastic_impact_leaves_the_limiter_where_gravity_pulls_away():
    K, cp, S, _ = parabola(k=0.0)
    x, _ = impact_step(state(RIGHT, 3.0, 1, impact_next=True), S, K, cp)
    assert x.w == 0.0
    # tan(pi/4) = 1 > mu, and gravity pulls away from the right limiter, down to phi = 0: it slides back
    x, ev, series, _, _ = after_impact(x, 3.0, S, K, cp)
    assert ev.kind == NO_EVENT and not series
    assert x.sigma == -1 and x.status == StatusCode.RUNNING


def test_a_plastic_impact_where_gravity_pulls_away_is_arrested_by_mu_s_inside_its_cone():
    # tan(pi/4) = 1 > mu = 0.05: with mu_s = 1.01 the particle stays on the limiter, arrested; 0.99 slides
    K, cp, S, _ = parabola(k=0.0)
    for mu_s, arrested in ((1.01, True), (0.99, False)):
        x, _ = impact_step(state(RIGHT, 3.0, 1, impact_next=True), S._replace(mu_s=mu_s), K, cp)
        x, ev, _, _, _ = after_impact(x, 3.0, S._replace(mu_s=mu_s), K, cp)
        assert (ev.kind == EventCode.ARREST) == arrested
        assert x.status == (StatusCode.ARRESTED if arrested else StatusCode.RUNNING)


def test_a_start_at_rest_is_held_by_mu_s():
    K, cp, S, _ = parabola(mu=0.05)
    for mu_s, arrested in ((0.11, True), (0.1, False)):   # tan 0.1 = 0.1003
        x, _, ev = start(S._replace(mu_s=mu_s), K, cp, 0.1, 0.0)
        assert (ev.kind == EventCode.ARREST) == arrested and (x.sigma == 0) == arrested


def test_a_plastic_impact_rests_on_a_limiter_that_gravity_pushes_into():
    K, cp, S, _ = parabola(k=0.0)
    S = S._replace(has_right=True, right=-0.3)  # a right limiter left of the bottom: gravity pushes into it
    x, _ = impact_step(state(-0.3, 2.0, 1, impact_next=True), S, K, cp)
    x, ev, series, _, _ = after_impact(x, 2.0, S, K, cp)
    assert ev.kind == EventCode.REST_ON_LIMITER and not series
    assert x.status == StatusCode.RESTING_ON_LIMITER and x.w == 0.0


def test_bounces_below_the_zeno_threshold_are_summed_as_a_geometric_series():
    K, cp, S, _ = parabola(k=0.5, mu=0.05)
    S = S._replace(has_right=True, right=-0.3)  # gravity pushes into this limiter, from outside the cone
    w = 1e-14  # a bounce far below ZENO_W g h q_scale
    x, _ = impact_step(state(-0.3, w, 1, impact_next=True), S, K, cp)
    x, ev, series, ratio, remaining = after_impact(x, w, S, K, cp)
    # away from the limiter (sin measured that way): a_up = g (sin + mu |cos|), a_down = g (sin - mu |cos|)
    sin, cos = math.sin(0.3), math.cos(0.3)
    a_up, a_down = G * (sin + 0.05 * cos), G * (sin - 0.05 * cos)
    lam = 0.5 * math.sqrt(a_down / a_up)  # k sqrt(a_down / a_up)
    v = 0.5 * math.sqrt(w)  # the speed after the impact, k v
    assert series and ratio == pytest.approx(lam, rel=1e-14)
    assert remaining == pytest.approx(v * (1 / a_up + 1 / math.sqrt(a_up * a_down)) / (1 - lam), rel=1e-13)
    assert ev.kind == EventCode.REST_ON_LIMITER and x.status == StatusCode.RESTING_ON_LIMITER
    assert x.t == 1.0 + remaining and x.w == 0.0
    assert x.W_impacts == pytest.approx(0.5 * M * (1 - 0.25) * w / (1 - lam * lam), rel=1e-13)  # every impact's loss


# --- departure --------------------------------------------------------------------------------------
@pytest.mark.parametrize("sigma", [1, -1])
def test_departure_takes_the_branch_of_the_normal_force_and_the_time_from_a_turning_point(sigma):
    K, cp, S, _ = parabola()
    # the parabola is convex: N = kappa w + g cos alpha > 0, so s = sigma
    x, ev, s = depart(state(0.2, 1.0, sigma, tail_next=1e-9, t_err=0.0), S, K, cp, 10.0)
    assert ev.kind == NO_EVENT and s == sigma and x.nsign == 1
    assert x.t == 1.0 + 1e-9 and x.tail_next == 0.0 and x.t_err == 4.0 * 2.220446049250313e-16 * 1e-9
    # after an interval that ended at N = 0 the branch flips, whatever N's sign here
    x, _, s = depart(state(0.2, 1.0, sigma, flip=True), S, K, cp, 10.0)
    assert x.nsign == -1 and s == -sigma and not x.flip


def test_departure_stops_at_t_max_when_the_time_from_a_turning_point_passes_it():
    K, cp, S, _ = parabola()
    x, _, _ = depart(state(0.2, 1.0, 1, t=1.0, tail_next=0.5), S, K, cp, 1.2)
    assert x.t == 1.2


# --- events 2: the turning point's rest test --------------------------------------------------------
def at_turn(phi, mu, sigma, mu_s=None):
    K, cp, S, _ = parabola(mu=mu)
    if mu_s is not None:
        S = S._replace(mu_s=mu_s)   # the scene's static friction (physics.md, "Events" 2)
    x = state(phi, 0.0, sigma, t=2.0)
    iv = Interval(0.0, phi, 1.0, 0.0, sigma, sigma, End.TURN, 0.5, 0.0, 0.0, QUAD_OK)
    roots, count = np.empty((4, 1)), np.zeros(4, dtype=np.int64)
    return turning_point(x, iv, S, K, cp, roots, count)


@pytest.mark.parametrize("phi, mu_s, held", [(0.3, 0.31, True), (0.3, 0.309, False), (-0.3, 0.31, True),
                                             (0.04, 0.05, True)])
def test_at_a_turning_point_static_friction_mu_s_decides_and_kinetic_mu_does_not(phi, mu_s, held):
    # mu = 0.05 < |tan 0.3| = 0.3093: the sliding cone alone reverses; mu_s decides (0.309 < 0.3093 <= 0.31)
    x, ev = at_turn(phi, 0.05, 1 if phi > 0 else -1, mu_s=mu_s)
    assert (ev.kind == EventCode.ARREST) == held == (abs(math.tan(phi)) <= mu_s)
    assert x.status == (StatusCode.ARRESTED if held else StatusCode.RUNNING)


@pytest.mark.parametrize("phi, mu", [(0.04, 0.05), (-0.04, 0.05), (0.3, 0.31), (0.3, 0.309)])
def test_at_a_turning_point_friction_holds_iff_the_slope_is_inside_the_cone(phi, mu):
    x, ev = at_turn(phi, mu, 1 if phi > 0 else -1)
    held = abs(math.tan(phi)) <= mu  # alpha = phi on the parabola in its tangent angle
    if held:
        assert ev.kind == EventCode.ARREST and x.status == StatusCode.ARRESTED
    else:
        # a reversal: it slides down the slope, towards phi = 0
        assert ev.kind == EventCode.REVERSAL and x.status == StatusCode.RUNNING
        assert x.sigma == (-1 if phi > 0 else 1)
    assert (ev.t, ev.q, x.q, x.w) == (2.0, phi, phi, 0.0)
    assert ev.energy == pytest.approx(M * G * z(phi), rel=1e-14)


def test_arriving_at_a_limiter_makes_an_impact_next_with_w_from_g():
    K, cp, S, _ = parabola(mu=0.05)
    Gb = 2.0
    iv = Interval(0.0, RIGHT, 3.0, Gb, 1, 1, End.LIMIT, 0.25, 0.125, 1e-16, QUAD_OK)
    x, ev = arrive(state(0.0, 3.0, 1, W_friction=0.5), iv, S, K, cp)
    assert ev.kind == NO_EVENT and x.impact_next and x.q == RIGHT
    assert x.w == pytest.approx(Gb * math.exp(-2 * 0.05 * RIGHT), rel=1e-15)  # G = w exp(2 s mu alpha)
    assert (x.t, x.W_friction) == (1.25, 0.5 + M * 0.125)


# --- time: an interval against a closed form --------------------------------------------------------
@pytest.mark.parametrize("v0", [0.1, 0.5, 0.9])
def test_the_time_to_a_turning_point_on_the_frictionless_cycloid_is_the_tautochrones(v0):
    from symvib.numeric.engine.loop import setup_of

    Rc = 0.05
    scene = scene_from_dict({"curve": {"shape": "cycloid"}, "parameters": {"R": Rc},
                             "physics": {"g": G, "m": M, "mu": 0.0, "restitution": 1.0},
                             "initial": {"q": 0.0, "qdot": 1.0}})
    K = Kernels(*kernel_functions(load("cycloid")))
    cp = (Rc,)
    S = setup_of(scene_row(scene), K, cp)
    R = rules(NODES)
    region, roots, count = map_new(0.0, S.lo, S.hi, S.mu, K, cp, CRIT_STEP * S.scale)
    work = scratch(1, WORK_ROWS * max(len(R.Xw), len(R.Xp)))[0]
    x = state(0.0, v0 * v0, 1, t=0.0)  # at the lowest point with speed v0 (w = v^2)
    iv = interval(x, 1, S, K, cp, R, region, roots, count, work, np.empty((1, 4)))
    # s = 4 R sin(phi/2), z = s^2 / (8 R): harmonic with omega^2 = g / (4 R); a quarter period to rest
    assert iv.end == End.TURN
    assert iv.qb == pytest.approx(2 * math.asin(v0 / math.sqrt(G / (4 * Rc)) / (4 * Rc)), rel=1e-12)
    assert iv.T == pytest.approx(math.pi * math.sqrt(Rc / G), rel=1e-12)
    assert iv.W == 0.0 and iv.flag == QUAD_OK and iv.T_err < 1e-12


# --- the stop at t_max ------------------------------------------------------------------------------
def test_the_stop_at_t_max_ends_inside_the_interval_at_t_max():
    K, cp, S, _ = parabola(mu=0.05)
    R = rules(NODES)
    q0, w0 = 0.0, 4.0
    x = state(q0, w0, 1, t=0.0)
    region, roots, count = map_new(q0, S.lo, S.hi, S.mu, K, cp, CRIT_STEP * S.scale)
    work = scratch(1, WORK_ROWS * max(len(R.Xw), len(R.Xp)))[0]
    dummy = np.empty((1, 4))
    iv = interval(x, 1, S, K, cp, R, region, roots, count, work, dummy)
    assert iv.end == End.TURN and iv.T > 0.0  # up the right slope, short of the limiter
    t_max = 0.6 * iv.T
    stopped, part = stop_at_t_max(x, iv, t_max, S, K, cp, R, work, dummy, roots, count)
    assert stopped.status == StatusCode.T_MAX and stopped.t == t_max
    assert q0 < stopped.q < iv.qb and part.qb == stopped.q
    assert part.T == pytest.approx(t_max, rel=1e-12)  # the part before the stop takes t_max
    # and the whole run stops there too (qdot0 = 2 at phi = 0, where h = p = 1: w = 4)
    out = run(S, K, cp, R, q0, 2.0, t_max, 100, False)
    assert out.status == StatusCode.T_MAX and out.t == t_max and out.q == stopped.q


def test_the_start_and_the_finish():
    K, cp, S, _ = parabola(mu=0.05)
    x, E0, ev = start(S, K, cp, 0.04, 0.0)  # at rest inside the cone (tan 0.04 < 0.05): arrested at once
    assert ev.kind == EventCode.ARREST and x.status == StatusCode.ARRESTED
    assert E0 == pytest.approx(M * G * z(0.04), rel=1e-14)
    x, _, ev = start(S, K, cp, 0.1, 0.0)  # at rest outside it: it slides down
    assert ev.kind == NO_EVENT and x.status == StatusCode.RUNNING and x.sigma == -1
    x, E0, ev = start(S, K, cp, RIGHT, 1.0)  # on the right limiter moving into it: an impact next
    assert ev.kind == NO_EVENT and x.impact_next and x.w == pytest.approx(h(RIGHT) ** 2, rel=1e-14)
    done, qdot, E = finish(x._replace(status=StatusCode.MAX_EVENTS, w=0.0), S, K, cp)
    assert done.sigma == 0 and qdot == 0.0 and E == pytest.approx(M * G * z(RIGHT), rel=1e-14)


def test_a_run_in_reused_arrays_is_the_run_in_fresh_ones():
    # A sweep runs its scenes in one set of arrays (run_arrays): whatever an earlier run left there,
    # and however small the logs start (they grow between passes), the run is the same.
    K, cp, S, _ = parabola(mu=0.02, k=0.9)
    R = rules(NODES)
    fresh = run(S, K, cp, R, 0.0, 6.0, 30.0, 200, True)
    assert fresh.n_events > 8 and fresh.n_intervals > 8  # more than the small logs below hold
    A = run_arrays(R, 3, 1)
    run_on(S, K, cp, R, 0.3, -4.0, 5.0, 200, True, A)  # another run leaves its state in A
    A.region[:] = np.nan
    A.work[:] = np.nan
    A.roots[:] = np.linspace(-0.4, 0.6, A.roots.size).reshape(A.roots.shape)  # stale points on the path
    A.count[:] = A.roots.shape[1]
    again = run_on(S, K, cp, R, 0.0, 6.0, 30.0, 200, True, A)
    assert (again.status, again.n_events, again.n_intervals) == (fresh.status, fresh.n_events, fresh.n_intervals)
    assert np.array_equal(again.events[:again.n_events], fresh.events[:fresh.n_events])
    assert np.array_equal(again.intervals[:again.n_intervals], fresh.intervals[:fresh.n_intervals])
    assert (again.t, again.q, again.qdot, again.E_final) == (fresh.t, fresh.q, fresh.qdot, fresh.E_final)


# --- time: the steps of the quadrature --------------------------------------------------------------
def test_a_half_anchored_on_a_turning_point_is_integrated_in_the_square_root_of_the_distance():
    from symvib.numeric.engine.timing import half_anchor

    K, cp, S, _ = parabola(mu=0.05)
    roots, count = np.empty((4, 1)), np.zeros(4, dtype=np.int64)
    qa, qb, half = 0.0, 0.4, 0.2
    # the half from qb, where G = 0 (a turning point), walked back towards qa
    e, d, gd, Ge, root, delta, r_lo, r_hi, Gstart, tau0 = half_anchor(1, qa, qb, 4.0, 0.0, 1, 1, half, S, K, cp,
                                                                      roots, count)
    assert (e, d, Ge, Gstart, tau0) == (qb, -1.0, 0.0, 0.0, 0.0)
    assert gd == 2 * G  # G' = -2 g F_s' d, walking back (d = -1)
    assert root and delta == 0.0 and r_lo == 0.0 and r_hi == math.sqrt(half)
    # the half from qa, where G is far from 0: the plain variable
    e, d, _, Ge, root, delta, r_lo, r_hi, _, _ = half_anchor(0, qa, qb, 4.0, 0.0, 1, 1, half, S, K, cp, roots, count)
    assert (e, d, Ge) == (qa, 1.0, 4.0) and not root and (delta, r_lo, r_hi) == (0.0, 0.0, half)


def test_a_panels_error_and_the_halves_disagreement():
    from symvib.numeric.engine.timing import midpoint_error, panel_error

    # away from a root: the truncation error of T plus dT/dG times that of G is what halving fixes
    tol, fixable, spread = panel_error(0.0, 0.1, 0.0, 0.4, False, 0.5, 2.0, 1e-9, 1e-8, 3.0, 1e-15, 1e-14, 1e-10, 1e-12)
    assert tol == 1e-10 * 2.0 + 1e-12 * 0.25 and fixable == 1e-9 + 3.0 * 1e-8
    assert spread == 3.0 * (1e-14 + 1e-8 + 1e-15)
    # from the root itself G's errors are relative: the time's is half of theirs
    _, fixable, _ = panel_error(0.0, 0.1, 0.0, 0.4, True, 0.5, 2.0, 1e-9, 1e-8, 3.0, 1e-15, 0.0, 1e-10, 1e-12)
    assert fixable == 1e-9 + 0.5 * 2.0 / 0.5 * 1e-8
    # halves that agree at the midpoint add nothing; a disagreement dG costs dT/dG dG
    assert midpoint_error(False, 2.0, 2.0, 1.0, 0.5, 7.0) == 0.0
    assert midpoint_error(False, 2.0 + 1e-12, 2.0, 1.0, 0.5, 7.0) == 7.0 * abs((2.0 + 1e-12) - 2.0)


def test_an_accepted_panel_is_recorded_by_column_name():
    from symvib.numeric.engine.timing import PANEL_COLUMNS, PANELS, PanelColumn, record_panel

    out = np.zeros((2, PANEL_COLUMNS))
    o = record_panel(PANELS, out, 0, 1, 0.25, 0.5, 3.0, -1.0, 0.125, 0.0625, True, 1e-3, 0.0, 0.0, None, None)
    assert o == 1
    row = out[0]
    assert (row[PanelColumn.half], row[PanelColumn.r1], row[PanelColumn.r2]) == (1, 0.25, 0.5)
    assert (row[PanelColumn.G1], row[PanelColumn.G2]) == (3.0, 2.0)
    assert (row[PanelColumn.tau1], row[PanelColumn.tau2]) == (0.125, 0.1875)
    assert (row[PanelColumn.root], row[PanelColumn.delta]) == (1.0, 1e-3)
