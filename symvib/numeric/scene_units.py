"""Units and quantities of a scene: every field's SI unit, values with units, and ``mu`` of ``alpha0``.

Every quantity of a scene is in SI units, the coordinate ``q`` in its own
(``rad`` or ``m``): :data:`FIELD_UNITS` states each field's (:func:`field_unit`
for a given curve), and ``docs/scenes.md`` shows it (:func:`units_table`).  An
angle may carry its unit after a blank (``alpha0 = "3 deg"``, ``right = "pi/4
rad"``, ``qdot = "90 deg/s"``; :data:`VALUE_UNITS`), any other field only its
own SI unit (``t_max = "10 s"``); a user curve's parameters that are angles
(:func:`angle_parameters`) take angle units too.  :func:`read_number` reads
one value of a scene file's table (a number, or an expression that may end in
a unit) as a float in SI, and :func:`friction_coefficient` is the one
conversion of a friction angle ``alpha0`` to ``mu = tan(alpha0)``.

A value that cannot be read raises a :class:`~symvib.numeric.scene.SceneError`
naming its field (:mod:`symvib.numeric.scene_checks`, the one scene module
this one imports).

This module is in the numeric wing: it imports neither SymPy nor NumPy.

Examples
--------
>>> from symvib.shapes import shape
>>> round(read_number({"alpha0": "3 deg"}, "alpha0", "physics", shape=shape("circle")), 9)
0.052359878
>>> read_number({"t_max": "10 min"}, "t_max", "run", shape=shape("circle"))
Traceback (most recent call last):
...
symvib.numeric.scene.SceneError: run.t_max: unknown unit 'min': this field is in s (SI), the one unit it takes; ...
"""
from __future__ import annotations

import math
import re

from symvib import expr as _expr
from symvib.numeric.scene_checks import SceneError, finite, show_value
from symvib.shapes import Shape

__all__ = ["FIELD_UNITS", "STATIC_FRICTION_FIELDS", "DRAG_FIELDS",
           "TEXT_FIELDS", "VALUE_UNITS", "ANGLE_UNIT", "TRIGONOMETRIC", "field_unit",
           "angle_parameters", "units_table", "friction_coefficient", "read_number"]

#: The SI unit of every scene field that is a quantity, the one table of them: the schema docs
#: (``docs/scenes.md``, written by :func:`units_table`) and the JSON of a result
#: (:meth:`symvib.numeric.events.Result.to_dict`) read it.  ``"1"`` is a dimensionless number;
#: ``"[q]"`` the unit of the curve's coordinate (:attr:`symvib.shapes.Shape.unit`: ``rad`` for the
#: angle of the catalogue's parametric shapes, ``m`` for the ``x`` of a graph).  The catalogue's
#: parameters are lengths; a user curve's parameters have the units its expressions give them
#: (``x`` and ``z`` in m).  Units may be written in values only where :data:`VALUE_UNITS` has some.
FIELD_UNITS = {
    "curve.x": "m",
    "curve.z": "m",
    "curve.h": "m/[q]",
    "curve.alpha": "rad",
    "curve.domain": "[q]",
    "curve.q_scale": "[q]",
    "parameters.*": "m",
    "physics.g": "m/s^2",
    "physics.m": "kg",
    "physics.mu": "1",
    "physics.alpha0": "rad",
    "physics.mu_s": "1",
    "physics.alpha0_s": "rad",
    "physics.restitution": "1",
    "physics.drag": "kg/m",
    "physics.restitution_curve": "1",
    "limiters.left": "[q]",
    "limiters.right": "[q]",
    "initial.q": "[q]",
    "initial.qdot": "[q]/s",
    "run.t_max": "s",
    "run.max_events": "1",
}
#: Fields of :data:`FIELD_UNITS` a scene has only when it gives static friction (``mu_s`` or
#: ``alpha0_s``): the JSON of a result of a scene without them lists no unit for them, so that its
#: outputs are what they were before static friction existed.
STATIC_FRICTION_FIELDS = ("physics.mu_s", "physics.alpha0_s")
#: Fields of :data:`FIELD_UNITS` a scene has only when it has air drag (``drag > 0``): as
#: :data:`STATIC_FRICTION_FIELDS`, the JSON of a result without drag lists no unit for them.
DRAG_FIELDS = ("physics.drag",)

#: Fields of :data:`FIELD_UNITS` only a unilateral scene lists in its result's JSON (physics.md, "Flight
#: and landing"): a bilateral scene's outputs are what they were before flights existed.
FLIGHT_FIELDS = ("physics.restitution_curve",)
#: Scene fields that are text or names, not quantities (they have no unit).
TEXT_FIELDS = ("name", "description", "curve.shape", "curve.name", "curve.q", "curve.params", "curve.closed_form",
               "physics.contact")
#: Units a value may carry (``alpha0 = "3 deg"``), by the SI unit of its field: unit -> factor to SI.
#: ``deg`` is ``pi/180`` rad.  Only angles (and angular rates) take units in values.
VALUE_UNITS = {
    "rad": {"rad": 1.0, "deg": math.pi / 180.0},
    "rad/s": {"rad/s": 1.0, "deg/s": math.pi / 180.0},
}
#: A value with a unit: an expression, blanks, then the unit (``"pi/6 rad"``, ``"3 deg"``, ``"90 deg/s"``).
_UNIT_NAME = r"[A-Za-z_][A-Za-z0-9_]*(?:/[A-Za-z_][A-Za-z0-9_]*)?"
_WITH_UNIT = re.compile(rf"(?s)(?P<value>.*?\S)\s+(?P<unit>{_UNIT_NAME})\s*")
#: The unit of an angle-valued curve parameter (its values may carry ``deg``, as any angle's).
ANGLE_UNIT = "rad"
#: Functions whose argument is an angle: a parameter found only in their arguments is one.
TRIGONOMETRIC = frozenset({"sin", "cos", "tan"})


def friction_coefficient(alpha0, field: str = "physics.alpha0") -> float:
    """The friction coefficient ``mu = tan(alpha0)`` of a friction angle ``alpha0`` (radians).

    The one conversion of the package: scene files, :meth:`Scene.replace` and
    sweeps that vary ``alpha0`` all call it.

    Raises
    ------
    SceneError
        Naming ``field`` when ``alpha0`` is not a finite number in ``[0, pi/2)``.

    Examples
    --------
    >>> round(friction_coefficient(0.05), 9)
    0.050041708
    >>> friction_coefficient(2.0)
    Traceback (most recent call last):
    ...
    symvib.numeric.scene.SceneError: physics.alpha0: friction angle must be in [0, pi/2) radians, got 2.0
    """
    alpha0 = finite(alpha0, field)
    if not 0 <= alpha0 < math.pi / 2:
        raise SceneError(field, f"friction angle must be in [0, pi/2) radians, got {alpha0}")
    return math.tan(alpha0)


def field_unit(name: str, shape: Shape | None = None) -> str | None:
    """The SI unit of scene field ``name`` (:data:`FIELD_UNITS`), for the curve ``shape``.

    ``"[q]"`` becomes the coordinate's unit (:attr:`symvib.shapes.Shape.unit`); a
    parameter's unit is ``m`` for a catalogue shape and ``None`` (not known) for
    a user curve.  Without ``shape`` the table's entry is returned as it is.

    Raises
    ------
    KeyError
        When ``name`` is not a quantity of a scene.

    Examples
    --------
    >>> from symvib.shapes import shape
    >>> field_unit("initial.qdot", shape("circle")), field_unit("limiters.left", shape("catenary"))
    ('rad/s', 'm')
    >>> field_unit("parameters.R"), field_unit("physics.g")
    ('m', 'm/s^2')
    """
    key = "parameters.*" if name.startswith("parameters.") else name
    unit = FIELD_UNITS[key]
    if shape is None:
        return unit
    if key == "parameters.*" and not shape.in_catalogue:
        return ANGLE_UNIT if name.split(".", 1)[1] in angle_parameters(shape) else None
    return unit.replace("[q]", shape.unit)


def angle_parameters(shape: Shape) -> frozenset:
    """The parameters of a user curve that are angles: every use of them in ``x`` and ``z`` lies
    inside the argument of a trigonometric function (``z = "x*tan(beta)"``), or in the tangent
    angle ``alpha`` given with the curve.  Their values may carry angle units (``"17 deg"``).

    Examples
    --------
    >>> from symvib.shapes import Shape
    >>> sorted(angle_parameters(Shape(name="ramp", kind="graph", q="x", z="x*tan(beta) + c*x**2",
    ...                               params={"beta": "real", "c": "positive"})))
    ['beta']
    """
    names = set(shape.params)
    outside, inside_ = set(), set()
    for text, angle in ((shape.x, False), (shape.z, False), (shape.alpha, True)):
        if not text:
            continue
        try:
            tree = _expr.parse(text, symbols=_expr.ANY_NAME, field="curve").tree
        except _expr.ExpressionError:
            return frozenset()
        _collect(tree, angle, names, outside, inside_)
    return frozenset(inside_ - outside)


def _collect(node: tuple, angle: bool, names: set, outside: set, inside_: set) -> None:
    """Sort the parameter names of ``node`` by whether they sit in an angle (``angle``) or not."""
    kind = node[0]
    if kind == "sym":
        if node[1] in names:
            (inside_ if angle else outside).add(node[1])
    elif kind == "bin":
        _collect(node[2], angle, names, outside, inside_)
        _collect(node[3], angle, names, outside, inside_)
    elif kind == "neg":
        _collect(node[1], angle, names, outside, inside_)
    elif kind == "call":
        for arg in node[2:]:
            _collect(arg, angle or node[1] in TRIGONOMETRIC, names, outside, inside_)


def _value_units(name: str, unit: str) -> str:
    """The units a value of field ``name`` (SI unit ``unit``) may carry, as text for the table."""
    if name.startswith("curve."):
        return "-"  # expressions of the curve, not values
    if "[q]" in unit:
        angle, length = unit.replace("[q]", "rad"), unit.replace("[q]", "m")
        return f"{', '.join(VALUE_UNITS[angle])} (an angle coordinate); {_value_units(name, length)} (a length)"
    accepted = list(VALUE_UNITS.get(unit, ()))
    if unit not in accepted and re.fullmatch(_UNIT_NAME, unit):
        accepted.append(unit)
    return ", ".join(accepted) or "-"


def units_table() -> str:
    """:data:`FIELD_UNITS` as a Markdown table (``docs/scenes.md`` holds it; a test keeps it current).

    Examples
    --------
    >>> print("\\n".join(units_table().splitlines()[:3]))
    | field | SI unit | units a value may carry |
    | --- | --- | --- |
    | `curve.x` | m | - |
    """
    lines = ["| field | SI unit | units a value may carry |", "| --- | --- | --- |"]
    lines += [f"| `{name}` | {unit} | {_value_units(name, unit)} |" for name, unit in FIELD_UNITS.items()]
    return "\n".join(lines)


def _split_unit(text: str, field_: str, unit: str | None, symbols) -> tuple[str, float]:
    """``(expression, factor to SI)`` of a value that may end in a unit (``"3 deg"``).

    A text ends in a unit when it is an expression, blanks and a name; the expression
    then must parse on its own (``"2 * pi"`` is an expression, not ``2 *`` in ``pi``).
    """
    if len(text) > _expr.MAX_LENGTH:
        return text, 1.0  # the parser's caps apply to the whole text, unit included
    match = _WITH_UNIT.fullmatch(text)
    if match is None:
        return text, 1.0
    try:
        _expr.parse(match["value"], symbols=tuple(symbols or ()), field=field_)
    except _expr.ExpressionError:
        return text, 1.0
    given = match["unit"]
    accepted = VALUE_UNITS.get(unit or "", {})
    if given in accepted or given == unit:
        return match["value"], accepted.get(given, 1.0)
    if accepted:
        raise SceneError(field_, f"unknown unit {show_value(given)}; this field is in {unit} and takes "
                                 f"{', '.join(accepted)}")
    if unit == "1":
        raise SceneError(field_, f"takes no unit (a dimensionless number), got the unit {show_value(given)}")
    if unit is None:
        hint = (" (a curve parameter is an angle when the curve uses it only inside "
                f"{', '.join(sorted(TRIGONOMETRIC))} or its alpha)") if field_.startswith("parameters.") else ""
        raise SceneError(field_, f"takes no unit, got {show_value(given)}; units are accepted on angles only "
                                 f"({', '.join(VALUE_UNITS['rad'])}){hint}")
    angles = ", ".join(VALUE_UNITS["rad"])
    if re.fullmatch(_UNIT_NAME, unit):
        raise SceneError(field_, f"unknown unit {show_value(given)}: this field is in {unit} (SI), the one unit it "
                                 f"takes; other units are accepted on angles only ({angles})")
    raise SceneError(field_, f"takes no unit, got {show_value(given)}: write the number in {unit} (SI); units are "
                             f"accepted on angles only ({angles})")


def read_number(section: dict, key: str, prefix: str, symbols=None, default=None, shape: Shape | None = None):
    """The value of ``section[key]``, field ``prefix.key``, as a finite float in SI (``default`` when absent).

    The value is a number, or an expression string (:func:`symvib.expr.number`,
    of the names ``symbols`` maps to values) that may end in a unit the field
    takes (:func:`field_unit` of ``shape``; without ``shape`` it takes none).

    Raises
    ------
    SceneError
        Naming the field when the value is not a number, not finite, not an
        expression, or carries a unit the field does not take.
    """
    if key not in section:
        return default
    value = section[key]
    field_ = f"{prefix}.{key}"
    if isinstance(value, bool):
        raise SceneError(field_, f"must be a number, got {value!r}")
    if isinstance(value, (int, float)):
        return finite(value, field_)
    if not isinstance(value, str):
        raise SceneError(field_, f"must be a number or an expression string, got {type(value).__name__}")
    text, factor = _split_unit(value, field_, field_unit(field_, shape) if shape is not None else None, symbols)
    try:
        number = _expr.number(text, field=field_, symbols=symbols)
    except _expr.ExpressionError as exc:
        raise SceneError(exc.field, exc.reason) from None
    return number if factor == 1.0 else finite(number * factor, field_)
