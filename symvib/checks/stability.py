"""The stability suite: hard scenes with a known right outcome, and one classifier for every method.

Each :class:`Case` is a scene plus how its right outcome was derived,
independently of the driver: a closed form where the mechanics gives one, an
mpmath computation otherwise (:func:`symvib.checks.reference.phase_reference`, or
the frictionless event generator :func:`frictionless_events`, which uses
energy conservation ``w = 2 (e - g z)`` and tanh-sinh quadratures of
``h / sqrt(w)``).  :func:`expected` computes it (cached per process) as an
:class:`Expected` outcome, and :func:`classify` sorts any method's events
into one of :data:`OUTCOMES`:

``correct``
    the right event sequence and status, every checked time and position
    within the case's tolerance;
``inaccurate``
    the right sequence, but a time, position or speed off by more than it;
``missed impact``
    the first difference is an impact the method did not find;
``wrong arrest``
    the first difference is an arrest or a rest (found where there is none, or missed);
``wrong event sequence``
    any other difference of the sequence;
``NaN``
    a non-finite number in the method's state;
``did not finish``
    the method spent its budget (CPU time, events or time bound) before the
    outcome, or its solver failed.

Event sequences are compared as labels: ``impact+``/``impact-`` (impact
with ``qdot > 0``, i.e. on the right limiter, or ``< 0``), ``reversal``,
``arrest``, ``rest_on_limiter``, ``normal_sign_change``.  A Zeno case
accepts any number of bounces (``impact``, ``reversal`` pairs at the limiter)
before the final rest, and checks the accumulation time instead.

Examples
--------
>>> e = Expected(labels=("impact+", "arrest"), status="arrested", times=(0.5, 1.0), positions=(0.7, 0.1))
>>> classify(e, "arrested", [("impact", 0.5, 0.7, 1.0), ("arrest", 1.0, 0.1, 0.0)])
'correct'
>>> classify(e, "arrested", [("arrest", 1.2, 0.3, 0.0)])
'missed impact'
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cache

from symvib.numeric.scene import scene_from_dict

__all__ = ["Case", "Expected", "OUTCOMES", "CORRECT", "INACCURATE", "MISSED_IMPACT", "WRONG_ARREST",
           "WRONG_SEQUENCE", "NAN", "DID_NOT_FINISH", "cases", "case", "expected", "classify", "labels",
           "frictionless_events"]

CORRECT = "correct"
INACCURATE = "inaccurate"
MISSED_IMPACT = "missed impact"
WRONG_ARREST = "wrong arrest"
WRONG_SEQUENCE = "wrong event sequence"
NAN = "NaN"
DID_NOT_FINISH = "did not finish"
#: Every outcome, best first.
OUTCOMES = (CORRECT, INACCURATE, MISSED_IMPACT, WRONG_ARREST, WRONG_SEQUENCE, NAN, DID_NOT_FINISH)

#: Default tolerance on event times (s) and positions (units of q) for "correct".
EVENT_TOL = 1e-6
#: Digits of the mpmath truths.
TRUTH_DPS = 30
_RESTS = ("arrest", "rest_on_limiter")
_G = 9.81
_M = 0.2
_ALPHA0 = 0.05


@dataclass(frozen=True)
class Expected:
    """The right outcome of a case.

    Attributes
    ----------
    labels : tuple of str
        The event sequence (see :func:`labels`); for a Zeno case, the events
        before the bounces start plus the final ``rest_on_limiter``.
    status : str
        The run's final status (a :class:`symvib.numeric.events.Status` value).
    times, positions : tuple of float
        Times and positions of the first ``len(times)`` events.
    tol : float
        Allowed absolute error of those times and positions.
    final_time : float or None
        Time of the last event (the Zeno accumulation time), checked to ``tol``.
    final_speed : float or None
        ``|qdot_before|`` of the last event, checked to ``speed_rtol`` relative.
    zeno : bool
        Any number of ``impact``/``reversal`` bounces may precede the final rest.
    """

    labels: tuple
    status: str
    times: tuple = ()
    positions: tuple = ()
    tol: float = EVENT_TOL
    final_time: float | None = None
    final_speed: float | None = None
    speed_rtol: float = 1e-9
    zeno: bool = False


@dataclass(frozen=True)
class Case:
    """One scene of the suite: what it tests and how its right outcome is derived."""

    name: str
    title: str
    scene: object
    derivation: str
    truth: object = field(repr=False, compare=False)


def labels(events) -> tuple:
    """Sequence labels of events given as ``(kind, t, q, qdot_before, ...)`` tuples or Event records."""
    out = []
    for e in events:
        kind = e[0] if isinstance(e[0], str) else e[0].value
        if kind == "impact":
            kind = "impact+" if e[3] > 0 else "impact-"
        out.append(kind)
    return tuple(out)


def classify(exp: Expected, status: str, events, message: str = "") -> str:
    """Sort a method's run into one of :data:`OUTCOMES` against the expected outcome.

    Parameters
    ----------
    exp : Expected
    status : str
        The run's status (``"failed"`` for a peer whose solver failed or ran out of budget).
    events : sequence
        ``(kind, t, q, qdot_before, ...)`` tuples (peers) or :class:`symvib.numeric.events.Event` records.
    message : str
        The method's failure message, if any.
    """
    rows = [(e[0] if isinstance(e[0], str) else e[0].value, float(e[1]), float(e[2]), float(e[3])) for e in events]
    if "non-finite" in message or any(not math.isfinite(x) for r in rows for x in r[1:]):
        return NAN
    got = labels(rows)
    want = exp.labels
    if exp.zeno and got:
        # Any number of bounces (reversal, impact) at the limiter before the final rest.
        head = len(want) - 1
        rest = got[-1] == "rest_on_limiter"
        body = got[head:-1] if rest else got[head:]
        # (A bounce's impact may be recorded with zero speed, so its side label is not compared.)
        bounces = got[:head] == want[:-1] and all(x == "reversal" if i % 2 == 0 else x.startswith("impact")
                                                  for i, x in enumerate(body))
        if bounces and rest:
            got = want
        elif bounces and status in ("max_events", "t_max"):
            return DID_NOT_FINISH
    if got == want and status == exp.status:
        return CORRECT if _accurate(exp, rows) else INACCURATE
    n = 0
    while n < min(len(got), len(want)) and got[n] == want[n]:
        n += 1
    if status == "failed":
        return DID_NOT_FINISH
    if n == len(got) and status in ("max_events", "t_max") and status != exp.status:
        return DID_NOT_FINISH
    w = want[n] if n < len(want) else None
    g = got[n] if n < len(got) else None
    if w is not None and w.startswith("impact") and not (g or "").startswith("impact"):
        return MISSED_IMPACT
    if w in _RESTS or g in _RESTS:
        return WRONG_ARREST
    if got == want:  # same events, different status
        return WRONG_ARREST if exp.status in ("arrested", "resting_on_limiter") else WRONG_SEQUENCE
    return WRONG_SEQUENCE


def _accurate(exp: Expected, rows) -> bool:
    for (_, t, q, _), te, qe in zip(rows, exp.times, exp.positions):
        if not (abs(t - te) <= exp.tol and abs(q - qe) <= exp.tol):
            return False
    if exp.final_time is not None and not abs(rows[-1][1] - exp.final_time) <= exp.tol:
        return False
    if exp.final_speed is not None and not abs(abs(rows[-1][3]) - exp.final_speed) <= exp.speed_rtol * exp.final_speed:
        return False
    return True


# --- the truths ----------------------------------------------------------------------------------
def _from_reference(scene, status, tol=EVENT_TOL, max_events=None):
    from symvib.checks.reference import phase_reference

    ref = phase_reference(scene, dps=TRUTH_DPS, max_events=max_events)
    rows = [(e.kind, float(e.t), float(e.q), float(e.qdot_before)) for e in ref]
    return Expected(labels=labels(rows), status=status, times=tuple(r[1] for r in rows),
                    positions=tuple(r[2] for r in rows), tol=tol)


def _from_time_reference(scene, status, tol=EVENT_TOL, max_events=None):
    from symvib.checks.reference_time import time_reference

    ref = time_reference(scene, dps=TRUTH_DPS, max_events=max_events)
    rows = [(e.kind, float(e.t), float(e.q), float(e.qdot_before)) for e in ref]
    return Expected(labels=labels(rows), status=status, times=tuple(r[1] for r in rows),
                    positions=tuple(r[2] for r in rows), tol=tol)


def frictionless_events(scene, max_events: int, dps: int = TRUTH_DPS) -> list:
    """Events of ``scene`` with ``mu = 0`` from energy conservation (mpmath, ``dps`` digits).

    Between events the specific energy ``e = w/2 + g z`` is constant, so the
    limiter ahead is reached iff ``e > g z(q_lim)`` (for a curve whose ``z``
    has one minimum between the limiters), the turning point solves
    ``g z(q*) = e``, and the time is ``Integral h dq / sqrt(2 (e - g z))``
    (tanh-sinh).  An impact maps ``w -> k**2 w``.  Returns
    ``(kind, t, q, qdot_before)`` tuples of floats; needs two limiters.
    """
    import mpmath
    import sympy as sp

    c = scene.shape.curve()
    with mpmath.workdps(dps):
        mp = mpmath.mpf
        vals = {p: sp.Float(repr(v), dps + 10) for p, v in zip(c.params, scene.param_values)}
        h = sp.lambdify(c.q, c.h.subs(vals), "mpmath")
        z = sp.lambdify(c.q, c.z.subs(vals), "mpmath")
        g, k = mp(repr(scene.g)), mp(repr(scene.k))
        left, right = mp(repr(scene.left)), mp(repr(scene.right))
        q, qd = mp(repr(scene.q0)), mp(repr(scene.qdot0))
        e = (h(q) * qd) ** 2 / 2 + g * z(q)
        sigma = 1 if qd > 0 else -1
        t = mp(0)
        out = []
        memo = {}

        def travel(a, b, en):
            key = (a, b, en)
            if key not in memo:
                memo[key] = abs(mpmath.quad(lambda x: h(x) / mpmath.sqrt(max(2 * (en - g * z(x)), mp(0))), [a, b]))
            return memo[key]

        while len(out) < max_events:
            bound = right if sigma > 0 else left
            if e > g * z(bound):
                t += travel(q, bound, e)
                v = sigma * mpmath.sqrt(2 * (e - g * z(bound))) / h(bound)
                out.append(("impact", float(t), float(bound), float(v)))
                e = g * z(bound) + k * k * (e - g * z(bound))
                q, sigma = bound, -sigma
            else:
                qs = mpmath.findroot(lambda x: g * z(x) - e, (q if g * z(q) < e else (q + bound) / 2, bound),
                                     solver="anderson")
                t += travel(q, qs, e)
                out.append(("reversal", float(t), float(qs), 0.0))
                q, sigma = qs, -sigma
        return out


def _from_frictionless(scene, status, max_events, tol=EVENT_TOL, final_only=False):
    rows = frictionless_events(scene.replace(mu=0.0), max_events)
    if final_only:
        return Expected(labels=labels(rows), status=status, tol=tol, final_time=rows[-1][1],
                        final_speed=abs(rows[-1][3]), times=(rows[0][1],), positions=(rows[0][2],))
    return Expected(labels=labels(rows), status=status, times=tuple(r[1] for r in rows),
                    positions=tuple(r[2] for r in rows), tol=tol)


def _parabola_F(mu, p=1.0):
    """Closed form ``F_+(phi) = p exp(2 mu phi) / (2 cos(phi)**2)`` on the paper parabola (mpmath)."""
    import mpmath

    return lambda x: p * mpmath.exp(2 * mu * x) / (2 * mpmath.cos(x) ** 2)


def _parabola_qdot0_for(target_G_at, q_at, alpha0=_ALPHA0, g=_G, p=1.0):
    """``phidot0`` at ``phi = 0`` for which ``G = w exp(2 mu phi)`` equals ``target_G_at`` at ``q_at``."""
    import mpmath

    with mpmath.workdps(40):
        mu = mpmath.tan(mpmath.mpf(alpha0))
        F = _parabola_F(mu, p)
        C = target_G_at + 2 * g * F(q_at)
        return float(mpmath.sqrt(C - 2 * g * F(0)) / p)


def _incline(restitution, mu=0.1, slope=0.5, x0=1.0):
    return scene_from_dict({
        "name": "incline", "curve": {"z": "c*x"}, "parameters": {"c": slope},
        "physics": {"g": _G, "m": _M, "mu": mu, "restitution": restitution},
        "limiters": {"left": 0}, "initial": {"q": x0, "qdot": 0.0}})


def _incline_truth(scene, slope=0.5, x0=1.0):
    """Closed form on the incline ``z = c x`` (limiter at the foot, start at rest at ``x0``).

    Down the slope the particle accelerates at ``a_d = g (sin a - mu cos a)``,
    up it decelerates at ``a_u = g (sin a + mu cos a)`` (``tan a = c``).  From
    ``L = x0 / cos a``: first impact at ``t1 = sqrt(2 L / a_d)`` with speed
    ``v1 = sqrt(2 a_d L)``; a bounce with speed ``k v`` lasts
    ``k v (1/a_u + 1/sqrt(a_u a_d))`` and returns at ``r v``,
    ``r = k sqrt(a_d / a_u)``, so the accumulation time is the geometric sum
    ``t_Z = t1 + k v1 (1/a_u + 1/sqrt(a_u a_d)) / (1 - r)``.
    """
    import mpmath

    with mpmath.workdps(40):
        a = mpmath.atan(mpmath.mpf(repr(slope)))
        g, mu, k = mpmath.mpf(repr(scene.g)), mpmath.mpf(repr(scene.mu)), mpmath.mpf(repr(scene.k))
        ad = g * (mpmath.sin(a) - mu * mpmath.cos(a))
        au = g * (mpmath.sin(a) + mu * mpmath.cos(a))
        L = mpmath.mpf(repr(x0)) / mpmath.cos(a)
        t1 = mpmath.sqrt(2 * L / ad)
        v1 = mpmath.sqrt(2 * ad * L)
        qdot1 = -v1 * mpmath.cos(a)  # qdot = v / h, h = 1 / cos a
        r = k * mpmath.sqrt(ad / au)
        tz = t1 + k * v1 * (1 / au + 1 / mpmath.sqrt(au * ad)) / (1 - r)
        return float(t1), float(qdot1), float(tz)


def _paper_parabola(**physics):
    data = {"curve": {"shape": "parabola"}, "parameters": {"p": 1.0},
            "physics": {"g": _G, "m": _M, "alpha0": _ALPHA0, "restitution": 0.8},
            "limiters": {"left": "-pi/6", "right": "pi/4"}, "initial": {"q": 0.0, "qdot": 7.0}}
    for key in ("limiters", "initial", "run"):
        if key in physics:
            data[key] = physics.pop(key)
    if "mu" in physics:
        data["physics"].pop("alpha0")
    data["physics"].update(physics)
    return scene_from_dict(data)


def _circle(alpha0, qdot0, limiters=None, **run):
    data = {"curve": {"shape": "circle"}, "parameters": {"R": 0.5},
            "physics": {"g": _G, "m": _M, "alpha0": alpha0, "restitution": 1.0},
            "limiters": limiters or {}, "initial": {"q": 0.0, "qdot": qdot0}}
    if run:
        data["run"] = run
    return scene_from_dict(data)


def _cone_edge():
    import mpmath

    with mpmath.workdps(40):
        edge = mpmath.atan(mpmath.tan(mpmath.mpf(_ALPHA0)))
        return _paper_parabola(initial={"q": 0.0, "qdot": _parabola_qdot0_for(0, edge)})


def _cone_edge_truth(scene):
    base = _from_reference(scene, "arrested")
    return Expected(labels=("arrest",), status="arrested", times=base.times, positions=(_ALPHA0,), tol=EVENT_TOL)


def _large_friction_truth(scene):
    """Arrest at the first turning point: ``F_+(q*) = F_+(0) + w0 / (2 g)`` (closed form), time by tanh-sinh."""
    import mpmath

    with mpmath.workdps(TRUTH_DPS):
        mu, g = mpmath.mpf(repr(scene.mu)), mpmath.mpf(repr(scene.g))
        F = _parabola_F(mu)
        w0 = mpmath.mpf(repr(scene.qdot0)) ** 2
        C = w0 + 2 * g * F(0)
        qs = mpmath.findroot(lambda x: C - 2 * g * F(x), (mpmath.mpf("0.01"), mpmath.mpf("1.3")), solver="anderson")
        h = lambda x: 1 / mpmath.cos(x) ** 3  # noqa: E731 - p = 1
        t = mpmath.quad(lambda x: h(x) * mpmath.exp(mu * x) / mpmath.sqrt(max(C - 2 * g * F(x), 0)), [0, qs])
    assert abs(mpmath.tan(qs)) <= mu
    return Expected(labels=("arrest",), status="arrested", times=(float(t),), positions=(float(qs),))


def _near_edge_truth(scene):
    """Released at rest just outside the cone edge of the paper parabola: it slides through the edge
    and stops at the mirror point, where friction holds it.

    On the branch ``s = -1`` (moving down, ``N > 0``) ``G(phi) = 2 g (F_-(phi0) - F_-(phi))`` with the
    closed form ``F_-(phi) = p exp(-2 mu phi) / (2 cos(phi)^2)``; the turning point is its other root
    and the time ``Integral h exp(-mu phi) / sqrt(G) dphi`` (``h = p / cos(phi)^3``, ``p = 1``), both at
    50 digits, where the cancellation of ``F_-(phi0) - F_-(phi)`` (about 1e-18 of ``F``) costs nothing.
    """
    import mpmath

    with mpmath.workdps(50):
        mu, g = mpmath.tan(mpmath.mpf(_ALPHA0)), mpmath.mpf(repr(scene.g))
        q0 = mpmath.mpf(repr(scene.q0))
        F = _parabola_F(-mu)
        G = lambda x: 2 * g * (F(q0) - F(x))  # noqa: E731
        edge = mpmath.atan(mu)
        qs = mpmath.findroot(G, (2 * edge - q0 - (q0 - edge), edge), solver="anderson")
        # x = c + r sin(theta) takes the inverse square roots at both ends away (G ~ r^2 cos^2 there).
        c, r = (q0 + qs) / 2, (q0 - qs) / 2

        def rate(theta):
            x = c + r * mpmath.sin(theta)
            Gx = G(x)
            return mpmath.exp(-mu * x) / mpmath.cos(x) ** 3 * r * mpmath.cos(theta) / mpmath.sqrt(Gx) if Gx > 0 else 0

        t = mpmath.quad(rate, [-mpmath.pi / 2, 0, mpmath.pi / 2])
    assert abs(mpmath.tan(qs)) <= mu
    return Expected(labels=("arrest",), status="arrested", times=(float(t),), positions=(float(qs),), tol=1e-9)


def _zeno_truth(scene):
    t1, qdot1, tz = _incline_truth(scene)
    return Expected(labels=("impact-", "rest_on_limiter"), status="resting_on_limiter", times=(t1,),
                    positions=(0.0,), final_time=tz, zeno=True, tol=1e-9)


def _zeno_parabola_truth(scene):
    """Accumulation time from the reference's last bounces: ``t_inf = t_n + d r / (1 - r)``, ``r = d_n / d_(n-1)``."""
    base = _from_reference(scene, "resting_on_limiter", max_events=40)
    t = [tt for tt, lab in zip(base.times, base.labels) if lab.startswith("impact")]
    d1, d2 = t[-1] - t[-2], t[-2] - t[-3]
    r = d1 / d2
    first = base.labels.index("impact+") if "impact+" in base.labels else base.labels.index("impact-")
    return Expected(labels=base.labels[:first + 1] + ("rest_on_limiter",), status="resting_on_limiter",
                    times=base.times[:first + 1], positions=base.positions[:first + 1],
                    final_time=t[-1] + d1 * r / (1 - r), zeno=True, tol=1e-7)


def _plastic_stay_truth(scene):
    t1, qdot1, _ = _incline_truth(scene)
    return Expected(labels=("impact-", "rest_on_limiter"), status="resting_on_limiter", times=(t1, t1),
                    positions=(0.0, 0.0), tol=1e-9)


def cases() -> list:
    """The catalogue of the stability suite (scenes as data, truths lazy)."""
    grazing_qdot0 = _parabola_qdot0_for_grazing(1e-9)
    out = [
        Case("grazing", "grazing impact (w = 1e-9 at the limiter)",
             _paper_parabola(initial={"q": 0.0, "qdot": grazing_qdot0}, run={"max_events": 6}),
             "phidot0 from the closed form F_+ so that w(pi/4) = 1e-9 m^2/s^2; events: mpmath phase reference",
             lambda s: _from_reference(s, "max_events")),
        Case("cone-edge", "turning point exactly on the friction-cone edge",
             _cone_edge(),
             "phidot0 from the closed form F_+ so that the turning point is phi = alpha0 (tan phi = mu): "
             "arrest there; time: mpmath phase reference",
             _cone_edge_truth),
        Case("zeno", "Zeno accumulation at a limiter (incline, k = 0.8)",
             _incline(0.8),
             "incline z = x/2, mu = 0.1: first impact and accumulation time from the geometric series "
             "t_Z = t1 + k v1 (1/a_u + 1/sqrt(a_u a_d)) / (1 - k sqrt(a_d/a_u)) (closed form)",
             _zeno_truth),
        Case("zeno-parabola", "Zeno accumulation on a curve (parabola, k = 0.8)",
             _paper_parabola(limiters={"right": -0.3}, initial={"q": -0.6, "qdot": 0.0}),
             "paper parabola, limiter at phi = -0.3, released at rest at -0.6: 40 events of the mpmath phase "
             "reference, the accumulation time extrapolated by their own geometric ratio (to ~1e-7)",
             _zeno_parabola_truth),
        Case("plastic-stay", "plastic impact k = 0 that stays",
             _incline(0.0),
             "incline z = x/2: impact at t1 = sqrt(2 L / a_d), then gravity holds it on the limiter (closed form)",
             _plastic_stay_truth),
        Case("plastic-slide", "plastic impact k = 0 that slides away",
             _paper_parabola(restitution=0.0),
             "paper parabola, k = 0: impact at pi/4 with nothing left, slides back; mpmath phase reference",
             lambda s: _from_reference(s, "arrested")),
        Case("mu-to-0", "mu -> 0 (mu = 1e-12, k = 0.8, 40 events)",
             _paper_parabola(mu=1e-12, run={"max_events": 40}),
             "energy conservation w = 2 (e - g z), times by tanh-sinh (mpmath); mu = 1e-12 moves them by ~1e-11",
             lambda s: _from_frictionless(s, "max_events", 40)),
        Case("elastic-long", "mu = 0, k = 1 over a long horizon (1000 impacts)",
             _paper_parabola(mu=0.0, restitution=1.0, run={"max_events": 1000}),
             "energy conservation: periodic motion, the two limiter-to-limiter times by tanh-sinh (mpmath)",
             lambda s: _from_frictionless(s, "max_events", 1000)),
        Case("large-friction", "large friction (mu = 5): arrest at the first turning point",
             _paper_parabola(mu=5.0),
             "turning point from the closed form F_+(q*) = F_+(0) + w0/(2g), abs(tan q*) <= mu; time by tanh-sinh",
             _large_friction_truth),
        Case("thousands", "2000 impacts, mu = 0, k = 0.9999 (energy budget)",
             _paper_parabola(mu=0.0, restitution=0.9999, run={"max_events": 2000}),
             "energy conservation between impacts, w -> k^2 w at each: speed and time of the 2000th impact (mpmath)",
             lambda s: _from_frictionless(s, "max_events", 2000, final_only=True)),
        Case("cycloid-cusp", "limiter next to the cycloid cusp (pi - 0.01)",
             scene_from_dict({"curve": {"shape": "cycloid"}, "parameters": {"R": 0.05},
                              "physics": {"g": _G, "m": _M, "alpha0": _ALPHA0, "restitution": 0.9},
                              "limiters": {"left": "-pi/6", "right": "pi - 0.01"},
                              "initial": {"q": 0.0, "qdot": 30.0}, "run": {"max_events": 12}}),
             "h -> 0 at the cusp: phidot > 1000 at the limiter; mpmath phase reference",
             lambda s: _from_reference(s, "max_events")),
        Case("normal-sign", "normal force changing sign (circle above its horizontal diameter)",
             _circle(_ALPHA0, 8.5, max_events=8),
             "no limiter, phidot0 = 8.5 on R = 0.5: N < 0 above the diameter; mpmath phase reference",
             lambda s: _from_reference(s, "max_events")),
        Case("near-stop", "near-stop inside an interval (circle, over the top at a crawl)",
             scene_from_dict({"curve": {"shape": "circle"}, "parameters": {"R": 0.5},
                              "physics": {"g": _G, "m": _M, "mu": 0.05, "restitution": 0.8},
                              "initial": {"q": 0.0, "qdot": 11.965}, "run": {"t_max": 3.0}}),
             "phidot0 = 11.965 on R = 0.5, mu = 0.05: the speed nearly vanishes inside the second interval "
             "(1/sqrt(w) peaks there); events: mpmath time reference (eq. 1 integrated at 30 digits), to 1e-9 s",
             lambda s: _from_time_reference(s, "t_max", tol=1e-9)),
        Case("short-scale", "a user curve 1e-4 m across, no q_scale given",
             scene_from_dict({"curve": {"z": "x**2/(2*p)"}, "parameters": {"p": 1e-4},
                              "physics": {"g": _G, "m": _M, "mu": 0.05, "restitution": 0.8},
                              "limiters": {"left": -1e-4, "right": 1.5e-4}, "initial": {"q": 0.0, "qdot": 0.05},
                              "run": {"max_events": 6}}),
             "the parabola z = x^2/(2p), p = 1e-4 m, as a user writes it (the default q_scale is 1 m); events: "
             "mpmath time reference (eq. 1 integrated at 30 digits), to 1e-9 s",
             lambda s: _from_time_reference(s, "max_events", tol=1e-9)),
        Case("near-edge", "released at rest 1e-9 (relative) outside the friction-cone edge",
             _paper_parabola(initial={"q": _ALPHA0 * (1 + 1e-9), "qdot": 0.0}),
             "paper parabola released at rest at phi0 = alpha0 (1 + 1e-9): it slides through the edge and is "
             "arrested at the mirror point after half a period of the motion about the edge; closed form F_- "
             "at 50 digits (time by tanh-sinh), to 1e-9 s",
             _near_edge_truth),
        Case("looping", "looping a full circle, no limiter",
             _circle(0.02, 11.0, max_events=8),
             "phidot0 = 11 on R = 0.5 goes over the top three times (N < 0 near it from the second pass) "
             "before it swings back; mpmath phase reference",
             lambda s: _from_reference(s, "max_events")),
    ]
    return out


def _parabola_qdot0_for_grazing(eps):
    import mpmath

    with mpmath.workdps(40):
        mu = mpmath.tan(mpmath.mpf(_ALPHA0))
        ql = mpmath.pi / 4
        return _parabola_qdot0_for(eps * mpmath.exp(2 * mu * ql), ql)


def case(name: str) -> Case:
    """The catalogue case called ``name``."""
    for c in cases():
        if c.name == name:
            return c
    raise ValueError(f"stability case: unknown name {name!r}; known: {', '.join(c.name for c in cases())}")


@cache
def expected(name: str) -> Expected:
    """The right outcome of case ``name`` (computed once per process; mpmath, seconds)."""
    c = case(name)
    return c.truth(c.scene)
