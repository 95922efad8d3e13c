"""Flights in a sweep: the rows of unilateral scenes followed past their lift-off (physics.md, "Flight and landing").

The compiled sweep loop (:func:`symvib.numeric.driver.sweep_function`) runs a scene's first
sliding stretch, as the engine runs it for :func:`~symvib.numeric.driver.simulate`; on a
unilateral curve (``physics.contact = "unilateral"``) it ends where ``N`` reaches 0, with status
``left_curve``.  :func:`follow_rows` continues those rows in Python after the chunk: each one's
scene is run by the single-scene driver, whose same engine stretch ends
there too and is then followed by :func:`symvib.numeric.flights.follow` (the lift-off, flights,
landings, bounces and their accumulation, sliding again, until the run stops), and the row's
summary columns and logged events become that run's.  So every row of a unilateral sweep is what
``simulate`` gives for its scene: status, events, final state, energies
(``tests/test_sweep_flights.py``).  A row that never lifts off keeps the compiled loop's values.

A sweep of unilateral scenes has the columns :data:`COLUMNS` after the summary ones: ``flights``
and ``landings``, the counts ``Result.stats["flights"]`` and ``["landings"]`` (a summed
bouncing-ball accumulation adds to ``flights`` the bounces its local model takes one by one
before the series is summed; the ``landing`` event that ends it is not among ``landings``), and
``landing_loss``, the energy lost at landings (``W_landing``, the energy budget's
``landing_loss``; J), all 0 on a row that never flies.  A bilateral sweep has none of them
(:func:`column_names`), so its columns, chunks and identity are what they were.

The followed rows cost what ``simulate`` costs them (flights are computed in Python, about 10
milliseconds a flight, on either backend): a sweep of scenes that fly is much slower than one whose
scenes slide (docs/sweeps.md, "Flights").

Examples
--------
>>> from symvib.numeric.scene import scene_from_dict
>>> scene = scene_from_dict({"curve": {"shape": "circle"}, "parameters": {"R": 0.5},
...     "physics": {"mu": 0.05, "restitution": 1, "contact": "unilateral", "restitution_curve": 0.5},
...     "initial": {"q": 0, "qdot": 8}})
>>> column_names(scene), column_names(scene.replace(contact="bilateral"))
(['flights', 'landings', 'landing_loss'], [])
>>> from symvib.numeric.sweep import sweep
>>> res = sweep(scene, {"qdot": "2,8"}, backend="python")
>>> list(res.status_names()), res["flights"].tolist(), bool(res["landing_loss"][1] > 0)
(['arrested', 'arrested'], [0, 17], True)
"""
from __future__ import annotations

import numpy as np

from symvib.numeric.layout import EVENT_KINDS, STATUSES, EventCode, EventColumn, StatusCode, Summary
from symvib.numeric.sweep.sensitivity_columns import scene_of_row

__all__ = ["COLUMNS", "INTEGER_COLUMNS", "LABELS", "unilateral", "column_names", "follow_rows", "row_values"]

#: The columns a sweep of unilateral scenes adds after the summary columns, in order.
COLUMNS = ("flights", "landings", "landing_loss")
#: Those of :data:`COLUMNS` that are counts (``int64``); ``landing_loss`` is ``float64``.
INTEGER_COLUMNS = ("flights", "landings")
#: Long name, units and LaTeX symbol of each of :data:`COLUMNS` (as
#: :data:`symvib.numeric.sweep.labels.COLUMN_LABELS` holds the summary columns').
LABELS = {
    "flights": ("number of flights", "1", "N_\\mathrm{{flights}}"),
    "landings": ("number of landings computed one by one", "1", "N_\\mathrm{{landings}}"),
    "landing_loss": ("energy lost at landings", "J", "W_\\mathrm{{landing}}"),
}
#: Event kinds counted by the summary's count columns (:class:`~symvib.numeric.layout.Summary`).
_COUNTED = {"impacts": EventCode.IMPACT, "reversals": EventCode.REVERSAL,
            "normal_sign_changes": EventCode.NORMAL_SIGN_CHANGE}


def unilateral(scene) -> bool:
    """Whether ``scene``'s contact is unilateral (its sweep follows flights and has :data:`COLUMNS`)."""
    return getattr(scene, "contact", "bilateral") == "unilateral"


def column_names(scene) -> list:
    """The flight columns of a sweep of ``scene``: :data:`COLUMNS` for a unilateral scene, else none."""
    return list(COLUMNS) if unilateral(scene) else []


def _row_prepared(base, scene, varies_parameters: bool):
    """The prepared curve of a row's ``scene``: the base scene's ``base``, or, where the sweep varies the
    curve's parameters, the row's (its domain follows them: :func:`~symvib.numeric.prepared.prepared_of`)."""
    if not varies_parameters:
        return base
    from symvib import regular
    from symvib.numeric.prepared import NotPrepared, Prepared, prepared_of
    from symvib.numeric.scene import declared_domain

    try:
        return prepared_of(scene, base.kernels)
    except NotPrepared:   # a user curve whose record lacks these values: regular on its declared domain,
        lo, hi = declared_domain(scene)   # as the sweep's compiled rows take it (the base's domain is regular)
        scale = float(base.kernels.q_scale_scalar(*scene.param_values))
        return Prepared(base.kernels, regular.RunDomain(lo, hi, scale, regular.reference_point(lo, hi, scale), False))


def row_values(result, log_events: int) -> tuple:
    """``(summary, flights, log)`` of a :class:`~symvib.numeric.events.Result`: its summary row (columns
    :class:`~symvib.numeric.layout.Summary`, as the compiled sweep loop writes them), its :data:`COLUMNS`
    as a dict, and its first ``log_events`` events as rows of
    :class:`~symvib.numeric.layout.EventColumn` (zeros past its events)."""
    budget, stats = result.energy_budget, result.stats
    codes = [EVENT_KINDS.index(e.kind.value) for e in result.events]
    summary = np.zeros(len(Summary))
    summary[Summary.status] = STATUSES.index(result.status.value)
    summary[Summary.events] = len(codes)
    for name, code in _COUNTED.items():
        summary[Summary[name]] = codes.count(int(code))
    summary[[Summary.t_final, Summary.q_final, Summary.qdot_final]] = (result.t_final, result.q_final,
                                                                        result.qdot_final)
    summary[[Summary.friction_work, Summary.impact_loss, Summary.E0, Summary.E_final]] = (
        budget.friction_work, budget.impact_loss, budget.initial, budget.final)
    summary[Summary.zeno_ratio] = result.zeno.ratio if result.zeno is not None else 0.0
    summary[Summary.t_err] = stats.get("t_err", np.nan)
    landing = budget.landing_loss   # None: the run never landed (NaN where it failed before it could)
    if landing is None:
        landing = np.nan if result.status.is_error else 0.0
    flown = {"flights": int(stats.get("flights", 0)), "landings": int(stats.get("landings", 0)),
             "landing_loss": float(landing)}
    log = np.zeros((log_events, len(EventColumn)))
    for j, (code, e) in enumerate(zip(codes[:log_events], result.events)):
        log[j] = (code, e.t, e.q, e.qdot_before, e.qdot_after, e.energy, e.t_err)
    return summary, flown, log


def follow_rows(spec, values, columns: dict, log, backend: str = "auto") -> dict:
    """Follow the flights of a chunk's rows that ended ``left_curve`` (a sweep of unilateral scenes).

    Parameters
    ----------
    spec : SweepSpec
        The sweep (its base scene unilateral).
    values : sequence of ndarray
        The chunk's varied values, one array per axis.
    columns : dict
        The chunk's columns as the compiled loop left them (``status`` and the other summary
        columns, by name): the followed rows' values are replaced in place.
    log : ndarray or None
        The chunk's event log (``(rows, log_events, EVENT_WIDTH)``), replaced in place for the
        followed rows; None when no events are logged.
    backend : {"auto", "numba", "python"}
        The sweep's backend: the followed rows' sliding stretches run on it (``"auto"`` as the
        sweep resolves it, :func:`~symvib.numeric.backends.resolve_backend`; on numba the curve's
        single-scene engine is compiled too, once, and cached as the sweep's is).

    Returns
    -------
    dict
        The :data:`COLUMNS` of the chunk (0 on the rows that never left the curve).

    Raises
    ------
    SceneError
        Where the driver refuses a row's run (naming the field), with ``(sweep row N)`` appended.
    """
    from symvib.numeric.backends import resolve_backend
    from symvib.numeric.driver import simulate
    from symvib.numeric.prepared import prepared_of
    from symvib.numeric.scene import SceneError

    status = columns["status"]
    n = len(status)
    out = {name: np.zeros(n, dtype=np.int64 if name in INTEGER_COLUMNS else np.float64) for name in COLUMNS}
    rows = np.flatnonzero(status == StatusCode.LEFT_CURVE)
    if not rows.size:
        return out
    backend = resolve_backend(backend)
    base = prepared_of(spec.scene)
    varies = any(a.field.startswith("parameters.") for a in spec.axes)
    for i in rows:
        try:
            scene = scene_of_row(spec.scene, spec.axes, values, int(i))
            result = simulate(scene, nodes=spec.nodes, samples=False, backend=backend,
                              prepared=_row_prepared(base, scene, varies))
        except SceneError as exc:   # (a refusal of the row's run, as simulate refuses it: naming the row)
            raise SceneError(exc.field, f"{exc.reason} (sweep row {int(columns['row'][i])})") from None
        summary, flown, events = row_values(result, spec.log_events)
        for column in Summary:
            columns[column.name][i] = summary[column]
        for name, value in flown.items():
            out[name][i] = value
        if log is not None:
            log[i] = events
    return out
