"""Flight and landing on a unilateral curve: the laws, in closed form (physics.md, "Flight and landing").

NumPy and the curve's generated kernels only (no SymPy, no engine): the ballistic
path (:func:`path`), the signed distance of a point from the curve (:class:`Stretch`),
the first landing of a path on the curve (:func:`landing`), the landing law
(:func:`landing_law`), the crossing of a limiter's line (:func:`limiter_crossing`)
and the bouncing-ball accumulation on the tangent line (:func:`accumulation`).
:mod:`symvib.numeric.flights` runs them between the engine's sliding stretches.

Examples
--------
>>> path(0.5, 0.0, 1.0, 2.0, 3.0, 10.0)      # x0, z0, vx, vz at t = 0.5 with g = 10
(1.0, 1.25, 2.0, -2.0)
>>> law = landing_law(1.0, -2.0, 1.0, 0.0, 0.5, 0.2)   # flat floor: V = (1, -2), e = 0.5, mu = 0.2
>>> law.u_after, round(law.v_after, 12), law.stick
(1.0, 0.4, False)
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

__all__ = ["path", "Stretch", "landing", "Landing", "landing_law", "LandingLaw", "limiter_crossing",
           "accumulation", "Accumulation", "LandingNotFound", "EPS", "GRAZE", "LIFT_START", "SAMPLE_STEP",
           "KAPPA_SAFETY", "TOUCH_RTOL", "HORIZON", "ACCUMULATION_W", "MAX_LOCAL_BOUNCES", "LANDED", "TOUCHED",
           "LEFT_STRETCH", "MAX_EVALUATIONS", "SAMPLED"]

#: Unit roundoff of a double.
EPS = 2.220446049250313e-16
#: Separation (a share of the run's length scale, in metres) beyond which a lifted particle counts as
#: off the curve: the search for its landing starts there (physics.md, "Flight and landing" 3).
GRAZE = 1e6 * EPS
#: First trial time of a lift-off's search, a share of the flight's time scale ``v / g`` (doubled until
#: the separation passes :data:`GRAZE`).
LIFT_START = 1e-9
#: Spacing of the curve's samples, a share of the run's length scale (in ``q``).
SAMPLE_STEP = 1.0 / 64.0
#: ``kappa_max`` is this times the largest ``|kappa|`` sampled on the stretch.
KAPPA_SAFETY = 1.5
#: An undecided time interval shorter than this share of its time is a tangential touch.
TOUCH_RTOL = 1e-14
#: The landing is searched at most this many length scales from the launch where neither a limiter
#: nor the domain's end bounds it.
HORIZON = 100.0
#: A bounce whose normal speed ``u`` has ``u^2 < ACCUMULATION_W g L`` (``L`` the length scale in
#: metres) starts a bouncing-ball accumulation, summed on the tangent line.
ACCUMULATION_W = 1e-10
#: Most bounces of the local model taken one by one before the regimes' test must hold.
MAX_LOCAL_BOUNCES = 100_000
#: Kinds of :class:`Landing`: on the curve across it, on the curve at a tangential touch, none
#: before the path left the searched stretch.
LANDED, TOUCHED, LEFT_STRETCH = 0, 1, 2
#: Most evaluations of the signed distance one landing search may take (a safeguard: the tests of
#: :func:`landing` end long before it on every curve the engine runs); past it the run stops with
#: status ``tolerance_not_met`` (:class:`LandingNotFound`).
MAX_EVALUATIONS = 50_000
#: The kernels a :class:`Stretch` samples (the stretch ends where one is not finite).
SAMPLED = ("x", "z", "dx", "dz", "h", "dh", "dalpha", "kappa")


class LandingNotFound(RuntimeError):
    """The landing search used up :data:`MAX_EVALUATIONS` distances without deciding."""


def path(t, x0, z0, vx, vz, g):
    """The ballistic path at time ``t`` after ``(x0, z0)`` with velocity ``(vx, vz)``: ``(x, z, vx, vz)``
    (physics.md, "Flight and landing" 2)."""
    return x0 + vx * t, z0 + vz * t - 0.5 * g * t * t, vx, vz - g * t


class Stretch:
    """The curve between ``qa`` and ``qb`` as a landing sees it: samples, ``kappa_max`` and the signed
    distance of a point (physics.md, "Flight and landing" 3).

    Parameters
    ----------
    mod : module
        The curve's generated kernels (``x, z, dx, dz, h, dh, alpha, dalpha, kappa`` and ``*_scalar``).
    cp : tuple
        The curve's parameter values.
    qa, qb : float
        The searched stretch (finite, ``qa < qb``).
    scale : float
        The run's length scale in ``q`` (:func:`symvib.numeric.engine.scan.curve_scale`).
    q_near : float
        Where a tie between equally near samples goes (the launch: a curve that overlaps itself,
        a circle run over several turns, lands on the turn nearest in ``q``).
    """

    def __init__(self, mod, cp, qa, qb, scale, q_near):
        self.mod, self.cp, self.qa, self.qb, self.q_near = mod, tuple(cp), float(qa), float(qb), float(q_near)
        n = max(2, int(math.ceil((qb - qa) / (SAMPLE_STEP * scale))) + 1)
        q = np.linspace(qa, qb, n)
        with np.errstate(all="ignore"):
            values = {name: np.asarray(np.broadcast_to(getattr(mod, name)(q, *cp), q.shape), dtype=float)
                      for name in SAMPLED}
        # Where a kernel is not finite (it overflows far out, e.g. exp(x^2/b^2) in a Gaussian's h'),
        # the stretch ends at the last finite sample on each side of the launch: what lies beyond
        # is not searched (a flight that gets there leaves the stretch; physics.md, "Flight and landing" 6).
        finite = np.all([np.isfinite(v) for v in values.values()], axis=0)
        i = int(np.clip(np.searchsorted(q, q_near), 0, n - 1))
        self.cut = (False, False)
        if finite[i]:
            bad = np.flatnonzero(~finite)
            lo, hi = bad[bad < i], bad[bad > i]
            first, last = (int(lo[-1]) + 1 if len(lo) else 0), (int(hi[0]) - 1 if len(hi) else n - 1)
            # (a scalar kernel may overflow where its array form gave a finite value, x / inf = 0:
            # the ends move in, by bisection, to where the scalar kernels are finite too)
            first, last = self._scalar_finite(q, i, first, -1), self._scalar_finite(q, i, last, 1)
            if (first, last) != (0, n - 1) and last - first >= 1:
                self.cut = (first > 0, last < n - 1)
                q = q[first:last + 1]
                values = {name: v[first:last + 1] for name, v in values.items()}
                self.qa, self.qb = float(q[0]), float(q[-1])
        self.q, self.x, self.z = q, values["x"], values["z"]
        kappa = values["kappa"]
        finite = np.isfinite(kappa)   # (no bound where the curvature is not finite: the Lipschitz test alone)
        self.kappa_max = KAPPA_SAFETY * float(np.max(np.abs(kappa[finite]))) if finite.all() else math.inf
        # |d kappa / ds| between neighbouring samples (the cubic test of landing(); inf: none)
        ds = np.hypot(np.diff(self.x), np.diff(self.z))
        with np.errstate(all="ignore"):
            slope = np.abs(np.diff(kappa)) / ds
        self.kappa_slope_max = (KAPPA_SAFETY * float(np.max(slope)) if finite.all() and np.all(np.isfinite(slope))
                                else math.inf)
        # Between samples the curve may bulge out of their box by about a sample's length.
        step = self.step = float(np.max(ds))
        # each sample's longer neighbouring segment: how far the curve near it may come closer than it
        self.local_step = np.maximum(np.concatenate(([0.0], ds)), np.concatenate((ds, [0.0])))
        self.box = (float(self.x.min()) - step, float(self.x.max()) + step, float(self.z.min()) - step,
                    float(self.z.max()) + step)

    def _finite_at(self, q) -> bool:
        """Whether every scalar kernel of :data:`SAMPLED` is finite at ``q`` (none overflows)."""
        m, cp = self.mod, self.cp
        try:
            return all(math.isfinite(getattr(m, f"{name}_scalar")(q, *cp)) for name in SAMPLED)
        except (ArithmeticError, ValueError):
            return False

    def _scalar_finite(self, q, inner, end, side) -> int:
        """The sample index nearest ``end`` (between ``inner``, the launch's, and ``end``, on ``side``)
        where the scalar kernels are finite, assuming they fail only beyond some index (an overflow
        far out); ``inner`` itself when they fail there too."""
        if self._finite_at(float(q[end])):
            return end
        good, bad = inner, end
        if not self._finite_at(float(q[good])):
            return inner
        while abs(bad - good) > 1:
            mid = (good + bad) // 2
            good, bad = (mid, bad) if self._finite_at(float(q[mid])) else (good, mid)
        return good

    def point(self, q):
        """``(x, z, x', z')`` at ``q``."""
        m, cp = self.mod, self.cp
        return m.x_scalar(q, *cp), m.z_scalar(q, *cp), m.dx_scalar(q, *cp), m.dz_scalar(q, *cp)

    def second(self, q, dx, dz):
        """``(x'', z'')`` at ``q`` from ``h' / h`` and ``alpha'``: ``x'' = (h'/h) x' - alpha' z'``,
        ``z'' = (h'/h) z' + alpha' x'``."""
        m, cp = self.mod, self.cp
        r, da = m.dh_scalar(q, *cp) / m.h_scalar(q, *cp), m.dalpha_scalar(q, *cp)
        return r * dx - da * dz, r * dz + da * dx

    def _foot(self, X, Z, q):
        """``x' (X - x) + z' (Z - z)``: zero where ``q`` is the foot of the normal through ``(X, Z)``."""
        x, z, dx, dz = self.point(q)
        return dx * (X - x) + dz * (Z - z)

    def nearest(self, X, Z):
        """``(q*, d)``: the nearest point of the stretch to ``(X, Z)`` and the signed distance, ``> 0`` on
        the side of ``n = (-z', x') / h`` (the particle's)."""
        d2 = (self.x - X) ** 2 + (self.z - Z) ** 2
        # The local minima of the samples' distance about as near as the nearest (within two samples'
        # length, each sample's own and the nearest's: a steep stretch far off has long segments
        # that must not make its far minima candidates): the one nearest in q to q_near (a curve
        # over several turns has one per turn).
        i0 = int(np.argmin(d2))
        reach = math.sqrt(float(d2[i0])) + 2.0 * np.maximum(self.local_step, self.local_step[i0])
        last = len(self.q) - 1
        pad = np.concatenate(([np.inf], d2, [np.inf]))
        minima = np.flatnonzero((d2 <= reach * reach) & (d2 <= pad[:-2]) & (d2 <= pad[2:]))
        i = int(minima[np.argmin(np.abs(self.q[minima] - self.q_near))])
        best = float(d2[i])
        a, b = self.q[max(i - 1, 0)], self.q[min(i + 1, len(self.q) - 1)]
        fa, fb = self._foot(X, Z, a), self._foot(X, Z, b)
        q = self.q[i]
        if fa > 0.0 > fb:   # the foot lies between: Newton, else false position (Illinois), kept in [a, b]
            side = 0
            for _ in range(100):
                x, z, dx, dz = self.point(q)
                f = dx * (X - x) + dz * (Z - z)
                if f == 0.0:
                    break
                if f > 0.0:
                    a, fa = q, f
                    if side > 0:
                        fb *= 0.5
                    side = 1
                else:
                    b, fb = q, f
                    if side < 0:
                        fa *= 0.5
                    side = -1
                ddx, ddz = self.second(q, dx, dz)
                slope = ddx * (X - x) + ddz * (Z - z) - (dx * dx + dz * dz)
                nxt = q - f / slope if slope < 0.0 else math.nan
                if not a < nxt < b:
                    nxt = a - fa * (b - a) / (fb - fa)
                    if not a < nxt < b:
                        nxt = 0.5 * (a + b)
                if abs(nxt - q) <= 4.0 * EPS * abs(q) + 1e-300 or b - a <= 4.0 * EPS * max(abs(a), abs(b)):
                    q = nxt
                    break
                q = nxt
        else:   # no foot inside: the nearest of the three
            ia, ib = max(i - 1, 0), min(i + 1, last)
            cands = [(a, float(d2[ia])), (b, float(d2[ib])), (q, best)]
            q = min(cands, key=lambda c: c[1])[0]
        x, z, dx, dz = self.point(q)
        h = math.hypot(dx, dz)
        side = (-dz * (X - x) + dx * (Z - z)) / h
        return float(q), math.copysign(math.hypot(X - x, Z - z), side)

    def motion(self, X, Z, VX, VZ, g):
        """``(d, d', d'')``: the signed distance of the point ``(X, Z)`` moving with ``(VX, VZ)`` under
        gravity, and its first two time derivatives (physics.md, "Flight and landing" 3):
        ``d' = V . n``, ``d'' = -g cos(alpha) - kappa v_t^2 / (1 - kappa d)`` at the nearest point."""
        q, d = self.nearest(X, Z)
        m, cp = self.mod, self.cp
        dx, dz = m.dx_scalar(q, *cp), m.dz_scalar(q, *cp)
        h = math.hypot(dx, dz)
        tx, tz = dx / h, dz / h
        v_t = tx * VX + tz * VZ
        kappa = float(m.kappa_scalar(q, *cp))
        return d, -tz * VX + tx * VZ, -g * tx - kappa * v_t * v_t / (1.0 - kappa * d)

    def exit_time(self, x0, z0, vx, vz, g):
        """The time after which the path from ``(x0, z0)`` is outside the stretch's box for good."""
        xlo, xhi, zlo, _ = self.box
        t_z = (vz + math.sqrt(max(vz * vz + 2.0 * g * (z0 - zlo), 0.0))) / g
        t_x = math.inf
        if vx > 0.0:
            t_x = (xhi - x0) / vx
        elif vx < 0.0:
            t_x = (xlo - x0) / vx
        return max(min(t_z, t_x), 0.0)


class Landing(NamedTuple):
    """The end of a flight: ``kind`` (:data:`LANDED`, :data:`TOUCHED`, :data:`LEFT_STRETCH`), its time
    ``t`` after the launch and the curve's ``q`` there (the nearest point, for :data:`LEFT_STRETCH`)."""

    kind: int
    t: float
    q: float


def landing(stretch, x0, z0, vx, vz, g, u, length):
    """The first landing of the path from ``(x0, z0)`` with ``(vx, vz)`` on ``stretch`` (physics.md,
    "Flight and landing" 3).

    Parameters
    ----------
    stretch : Stretch
    x0, z0, vx, vz, g : float
        The launch and gravity.
    u : float
        The normal speed of the launch (``> 0`` after a bounce, 0 at a lift-off).
    length : float
        The run's length scale in metres (the graze threshold :data:`GRAZE` is a share of it).

    Returns
    -------
    Landing
    """
    t_end = stretch.exit_time(x0, z0, vx, vz, g)
    count = [0]

    def motion(t):
        count[0] += 1
        if count[0] > MAX_EVALUATIONS:
            raise LandingNotFound(f"the landing search took more than {MAX_EVALUATIONS} distances without "
                                  "deciding whether the flight lands")
        return stretch.motion(*path(t, x0, z0, vx, vz, g), g)

    def speed(t):
        return math.hypot(vx, vz - g * t)

    v0 = speed(0.0)
    kmax = stretch.kappa_max
    outside = (math.nan, math.nan, math.nan)
    if u > 0.0 and math.isfinite(kmax):
        t0 = u / (g + 2.0 * kmax * v0 * v0)   # d >= u t - A t^2 / 2 > 0 before 2 u / A
        M0 = motion(t0) if t0 < t_end else outside
    else:   # a lift-off (or no curvature bound): from where the separation is past the graze threshold
        t0 = LIFT_START * max(v0 / g, math.sqrt(length / g))
        M0 = motion(t0) if t0 < t_end else outside
        while t0 < t_end and abs(M0[0]) <= GRAZE * length:
            t0 *= 2.0
            M0 = motion(t0) if t0 < t_end else outside
    if not t0 < t_end:
        x, z, _, _ = path(t_end, x0, z0, vx, vz, g)
        return Landing(LEFT_STRETCH, t_end, stretch.nearest(x, z)[0])
    if M0[0] <= 0.0:   # into the curve at once (a graze on the wrong side): lands there
        return Landing(TOUCHED, t0, stretch.nearest(*path(t0, x0, z0, vx, vz, g)[:2])[0])
    stack = [(t0, M0, t_end, motion(t_end))]
    ks = stretch.kappa_slope_max
    while stack:
        ta, Ma, tb, Mb = stack.pop()
        da, db = Ma[0], Mb[0]
        dt = tb - ta
        tm = ta + 0.5 * dt
        if db <= 0.0:   # a crossing in [ta, tb]: its first one
            if not ta < tm < tb:
                t = tb if -db < da else ta
                x, z, _, _ = path(t, x0, z0, vx, vz, g)
                return Landing(LANDED, t, stretch.nearest(x, z)[0])
        else:
            vmax = max(speed(ta), speed(tb))
            if da + db > vmax * dt:
                continue   # 1-Lipschitz: root-free
            near = kmax * (max(da, db) + 0.5 * vmax * dt) <= 0.5   # within half the radius of curvature
            A = g + 2.0 * kmax * vmax * vmax
            if near and min(da, db) > A * dt * dt / 8.0:   # (inf: never)
                continue   # |d''| <= A: root-free
            J = (6.0 * g * kmax + (8.0 * ks + 12.0 * kmax * kmax) * vmax * vmax) * vmax   # a bound of |d'''|
            if near and (_cubic_clear(da, Ma[1], Ma[2], J, dt) or _cubic_clear(db, -Mb[1], Mb[2], J, dt)):
                continue   # Taylor from an end with |d'''| <= J: root-free (after a lift-off d ~ t^3)
            if dt <= TOUCH_RTOL * tb or not ta < tm < tb:
                t = ta if da <= db else tb
                x, z, _, _ = path(t, x0, z0, vx, vz, g)
                return Landing(TOUCHED, t, stretch.nearest(x, z)[0])
        Mm = motion(tm)
        stack.append((tm, Mm, tb, Mb))
        stack.append((ta, Ma, tm, Mm))
    x, z, _, _ = path(t_end, x0, z0, vx, vz, g)
    return Landing(LEFT_STRETCH, t_end, stretch.nearest(x, z)[0])


def _cubic_clear(d, d1, d2, J, span):
    """Whether ``p(s) = d + d1 s + d2 s^2 / 2 - J s^3 / 6``, a lower bound of the distance ``s`` after
    an end where it is ``d > 0`` with derivatives ``d1, d2`` (given a bound ``J`` of the third
    derivative), stays positive for ``0 <= s <= span``."""
    if not (d > 0.0 and math.isfinite(J) and J >= 0.0):
        return False

    def p(s):
        return d + s * (d1 + s * (0.5 * d2 - s * J / 6.0))

    if not p(span) > 0.0:
        return False
    # p' = d1 + d2 s - J s^2 / 2; its local minimum (where p'' = d2 - J s > 0) inside (0, span)
    if J > 0.0:
        disc = d2 * d2 + 2.0 * J * d1
        s = (d2 - math.sqrt(disc)) / J if disc >= 0.0 else math.nan
    else:
        s = -d1 / d2 if d2 > 0.0 else math.nan
    return not (0.0 < s < span) or p(s) > 0.0


class LandingLaw(NamedTuple):
    """The landing law's outcome: normal and tangential velocity before (``u_before <= 0``,
    ``v_before``) and after (``u_after >= 0``, ``v_after``), whether it stuck, and the kinetic energy
    per unit mass it removed."""

    u_before: float
    v_before: float
    u_after: float
    v_after: float
    stick: bool
    loss: float


def landing_law(vx, vz, tx, tz, e, mu):
    """The landing law (physics.md, "Flight and landing" 4) for the velocity ``(vx, vz)`` on a curve of
    unit tangent ``(tx, tz)`` (normal ``n = (-tz, tx)``), restitution ``e`` and friction ``mu``.

    Newton: ``u -> -e u``, normal impulse ``J_n = (1 + e) |u|``; Coulomb: the tangential velocity stops
    when ``|v| <= mu J_n`` (sticking), else loses ``mu J_n`` (sliding).

    Examples
    --------
    >>> landing_law(0.1, -2.0, 1.0, 0.0, 0.0, 0.5).stick     # |v| = 0.1 <= 0.5 * 2: sticks
    True
    """
    u = -tz * vx + tx * vz
    v = tx * vx + tz * vz
    u_in = min(u, 0.0)   # (a touch may give a rounding-sized u > 0: nothing to reverse)
    jn = (1.0 + e) * -u_in
    u_after = -e * u_in
    stick = abs(v) <= mu * jn
    v_after = 0.0 if stick else v - math.copysign(mu * jn, v)
    loss = 0.5 * ((u * u + v * v) - (u_after * u_after + v_after * v_after))
    return LandingLaw(u, v, u_after, v_after, stick, loss)


def limiter_crossing(t_stop, x0, z0, vx, vz, g, xl, zl, tx, tz, side):
    """The first time in ``(0, t_stop]`` at which the path crosses the normal line of the limiter at
    ``(xl, zl)`` (unit tangent ``(tx, tz)`` there) outwards, or ``inf`` (physics.md, "Flight and landing" 6).

    ``side`` is +1 for a right limiter (outwards: increasing ``q``), -1 for a left one;
    ``side e_t . (P(t) - C(L)) = b0 + b1 t + b2 t^2`` is positive beyond the line.

    Examples
    --------
    >>> limiter_crossing(10.0, 0.0, 0.0, 1.0, 0.0, 9.81, 2.0, 0.0, 1.0, 0.0, 1)   # a wall at x = 2
    2.0
    """
    b0 = side * (tx * (x0 - xl) + tz * (z0 - zl))
    b1 = side * (tx * vx + tz * vz)
    b2 = -side * tz * 0.5 * g
    roots = []
    if b2 == 0.0:
        if b1 != 0.0:
            roots.append(-b0 / b1)
    else:
        disc = b1 * b1 - 4.0 * b2 * b0
        if disc >= 0.0:
            sq = math.sqrt(disc)
            qq = -0.5 * (b1 + math.copysign(sq, b1))
            if qq != 0.0:
                roots += [qq / b2, b0 / qq]
            else:
                roots.append(0.0)
    if b0 > 0.0:
        return 0.0
    for r in sorted(roots):
        if 0.0 < r <= t_stop and 2.0 * b2 * r + b1 >= 0.0:
            return r
    return math.inf


class Accumulation(NamedTuple):
    """A bouncing-ball accumulation summed on the tangent line (physics.md, "Flight and landing",
    Bouncing-ball accumulation): its time, the displacement along the line, the tangential velocity
    after it, whether every landing of the summed tail sticks, and the bounces taken one by one."""

    time: float
    ds: float
    v_after: float
    stuck: bool
    bounces: int


def accumulation(u, v, a_t, a_n, e, mu):
    """The bouncing-ball accumulation from a launch with normal speed ``u > 0`` and tangential velocity
    ``v``, restitution ``0 < e < 1`` and friction ``mu``, where gravity's tangential component is
    ``-a_t`` (``a_t = g sin alpha``) and the particle is pressed onto the curve with ``a_n = kappa v^2 + g
    cos alpha > 0`` (``g cos alpha`` on a straight line).

    Bounces are taken one by one in closed form (``T = tau u``, ``tau = 2 / a_n``; landing with ``(-u,
    v - 2 r u)``, ``r = a_t / a_n``, ``tan alpha`` on a line) until one of the regimes of physics.md holds
    for every later bounce, then summed: stuck (``v = 0``, ``2 |r| <= mu (1 + e)``) or drifting one way.

    Examples
    --------
    >>> a = accumulation(1.0, 0.0, 0.0, 10.0, 0.5, 0.3)   # flat, vertical bounce: 2 u / (g (1 - e))
    >>> a.time, a.ds, a.v_after, a.stuck
    (0.4, 0.0, 0.0, True)
    """
    tau = 2.0 / a_n
    r = a_t / a_n
    f = mu * (1.0 + e)
    time, ds = 0.0, 0.0
    for n in range(MAX_LOCAL_BOUNCES):
        if v == 0.0 and 2.0 * abs(r) <= f:   # stuck: every landing sticks
            time += tau * u / (1.0 - e)
            ds += -0.5 * a_t * tau * tau * u * u / (1.0 - e * e)
            return Accumulation(time, ds, 0.0, True, n)
        v_land = v - 2.0 * r * u
        if v_land != 0.0:
            sigma = math.copysign(1.0, v_land)
            c = -2.0 * r - sigma * f
            v_inf = v + c * u / (1.0 - e)
            if sigma * v_land > f * u and sigma * v_inf > 0.0:   # drifting one way for good
                time += tau * u / (1.0 - e)
                ds += tau * u * (v / (1.0 - e) + c * u * e / ((1.0 - e) * (1.0 - e * e))) \
                    - 0.5 * a_t * tau * tau * u * u / (1.0 - e * e)
                return Accumulation(time, ds, v_inf, False, n)
        # one bounce of the local model
        T = tau * u
        time += T
        ds += v * T - 0.5 * a_t * T * T
        v = 0.0 if abs(v_land) <= f * u else v_land - math.copysign(f * u, v_land)
        u = e * u
    raise RuntimeError(f"accumulation: no regime after {MAX_LOCAL_BOUNCES} bounces")
