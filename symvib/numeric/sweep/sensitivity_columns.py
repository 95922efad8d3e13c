"""Opt-in sensitivity columns of a sweep: the final state's exact derivatives, scene by scene.

``sweep(..., sensitivities=("mu", "k"))`` (``symvib sweep ... --sensitivities mu,k``) adds,
per scene, the derivatives of the summary columns ``t_final``, ``q_final``,
``friction_work`` and ``impact_loss`` with respect to each named parameter,
``d_<column>_d_<parameter>`` (``d_t_final_d_mu``: the names of the summary columns and of
:attr:`symvib.numeric.sensitivity.Sensitivities.final`; a sweep of unilateral scenes adds
``landing_loss``'s, :data:`FLIGHT_QUANTITIES`), and ``sensitivity_reason``, a code
of :data:`REASONS` that says why a row's derivatives are NaN (0: they exist).  A parameter is
one of :data:`~symvib.numeric.sensitivity.PARAMETERS` or of the curve's, by its name (``p``)
or as ``parameters.p`` (physics.md, "Sensitivities" 9), as ``Result.sensitivities`` takes it.

The compiled sweep loop keeps no intervals, so these columns are computed per scene
from the single-scene driver's run (:func:`symvib.numeric.driver.simulate`, the same
events) and :func:`symvib.numeric.sensitivity.sensitivities`: a slower path, taken only
when asked (``benchmarks/bench_fit.py --sweep`` measures its cost per scene).

Examples
--------
>>> column_names(("mu", "k"))[:3], column_names(("mu",))[-1]
(['d_t_final_d_mu', 'd_t_final_d_k', 'd_q_final_d_mu'], 'sensitivity_reason')
>>> from symvib.numeric.scene import resolve_scene
>>> column_names(("mu",), resolve_scene("paper-parabola").replace(contact="unilateral"))[-2:]
['d_landing_loss_d_mu', 'sensitivity_reason']
>>> REASONS[reason_code("a Zeno accumulation of impacts (infinitely many events)")]
'a Zeno accumulation of impacts'
"""
from __future__ import annotations

import warnings

import numpy as np

from symvib.numeric.scene import SceneError
from symvib.numeric.sensitivity import PARAMETERS
from symvib.numeric.sensitivity_curve import CURVE_PREFIX, resolve_wrt

__all__ = ["QUANTITIES", "FLIGHT_QUANTITIES", "quantities", "REASON_COLUMN", "REASONS", "OTHER_REASON",
           "column_names", "check_wrt", "reason_code", "compute",
           "column_attrs", "scene_of_row"]

#: Summary columns whose derivatives a sweep can add (the keys of ``Sensitivities.final``).
QUANTITIES = ("t_final", "q_final", "friction_work", "impact_loss")
#: Those a sweep of unilateral scenes adds (its flight column ``landing_loss``).
FLIGHT_QUANTITIES = ("landing_loss",)
#: The integer column that says why a row's derivatives are NaN.
REASON_COLUMN = "sensitivity_reason"
#: Why a row has no derivatives, by code (0: it has them); matched to the sensitivities' reasons by
#: the words in :data:`_KEYWORDS`.  The codes are stored in sweep files: new ones are appended.
REASONS = (
    "",
    "the run did not end at rest (no final state to differentiate)",
    "a turning point on the edge of the friction cone",
    "a turning point on a limiter (grazing)",
    "a Zeno accumulation of impacts",
    "a tangential zero of the normal force (it touches 0 without crossing it)",
    "the particle leaves the curve",
    "the time derivative's quadrature did not converge",
    "the run failed",
    "the run starts at rest: no derivative in qdot0",
    "another reason (see Result.sensitivities())",
    "a tangential landing (the flight touches the curve)",
    "a landing on the edge between sticking and sliding",
    "a bouncing-ball accumulation",
)
#: The code of a reason none of :data:`_KEYWORDS` names.
OTHER_REASON = 10
_KEYWORDS = ((2, "friction cone"), (3, "grazing"), (4, "zeno"), (5, "normal force"), (6, "leaves the curve"),
             (7, "quadrature"), (9, "starts at rest"), (11, "tangential landing"),
             (12, "between sticking and sliding"), (13, "bouncing-ball accumulation"))
#: Varied field -> the :class:`~symvib.numeric.scene.Scene` attribute it sets.
SCENE_ATTRIBUTES = {"initial.q": "q0", "initial.qdot": "qdot0", "physics.mu": "mu", "physics.alpha0": "alpha0",
                    "physics.mu_s": "mu_s", "physics.alpha0_s": "alpha0_s", "physics.restitution": "k",
                    "physics.g": "g", "physics.m": "m", "limiters.left": "left",
                    "limiters.right": "right", "run.t_max": "t_max", "run.max_events": "max_events"}
#: Units of the parameters (``{q}``: the curve coordinate's).
PARAMETER_UNITS = {"mu": "1", "k": "1", "qdot0": "{q}/s", "q0": "{q}", "left": "{q}", "right": "{q}"}


def quantities(scene=None) -> tuple:
    """The summary columns differentiated in a sweep of ``scene``: :data:`QUANTITIES`, and
    :data:`FLIGHT_QUANTITIES` where its contact is unilateral."""
    return QUANTITIES + (FLIGHT_QUANTITIES if getattr(scene, "contact", "bilateral") == "unilateral" else ())


def column_names(wrt, scene=None) -> list:
    """The columns a sweep of ``scene`` with sensitivities ``wrt`` adds, in order."""
    return [f"d_{quantity}_d_{p}" for quantity in quantities(scene) for p in wrt] + ([REASON_COLUMN] if wrt else [])


def check_wrt(scene, wrt, axes=()) -> tuple:
    """``wrt`` as a tuple of distinct parameter names, checked against the scene and the varied fields.

    Raises
    ------
    SceneError
        Naming ``sensitivities``: an unknown or repeated name, or a limiter the scene lacks.
    """
    if isinstance(wrt, str):
        wrt = tuple(p.strip() for p in wrt.split(",") if p.strip())
    try:
        wrt = tuple(wrt or ())
    except TypeError:
        raise SceneError("sensitivities", f"give parameter names (a list, or 'mu,k'), got {wrt!r:.80}") from None
    curve = tuple(name for name, _ in scene.params)
    known = PARAMETERS + curve + tuple(CURVE_PREFIX + name for name in curve)
    unknown = [p for p in wrt if not isinstance(p, str) or p not in known]
    if unknown or len(set(wrt)) != len(wrt):
        raise SceneError("sensitivities", f"{unknown[0] if unknown else wrt!r}: give distinct names from "
                                          f"{', '.join(PARAMETERS + curve)}")
    try:    # (a curve parameter by its name or as parameters.<name>; a name that is both is refused)
        if wrt:
            resolve_wrt(scene, wrt, "sensitivities")
    except ValueError as err:     # (a limiter the scene lacks may be a varied one: checked below)
        if "limiter" not in str(err):
            raise SceneError("sensitivities", str(err).split(": ", 1)[1]) from None
    varied = {a.field for a in axes}
    for side in ("left", "right"):
        if side in wrt and getattr(scene, side) is None and f"limiters.{side}" not in varied:
            raise SceneError("sensitivities", f"the scene has no {side} limiter to differentiate with respect to")
    return wrt


def reason_code(reason: str) -> int:
    """The :data:`REASONS` code of a reason text of :class:`~symvib.numeric.sensitivity.Sensitivities`."""
    text = reason.lower()
    return next((code for code, word in _KEYWORDS if word in text), OTHER_REASON)


def scene_of_row(scene, axes, values, i: int):
    """The :class:`~symvib.numeric.scene.Scene` of row ``i`` of a chunk (``values``: one array per axis)."""
    changes, params = {}, {}
    for axis, v in zip(axes, values):
        value = float(np.asarray(v)[i])
        if axis.field.startswith("parameters."):
            params[axis.field.split(".", 1)[1]] = value
        elif axis.field == "run.max_events":
            changes["max_events"] = int(value)
        else:
            changes[SCENE_ATTRIBUTES[axis.field]] = value
    if params:
        changes["params"] = params
    return scene.replace(**changes)


def compute(spec, values, status, backend: str = "auto") -> dict:
    """The sensitivity columns of a chunk: each scene run by the driver and differentiated.

    ``values`` are the chunk's varied values (one array per axis), ``status`` the sweep's status
    codes of its rows (a failed run gets NaN and code 8 without running again).
    """
    from symvib.numeric.driver import simulate
    from symvib.numeric.layout import ERROR_CODES
    from symvib.numeric.prepared import prepared_of
    from symvib.numeric.sensitivity import sensitivities

    wrt = spec.sensitivities
    n = len(status)
    differentiated = quantities(spec.scene)
    out = {name: np.full(n, np.nan) for name in column_names(wrt, spec.scene)}
    out[REASON_COLUMN] = np.zeros(n, dtype=np.int64)
    prepared = prepared_of(spec.scene)
    for i in range(n):
        if int(status[i]) in ERROR_CODES:
            out[REASON_COLUMN][i] = 8
            continue
        scene = scene_of_row(spec.scene, spec.axes, values, i)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = simulate(scene, samples=False, backend=backend, prepared=prepared)
        if result.status.is_error:
            out[REASON_COLUMN][i] = 8
            continue
        sens = sensitivities(result, wrt, prepared=prepared, compile=True)
        for quantity in differentiated:
            for j, p in enumerate(wrt):
                out[f"d_{quantity}_d_{p}"][i] = sens.final[quantity][j]
        out[REASON_COLUMN][i] = _row_reason(sens, result, differentiated)
    return out


def _row_reason(sens, result, differentiated=QUANTITIES) -> int:
    """Why a row's derivatives (of the columns ``differentiated``) are NaN: its first event without
    them, else a start at rest, else the run's end; 0 where every derivative is a number."""
    finals = np.concatenate([sens.final[q] for q in differentiated])
    if np.all(np.isfinite(finals)):
        return 0
    first = next((why for why in sens.reasons if why), "")
    if first:
        return reason_code(first)
    if sens.notes:
        return reason_code(next(iter(sens.notes.values())))
    return 1 if result.status.value not in ("arrested", "resting_on_limiter") else OTHER_REASON


def column_attrs(scene, name: str, quantity_labels: dict) -> dict:
    """``units`` and ``long_name`` of a sensitivity column (``quantity_labels``: the summary columns'
    ``(long name, units, latex)``)."""
    unit = scene.shape.unit
    if name == REASON_COLUMN:
        return {"units": "1", "long_name": "why the row's derivatives are NaN (code: flag_meanings)",
                "flag_values": list(range(len(REASONS))), "flag_meanings": " ".join(
                    r.replace(" ", "_") or "differentiable" for r in REASONS)}
    quantity, p = name[2:].rsplit("_d_", 1)
    q_units = quantity_labels[quantity][1].format(q=unit)
    p_units = PARAMETER_UNITS[p].format(q=unit) if p in PARAMETER_UNITS else f"units of {p}"   # (a curve's)
    units = q_units if p_units == "1" else f"({q_units})/({p_units})"
    return {"units": units, "long_name": f"derivative of {quantity} with respect to {p}"}
