"""A run of a scene with air drag, event by event (physics.md, "Air drag", "Events").

:func:`symvib.numeric.driver.simulate` hands a scene with ``physics.drag > 0`` to
:func:`simulate_drag`; a scene without drag never reaches this module, so the
engine (:mod:`symvib.numeric.engine`, plain or compiled) runs as it did.  This
path is NumPy and plain Python only, whatever ``backend`` asked for: drag scenes
run here on every backend (``stats["backend"]`` is ``"python"`` and
``stats["drag"]`` says so), and sweeps refuse them
(:func:`symvib.numeric.driver.sweep_function`).

The laws at events are the engine's own functions
(:mod:`symvib.numeric.engine.laws`: the impact, the rest test with ``mu_s``, the
side of a limiter, the Zeno series); what differs is the phase trajectory,
``w = exp(-Phi) [C - 2 g D]`` by quadrature (:mod:`symvib.numeric.drag_phase`).
An interval from the current state on the branch ``s = sigma sign(N)`` is
searched window by window (:data:`WINDOW` length scales, walked with the motion)
for its first end: ``G = exp(Phi) w`` reaching 0 (a turning point, also inside a
dip of ``G`` between two points, at the friction cone's edge where ``z' + s mu
x'`` changes sign), ``N = kappa w + g cos alpha`` changing sign, a limiter, the
end of the regular domain.  Ends are bracketed and bisected to neighbouring
doubles; then the interval's time, friction work and drag work come from
:func:`symvib.numeric.drag_phase.span`.

A Zeno accumulation at a limiter is summed with the drag-free local model of
physics.md ("Events") once it applies and the drag's share of a bounce,
``gamma`` times the bounce's length, is below :data:`ZENO_DRAG` (the series'
time and losses are then right to that share); until then bounces are simulated
one by one.

Examples
--------
>>> import symvib
>>> scene = symvib.load_scene("paper-circle-7").replace(drag=0.02)
>>> result = simulate_drag(scene)
>>> result.status.value, result.energy_budget.relative_residual < 1e-12
('arrested', True)
"""
from __future__ import annotations

import math
import time
from functools import partial
from typing import NamedTuple

from symvib.numeric.drag_phase import PANEL, DragCurve, panels, span, walk
from symvib.numeric.engine.bind import kernel_functions
from symvib.numeric.engine.laws import (
    SLIDE,
    energy,
    impact,
    nsign_of,
    qdot_of,
    rest,
    rest_outcome,
    side_at,
    zeno_series,
)
from symvib.numeric.engine.scan import EDGE_RTOL, curve_scale
from symvib.numeric.engine.state import Kernels
from symvib.numeric.events import EnergyBudget, Event, Result, ZenoInfo, kind_of, status_of
from symvib.numeric.layout import EventCode, StatusCode
from symvib.numeric.trusted import BUDGET_RTOL

__all__ = ["simulate_drag", "WINDOW", "ZENO_DRAG", "TOLERANCE_FACTOR", "DragInterval", "NO_DENSE"]

#: Length of one search window, in run length scales (8 panels of :data:`~symvib.numeric.drag_phase.PANEL`).
WINDOW = 8 * PANEL
#: Most panels of a search window (where the drag narrows them: 32 e-folds of its factor at most).
WINDOW_PANELS = 64
#: A Zeno series at a limiter is summed (drag-free local model) once the drag's share of the
#: next bounce, ``gamma`` times its length up the slope, is below this.
ZENO_DRAG = 1e-12
#: An interval whose time's estimated error exceeds this many times its tolerance ends the run
#: ``tolerance_not_met`` (as :data:`symvib.numeric.engine.loop.TOLERANCE_FACTOR`).
TOLERANCE_FACTOR = 100.0
#: Why an interval ends.
TURN, LIMIT, NSIGN, DOMAIN = "turn", "limit", "nsign", "domain"
#: What ``stats["drag"]`` says of a drag run.
NOTE = ("air drag: run on the NumPy drag path (symvib.numeric.drag_run) whatever the backend; "
        "the compiled engine has no drag")


class DragInterval(NamedTuple):
    """One motion interval of a drag run: from ``qa`` (squared speed ``wa``) to ``qb`` moving
    ``sigma`` on branch ``s``, ending at a turning point or not, from ``t0`` for ``T``; the
    friction and drag work per unit mass and the impact losses (J) before it."""

    qa: float
    qb: float
    wa: float
    sigma: int
    s: int
    end_root: bool
    t0: float
    T: float
    Wf0: float
    Wd0: float
    Wimp0: float


class _State:
    """The run's mutable state (one run: plain attributes)."""

    def __init__(self, t, q, w, sigma):
        self.t, self.q, self.w, self.sigma = t, q, w, sigma
        self.side, self.nsign, self.flip, self.impact_next = 0, 1, False, False
        self.Wf = self.Wimp = self.Wd = self.t_err = 0.0
        self.status = StatusCode.RUNNING


def simulate_drag(scene, prepared=None, *, rtol: float = 1e-12, atol: float = 0.0, wall_time=None,
                  samples: bool = True) -> Result:
    """Simulate a scene with air drag (``scene.drag > 0``) until arrest, rest, ``t_max`` or
    ``max_events`` (physics.md, "Air drag", "Events"); see the module's description.

    Returns
    -------
    Result
        As :func:`symvib.numeric.driver.simulate`'s, with the drag work in the energy budget
        (``EnergyBudget.drag_work``) and its samples
        (:class:`symvib.numeric.drag_samples.DragSamples`, with ``W_drag``); no dense output yet
        (``Result.dense`` raises :data:`NO_DENSE`; the animation interpolates the samples).
    """
    from symvib.numeric.prepared import prepared_of

    prep = prepared_of(scene) if prepared is None else prepared
    mod = prep.kernels
    cp = tuple(float(v) for v in scene.param_values)
    K = Kernels(*kernel_functions(mod))
    lo, hi = K.domain(*cp)
    scale = curve_scale(K, cp, scene.q0, lo, hi, scene.left is not None, _num(scene.left), scene.right is not None,
                        _num(scene.right), K.q_scale(*cp))
    c = DragCurve.of(mod, cp, g=scene.g, mu=scene.mu, gamma=scene.drag / scene.m, scale=scale)
    run = _Run(scene, K, cp, c, lo, hi, scale, rtol, atol, wall_time)
    run.go()
    x = run.x
    E = energy(x.q, x.w, scene.m, scene.g, K, cp)
    sigma = x.sigma if x.w > 0.0 else 0
    qdot = qdot_of(x.q, x.w, sigma, K, cp) if sigma != 0 else 0.0
    values = (x.t, x.q, qdot, run.E0, E, x.Wf, x.Wimp, x.Wd)
    status = x.status
    if not all(math.isfinite(v) for v in values):
        status = StatusCode.NON_FINITE
    budget = EnergyBudget(run.E0, E, x.Wf, x.Wimp, drag_work=x.Wd)
    if status not in (StatusCode.NON_FINITE, StatusCode.TOLERANCE_NOT_MET) and \
            abs(budget.residual) > BUDGET_RTOL * max(abs(run.E0), abs(E), abs(x.Wf), abs(x.Wimp), abs(x.Wd)):
        status = StatusCode.ENERGY_BUDGET_MISMATCH
    stats = {"intervals": len(run.intervals) if samples else None, "backend": "python", "t_err": x.t_err,
             "domain": (prep.domain.lo, prep.domain.hi), "drag": NOTE}
    if status == StatusCode.TOLERANCE_NOT_MET:
        stats["accuracy"] = (f"error: the time of the motion interval from {scene.shape.q} = {x.q:.12g} to "
                             f"{run.q_bad:.12g} (starting at t = {x.t:.12g} s) could not be brought within its "
                             f"tolerance (rtol {rtol:g}, atol {atol:g} s); the run stopped at its start")
    if status == StatusCode.WALL_TIME_LIMIT:
        stats["stopped"] = (f"the drag path's wall-clock limit of {wall_time:g} s was reached at t = {x.t:.12g} s, "
                            f"after {len(run.events):,} events; those are right, the run is unfinished")
    zinfo = None
    if run.zeno is not None:
        ratio, simulated, remaining, side = run.zeno
        zinfo = ZenoInfo("right" if side > 0 else "left", ratio, simulated, remaining, x.t)
    return Result(scene=scene, status=status_of(status), events=tuple(run.events), energy_budget=budget,
                  t_final=x.t, q_final=x.q, qdot_final=qdot, zeno=zinfo, stats=stats,
                  sampler=partial(_samples, run, scene, mod, cp) if samples else None,
                  interpolant=_no_dense if samples else None)


#: Why a drag run has no dense output.
NO_DENSE = ("the dense output (state at any time) is not computed for a run with air drag yet (its "
            "events, samples and energy budget are; physics.md, \"Air drag\")")


def _samples(run, scene, mod, cp):
    """The sampler of a drag run: ``(samples, None)`` (:func:`symvib.numeric.drag_samples.samples`)."""
    from symvib.numeric.drag_samples import samples

    return samples(run, scene, mod, cp), None


def _no_dense(result):
    """The interpolant of a drag run: a ValueError that says why there is none."""
    raise ValueError(f"dense output: {NO_DENSE}")


def _num(v):
    return 0.0 if v is None else float(v)


class _Run:
    """The event loop of one drag run (physics.md, "Events"), in the engine's order of steps."""

    def __init__(self, scene, K, cp, c, lo, hi, scale, rtol, atol, wall_time):
        self.scene, self.K, self.cp, self.c, self.scale = scene, K, cp, c, scale
        self.rtol, self.atol = rtol, atol
        self.deadline = time.monotonic() + wall_time if wall_time else None
        self.lo = lo + EDGE_RTOL * max(1.0, abs(lo)) if math.isfinite(lo) else -math.inf
        self.hi = hi - EDGE_RTOL * max(1.0, abs(hi)) if math.isfinite(hi) else math.inf
        self.events, self.intervals = [], []
        self.zeno = None
        self.q_bad = math.nan

    # -- events ---------------------------------------------------------------------------------

    def log(self, code, q, before, after, w_after, t=None):
        s, x = self.scene, self.x
        self.events.append(Event(kind_of(int(code)), x.t if t is None else t, q, before, after,
                                 energy(q, w_after, s.m, s.g, self.K, self.cp),
                                 "plastic" if code == EventCode.IMPACT and s.k == 0.0 else "", x.t_err))

    def rest_at(self, q):
        """The rest test at ``q`` (physics.md, "Events" 2); True when the run ends there."""
        s, x = self.scene, self.x
        what, direction = rest(q, x.side, s.mu_static, self.K, self.cp)
        if what != SLIDE:
            code, status = rest_outcome(what)
            self.log(code, q, 0.0, 0.0, 0.0)
            x.status = status
            return True
        x.sigma = direction
        return False

    def go(self):
        s, K, cp = self.scene, self.K, self.cp
        q0, qdot0 = s.q0, s.qdot0
        w = (K.h(q0, *cp) * qdot0) ** 2
        sigma = 0 if qdot0 == 0.0 or w == 0.0 else (1 if qdot0 > 0.0 else -1)
        self.x = x = _State(0.0, q0, w, sigma)
        self.E0 = energy(q0, w, s.m, s.g, K, cp)
        x.side = side_at(q0, s.left is not None, _num(s.left), s.right is not None, _num(s.right))
        x.impact_next = sigma != 0 and x.side == sigma
        if not math.isfinite(self.E0):
            x.status = StatusCode.NON_FINITE
            return
        if s.contact == "unilateral" and K.N_w(q0, w, s.g, *cp) < 0.0:
            self.log(EventCode.LEFT_CURVE, q0, qdot0, qdot0, w)
            x.status = StatusCode.LEFT_CURVE
            return
        if sigma == 0 and self.rest_at(q0):
            return
        while x.status == StatusCode.RUNNING:
            self.step()

    def step(self):
        s, K, cp, x = self.scene, self.K, self.cp, self.x
        if self.deadline is not None and time.monotonic() > self.deadline:
            x.status = StatusCode.WALL_TIME_LIMIT
            return
        if not (math.isfinite(x.t) and math.isfinite(x.w) and math.isfinite(x.q)):
            x.status = StatusCode.NON_FINITE
            return
        if x.impact_next and self.impact():
            return
        if len(self.events) >= s.max_events:
            x.status = StatusCode.MAX_EVENTS
            return
        x.nsign = -x.nsign if x.flip else nsign_of(x.q, x.w, s.g, K, cp)
        x.flip = False
        if s.contact == "unilateral" and x.nsign < 0:
            qd = qdot_of(x.q, x.w, x.sigma, K, cp)
            self.log(EventCode.LEFT_CURVE, x.q, qd, qd, x.w)
            x.status = StatusCode.LEFT_CURVE
            return
        branch = x.sigma * x.nsign
        end, qe = self.locate(branch)
        T, Wf, Wd, w_end, err, ok = span(self.c, x.q, qe, x.sigma, branch, x.w, end == TURN, self.rtol)
        if not ok or err > TOLERANCE_FACTOR * (self.rtol * (x.t + T) + self.atol):
            x.status = StatusCode.TOLERANCE_NOT_MET
            self.q_bad = qe
            return
        if x.t + T > s.t_max:
            self.stop_at_t_max(branch, qe, end == TURN, T)
            return
        self.intervals.append(DragInterval(x.q, qe, x.w, x.sigma, branch, end == TURN, x.t, T, x.Wf / s.m,
                                           x.Wd / s.m, x.Wimp))
        x.t += T
        x.t_err += err
        x.Wf += s.m * Wf
        x.Wd += s.m * Wd
        x.q, x.w = qe, w_end
        if end == LIMIT:
            x.impact_next = True
        elif end == NSIGN:
            qd = qdot_of(qe, w_end, x.sigma, K, cp)
            if s.contact == "unilateral":
                self.log(EventCode.LEFT_CURVE, qe, qd, qd, w_end)
                x.status = StatusCode.LEFT_CURVE
            else:
                self.log(EventCode.NORMAL_SIGN_CHANGE, qe, qd, qd, w_end)
                x.flip = True
        elif end == DOMAIN:
            x.status = StatusCode.LEFT_DOMAIN
        else:   # a turning point: the rest test, else a reversal
            x.w = 0.0
            x.side = side_at(qe, s.left is not None, _num(s.left), s.right is not None, _num(s.right))
            what, direction = rest(qe, x.side, s.mu_static, K, cp)
            if what != SLIDE:
                code, status = rest_outcome(what)
                self.log(code, qe, 0.0, 0.0, 0.0)
                x.status = status
            else:
                self.log(EventCode.REVERSAL, qe, 0.0, 0.0, 0.0)
                x.sigma = direction

    def impact(self):
        """The impact at the limiter ``x.q`` (physics.md, "Events" 1), then a plastic impact's rest
        test or a Zeno series; True when the run ends there."""
        s, K, cp, x = self.scene, self.K, self.cp, self.x
        w_before = x.w
        qd = qdot_of(x.q, x.w, x.sigma, K, cp)
        qd_after, w_after, loss = impact(qd, x.w, s.k, s.m)
        x.w = w_after
        x.Wimp += loss
        self.log(EventCode.IMPACT, x.q, qd, qd_after, w_after)
        x.side, x.sigma, x.impact_next = x.sigma, -x.sigma, False
        if x.w == 0.0:
            return self.rest_at(x.q)
        applies, ratio, remaining, w_imp, w_fric = zeno_series(x.q, w_before, x.sigma, s.g, s.mu, s.k, s.m,
                                                               self.scale, K, cp)
        if not applies or self.c.gamma * self.bounce_length(w_after) > ZENO_DRAG:
            return False
        simulated = sum(1 for _ in self._impacts_at(x.q))
        x.t += remaining
        x.t_err += 4.0 * 2.220446049250313e-16 * remaining
        x.Wimp += w_imp
        x.Wf += w_fric
        x.w = 0.0
        self.log(EventCode.REST_ON_LIMITER, x.q, 0.0, 0.0, 0.0)
        self.events[-1] = self.events[-1]._replace(
            detail=f"Zeno accumulation: geometric series of bounces, ratio {ratio:.9g} (drag-free local model)")
        self.zeno = (ratio, simulated, remaining, x.side)
        x.status = StatusCode.RESTING_ON_LIMITER
        return True

    def bounce_length(self, w_after):
        """The arc length a bounce leaving the limiter with squared speed ``w_after`` climbs:
        ``w / (2 a_up)``, ``a_up = g (sin + mu |cos|)`` away from the limiter."""
        K, cp, x, s = self.K, self.cp, self.x, self.scene
        hh = K.h(x.q, *cp)
        a_up = s.g * (x.sigma * K.dz(x.q, *cp) / hh + s.mu * abs(K.dx(x.q, *cp) / hh))
        return w_after / (2.0 * a_up) if a_up > 0.0 else math.inf

    def _impacts_at(self, q):
        for e in reversed(self.events):
            if e.kind.code == EventCode.IMPACT and e.q == q:
                yield e
            elif e.kind.code != EventCode.REVERSAL:
                return

    def stop_at_t_max(self, branch, qe, end_root, T):
        """The state where ``t`` reaches ``t_max`` inside the interval to ``qe`` (status ``T_MAX``)."""
        s, x = self.scene, self.x
        target = s.t_max - x.t
        a, b = x.q, qe
        for _ in range(200):
            mid = a + 0.5 * (b - a)
            if mid == a or mid == b:
                break
            if span(self.c, x.q, mid, x.sigma, branch, x.w, False, self.rtol)[0] < target:
                a = mid
            else:
                b = mid
        Tq, Wf, Wd, w_end, err, _ = span(self.c, x.q, a, x.sigma, branch, x.w, False, self.rtol)
        self.intervals.append(DragInterval(x.q, a, x.w, x.sigma, branch, False, x.t, Tq, x.Wf / s.m, x.Wd / s.m,
                                           x.Wimp))
        x.t = s.t_max
        x.t_err += err
        x.Wf += s.m * Wf
        x.Wd += s.m * Wd
        x.q, x.w = a, max(w_end, 0.0)
        x.status = StatusCode.T_MAX

    # -- the search for an interval's end ---------------------------------------------------------

    def barrier(self):
        """``(q, kind)`` of the first limiter or domain end in the direction of motion."""
        s, x = self.scene, self.x
        if x.sigma > 0:
            if s.right is not None and s.right > x.q:
                return float(s.right), LIMIT
            return self.hi, DOMAIN
        if s.left is not None and s.left < x.q:
            return float(s.left), LIMIT
        return self.lo, DOMAIN

    def locate(self, branch):
        """``(end, q_end)`` of the interval from the current state on ``branch`` (the module's search)."""
        x, c = self.x, self.c
        sigma = x.sigma
        stop, kind = self.barrier()
        q0, w0 = x.q, x.w
        while True:
            room = abs(stop - q0)
            length = min(WINDOW * self.scale, room, WINDOW_PANELS * c.panel(q0))
            if not length > 0.0:
                return kind, q0
            last = length == room
            root = w0 == 0.0
            wk = walk(c, q0, sigma, length, sigma, branch, w0, panels(c, q0, length), root)
            found = self.first_end(wk, q0, w0, branch)
            if found is not None:
                return found
            if last:
                return kind, stop
            q0, w0 = q0 + sigma * length, float(wk.w[-1])

    def first_end(self, wk, q0, w0, branch):
        """The first end inside a window (a turning point or a sign change of ``N``), or None."""
        x, K, cp, mu = self.x, self.K, self.cp, self.scene.mu
        qs = wk.q
        G, N, f = wk.G, wk.N, wk.f
        prev_q, prev_w = q0, w0
        if w0 > 0.0 and f[0] < 0.0 < x.sigma * (K.dz(q0, *cp) + branch * mu * K.dx(q0, *cp)):
            qc = self.edge(q0, qs[0], branch)   # a minimum of G before the window's first node
            if self.w_at(q0, w0, qc, branch) <= 0.0:
                return TURN, self.root(q0, w0, qc, branch, "G")
        for i in range(len(qs)):
            if G[i] <= 0.0:
                return TURN, self.root(prev_q, prev_w, qs[i], branch, "G")
            if N[i] != 0.0 and (N[i] > 0.0) != (x.nsign > 0):
                return NSIGN, self.root(prev_q, prev_w, qs[i], branch, "N")
            if i + 1 < len(qs) and f[i] > 0.0 and f[i + 1] < 0.0:
                # G has a minimum between two points (the friction cone's edge): its value there decides.
                qc = self.edge(qs[i], qs[i + 1], branch)
                wc = self.w_at(prev_q, prev_w, qc, branch)
                if wc <= 0.0:
                    return TURN, self.root(prev_q, prev_w, qc, branch, "G")
            prev_q, prev_w = qs[i], float(wk.w[i])
        return None

    def probe(self, qa, wa, q, branch):
        """The walk from ``(qa, wa)`` to ``q`` in one panel (``wa = 0``: from a turning point)."""
        x = self.x
        return walk(self.c, qa, x.sigma, abs(q - qa), x.sigma, branch, wa, 1, wa == 0.0)

    def w_at(self, qa, wa, q, branch):
        return float(self.probe(qa, wa, q, branch).w[-1]) if q != qa else wa

    def root(self, qa, wa, qb, branch, what):
        """The last double before ``qb`` (from ``qa``, where ``w = wa``) on which ``G > 0`` (``what =
        "G"``) or ``N`` keeps its sign (``"N"``): bisection to neighbouring doubles."""
        x = self.x

        def inside(q):
            if what == "G":
                return self.w_at(qa, wa, q, branch) > 0.0
            n = float(self.probe(qa, wa, q, branch).N[-1]) if q != qa else 1.0 * x.nsign
            return n != 0.0 and (n > 0.0) == (x.nsign > 0)

        a, b = qa, qb
        while True:
            mid = a + 0.5 * (b - a)
            if mid == a or mid == b:
                return a if what == "G" or a != qa else b
            if inside(mid):
                a = mid
            else:
                b = mid

    def edge(self, a, b, branch):
        """Where ``sigma (z' + s mu x')`` changes sign from + to - between ``a`` and ``b``."""
        K, cp, x, mu = self.K, self.cp, self.x, self.scene.mu

        def f(q):
            return x.sigma * (K.dz(q, *cp) + branch * mu * K.dx(q, *cp))

        while True:
            mid = a + 0.5 * (b - a)
            if mid == a or mid == b:
                return a
            if f(mid) > 0.0:
                a = mid
            else:
                b = mid
