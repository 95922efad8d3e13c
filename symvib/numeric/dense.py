"""Dense output of a run: the state at any time, exact from the phase trajectory (paper eq. 2).

On a motion interval the branch ``s`` and the direction ``sigma`` are fixed, and
(physics.md, eq. 2)

    qdot^2 = w(q) / h(q)^2,   w = exp(-2 s mu alpha) G(q),   G(q) = C - 2 g F_s(q),

with ``C`` fixed by the interval's start state (the run's interval log keeps
``G`` at both ends of every interval).  The time to reach ``q`` is the
quadrature ``t(q) = t0 + Integral h dq / sqrt(w) = t0 + Integral h exp(s mu alpha) dq / sqrt(G)``
(physics.md, "Time"), and ``q(t)`` is its inverse.  Both are computed as the
engine computes an interval's duration (:func:`symvib.numeric.engine.timing.quad`),
on the very panels it took (the plain engine's ``quad`` run once more per interval,
recording them): the interval is split at its midpoint and each half is anchored
at its outer end, where ``G`` is known exactly; ``G`` at the Gauss nodes is rebuilt
from the anchor by integrating ``G' = -2 g F_s'``, so it keeps its relative
accuracy next to a turning point; near a (real or virtual) root the variable
``r = sqrt(xi)``, ``xi`` the distance from that root, removes the inverse square
root, on panels graded geometrically from the root and refined where the error
estimate asked for it.  :class:`DenseOutput` keeps, per half, the panel edges
with ``G`` and the time at each; a query integrates one partial panel, and
``q(t)`` is found by a safeguarded Newton iteration in ``r`` (where the time is a
smooth function, nearly linear).  No time stepping is involved, so
the state at any time is as accurate as the events (about 1e-14).

The state is right-continuous: at an impact it is the state after it.  Past the
end of a run that came to rest (status ``arrested``, ``resting_on_limiter``) it
is the rest state; during a Zeno accumulation summed as a series (physics.md,
"Events" 3) it is the limiter with ``qdot = 0`` (the bounces there are below
``ZENO_W`` in ``w``: within about 1e-10 of the curve's length scale in ``q``).

Examples
--------
>>> from symvib.numeric.driver import simulate
>>> from symvib.numeric.scene import resolve_scene
>>> result = simulate(resolve_scene("paper-parabola"), backend="python")
>>> e = result.events[2]
>>> q, qdot = result.state(e.t)                  # the state just after the third impact
>>> bool(abs(q - e.q) < 1e-12 and abs(qdot - e.qdot_after) < 1e-12)
True
>>> t, qdot = result.at(0.3, interval=0)         # when and how fast it passes q = 0.3
>>> bool(abs(result.state(t)[0] - 0.3) < 1e-12)
True
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from symvib.numeric.engine.timing import PANEL_COLUMNS, PANELS, TINY, WORK_ROWS, PanelColumn
from symvib.numeric.layout import IntervalColumn
from symvib.numeric.quadrature import rule
from symvib.numeric.scenerow import scene_row

__all__ = ["DenseOutput", "checked_times", "NEWTON_MAXITER", "NEWTON_RTOL"]

#: Most iterations of the Newton solve of ``t(q) = t`` (it converges in about 5).
NEWTON_MAXITER = 60
#: Relative step in ``r`` at which the Newton solve stops.
NEWTON_RTOL = 4.0 * np.finfo(float).eps
#: The two halves of an interval: anchored at its start and at its end.
START, END = 0, 1


def checked_times(t, t_min: float, t_max: float, status: str) -> tuple:
    """``(times, flat)``: ``t`` as an array and flattened, once every time is finite and in ``[t_min,
    t_max]`` (else a ValueError naming ``t``, the span and the run's ``status``)."""
    times = np.asarray(t, dtype=float)
    flat = times.reshape(-1)
    outside = ~np.isfinite(flat) | (flat < t_min) | (flat > t_max)
    if outside.any():
        raise ValueError(f"t: the state is defined on [{t_min:g}, {t_max:g}] s (status {status}), "
                         f"got {flat[outside][0]!r}")
    return times, flat


@dataclass(frozen=True)
class _Half:
    """One half of a motion interval, anchored at ``e`` (where ``G = Ge``), entered in direction ``d``.

    ``r`` holds the panel edges in the quadrature variable (``xi = r^2 - delta``
    next to a root, ``xi = r`` otherwise; ``xi`` is the distance from ``e``),
    ``G`` and ``tau`` the value of ``G`` and the time from ``e`` at each edge.
    The first panel uses the weighted rule when it starts on the root itself.
    """

    e: float
    d: float
    s: int
    root: bool
    delta: float
    weighted: bool
    r: np.ndarray
    G: np.ndarray
    tau: np.ndarray


class DenseOutput:
    """The state of a run at any time (``state``, ``__call__``) and at any position (``at``).

    Built by :attr:`symvib.numeric.events.Result.dense` from the run's interval
    log; like ``solve_ivp``'s ``sol`` (an ``OdeSolution``), calling it returns
    ``[q, qdot]`` with shape ``(2,)`` for one time and ``(2, n)`` for ``n``.

    Parameters
    ----------
    result : Result
        The run (its scene, status and final state).
    kernels : module
        The curve's generated kernel module (vectorized ``node_p``, ``node_m``).
    params : tuple of float
        The curve's parameter values.
    intervals : ndarray
        The run's interval log (columns :class:`symvib.numeric.layout.IntervalColumn`).
    rules : Rules
        The rules and tolerances the run used (:func:`symvib.numeric.driver.rules`).
    """

    def __init__(self, result, kernels, params, intervals, rules):
        self.result = result
        self._K = kernels
        self._cp = tuple(float(v) for v in params)
        scene = result.scene
        self._g, self._mu = float(scene.g), float(scene.mu)
        ivs = np.array(intervals, dtype=float).reshape(-1, len(IntervalColumn))
        ivs.setflags(write=False)
        self._ivs = ivs
        self._t0 = ivs[:, IntervalColumn.t0]
        self._t1 = self._t0 + ivs[:, IntervalColumn.T]
        self._weighted_rule, self._plain_rule = rule(len(rules.Xw)), rule(len(rules.Xp))
        self._R = rules
        self._engine = None
        self._halves: dict = {}
        self._tails: dict = {}
        #: Time span where the state is defined (as ``OdeSolution``'s ``t_min``, ``t_max``);
        #: ``t_max`` is infinite for a run that came to rest.
        self.t_min = 0.0
        self.t_max = math.inf if result.status.value in _RESTING else float(result.t_final)

    @property
    def n_intervals(self) -> int:
        """Number of motion intervals (``interval`` of :meth:`at` runs over ``range(n_intervals)``)."""
        return len(self._ivs)

    @property
    def intervals(self) -> dict:
        """The motion intervals as columns: ``t_start``, ``t_end``, ``q_start``, ``q_end``,
        ``branch`` (``s = sigma sign(N)``) and ``direction`` (``sigma``)."""
        ivs = self._ivs
        return {"t_start": self._t0.copy(), "t_end": self._t1.copy(), "q_start": ivs[:, IntervalColumn.qa].copy(),
                "q_end": ivs[:, IntervalColumn.qb].copy(), "branch": ivs[:, IntervalColumn.s].astype(np.int64),
                "direction": ivs[:, IntervalColumn.sigma].astype(np.int64)}

    def __call__(self, t) -> np.ndarray:
        """``[q, qdot]`` at ``t``: shape ``(2,)`` for a number, ``(2, n)`` for ``n`` times."""
        q, qdot = self.state(t)
        return np.array([q, qdot], dtype=float)

    def state(self, t):
        """``(q, qdot)`` at time(s) ``t`` (a number or an array; the results have its shape).

        Raises
        ------
        ValueError
            Naming ``t`` when a time is not finite or outside ``[t_min, t_max]``.
        """
        times, flat = checked_times(t, self.t_min, self.t_max, self.result.status.value)
        q = np.full(flat.shape, float(self.result.q_final))
        qdot = np.full(flat.shape, float(self.result.qdot_final))
        inside = flat < float(self.result.t_final)
        i = np.searchsorted(self._t0, flat, side="right") - 1
        zeno = inside & ((i < 0) | (flat > self._t1[np.maximum(i, 0)]))
        # Between intervals: at rest where the last one ended (the summed bounces at the limiter,
        # or the fraction of an ulp between a turning point and the double the next starts on).
        qdot[zeno] = 0.0
        gap = zeno & (i >= 0)
        q[gap] = self._ivs[i[gap], IntervalColumn.qb]
        run = np.flatnonzero(inside & ~zeno)
        if run.size:
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
                q[run], qdot[run] = self._state_on(i[run], flat[run])
        if times.ndim == 0:
            return float(q[0]), float(qdot[0])
        return q.reshape(times.shape), qdot.reshape(times.shape)

    def at(self, q, interval=None):
        """``(t, qdot)`` where the particle is at position(s) ``q``.

        Parameters
        ----------
        q : float or array_like
        interval : int, optional
            The motion interval (``0 <= interval < n_intervals``, numbered as the
            samples' ``interval`` column); by default the first interval that
            reaches ``q`` (its first passage).

        Returns
        -------
        t, qdot : float or ndarray
            NaN where ``q`` is not on the interval (or never reached).
        """
        qs = np.asarray(q, dtype=float)
        flat = qs.reshape(-1)
        ivs = self._ivs
        lo = np.minimum(ivs[:, IntervalColumn.qa], ivs[:, IntervalColumn.qb])
        hi = np.maximum(ivs[:, IntervalColumn.qa], ivs[:, IntervalColumn.qb])
        if interval is None:  # the first interval whose span holds each q
            which = np.full(flat.shape, -1, dtype=np.int64)
            order = np.argsort(flat, kind="stable")
            ordered = flat[order]
            starts, ends = np.searchsorted(ordered, lo, "left"), np.searchsorted(ordered, hi, "right")
            left = int(np.isfinite(flat).sum())
            for j in range(len(ivs)):
                if left == 0:
                    break
                span = order[starts[j]:ends[j]]
                free = span[which[span] < 0]
                which[free] = j
                left -= len(free)
        else:
            if isinstance(interval, bool) or not isinstance(interval, (int, np.integer)) or \
                    not 0 <= interval < len(ivs):
                raise ValueError(f"interval: must be an integer in [0, {len(ivs)}) (the run's motion intervals), "
                                 f"got {interval!r}")
            which = np.where((flat >= lo[interval]) & (flat <= hi[interval]), int(interval), -1)
        t = np.full(flat.shape, np.nan)
        qdot = np.full(flat.shape, np.nan)
        found = np.flatnonzero(which >= 0)
        if found.size:
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
                t[found], qdot[found] = self._position_on(which[found], flat[found])
        if qs.ndim == 0:
            return float(t[0]), float(qdot[0])
        return t.reshape(qs.shape), qdot.reshape(qs.shape)

    # -- the quadrature ---------------------------------------------------------------------------

    def _node(self, s, q):
        """``(F_s', h, exp(s mu alpha))`` at ``q`` (an array), ``s`` per element."""
        s = np.broadcast_to(s, q.shape)
        out = [np.empty(q.shape) for _ in range(3)]
        pos = s > 0
        for mask, fn in ((pos, self._K.node_p), (~pos, self._K.node_m)):
            if mask.any():
                values = fn(q[mask], self._mu, *self._cp)
                for o, v in zip(out, values[:3]):
                    o[mask] = v
        return out

    def _panels(self, rl, r1, r2, start, e, d, s, delta, root, weighted):
        """Integrate ``m`` panels ``[r1, r2]`` (arrays of one length, one row each) with rule ``rl``.

        Returns ``G`` at ``r2``, the time over each panel, and ``h``, ``exp(s mu alpha)``
        and ``dq/dr`` at ``r2`` (for the derivative of the time and the state there).
        """
        hw = 0.5 * (r2 - r1)
        r = np.concatenate((r1[:, None] + hw[:, None] * (rl.x + 1.0), r2[:, None]), axis=1)
        rootc = root[:, None]
        xi = np.where(rootc, r * r - delta[:, None], r)
        dq = np.where(rootc, 2.0 * r, 1.0)
        qn = e[:, None] + d[:, None] * xi
        dF, h, ex = self._node(s[:, None], qn)
        gam = -2.0 * self._g * d[:, None] * dF
        dGdr = gam * dq
        n = rl.n
        if weighted:
            Gn = start[:, None] + (gam[:, :n] @ rl.cumulative_weighted.T) * (2.0 * hw * hw)[:, None]
        else:
            Gn = start[:, None] + (dGdr[:, :n] @ rl.cumulative.T) * hw[:, None]
        G_end = start + hw * (dGdr[:, :n] @ rl.weights)
        f = h[:, :n] * dq[:, :n] * ex[:, :n] / np.sqrt(np.maximum(Gn, TINY))
        time = hw * (f @ rl.weights)
        return G_end, time, h[:, n], ex[:, n], dq[:, n]

    def _half(self, i: int, side: int) -> _Half:
        """The panels of half ``side`` of interval ``i``: those the engine's ``quad`` took (built once)."""
        key = (i, side)
        half = self._halves.get(key)
        if half is None:
            for sd, h in enumerate(self._skeleton(i)):
                self._halves[(i, sd)] = h
            half = self._halves[key]
        return half

    def _skeleton(self, i: int) -> tuple:
        """Both halves of interval ``i`` as :func:`symvib.numeric.engine.timing.quad` integrated them:
        the plain engine's ``quad`` once more, in its mode that records the panels it accepts
        (so the state at an event's time is the event's state to rounding)."""
        if self._engine is None:
            from symvib.numeric.engine.bind import kernel_functions
            from symvib.numeric.engine.plain import plain_functions, plain_rules
            from symvib.numeric.engine.state import Kernels

            fns = plain_functions()
            K = Kernels(*kernel_functions(self._K))
            setup = fns["setup_of"](scene_row(self.result.scene), K, self._cp)
            self._engine = (fns, K, setup, plain_rules(self._R))
        fns, K, S, R = self._engine
        qa, qb, Ga, Gb, s, sigma = (float(v) for v in self._ivs[i, :IntervalColumn.t0])
        s, sigma = int(s), int(sigma)
        # The critical points the run knew there (for F_s' next to the cone edge).
        region, roots, count = fns["map_new"](qa, S.lo, S.hi, S.mu, K, self._cp, fns["CRIT_STEP"] * S.scale)
        fns["map_extend"](region, roots, count, qb, S.mu, K, self._cp, fns["CRIT_STEP"] * S.scale)
        while not fns["room"](roots, count):  # the scan stopped on a full row: grow it, scan on
            roots = fns["grown_roots"](roots, count)
            fns["map_extend"](region, roots, count, qb, S.mu, K, self._cp, fns["CRIT_STEP"] * S.scale)
        n = max(len(R.Xw), len(R.Xp))
        out = np.zeros((2 * fns["MAX_PANELS"] + 2, PANEL_COLUMNS))
        rows = fns["quad"](qa, qb, Ga, Gb, s, sigma, S, K, self._cp, R, fns["scratch"](1, WORK_ROWS * n)[0], PANELS,
                           out, 0, roots, count)[4]
        panels = out[:rows]
        halves = []
        for side, (e, d, Ge) in enumerate(((qa, float(sigma), Ga), (qb, -float(sigma), Gb))):
            p = panels[panels[:, PanelColumn.half] == side]
            if len(p):
                root, delta = bool(p[0, PanelColumn.root]), float(p[0, PanelColumn.delta])
                r = np.append(p[:, PanelColumn.r1], p[-1, PanelColumn.r2])
                G = np.append(p[:, PanelColumn.G1], p[-1, PanelColumn.G2])
                tau = np.append(p[:, PanelColumn.tau1], p[-1, PanelColumn.tau2])
            else:  # an empty interval
                root, delta = False, 0.0
                r, G, tau = np.zeros(1), np.full(1, Ge), np.zeros(1)
            halves.append(_Half(e, d, s, root, delta, root and len(r) > 1 and r[0] == 0.0, r, G, tau))
        # A turning point is stopped at on the last double before it, and the interval's time
        # carries the stretch from there to the root (timing.tail_time): what the panels miss.
        self._tails[i] = max(float(self._ivs[i, IntervalColumn.T]) - halves[0].tau[-1] - halves[1].tau[-1], 0.0)
        return tuple(halves)

    def _tail(self, i) -> np.ndarray:
        """Per interval of ``i``: the time between its end anchor and its end (a turning point's last ulp)."""
        for ii in set(i.tolist()):
            self._half(ii, END)
        return np.array([self._tails[ii] for ii in i.tolist()])

    def _gather(self, i, side, x, by):
        """Per-query arrays of the panel where each query lies: ``x`` is the time from the
        anchor (``by="tau"``) or ``r`` (``by="r"``) on half ``side`` of interval ``i``."""
        n = len(i)
        out = {name: np.zeros(n) for name in ("e", "d", "s", "delta", "r1", "r2", "G1", "tau1", "tau2")}
        root, weighted, empty = np.zeros(n, dtype=bool), np.zeros(n, dtype=bool), np.zeros(n, dtype=bool)
        key = 2 * i + side
        order = np.argsort(key, kind="stable")
        keys, starts = np.unique(key[order], return_index=True)
        for u, a, b in zip(keys.tolist(), starts.tolist(), [*starts[1:].tolist(), n]):
            idx = order[a:b]
            h = self._half(u // 2, u % 2)
            out["e"][idx], out["d"][idx], out["s"][idx], out["delta"][idx], root[idx] = h.e, h.d, h.s, h.delta, h.root
            panels = len(h.r) - 1
            if panels == 0:
                empty[idx] = True
                out["r1"][idx] = out["r2"][idx] = h.r[0]
                out["G1"][idx] = h.G[0]
                continue
            edges = h.tau if by == "tau" else h.r
            k = np.clip(np.searchsorted(edges, x[idx], side="right") - 1, 0, panels - 1)
            out["r1"][idx], out["r2"][idx], out["G1"][idx] = h.r[k], h.r[k + 1], h.G[k]
            out["tau1"][idx], out["tau2"][idx] = h.tau[k], h.tau[k + 1]
            weighted[idx] = h.weighted & (k == 0)
        return out, root, weighted, empty

    def _state_on(self, i, t):
        """``(q, qdot)`` at times ``t`` on intervals ``i`` (arrays of one length)."""
        intervals, where = np.unique(i, return_inverse=True)
        first_time = np.array([self._half(ii, START).tau[-1] for ii in intervals.tolist()])[where]
        tau = t - self._t0[i]
        side = np.where(tau <= first_time, START, END)
        target = np.where(side == START, tau, np.maximum(self._t1[i] - self._tail(i) - t, 0.0))
        c, root, weighted, empty = self._gather(i, side, target, "tau")
        e, d, s, delta = c["e"], c["d"], c["s"], c["delta"]
        empty |= target <= 0.0
        xi = np.zeros(len(i))
        G = c["G1"].copy()
        h_end = np.full(len(i), np.nan)
        ex_end = np.full(len(i), np.nan)
        for wt in (True, False):
            sel = np.flatnonzero((weighted == wt) & ~empty)
            if not sel.size:
                continue
            rl = self._weighted_rule if wt else self._plain_rule
            p = tuple(a[sel] for a in (e, d, s, delta, root))
            r1 = c["r1"][sel]
            r = self._newton(rl, wt, r1, c["r2"][sel], c["G1"][sel], c["tau1"][sel], c["tau2"][sel], target[sel], p)
            G[sel], _, h_end[sel], ex_end[sel], _ = self._panels(rl, r1, r, c["G1"][sel], *p, wt)
            xi[sel] = np.where(root[sel], r * r - delta[sel], r)
        if empty.any():  # at the anchor itself
            sel = np.flatnonzero(empty)
            _, h_end[sel], ex_end[sel] = self._node(s[sel], e[sel])
        q = e + d * xi
        sigma = np.where(side == START, d, -d)
        return q, self._qdot(sigma, G, h_end, ex_end)

    def _qdot(self, sigma, G, h, ex):
        """``qdot = sigma sqrt(w) / h`` with ``w = G exp(-2 s mu alpha)`` (physics.md, eq. 2)."""
        return sigma * np.sqrt(np.maximum(G, 0.0)) / (ex * h)

    def _newton(self, rl, weighted, r1, r2, G1, tau1, tau2, target, p):
        """``r`` in ``[r1, r2]`` where the time from the anchor reaches ``target`` (safeguarded Newton)."""
        lo, hi = r1.copy(), r2.copy()
        span = np.where(tau2 > tau1, tau2 - tau1, 1.0)
        r = r1 + np.clip((target - tau1) / span, 0.0, 1.0) * (r2 - r1)
        r = np.where((r > lo) & (r < hi), r, 0.5 * (lo + hi))
        live = np.ones(len(r), dtype=bool)
        for _ in range(NEWTON_MAXITER):
            sel = np.flatnonzero(live)
            if not sel.size:
                break
            rs = r[sel]
            G, time, h, ex, dq = self._panels(rl, r1[sel], rs, G1[sel], *(a[sel] for a in p), weighted)
            F = tau1[sel] + time - target[sel]
            slope = h * dq * ex / np.sqrt(np.maximum(G, TINY))
            lo[sel] = np.where(F < 0.0, rs, lo[sel])
            hi[sel] = np.where(F > 0.0, rs, hi[sel])
            new = rs - F / slope
            ok = np.isfinite(new) & (new > lo[sel]) & (new < hi[sel])
            new = np.where(ok, new, 0.5 * (lo[sel] + hi[sel]))
            done = (F == 0.0) | (np.abs(new - rs) <= NEWTON_RTOL * np.maximum(np.abs(rs), np.abs(r2[sel]) * 1e-300)) \
                | (hi[sel] - lo[sel] <= NEWTON_RTOL * np.abs(hi[sel]))
            r[sel] = np.where(F == 0.0, rs, new)
            live[sel[done]] = False
        return r

    def _position_on(self, i, q):
        """``(t, qdot)`` at positions ``q`` on intervals ``i`` (arrays of one length; ``q`` on them)."""
        ivs = self._ivs
        qa, qb = ivs[i, IntervalColumn.qa], ivs[i, IntervalColumn.qb]
        side = np.where(np.abs(q - qa) <= 0.5 * np.abs(qb - qa), START, END)
        xi = np.abs(q - np.where(side == START, qa, qb))
        # r of each query needs its half's root and delta: build the halves first
        halves = {(ii, sd): self._half(ii, sd) for ii, sd in set(zip(i.tolist(), side.tolist()))}
        root = np.array([halves[key].root for key in zip(i.tolist(), side.tolist())], dtype=bool)
        delta = np.array([halves[key].delta for key in zip(i.tolist(), side.tolist())])
        r = np.where(root, np.sqrt(xi + delta), xi)
        c, root, weighted, empty = self._gather(i, side, r, "r")
        e, d, s, delta, r1 = c["e"], c["d"], c["s"], c["delta"], c["r1"]
        r = np.clip(r, r1, np.maximum(r1, c["r2"]))
        empty |= r <= r1
        tau, G = c["tau1"].copy(), c["G1"].copy()
        h_end = np.full(len(i), np.nan)
        ex_end = np.full(len(i), np.nan)
        for wt in (True, False):
            sel = np.flatnonzero((weighted == wt) & ~empty)
            if not sel.size:
                continue
            rl = self._weighted_rule if wt else self._plain_rule
            G[sel], time, h_end[sel], ex_end[sel], _ = self._panels(
                rl, r1[sel], r[sel], c["G1"][sel], *(a[sel] for a in (e, d, s, delta, root)), wt)
            tau[sel] += time
        if empty.any():
            sel = np.flatnonzero(empty)
            xs = np.where(root[sel], r1[sel] ** 2 - delta[sel], r1[sel])
            _, h_end[sel], ex_end[sel] = self._node(s[sel], e[sel] + d[sel] * xs)
        t = np.where(side == START, self._t0[i] + tau, self._t1[i] - self._tail(i) - tau)
        sigma = np.where(side == START, d, -d)
        return t, self._qdot(sigma, G, h_end, ex_end)


#: Statuses after which the particle stays at rest forever.
_RESTING = ("arrested", "resting_on_limiter")
