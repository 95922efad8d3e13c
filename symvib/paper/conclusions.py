"""The paper's concluding claims about the motion, each checked against symvib's runs of its scenes.

The paper ends ("Concluding remarks", and the remarks after its circle scene)
with claims about the motion: the normal force, the elastic impact keeping the
speed, the speed at a reversal, the energies and their maxima per motion
interval, the sign of the friction power, a condition for several impacts on
the circle.  Each becomes a :class:`Claim`: the paper's words (a verbatim
substring of the seed, checked by ``tests/test_conclusions.py``), a verdict
(``true``, ``false`` or ``partly``) and the numbers of symvib's runs that
decide it.

The runs are the paper's scenes (``symvib/scenes/paper-*.toml``) with the
ideally elastic impact ``k = 1`` its conclusions discuss, simulated with the
plain-Python driver.  A *motion interval* runs from one event (or the start)
to the next; per-interval quantities come from dense samples of ``q`` between
the two events, with ``qdot**2`` from the closed-form phase trajectory (eq. 2)
of the generated kernels, its constant fitted to the state after the first
event (:func:`dense`).

Examples
--------
>>> [c.key for c in CLAIM_KEYS][:3]
['normal-force', 'elastic-impact', 'reversal-speed']
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from symvib.numeric.events import EventKind
from symvib.numeric.scene import packaged_scene
from symvib.shapes import PAPER_SCENES  # the scenes the claims are checked on

__all__ = ["Claim", "Interval", "CLAIM_KEYS", "PAPER_SCENES", "ELASTIC_K", "DENSE_POINTS", "paper_runs", "intervals",
           "dense", "conclusions", "conclusions_markdown", "several_impacts_bounds"]

#: The restitution of the paper's conclusions: the ideally elastic impact.
ELASTIC_K = 1.0
#: Samples of q per motion interval.
DENSE_POINTS = 401
#: Fraction of an interval's length, each side of a reversal, in which its F_N must be the smallest.
NEIGHBOURHOOD = 0.1
#: Relative size below which a difference counts as rounding (speeds, energies, forces).
ROUNDING = 1e-9
#: Initial angular velocities [rad/s] of the scan of the circle's several-impacts condition.
SCAN_QDOT0 = tuple(np.round(np.arange(2.5, 10.01, 0.5), 2))


@dataclass(frozen=True)
class ClaimKey:
    """A claim of the paper: its key and its words (a verbatim substring of the seed)."""

    key: str
    quote: str


#: The claims, in the paper's order, with the paper's words.
CLAIM_KEYS = (
    ClaimKey("normal-force", "The perpendicular pressure force on a rough parabola, cycloid and circle line does not "
                             "change its value."),
    ClaimKey("elastic-impact", "In the moment of impact of the heavy mass particle onto the elongation limiter (any "
                               "position), when the impact is ideally eleastic, the motion velocity intensity is not "
                               "changed."),
    ClaimKey("reversal-speed", "In the case of the heavy mass particle direction alternation, the velocity is equal "
                               "to zero."),
    ClaimKey("reversal-minimum", "in the point of alternation, the pressure force is of the local minimum value and "
                                 "the corresponding friction force alternates its direction."),
    ClaimKey("friction-direction", "The friction force direction is altered: in the point where the angular velocity "
                                   "of heavy mass particles is equal to zero and at the point of impact of heavy mass "
                                   "particles onto the elongation limiter."),
    ClaimKey("power-sign", "the power is always with a negative argument"),
    ClaimKey("power-maximum", "from the initial moment to the moment when the particle returns into the equilibrium "
                              "position, the maximum value of power of the sliding Coulomb's type force decreases "
                              "constantly"),
    ClaimKey("kinetic-maximum", "Kinetic energy, depending explicitly on the angular velocity of heavy mass "
                                "particles, permanently changes and its maximum value in the sequence motion "
                                "intervals is decreased."),
    ClaimKey("potential-impact", "the impact does not influence the potential energy"),
    ClaimKey("total-energy", "Total mechanical energy of the system constantly decreases"),
    ClaimKey("several-impacts", "The conditions needed for the heavy mass particle to have several impacts onto the "
                                "angular elongation limiter in the observed vibro-impact system are:"),
    ClaimKey("lower-friction", "for a lower friction coefficient and a larger initial velocity, there is a large "
                               "number of impacts and oscillations before the arrestment"),
)


@dataclass(frozen=True)
class Claim:
    """One checked claim: the paper's words, the verdict and the numbers that decide it."""

    key: str
    quote: str
    verdict: str
    numbers: str
    data: dict = field(default_factory=dict, compare=False)


@dataclass(frozen=True)
class Interval:
    """One motion interval: from the state after an event (or the start) to the next event."""

    index: int
    t0: float
    t1: float
    q0: float
    q1: float
    qdot0: float
    end: str

    @property
    def direction(self) -> int:
        """The sign of the velocity inside the interval (``+1`` or ``-1``)."""
        return 1 if self.q1 > self.q0 else -1


def paper_runs(results=None) -> dict:
    """``{scene name: Result}`` of the paper's scenes with ``k = 1`` (simulated unless given)."""
    from symvib import simulate

    results = dict(results or {})
    for name in PAPER_SCENES:
        if name not in results:
            results[name] = simulate(packaged_scene(name).replace(k=ELASTIC_K), backend="python", samples=False)
    return results


def intervals(result) -> list:
    """The motion intervals of a run, from its events (an interval without motion is left out)."""
    s = result.scene
    starts = [(0.0, s.q0, s.qdot0)] + [(e.t, e.q, e.qdot_after) for e in result.events[:-1]]
    out = []
    for (t0, q0, qd0), e in zip(starts, result.events):
        if e.q != q0:
            out.append(Interval(len(out), t0, e.t, q0, e.q, qd0, e.kind.value))
    return out


def dense(result, interval: Interval, points: int = DENSE_POINTS) -> dict:
    """Samples of one interval: ``q``, ``qdot``, ``F_N``, ``P_mu``, ``Ek``, ``Ep``, ``E`` (NumPy arrays).

    ``qdot**2`` is the generated closed-form phase trajectory of the branch
    ``s = sign(v)`` (``N > 0`` is checked), linear in its constant ``C``, so
    ``C`` follows from the state at the start of the interval.
    """
    from symvib.numeric.kernels import load

    scene = result.scene
    k = load(scene.shape.name)
    cp = tuple(scene.param_values)
    s = interval.direction
    qdot2 = k.qdot2_p if s > 0 else k.qdot2_m
    at0 = (qdot2(interval.q0, 0.0, scene.g, scene.mu, *cp), qdot2(interval.q0, 1.0, scene.g, scene.mu, *cp))
    C = (interval.qdot0**2 - at0[0]) / (at0[1] - at0[0])
    q = np.linspace(interval.q0, interval.q1, points)
    qdot = s * np.sqrt(np.clip(qdot2(q, C, scene.g, scene.mu, *cp), 0.0, None))
    out = {"q": q, "qdot": qdot, "qdot2_end": float(qdot2(interval.q1, C, scene.g, scene.mu, *cp)),
           "F_N": k.F_N(q, qdot, scene.g, scene.m, *cp), "P_mu": k.P_mu(q, qdot, scene.g, scene.m, scene.mu, *cp),
           "Ek": k.Ek(q, qdot, scene.m, *cp), "Ep": k.Ep(q, scene.g, scene.m, *cp),
           "E": k.E(q, qdot, scene.g, scene.m, *cp)}
    if np.any(out["F_N"] <= 0):
        raise ValueError(f"{scene.name}: N <= 0 in interval {interval.index}: the branch is not sign(v)")
    return out


def several_impacts_bounds(g: float, R: float, delta: float) -> tuple:
    """The paper's bounds on ``phidot0`` for several impacts on the circle:
    ``sqrt(2 g/R (1 - cos delta)) < phidot0 < sqrt(4 g/R - 2 g/R (1 - cos delta))``."""
    lift = 2 * g / R * (1 - math.cos(delta))
    return math.sqrt(lift), math.sqrt(4 * g / R - lift)


def _decreasing(values) -> tuple:
    """``(True, None)`` when strictly decreasing, else ``(False, j)``: the first ``values[j+1] >= values[j]``."""
    for j in range(len(values) - 1):
        if values[j + 1] >= values[j]:
            return False, j
    return True, None


def _fmt(x: float) -> str:
    return f"{x:.4g}"


def _short(name: str) -> str:
    return name.removeprefix("paper-")


def conclusions(results=None) -> tuple:
    """Check every claim of :data:`CLAIM_KEYS` on the paper's runs; one :class:`Claim` each.

    ``results`` may hold the ``k = 1`` runs already made (``{scene name: Result}``).
    """
    runs = paper_runs(results)
    ivs = {n: intervals(r) for n, r in runs.items()}
    samples = {n: [dense(runs[n], iv) for iv in ivs[n]] for n in runs}
    quote = {c.key: c.quote for c in CLAIM_KEYS}
    out = []

    def claim(key, verdict, numbers, **data):
        out.append(Claim(key, quote[key], verdict, numbers, data))

    # The normal force.
    ranges = {n: (min(float(d["F_N"].min()) for d in samples[n]), max(float(d["F_N"].max()) for d in samples[n]))
              for n in runs}
    changes = any(hi - lo > ROUNDING * hi for lo, hi in ranges.values())
    claim("normal-force", "false" if changes else "true",
          "F_N ranges over " + "; ".join(f"{_short(n)} [{_fmt(lo)}, {_fmt(hi)}] N" for n, (lo, hi) in ranges.items())
          + " (it keeps its sign: N > 0 throughout)", ranges=ranges)
    # The elastic impact keeps the speed.
    impacts = [(n, e) for n, r in runs.items() for e in r.events if e.kind is EventKind.IMPACT]
    worst = max(abs(abs(e.qdot_after) - abs(e.qdot_before)) / abs(e.qdot_before) for _, e in impacts)
    claim("elastic-impact", "true" if worst <= ROUNDING else "false",
          f"{len(impacts)} impacts with k = 1: largest relative change of the speed {worst:.1g}",
          worst=worst, impacts=len(impacts))
    # The speed at a reversal.
    ends = [(n, d, iv) for n in runs for d, iv in zip(samples[n], ivs[n]) if iv.end in ("reversal", "arrest")]
    at_end = max(abs(d["qdot2_end"]) / float(np.max(d["qdot"] ** 2)) for _, d, _ in ends)
    claim("reversal-speed", "true" if at_end <= ROUNDING else "false",
          f"{len(ends)} reversals and arrests: the closed-form phidot^2 there is at most {at_end:.1g} of the "
          "interval's largest", worst=at_end, reversals=len(ends))
    # The normal force is a local minimum at a reversal; the velocity (friction) changes sign there.
    margins, flips = [], []
    for n in runs:
        for a, b in zip(ivs[n], ivs[n][1:]):
            if a.end != "reversal":
                continue
            da, db = samples[n][a.index], samples[n][b.index]
            near = max(1, int(NEIGHBOURHOOD * DENSE_POINTS))
            around = np.concatenate([da["F_N"][-near:-1], db["F_N"][1:near]])
            margins.append(float(around.min() - da["F_N"][-1]))
            flips.append(a.direction != b.direction)
    local_min = all(m > 0 for m in margins)
    claim("reversal-minimum", "true" if local_min and all(flips) else "false",
          f"{len(margins)} reversals followed by motion: F_N there is below every sample within "
          f"{NEIGHBOURHOOD:.0%} of the adjacent intervals (smallest margin {_fmt(min(margins))} N); the velocity "
          f"changes sign at {sum(flips)} of them", margins=margins, flips=flips)
    # The friction direction changes at zero velocity and at impacts.
    flips_impact = [math.copysign(1, e.qdot_before) != math.copysign(1, e.qdot_after) for _, e in impacts]
    claim("friction-direction", "true" if all(flips_impact) and all(flips) else "false",
          f"the velocity, and with it the friction force, changes sign at {sum(flips_impact)} of {len(impacts)} "
          f"impacts and {sum(flips)} of {len(flips)} reversals; N > 0 throughout, so nowhere else")
    # The power of friction is never positive.
    top = max(float(d["P_mu"].max()) for n in runs for d in samples[n])
    low = min(float(d["P_mu"].min()) for n in runs for d in samples[n])
    claim("power-sign", "true" if top <= 0 else "false",
          f"P_mu lies in [{_fmt(low)}, {_fmt(top)}] W over all intervals (0 at reversals); the circle's printed "
          "P_mu is positive (errata)", top=top, low=low)
    # Maxima per interval: |P_mu| and Ek; Ep at impacts; E along the run.
    per = {n: {"P": [float(np.abs(d["P_mu"]).max()) for d in samples[n]],
               "Ek": [float(d["Ek"].max()) for d in samples[n]]} for n in runs}
    for key, what, unit in (("power-maximum", "P", "W"), ("kinetic-maximum", "Ek", "J")):
        rises = {}
        for n in runs:
            ok, j = _decreasing(per[n][what])
            if not ok:
                rises[n] = (j, per[n][what][j], per[n][what][j + 1])
        label = "max |P_mu|" if what == "P" else "max Ek"
        text = ("; ".join(f"{_short(n)}: {label} rises from interval {j + 1} to {j + 2} ({_fmt(a)} -> {_fmt(b)} {unit})"
                          for n, (j, a, b) in rises.items())
                + (f"; it falls in every interval on {', '.join(_short(n) for n in runs if n not in rises)}"
                   if len(rises) < len(runs) else ""))
        if not rises:
            text = f"{label} per interval falls from each interval to the next on all {len(runs)} scenes"
        claim(key, "true" if not rises else ("partly" if len(rises) < len(runs) else "false"), text,
              maxima={n: per[n][what] for n in runs}, rises=rises)
    jumps = []
    for n in runs:
        for iv, nxt in zip(ivs[n], ivs[n][1:]):
            if iv.end == "impact":
                jumps.append(abs(samples[n][iv.index]["Ep"][-1] - samples[n][nxt.index]["Ep"][0]))
    claim("potential-impact", "true" if max(jumps) <= ROUNDING else "false",
          f"Ep just before and just after each of {len(jumps)} impacts differ by at most {max(jumps):.1g} J "
          "(the impact changes the velocity, not the position)", jumps=jumps)
    rise_events = max(b.energy - a.energy for r in runs.values() for a, b in zip(r.events, r.events[1:]))
    rise_samples = max(float(np.max(np.diff(d["E"]))) for n in runs for d in samples[n])
    scale = max(r.energy_budget.initial for r in runs.values())
    claim("total-energy", "true" if rise_events < 0 and rise_samples <= ROUNDING * scale else "false",
          f"E falls at every event (largest change between events {_fmt(rise_events)} J) and along every "
          f"interval (largest change between consecutive samples {rise_samples:.1g} J)",
          rise_events=rise_events, rise_samples=rise_samples)
    out.append(_several_impacts(runs, quote["several-impacts"]))
    a, b = runs["paper-circle-3.8"], runs["paper-circle-7"]
    count = {n: (r.count(EventKind.IMPACT), r.count(EventKind.REVERSAL))
             for n, r in (("paper-circle-3.8", a), ("paper-circle-7", b))}
    more = count["paper-circle-7"][0] > count["paper-circle-3.8"][0] and \
        count["paper-circle-7"][1] > count["paper-circle-3.8"][1]
    claim("lower-friction", "true" if more else "false",
          f"circle-3.8 (mu = {_fmt(a.scene.mu)}, phidot0 = {_fmt(a.scene.qdot0)}): {count['paper-circle-3.8'][0]} "
          f"impact(s), {count['paper-circle-3.8'][1]} reversals; circle-7 (mu = {_fmt(b.scene.mu)}, phidot0 = "
          f"{_fmt(b.scene.qdot0)}): {count['paper-circle-7'][0]} impacts, {count['paper-circle-7'][1]} reversals",
          counts=count)
    order = {c.key: i for i, c in enumerate(CLAIM_KEYS)}
    return tuple(sorted(out, key=lambda c: order[c.key]))


def _several_impacts(runs, quote) -> Claim:
    """The circle's condition ``phi0 < delta`` and the bounds on ``phidot0``, against a scan of ``phidot0``."""
    from symvib import simulate

    rows, findings = {}, []
    for name in ("paper-circle-3.8", "paper-circle-7"):
        scene = runs[name].scene
        (R,) = scene.param_values
        lo, hi = several_impacts_bounds(scene.g, R, scene.right)
        scan = {}
        for qd in SCAN_QDOT0:
            r = simulate(scene.replace(qdot0=float(qd)), backend="python", samples=False)
            scan[float(qd)] = r.count(EventKind.IMPACT)
        inside = {qd: n for qd, n in scan.items() if lo < qd < hi}
        outside = {qd: n for qd, n in scan.items() if not lo < qd < hi}
        rows[name] = {"bounds": (lo, hi), "scan": scan, "sufficient": all(n >= 2 for n in inside.values()),
                      "necessary": all(n <= 1 for n in outside.values())}
        one = [qd for qd, n in inside.items() if n < 2]
        several = [qd for qd, n in outside.items() if n >= 2]
        findings.append(
            f"{_short(name)} (mu = {_fmt(scene.mu)}): bounds ({_fmt(lo)}, {_fmt(hi)}) rad/s; "
            + (f"fewer than 2 impacts inside them at phidot0 = {', '.join(_fmt(q) for q in one)}" if one
               else "2 or more impacts everywhere inside them")
            + (f"; 2 or more outside them at phidot0 = {', '.join(_fmt(q) for q in several)}" if several
               else "; at most 1 outside them"))
    sufficient = all(r["sufficient"] for r in rows.values())
    necessary = all(r["necessary"] for r in rows.values())
    verdict = "true" if sufficient and necessary else ("partly" if sufficient or necessary else "false")
    text = (f"phidot0 scanned over {SCAN_QDOT0[0]:g}-{SCAN_QDOT0[-1]:g} rad/s in steps of "
            f"{SCAN_QDOT0[1] - SCAN_QDOT0[0]:g} with k = 1 (bilateral contact, as in the scenes): "
            + "; ".join(findings)
            + ". The bounds are frictionless energy levels from the bottom; they ignore phi0 and mu")
    return Claim("several-impacts", quote, verdict, text, {"rows": rows})


def conclusions_markdown(claims) -> str:
    """The conclusions table (Markdown): the paper's claim, the verdict, the numbers."""
    lines = ["| # | the paper's claim | verdict | symvib's numbers (scenes with k = 1) |", "| ---: | --- | --- | --- |"]
    for i, c in enumerate(claims, 1):
        verdict = c.verdict if c.verdict == "true" else f"**{c.verdict}**"
        lines.append(f"| {i} | \"{c.quote}\" | {verdict} | {c.numbers.replace('|', chr(92) + '|')} |")
    return "\n".join(lines)
