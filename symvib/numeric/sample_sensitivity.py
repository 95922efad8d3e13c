"""Exact derivatives of a run's position at given times (physics.md, "Sensitivities" 7).

A tracked video gives the particle's position at sample times, not its events.
At a fixed time ``t`` inside a motion interval the position ``q(t)`` moves with
the parameters because the interval's time quadrature does: with ``t(q; p)``
the time at which the particle passes ``q``, ``Dq = -qdot D[t(q; p)]``.  The time
is measured from the interval's nearer end, over a piece whose ends keep their
distance ``xi`` from it (:meth:`symvib.numeric.sensitivity.Leg.position_tangent`),
so a sample next to a turning point, where ``D[t(q; p)]`` at fixed ``q`` grows
like ``1 / qdot``, has a finite derivative computed without cancellation.
Before and after a motion interval the particle rests, and its position's
derivative is that of the event it rests at.  At an impact's time ``q(t)`` has a
kink, and ``Dq`` jumps from ``DL - v_before Dt`` to ``DL - v_after Dt``: a sample
there (within ``AT_IMPACT``) has no derivative, and says so.  Coordinates: ``q``; ``x, z`` with
``Dx = x'(q) Dq``, ``Dz = z'(q) Dq``; the arc length ``s`` from the initial
position (as :class:`symvib.numeric.events.Samples`' ``s``), ``s = Integral_{q0}^{q}
h du``, ``Ds = h(q) Dq - h(q0) Dq0``.  In flight (a unilateral curve) the particle is on the
parabola launched at ``t0`` from ``P0`` with ``V0``: ``x, z`` move as ``DP0 + DV0 (t - t0) - V(t)
Dt0`` (physics.md, "Sensitivities" 10); ``q`` and ``s`` have no value there, and say so.

Examples
--------
>>> from symvib import simulate
>>> res = simulate("paper-parabola")
>>> sens = sample_sensitivities(res, [0.05, 0.6], wrt=("mu", "qdot0"))
>>> sens.columns, sens.values.shape, sens.derivatives.shape, sens.reasons
(('q',), (2, 1), (2, 1, 2), ('', ''))
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from symvib.numeric.quadrature import rule
from symvib.numeric.sensitivity import interval_tangents
from symvib.numeric.sensitivity_curve import resolve_wrt

__all__ = ["sample_sensitivities", "sample_positions", "SampleSensitivities", "COORDINATES", "arc_length"]

#: Coordinates a sample may give -> its columns.
COORDINATES = {"q": ("q",), "xz": ("x", "z"), "s": ("s",)}
#: Statuses after which the particle rests at its last event for ever.
RESTING = ("arrested", "resting_on_limiter")
#: Relative distance of a sample time from an impact's below which it is at the impact, where ``q(t)``
#: has a kink (its speed jumps): the derivative at fixed time jumps there too, and has no value.
AT_IMPACT = 1e-12
#: Gauss-Legendre nodes per piece of the arc-length quadrature, and the agreement of two piece counts.
ARC_NODES, ARC_RTOL = 16, 1e-14
#: Most pieces of the arc-length quadrature (doubled from 1 until two counts agree).
ARC_MAX_PIECES = 1024


@dataclass(frozen=True)
class SampleSensitivities:
    """A run's position at sample times and its derivatives (an immutable record).

    Attributes
    ----------
    wrt : tuple of str
    t : ndarray, shape (n,)
    columns : tuple of str
        ``("q",)``, ``("x", "z")`` or ``("s",)``.
    values : ndarray, shape (n, len(columns))
        The model's coordinates at ``t``.
    derivatives : ndarray, shape (n, len(columns), len(wrt))
        NaN where the position has no derivative (``reasons`` says why).
    reasons : tuple of str
        Per sample, why its derivatives are NaN (empty where they exist).
    """

    wrt: tuple
    t: np.ndarray
    columns: tuple
    values: np.ndarray
    derivatives: np.ndarray
    reasons: tuple


def sample_sensitivities(result, t, wrt=("mu", "k"), coordinates="q", *, prepared=None,
                         compile: bool = False) -> SampleSensitivities:
    """The position of ``result`` at times ``t`` and its derivatives with respect to ``wrt``.

    Parameters
    ----------
    result : symvib.numeric.events.Result
        A run that kept its intervals (``simulate(scene)``, samples on: the dense output needs them).
    t : array_like
        Sample times (s), in ``[0, result.dense.t_max]``.
    wrt : sequence of str
        As :func:`symvib.numeric.sensitivity.sensitivities`.
    coordinates : {"q", "xz", "s"}
        Key of :data:`COORDINATES`.
    prepared : Prepared, optional
    compile : bool
        Compile the quadratures if they are not yet (:func:`symvib.numeric.sensitivity.interval_tangents`).

    Returns
    -------
    SampleSensitivities
        Where a sample's derivatives are NaN, its reason says why: at an impact (a kink of
        ``q(t)``), after an event without derivatives, inside the interval a run stopped in.

    Raises
    ------
    ValueError
        Naming ``t`` (not finite, before the start or after the run's end), ``coordinates``,
        or (from the event sensitivities) ``wrt`` and ``result``.
    """
    times = _checked(result, t, coordinates)
    dense = result.dense
    bad = ~np.isfinite(times) | (times < 0) | (times > dense.t_max)
    if bad.any():
        raise ValueError(f"t: sample {int(np.flatnonzero(bad)[0]) + 1} ({float(times[bad][0])!r} s) is not in the "
                         f"run's time span [0, {dense.t_max:g}] s (status {result.status.value})")
    # (no event after the one that ends the last sample's interval, and the one after it, is needed)
    event_times = np.array([e.t for e in result.events])
    through = int(np.searchsorted(event_times, np.max(times), side="left")) + 1 if len(times) else None
    tangents = interval_tangents(result, wrt, prepared=prepared, through=through, compile=compile)
    sens = tangents.sensitivities
    q, qdot = (np.asarray(a, dtype=float).reshape(-1) for a in dense.state(times))
    flying = _flying(dense, times)
    on = ~flying
    Dq, reasons = _position_tangents(result, tangents, times, q, qdot)
    for name in sens.notes:
        Dq[:, sens.wrt.index(name)] = np.nan
    # (in flight the coordinates are evaluated at q0, a position on the curve, and replaced below)
    values, slopes = _coordinates(result, np.where(on, q, float(result.scene.q0)), coordinates, prepared)
    derivatives = slopes[:, :, None] * Dq[:, None, :]
    targets = resolve_wrt(result.scene, wrt)
    for j, (_, kind, name) in enumerate(targets):
        if kind == "scene" and name == "q0" and coordinates == "s":     # the arc length is measured from q0
            derivatives[:, 0, j] -= _h0(result, prepared)
        elif kind == "curve" and coordinates != "q" and on.any():    # the curve itself moves with its parameter
            derivatives[on, :, j] += _curve_parameter_part(result, q[on], coordinates, name, prepared)
    if flying.any():
        _in_flight(result, tangents, times, flying, coordinates, values, derivatives, reasons)
    return SampleSensitivities(sens.wrt, times, COORDINATES[coordinates], values, derivatives, tuple(reasons))


def _flying(dense, times) -> np.ndarray:
    """Which samples are in flight (a run with flights' dense output says; others never fly)."""
    in_flight = getattr(dense, "in_flight", None)
    if in_flight is None:
        return np.zeros(len(times), dtype=bool)
    return np.asarray(in_flight(times), dtype=bool).reshape(-1)


def _in_flight(result, tangents, times, flying, coordinates, values, derivatives, reasons) -> None:
    """The samples in flight, in place: ``x, z`` on the parabola and their derivatives at fixed time
    from the flight's launch tangents; ``q`` and ``s`` NaN with a reason."""
    g = float(result.scene.g)
    starts = np.array([f.t0 for f in tangents.flights])
    for k in np.flatnonzero(flying).tolist():
        values[k], derivatives[k] = np.nan, np.nan
        if coordinates != "xz":
            reasons[k] = (f"in flight: the particle is off the curve, its {coordinates} has no value "
                          "(coordinates='xz' has)")
            continue
        j = int(np.searchsorted(starts, times[k], side="right")) - 1
        if j < 0:
            reasons[k] = reasons[k] or "in a flight after an event without derivatives"
            continue
        f, tau = tangents.flights[j], float(times[k]) - tangents.flights[j].t0
        vz = f.Vz - g * tau
        values[k] = (f.X0 + f.Vx * tau, f.Z0 + f.Vz * tau - 0.5 * g * tau * tau)
        derivatives[k, 0] = f.DX0 + f.DVx * tau - f.Vx * f.Dt0
        derivatives[k, 1] = f.DZ0 + f.DVz * tau - vz * f.Dt0
        reasons[k] = ""


def sample_positions(result, t, coordinates="q", *, prepared=None) -> np.ndarray:
    """The model's coordinates at times ``t`` (shape (n, len(COORDINATES[coordinates]))), no derivatives;
    in flight ``x, z`` on the parabola, ``q`` and ``s`` NaN."""
    times = _checked(result, t, coordinates)
    dense = result.dense
    q = np.asarray(dense.state(times)[0], dtype=float).reshape(-1)
    flying = _flying(dense, times)
    values = _coordinates(result, np.where(flying, float(result.scene.q0), q), coordinates, prepared)[0]
    if flying.any():
        values[flying] = np.nan
        if coordinates == "xz":
            x, z, _, _ = dense.position(times[flying])
            values[flying, 0], values[flying, 1] = x, z
    return values


def _curve_parameter_part(result, q, coordinates, name, prepared) -> np.ndarray:
    """The derivative at fixed ``q`` of the coordinates with respect to the curve parameter ``name``
    (shape (n, columns)): ``dx/da, dz/da``, or ``Integral_{q0}^{q} dh/da`` for the arc length
    (physics.md, "Sensitivities" 9; the curve's jets, :mod:`symvib.numeric.jet_kernels`)."""
    from symvib.numeric.jet_kernels import load_jets

    jets = load_jets(result.scene.shape)
    _, cp = _kernels(result, prepared)
    fn = getattr(jets, f"param_jet_{jets.PARAM_JETS[name]}")
    part = lambda what, u: np.asarray(fn(u, *cp)[jets.PARAM_JET.index(what)], float) * np.ones_like(u)  # noqa: E731
    if coordinates == "xz":
        return np.stack([part("x", q), part("z", q)], axis=1)
    q0 = float(result.scene.q0)
    return np.array([arc_length(lambda u: part("h", u), q0, float(qi)) for qi in q])[:, None]


def _checked(result, t, coordinates) -> np.ndarray:
    """The sample times as floats, once ``result`` and ``coordinates`` are what they should be."""
    if not hasattr(result, "dense") or not hasattr(result, "scene"):
        raise ValueError(f"result: a run of symvib.simulate, got {type(result).__name__}")
    if not isinstance(coordinates, str) or coordinates not in COORDINATES:
        raise ValueError(f"coordinates: {coordinates!r:.80} is not one of {', '.join(COORDINATES)}")
    try:
        return np.asarray(t, dtype=float).ravel()
    except (TypeError, ValueError):
        raise ValueError(f"t: sample times in seconds (numbers), got {t!r:.80}") from None


def _kernels(result, prepared):
    from symvib.numeric.prepared import prepared_of

    return (prepared or prepared_of(result.scene)).kernels, tuple(result.scene.param_values)


def _h0(result, prepared) -> float:
    """``h`` at the initial position."""
    kernels, cp = _kernels(result, prepared)
    return float(kernels.h_scalar(float(result.scene.q0), *cp))


def _coordinates(result, q, coordinates, prepared) -> tuple:
    """The coordinates at positions ``q`` and their slopes ``d/dq`` (each shape (n, columns))."""
    kernels, cp = _kernels(result, prepared)
    of = lambda name, u: np.asarray(getattr(kernels, name)(u, *cp), float) * np.ones_like(u)  # noqa: E731
    if coordinates == "q":
        return q[:, None], np.ones((len(q), 1))
    if coordinates == "xz":
        return np.stack([of("x", q), of("z", q)], axis=1), np.stack([of("dx", q), of("dz", q)], axis=1)
    q0 = float(result.scene.q0)
    values = np.array([arc_length(lambda u: of("h", u), q0, float(qi)) for qi in q])
    return values[:, None], of("h", q)[:, None]


def _position_tangents(result, tangents, times, q, qdot):
    """``Dq`` at fixed time per sample (shape (n, parameters)) and the reasons where it has none."""
    sens, legs = tangents.sensitivities, tangents.legs
    P = len(sens.wrt)
    starts = np.array([leg.t_a for leg in legs])
    event_times = np.array([e.t for e in sens.events])
    impacts = np.array([e.t for e in sens.events if e.kind.value == "impact"])
    out = np.full((len(times), P), np.nan)
    reasons = []
    for k, t in enumerate(times):
        if len(impacts) and np.min(np.abs(impacts - t)) <= AT_IMPACT * max(t, 1e-300):
            reasons.append("at an impact: the position has a kink in time there, its derivative jumps")
            continue
        j = int(np.searchsorted(starts, t, side="right")) - 1
        if j >= 0 and t <= legs[j].t_e:
            D = legs[j].position_tangent(float(q[k]), float(qdot[k]))
            reasons.append("" if D is not None else "the time quadrature of its interval did not converge")
            if D is not None:
                out[k] = D
            continue
        # not in motion: at rest after the last event at or before t, unless an event without
        # derivatives (or the run's end inside an interval) comes first
        i = int(np.searchsorted(event_times, t, side="right")) - 1
        if i + 1 < len(sens.events) and sens.reasons[i + 1]:
            reasons.append(f"before event {i + 1}, which has no derivatives ({sens.reasons[i + 1]})")
        elif i >= 0 and sens.reasons[i]:
            reasons.append(f"after event {i}, which has no derivatives ({sens.reasons[i]})")
        elif i < 0 or (i + 1 == len(sens.events) and result.status.value not in RESTING):
            reasons.append(f"inside the interval the run stopped in (status {result.status.value}): "
                           "its end is no event")
        else:
            out[k] = sens.q[i]
            reasons.append("")
    return out, reasons


def arc_length(h, a: float, b: float) -> float:
    """``Integral_a^b h(u) du`` (``h`` vectorized): Gauss-Legendre on 1, 2, 4, ... equal pieces until two
    counts agree to ``ARC_RTOL``."""
    if a == b:
        return 0.0
    rl = rule(ARC_NODES)
    pieces, previous = 1, None
    while pieces <= ARC_MAX_PIECES:
        edges = np.linspace(a, b, pieces + 1)
        half = (edges[1:] - edges[:-1]) / 2
        nodes = (edges[:-1] + half)[:, None] + half[:, None] * rl.x[None, :]
        current = float(np.sum(half * (h(nodes.ravel()).reshape(nodes.shape) @ rl.weights)))
        if previous is not None and abs(current - previous) <= ARC_RTOL * max(abs(current), math.ulp(1.0)):
            return current
        previous, pieces = current, 2 * pieces
    return previous
