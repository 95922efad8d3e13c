"""The thin event-driven driver: ``simulate(scene)`` (physics.md, "Events").

Within one motion interval the branch ``s = sigma * sign(N)`` is fixed and the
phase trajectory (eq. 2) holds in closed form,

    G(q) = C - 2 g F_s(q) = w(q) exp(2 s mu alpha(q)),

so events are found in ``q``, not by stepping in time: walking in the
direction of motion over pieces on which ``G`` is monotone (split where
``F_s' = 0``, the edge of the friction cone), the limiter ahead is hit iff
``G`` stays positive up to it; otherwise the first root of ``G`` is the
turning point.  There the particle is arrested when ``|tan alpha| <= mu``
and reverses otherwise; an impact maps ``v -> -k v``; where the normal force
can change sign, its first zero ends the interval too.

Times come from ``t = Integral h dq / sqrt(w)``.  Each interval is split at
its midpoint and each half is anchored at its outer end, where ``G`` is known
exactly (the state, or 0 at a turning point).  ``G`` at the quadrature nodes is
rebuilt from the anchor by integrating ``G' = -2 g F_s'`` spectrally, so it
keeps full relative accuracy where it is small; near a (real or virtual)
root at distance ``delta`` behind the anchor the variable ``r = sqrt(xi)``,
``xi`` the distance from that root, removes the inverse square root, with
panels graded geometrically from ``sqrt(delta)`` (grazing impacts).

Hard cases: grazing, a turning point on the cone edge (arrest within
:data:`CONE_RTOL`), Zeno accumulation at a limiter (the bounces are summed as
a geometric series once they are below :data:`ZENO_W`), plastic impacts,
``mu = 0`` with ``k = 1`` (bounded by ``t_max``/``max_events``), the normal
force changing sign, and the ends of the curve's regular domain.

Examples
--------
>>> from symvib.scene import scene_from_dict
>>> scene = scene_from_dict({"curve": {"shape": "parabola"}, "parameters": {"p": 1},
...     "physics": {"g": 9.81, "m": 0.2, "alpha0": 0.05, "restitution": 0.8},
...     "limiters": {"left": "-pi/6", "right": "pi/4"}, "initial": {"q": 0, "qdot": 7}})
>>> result = simulate(scene)
>>> result.status.value, result.events[0].kind.value
('arrested', 'impact')
>>> result.energy_budget.relative_residual < 1e-12
True
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .events import EnergyBudget, Event, EventKind, Result, Samples, Status, ZenoInfo
from .kernels import load
from .quadrature import brent, rule, safe_newton

__all__ = ["simulate", "NODES"]

#: Chebyshev nodes per quadrature panel.
NODES = 16
#: Widest quadrature panel, in units of the curve's q_scale.
PANEL_Q = 0.5
#: A half-interval uses the root substitution when its anchor's (virtual) root
#: is closer than ROOT_RATIO times the half's length.
ROOT_RATIO = 1.0
#: Search window where no limiter bounds the motion, in units of q_scale.
WINDOW = 2.0
#: Width of the blocks in which critical points (F_s' = 0) are searched, in units of q_scale.
CRIT_BLOCK = 0.5
#: Sample points per block of the critical-point search.
CRIT_GRID = 24
#: Relative tolerance of the arrest test |tan alpha| <= mu at a turning point.
CONE_RTOL = 1e-9
#: A Zeno accumulation is summed analytically once w at an impact is below
#: ZENO_W * g * (a length of the curve); the local model is then exact to rounding.
ZENO_W = 1e-10
#: Samples of the normal force per interval when it may change sign.
N_SCAN = 32

_TURN, _LIMIT, _NSIGN, _PASS, _EDGE = "turn", "limiter", "nsign", "pass", "edge"


@dataclass
class _Interval:
    qa: float
    qb: float
    Ga: float
    Gb: float
    s: int
    sigma: int


class _Scene:
    """Kernels of one scene with its parameters bound, and the geometry caches."""

    def __init__(self, scene, nodes: int):
        mod = load(scene.shape)
        self.mod = mod
        self.scene = scene
        cp = scene.param_values
        self.cp = cp
        mu, g = scene.mu, scene.g
        self.mu, self.g, self.m = mu, g, scene.m
        self.rule = rule(nodes)
        sc = {1: "p", -1: "m"}
        self._F = {s: getattr(mod, f"F_{b}_scalar") for s, b in sc.items()}
        self._dF = {s: getattr(mod, f"dF_{b}_scalar") for s, b in sc.items()}
        self._dFv = {s: getattr(mod, f"dF_{b}") for s, b in sc.items()}
        self.scale = float(mod.q_scale_scalar(*cp))
        self.lo, self.hi = mod.domain(*cp)
        self.left = scene.left
        self.right = scene.right
        self._crit = {1: {}, -1: {}}
        self.safe = self._safe_region()

    # --- scalar geometry ----------------------------------------------------------
    def F(self, s, q):
        return self._F[s](q, self.mu, *self.cp)

    def dF(self, s, q):
        return self._dF[s](q, self.mu, *self.cp)

    def alpha(self, q):
        return self.mod.alpha_scalar(q, *self.cp)

    def h(self, q):
        return self.mod.h_scalar(q, *self.cp)

    def z(self, q):
        return self.mod.z_scalar(q, *self.cp)

    def sincos(self, q):
        h = self.h(q)
        return self.mod.dz_scalar(q, *self.cp) / h, self.mod.dx_scalar(q, *self.cp) / h

    def normal(self, q, w):
        """N per unit mass: kappa w + g cos(alpha)."""
        return self.mod.N_w_scalar(q, w, self.g, *self.cp)

    def G(self, s, C, q):
        return C - 2.0 * self.g * self.F(s, q)

    # --- critical points of G on branch s (F_s' = 0) ---------------------------------
    def criticals(self, s, a, b):
        """Sorted critical points of branch s strictly between a and b."""
        lo, hi = min(a, b), max(a, b)
        width = CRIT_BLOCK * self.scale
        out = []
        for k in range(math.floor(lo / width), math.floor(hi / width) + 1):
            out += [c for c in self._block(s, k, width) if lo < c < hi]
        return sorted(out)

    def _block(self, s, k, width):
        cache = self._crit[s]
        if k in cache:
            return cache[k]
        b0, b1 = k * width, (k + 1) * width
        b0, b1 = max(b0, self.lo), min(b1, self.hi)
        roots = []
        if b0 < b1:
            inner = (b1 - b0) * 1e-12
            grid = np.linspace(b0 + inner, b1 - inner, CRIT_GRID)
            vals = self._dFv[s](grid, self.mu, *self.cp)
            f = lambda x: self.dF(s, x)  # noqa: E731
            for i in np.nonzero(np.sign(vals[:-1]) * np.sign(vals[1:]) <= 0)[0]:
                a, b = float(grid[i]), float(grid[i + 1])
                fa, fb = float(vals[i]), float(vals[i + 1])
                if fa == 0.0 and i > 0:
                    continue  # already found as the right end of the previous cell
                roots.append(brent(f, a, b, fa, fb))
        cache[k] = roots
        return roots

    # --- where N > 0 is guaranteed ---------------------------------------------------
    def _safe_region(self):
        """Interval around q0 on which kappa >= 0 and cos(alpha) > 0 (then N > 0 for any w)."""
        q0 = self.scene.q0
        step = CRIT_BLOCK * self.scale / CRIT_GRID
        bounds = []
        for direction, limit in ((-1, self.left if self.left is not None else self.lo),
                                 (1, self.right if self.right is not None else self.hi)):
            reach = min(abs(limit - q0), 4 * math.pi * max(self.scale, 1.0))
            n = max(2, int(math.ceil(reach / step)))
            qs = q0 + direction * np.linspace(0.0, reach, n + 1)
            qs = qs[(qs > self.lo) & (qs < self.hi)]
            kappa = self.mod.kappa(qs, *self.cp)
            cos = self.mod.dx(qs, *self.cp)
            ok = (kappa >= 0) & (cos > 0)
            bad = np.nonzero(~ok)[0]
            edge = qs[bad[0] - 1] if len(bad) else (limit if abs(limit - q0) <= reach else qs[-1])
            if len(bad) and bad[0] == 0:
                edge = q0
            bounds.append(float(edge))
        return tuple(sorted(bounds))


def simulate(scene, *, nodes: int = NODES, samples: bool = True) -> Result:
    """Simulate ``scene`` event by event until arrest, rest, ``t_max`` or ``max_events``.

    Parameters
    ----------
    scene : Scene
    nodes : int
        Chebyshev nodes per quadrature panel (the accuracy knob of the times).
    samples : bool
        Keep per-interval samples for plotting.

    Returns
    -------
    Result
        Status, events, samples and energy budget.
    """
    return _Run(scene, nodes, samples).run()


class _Run:
    def __init__(self, scene, nodes, keep_samples):
        self.sc = _Scene(scene, nodes)
        self.scene = scene
        self.keep = keep_samples
        self.events = []
        self.t = 0.0
        self.Wf = 0.0
        self.Wimp = 0.0
        self.zeno = None
        self.status = None
        self.pieces = []  # sample arrays per interval
        self.stats = {"intervals": 0, "nodes": 0}

    # --- helpers -------------------------------------------------------------------------
    def energy(self, q, w):
        sc = self.sc
        return sc.m * (0.5 * w + sc.g * sc.z(q))

    def qdot(self, q, w, sigma):
        return sigma * math.sqrt(max(w, 0.0)) / self.sc.h(q)

    def limiter_side(self, q):
        if self.scene.right is not None and q == self.scene.right:
            return 1
        if self.scene.left is not None and q == self.scene.left:
            return -1
        return 0

    def add(self, kind, q, qdot_before, qdot_after, energy, detail=""):
        self.events.append(Event(kind, self.t, q, qdot_before, qdot_after, energy, detail))

    def nsign(self, q, w):
        n = self.sc.normal(q, w)
        if n == 0.0:
            n = self.sc.sincos(q)[1] or 1.0
        return 1 if n > 0 else -1

    # --- rest ------------------------------------------------------------------------
    def rest(self, q):
        """At rest at q: arrest, rest on a limiter, or the sliding direction."""
        sc = self.sc
        sin, cos = sc.sincos(q)
        pull = -sin  # tangential gravity along +q, per g
        side = self.limiter_side(q)
        if side and pull * side > 0:
            return "limiter", 0
        if abs(sin) <= sc.mu * abs(cos) * (1.0 + CONE_RTOL) + 4 * np.finfo(float).eps:
            return "arrest", 0
        return "slide", 1 if pull > 0 else -1

    # --- event location ------------------------------------------------------------------
    def locate(self, q, sigma, s, Ga):
        """Next event from q moving sigma on branch s with G(q) = Ga: (kind, q_end, G_end)."""
        sc = self.sc
        g2 = 2.0 * sc.g
        C = Ga + g2 * sc.F(s, q)
        limiter = self.scene.right if sigma > 0 else self.scene.left
        if limiter is not None:
            bound, kind = limiter, _LIMIT
        else:
            edge = sc.hi if sigma > 0 else sc.lo
            window = q + sigma * WINDOW * sc.scale
            if math.isfinite(edge) and (edge - window) * sigma <= 0:
                bound, kind = edge, _EDGE
            else:
                bound, kind = window, _PASS
        stops = sc.criticals(s, q, bound)
        if sigma < 0:
            stops = stops[::-1]
        a, Gq = q, Ga
        G = lambda x: C - g2 * sc.F(s, x)  # noqa: E731
        dG = lambda x: -g2 * sc.dF(s, x)  # noqa: E731
        for b in stops + [bound]:
            Gb = 0.0 if (b == bound and kind == _EDGE and sc.h(b) == 0.0) else G(b)
            if Gb <= 0.0:
                root = safe_newton(G, dG, a, b, Gq, Gb)
                return self._check_normal(q, root, sigma, s, C, Ga, _TURN, 0.0)
            a, Gq = b, Gb
        return self._check_normal(q, bound, sigma, s, C, Ga, kind, Gq)

    def _check_normal(self, q, qe, sigma, s, C, Ga, kind, Ge):
        """An earlier zero of N on [q, qe] ends the interval there instead."""
        sc = self.sc
        lo, hi = min(q, qe), max(q, qe)
        if sc.safe[0] <= lo and hi <= sc.safe[1]:
            return kind, qe, Ge
        g2 = 2.0 * sc.g
        nsgn = 1 if s * sigma > 0 else -1
        x = rule(N_SCAN).x
        qs = q + (qe - q) * 0.5 * (x + 1.0)
        G = C - g2 * np.array([sc.F(s, v) for v in qs])
        alpha = sc.mod.alpha(qs, *sc.cp)
        w = np.exp(-2.0 * s * sc.mu * alpha) * np.maximum(G, 0.0)
        N = sc.mod.N_w(qs, w, sc.g, *sc.cp) * nsgn
        bad = np.nonzero(N < 0)[0]
        if not len(bad):
            return kind, qe, Ge
        i = bad[0]
        a = q if i == 0 else float(qs[i - 1])
        b = float(qs[i])

        def Nf(v):
            Gv = C - g2 * sc.F(s, v)
            return sc.normal(v, math.exp(-2.0 * s * sc.mu * sc.alpha(v)) * max(Gv, 0.0)) * nsgn

        fa = Nf(a) if i else abs(Nf(q)) or 0.0
        root = brent(Nf, a, b, fa, Nf(b))
        return _NSIGN, root, C - g2 * sc.F(s, root)

    # --- time quadrature ------------------------------------------------------------------
    def quadrature(self, iv: _Interval):
        """Time, friction work (per unit mass) and node samples of one interval."""
        sc = self.sc
        R = sc.rule
        n = R.n
        g2 = 2.0 * sc.g
        L = abs(iv.qb - iv.qa)
        if L == 0.0:
            return 0.0, 0.0, None
        half = 0.5 * L
        panels = []  # (half, root mode, e, d, delta, r1, r2)
        maxq = PANEL_Q * sc.scale
        for k, (e, d, Ge) in enumerate(((iv.qa, iv.sigma, iv.Ga), (iv.qb, -iv.sigma, iv.Gb))):
            gamma = -d * g2 * sc.dF(iv.s, e)
            if Ge == 0.0 or (gamma > 0.0 and Ge < ROOT_RATIO * gamma * half):
                delta = Ge / gamma if Ge > 0.0 else 0.0
                r_lo, r_hi = math.sqrt(delta), math.sqrt(delta + half)
                edges = [r_lo]
                if r_lo > 0.0:
                    r = r_lo
                    while 2.0 * r < r_hi:
                        r *= 2.0
                        edges.append(r)
                edges.append(r_hi)
                for r1, r2 in zip(edges[:-1], edges[1:]):
                    parts = max(1, math.ceil((r2 * r2 - r1 * r1) / maxq))
                    step = (r2 - r1) / parts
                    for j in range(parts):
                        panels.append((k, True, e, d, delta, r1 + j * step, r1 + (j + 1) * step))
            else:
                parts = max(1, math.ceil(half / maxq))
                step = half / parts
                for j in range(parts):
                    panels.append((k, False, e, d, 0.0, j * step, (j + 1) * step))
        P = len(panels)
        arr = np.array([(p[0], p[1], p[2], p[3], p[4], p[5], p[6]) for p in panels], dtype=float)
        halfk, root, e, d, delta, r1, r2 = arr.T
        root = root.astype(bool)
        scale = 0.5 * (r2 - r1)
        r = r1[:, None] + scale[:, None] * (R.x[None, :] + 1.0)
        xi = np.where(root[:, None], r * r - delta[:, None], r)
        qn = e[:, None] + d[:, None] * xi
        dqdr = np.where(root[:, None], 2.0 * r, 1.0)  # |dq/dr|
        cp = sc.cp
        mod = sc.mod
        dF = sc._dFv[iv.s](qn, sc.mu, *cp)
        gam = -g2 * dF * d[:, None]  # dG/dxi: rate of G moving away from the anchor
        dGdr = gam * dqdr
        cum = (dGdr @ R.cumulative.T) * scale[:, None]
        # A panel starting at a root (r = 0): G = Integral 2 rho gamma d rho, with the
        # weight (x + 1) integrated exactly, keeps full relative accuracy as r -> 0.
        at_root = root & (r1 == 0.0)
        if at_root.any():
            cum[at_root] = 2.0 * (gam[at_root] @ R.cumulative_weighted.T) * (scale[at_root, None] ** 2)
        total = (dGdr @ R.weights) * scale
        # Chain the panels of each half outward from its anchor.
        Ganchor = np.where(halfk == 0, iv.Ga, iv.Gb)
        start = np.empty(P)
        for k in (0, 1):
            idx = np.nonzero(halfk == k)[0]
            start[idx] = Ganchor[idx] + np.concatenate(([0.0], np.cumsum(total[idx])[:-1]))
        Gn = start[:, None] + cum
        Gn = np.maximum(Gn, np.finfo(float).tiny)
        alpha = mod.alpha(qn, *cp)
        h = mod.h(qn, *cp)
        expo = np.exp(iv.s * sc.mu * alpha)
        f_t = h * dqdr * expo / np.sqrt(Gn)
        w = Gn / (expo * expo)
        N = mod.N_w(qn, w, sc.g, *cp)
        f_w = sc.mu * np.abs(N) * h * dqdr
        T_p = (f_t @ R.weights) * scale
        W_p = (f_w @ R.weights) * scale
        T = float(T_p.sum())
        Wf = float(W_p.sum())
        self.stats["nodes"] += P * n
        node_data = None
        if self.keep:
            tcum = (f_t @ R.cumulative.T) * scale[:, None]
            tau = np.empty_like(tcum)
            for k in (0, 1):
                idx = np.nonzero(halfk == k)[0]
                before = np.concatenate(([0.0], np.cumsum(T_p[idx])[:-1]))
                tau[idx] = before[:, None] + tcum[idx]
            t_rel = np.where(halfk[:, None] == 0, tau, T - tau)
            order = np.argsort(t_rel, axis=None)
            node_data = (t_rel.ravel()[order], qn.ravel()[order], w.ravel()[order], N.ravel()[order])
        return T, Wf, node_data

    # --- the run ----------------------------------------------------------------------------
    def run(self) -> Result:
        scene, sc = self.scene, self.sc
        q = scene.q0
        h0 = sc.h(q)
        w = (h0 * scene.qdot0) ** 2
        sigma = 0 if scene.qdot0 == 0 else (1 if scene.qdot0 > 0 else -1)
        self.E0 = self.energy(q, w)
        flip = False
        nsign = 0
        if sigma == 0:
            q, w, sigma = self.after_rest(q)
        elif self.limiter_side(q) == sigma:
            q, w, sigma = self.impact(q, w, sigma)
        while self.status is None:
            if len(self.events) >= scene.max_events:
                self.status = Status.MAX_EVENTS
                break
            # The sign of N is read off the state, except right after it changed
            # sign (N = 0 there): then it is the flipped one.
            nsign = -nsign if flip else self.nsign(q, w)
            flip = False
            s = sigma * nsign
            Ga = w * math.exp(2.0 * s * sc.mu * sc.alpha(q))
            kind, qb, Gb = self.locate(q, sigma, s, Ga)
            iv = _Interval(q, qb, Ga, Gb, s, sigma)
            T, Wf, nodes = self.quadrature(iv)
            self.stats["intervals"] += 1
            if self.t + T > scene.t_max:
                self.finish_at_tmax(iv)
                break
            wb = math.exp(-2.0 * s * sc.mu * sc.alpha(qb)) * Gb
            self.keep_samples(iv, nodes, w, wb, T)
            self.t += T
            self.Wf += sc.m * Wf
            if kind == _TURN:
                q, w, sigma = self.after_turn(qb, sigma)
            elif kind == _LIMIT:
                q, w, sigma = self.impact(qb, wb, sigma)
            elif kind == _NSIGN:
                e = self.energy(qb, wb)
                qd = self.qdot(qb, wb, sigma)
                self.add(EventKind.NORMAL_SIGN_CHANGE, qb, qd, qd, e)
                q, w = qb, wb
                flip = True
            elif kind == _PASS:
                q, w = qb, wb
            else:  # the end of the regular domain
                self.status = Status.LEFT_DOMAIN
                self.q_final, self.w_final, self.sigma_final = qb, wb, sigma
        return self.result()

    def finish_at_tmax(self, iv):
        """Stop inside interval iv where t reaches t_max."""
        sc = self.sc
        target = self.scene.t_max - self.t
        C = iv.Ga + 2.0 * sc.g * sc.F(iv.s, iv.qa)

        def part(qe):
            Ge = C - 2.0 * sc.g * sc.F(iv.s, qe)
            return self.quadrature(_Interval(iv.qa, qe, iv.Ga, max(Ge, 0.0), iv.s, iv.sigma))

        def excess(qe):
            return part(qe)[0] - target

        qe = brent(excess, iv.qa, iv.qb, -target, excess(iv.qb))
        T, Wf, nodes = part(qe)
        Ge = max(C - 2.0 * sc.g * sc.F(iv.s, qe), 0.0)
        we = math.exp(-2.0 * iv.s * sc.mu * sc.alpha(qe)) * Ge
        self.keep_samples(_Interval(iv.qa, qe, iv.Ga, Ge, iv.s, iv.sigma), nodes,
                          iv.Ga * math.exp(-2.0 * iv.s * sc.mu * sc.alpha(iv.qa)), we, T)
        self.t = self.scene.t_max
        self.Wf += sc.m * Wf
        self.status = Status.T_MAX
        self.q_final, self.w_final, self.sigma_final = qe, we, iv.sigma

    def keep_samples(self, iv, nodes, wa, wb, T):
        """Store an interval's node samples (with its end points) for :meth:`samples`."""
        if self.keep and nodes is not None:
            self.pieces.append((self.t, T, iv, nodes, wa, wb))

    def after_turn(self, q, sigma):
        """A turning point: arrest, rest on a limiter, or reversal."""
        return self.after_rest(q, turning=True, sigma_in=sigma)

    def after_rest(self, q, *, turning=False, sigma_in=0):
        outcome, direction = self.rest(q)
        e = self.energy(q, 0.0)
        if outcome == "arrest":
            self.add(EventKind.ARREST, q, 0.0, 0.0, e)
            self.status = Status.ARRESTED
        elif outcome == "limiter":
            self.add(EventKind.REST_ON_LIMITER, q, 0.0, 0.0, e)
            self.status = Status.RESTING_ON_LIMITER
        else:
            if turning:
                self.add(EventKind.REVERSAL, q, 0.0, 0.0, e)
            self.q_final, self.w_final, self.sigma_final = q, 0.0, direction
            return q, 0.0, direction
        self.q_final, self.w_final, self.sigma_final = q, 0.0, 0
        return q, 0.0, 0

    def impact(self, q, w, sigma):
        """v -> -k v at a limiter; Zeno accumulations summed; plastic impacts come to rest."""
        sc, k = self.sc, self.scene.k
        qd = self.qdot(q, w, sigma)
        w_after = k * k * w
        self.Wimp += 0.5 * sc.m * (1.0 - k * k) * w
        e_after = self.energy(q, w_after)
        detail = "plastic" if k == 0.0 else ""
        self.add(EventKind.IMPACT, q, qd, -k * qd, e_after, detail)
        if w_after == 0.0:
            return self.after_rest(q)
        zeno = self.zeno_at(q, w, sigma)
        if zeno is not None:
            return zeno
        self.q_final, self.w_final, self.sigma_final = q, w_after, -sigma
        return q, w_after, -sigma

    def zeno_at(self, q, w, sigma):
        """Sum the bounces at a limiter analytically once they are tiny (returns the rest state)."""
        sc, k = self.sc, self.scene.k
        sin, cos = sc.sincos(q)
        away = -sigma  # direction of motion after the impact
        a_up = sc.g * (away * sin + sc.mu * abs(cos))  # deceleration moving away, uphill
        a_down = sc.g * (away * sin - sc.mu * abs(cos))  # acceleration back into the limiter
        if not (a_down > 0.0 and k > 0.0):
            return None
        length = sc.h(q) * sc.scale
        if w >= ZENO_W * sc.g * length:
            return None
        lam_w = k * k * a_down / a_up  # ratio of successive w at impact
        if not lam_w < 1.0:
            return None
        ratio = math.sqrt(lam_w)
        v_after = k * math.sqrt(w)
        remaining = v_after * (1.0 / a_up + 1.0 / math.sqrt(a_up * a_down)) / (1.0 - ratio)
        # All kinetic energy left after this impact is dissipated: impacts take
        # (1 - k^2) of each later w, friction the rest.
        kinetic = 0.5 * sc.m * k * k * w
        w_imp = 0.5 * sc.m * (1.0 - k * k) * lam_w * w / (1.0 - lam_w)
        self.Wimp += w_imp
        self.Wf += kinetic - w_imp
        simulated = self.count_run(q)
        self.t += remaining
        side = "right" if sigma > 0 else "left"
        self.zeno = ZenoInfo(side, ratio, simulated, remaining, self.t)
        self.add(EventKind.REST_ON_LIMITER, q, 0.0, 0.0, self.energy(q, 0.0),
                 f"Zeno accumulation: geometric series of bounces, ratio {ratio:.9g}")
        self.status = Status.RESTING_ON_LIMITER
        self.q_final, self.w_final, self.sigma_final = q, 0.0, 0
        return q, 0.0, 0

    def count_run(self, q):
        n = 0
        for e in reversed(self.events):
            if e.kind is EventKind.IMPACT and e.q == q:
                n += 1
            elif e.kind is not EventKind.REVERSAL:
                break
        return n

    # --- result ---------------------------------------------------------------------------------
    def result(self) -> Result:
        sc = self.sc
        q, w, sigma = self.q_final, self.w_final, self.sigma_final
        if self.status is Status.MAX_EVENTS and not hasattr(self, "q_final"):
            q, w, sigma = self.scene.q0, 0.0, 0
        E_final = self.energy(q, w)
        budget = EnergyBudget(self.E0, E_final, self.Wf, self.Wimp)
        return Result(scene=self.scene, status=self.status, events=tuple(self.events),
                      samples=self.samples() if self.keep else None, energy_budget=budget,
                      t_final=self.t, q_final=q, qdot_final=self.qdot(q, w, sigma) if sigma else 0.0,
                      zeno=self.zeno, stats=dict(self.stats))

    def samples(self) -> Samples:
        """All intervals' samples: start point, quadrature nodes, end point."""
        sc = self.sc
        if not self.pieces:
            empty = np.zeros(0)
            return Samples(*(empty.copy() for _ in range(8)), np.zeros(0, dtype=int), np.zeros(0, dtype=int))
        cols = {k: [] for k in ("t", "q", "w", "N", "sigma", "interval", "branch")}
        for idx, (t0, T, iv, (t_rel, qn, w, N), wa, wb) in enumerate(self.pieces):
            cols["t"] += [[t0], t0 + t_rel, [t0 + T]]
            cols["q"] += [[iv.qa], qn, [iv.qb]]
            cols["w"] += [[wa], w, [wb]]
            cols["N"] += [[sc.normal(iv.qa, wa)], N, [sc.normal(iv.qb, wb)]]
            size = len(qn) + 2
            cols["sigma"].append(np.full(size, iv.sigma))
            cols["interval"].append(np.full(size, idx))
            cols["branch"].append(np.full(size, iv.s))
        t, q, w, N, sig = (np.concatenate([np.asarray(a, dtype=float) for a in cols[k]])
                           for k in ("t", "q", "w", "N", "sigma"))
        m, g, mu = sc.m, sc.g, sc.mu
        v = np.sqrt(np.maximum(w, 0.0))
        Ep = m * g * sc.mod.z(q, *sc.cp)
        return Samples(t=t, q=q, qdot=sig * v / sc.mod.h(q, *sc.cp), F_N=m * N,
                       P_mu=-mu * m * np.abs(N) * v, Ek=0.5 * m * w, Ep=Ep, E=0.5 * m * w + Ep,
                       interval=np.concatenate(cols["interval"]), branch=np.concatenate(cols["branch"]))
