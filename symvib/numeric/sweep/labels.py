"""Names, units (SI), descriptions and LaTeX symbols of a sweep's varied fields and summary columns.

What a labelled dataset (:mod:`symvib.numeric.sweep.labelled`) and a map
(:mod:`symvib.numeric.sweepmaps`) call a column: a varied field gets a short
readable name (``initial.qdot`` -> ``qdot0``, ``physics.mu`` -> ``mu``, a curve
parameter its own name), and every column the attributes ``units`` (SI, as
UDUNITS and pint spell them: ``1`` for a pure number), ``long_name`` and
``latex``.  Units of the coordinate ``q`` follow the curve (``rad`` for an
angle, ``m`` for a graph's ``x``): the tables write them ``{q}``.

The units of the varied fields are the scene's own table
(:data:`symvib.numeric.scene.FIELD_UNITS`, read by :func:`symvib.numeric.scene.field_unit`).

Examples
--------
>>> from symvib.numeric.scene import resolve_scene
>>> scene = resolve_scene("paper-parabola")
>>> axis_name(scene, "initial.qdot"), axis_name(scene, "physics.mu"), axis_name(scene, "parameters.p")
('qdot0', 'mu', 'p')
>>> attrs = field_attrs(scene, "initial.qdot")
>>> attrs["units"], attrs["long_name"], attrs["latex"]
('rad/s', 'initial speed', '$\\\\dot{\\\\varphi}_0$')
>>> axis_label(scene, "physics.mu")
'friction coefficient $\\\\mu$ [-]'
>>> column_attrs(scene, "friction_work")["units"]
'J'
"""
from __future__ import annotations

from symvib.numeric.layout import SUMMARY_COLUMNS
from symvib.numeric.scene import field_unit
from symvib.numeric.sweep.flights import LABELS as FLIGHT_LABELS

__all__ = ["FIELD_LABELS", "COLUMN_LABELS", "axis_name", "field_attrs", "column_attrs",
           "axis_label", "label", "unit_text", "coordinate_latex"]

#: Varied fields: dotted name -> (readable name, long name, LaTeX symbol; ``{q}`` is the coordinate's symbol).
FIELD_LABELS = {
    "initial.q": ("q0", "initial position", "{q}_0"),
    "initial.qdot": ("qdot0", "initial speed", "\\dot{{{q}}}_0"),
    "physics.mu": ("mu", "friction coefficient", "\\mu"),
    "physics.alpha0": ("alpha0", "friction angle", "\\alpha_0"),
    "physics.mu_s": ("mu_s", "static friction coefficient", "\\mu_s"),
    "physics.alpha0_s": ("alpha0_s", "static friction angle", "\\alpha_{{0s}}"),
    "physics.restitution": ("k", "restitution coefficient", "k"),
    "physics.g": ("g", "gravitational acceleration", "g"),
    "physics.m": ("m", "mass", "m"),
    "limiters.left": ("left", "left limiter", "{q}_\\mathrm{{left}}"),
    "limiters.right": ("right", "right limiter", "{q}_\\mathrm{{right}}"),
    "run.t_max": ("t_max", "time limit", "t_\\mathrm{{max}}"),
    "run.max_events": ("max_events", "event limit", "N_\\mathrm{{max}}"),
}
#: Summary columns (:data:`symvib.numeric.layout.SUMMARY_COLUMNS`), derived ones and the flight
#: columns of a sweep of unilateral scenes: name -> (long name, units, LaTeX symbol).
COLUMN_LABELS = {
    "status": ("why the run stopped (code: flag_meanings)", "1", ""),
    "events": ("number of events", "1", "N_\\mathrm{{events}}"),
    "impacts": ("number of impacts", "1", "N_\\mathrm{{impacts}}"),
    "reversals": ("number of reversals", "1", "N_\\mathrm{{reversals}}"),
    "normal_sign_changes": ("number of sign changes of the normal reaction", "1", "N_\\sigma"),
    "t_final": ("arrest (or rest, or stop) time", "s", "t_\\mathrm{{final}}"),
    "q_final": ("arrest (or rest, or stop) position", "{q}", "{q}_\\mathrm{{final}}"),
    "qdot_final": ("final speed", "{q}/s", "\\dot{{{q}}}_\\mathrm{{final}}"),
    "friction_work": ("energy lost to friction", "J", "W_\\mathrm{{friction}}"),
    "impact_loss": ("energy lost in impacts", "J", "W_\\mathrm{{impacts}}"),
    "E0": ("initial energy", "J", "E_0"),
    "E_final": ("final energy", "J", "E_\\mathrm{{final}}"),
    "zeno_ratio": ("ratio of successive bounce speeds of a Zeno accumulation (0 if none)", "1", "r_\\mathrm{{Zeno}}"),
    "t_err": ("estimated error of the final time (physics.md, Accuracy)", "s", "\\delta t_\\mathrm{{final}}"),
    "impact_share": ("share of the energy lost to impacts, W_impacts / (W_friction + W_impacts)", "1",
                     "W_\\mathrm{{impacts}} / (W_\\mathrm{{friction}} + W_\\mathrm{{impacts}})"),
}
COLUMN_LABELS.update(FLIGHT_LABELS)   # a sweep of unilateral scenes' columns (symvib.numeric.sweep.flights)
assert set(SUMMARY_COLUMNS) <= set(COLUMN_LABELS), "every summary column needs a label"
#: LaTeX of the curve coordinates' names; others are written as they are.
_GREEK = {"phi": "\\varphi", "theta": "\\theta", "psi": "\\psi", "chi": "\\chi", "alpha": "\\alpha",
          "beta": "\\beta", "s": "s"}


def coordinate_latex(scene) -> str:
    """The LaTeX symbol of the curve's coordinate (``phi`` -> ``\\varphi``)."""
    return _GREEK.get(scene.shape.q, scene.shape.q)


def _units(scene, template: str) -> str:
    return template.format(q=scene.shape.unit)


def axis_name(scene, field: str) -> str:
    """The readable name of a varied field (``qdot0``, ``mu``, a curve parameter's own name).

    A curve parameter whose name is taken by another field or a summary column
    keeps its dotted name (``parameters.k``).
    """
    if field in FIELD_LABELS:
        return FIELD_LABELS[field][0]
    name = field.split(".", 1)[1]
    taken = {n for n, _, _ in FIELD_LABELS.values()} | set(COLUMN_LABELS) | {"row", "event_log"}
    return field if name in taken else name


def field_attrs(scene, field: str) -> dict:
    """``units``, ``long_name``, ``latex`` and ``field`` (the dotted name) of a varied field."""
    q = coordinate_latex(scene)
    units = field_unit(field, scene.shape) or ""
    if field in FIELD_LABELS:
        _, long_name, latex = FIELD_LABELS[field]
    else:
        name = field.split(".", 1)[1]
        long_name = f"curve parameter {name}"
        latex = _GREEK.get(name, name)
    return {"units": units, "long_name": long_name, "latex": f"${latex.format(q=q)}$", "field": field}


def column_attrs(scene, name: str) -> dict:
    """``units``, ``long_name`` and ``latex`` of a summary (or derived) column."""
    long_name, units, latex = COLUMN_LABELS[name]
    out = {"units": _units(scene, units), "long_name": long_name}
    if latex:
        out["latex"] = f"${latex.format(q=coordinate_latex(scene))}$"
    return out


def unit_text(units: str) -> str:
    """Units as a label shows them: ``-`` for a pure number, ``m/s²`` for ``m/s^2``."""
    return "-" if units == "1" else units.replace("^2", "²")


def label(attrs: dict, *, symbol: bool = True) -> str:
    """``long name $symbol$ [units]`` of a column's attributes (for an axis or a colour bar)."""
    text = attrs["long_name"]
    if symbol and attrs.get("latex"):
        text += f" {attrs['latex']}"
    return f"{text} [{unit_text(attrs['units'])}]" if attrs["units"] else text


def axis_label(scene, field: str) -> str:
    """The axis label of a varied field: ``initial speed $\\dot{\\varphi}_0$ [rad/s]``."""
    return label(field_attrs(scene, field))
