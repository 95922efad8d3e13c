"""Scenes: a curve, its parameters, friction, limiters and an initial state.

This module is where callers take the scene's names from
(``from symvib.numeric.scene import scene_from_dict``); each concept lives in a
module of its own, and each of those imports only the ones listed before it:

1. :mod:`symvib.numeric.scene_checks`: :class:`SceneError` and every check
   that names a field (:data:`CHECKS` of a scene's numbers, :class:`SceneNumbers`,
   :func:`check_numbers`, the curve's :func:`declared_domain`).
2. :mod:`symvib.numeric.scene_units`: each field's SI unit (:data:`FIELD_UNITS`,
   :func:`field_unit`, :func:`units_table`), values with units
   (:data:`VALUE_UNITS`) and ``mu`` of a friction angle
   (:func:`friction_coefficient`).
3. :mod:`symvib.numeric.scene_model`: the :class:`Scene` itself, checked when built.
4. :mod:`symvib.numeric.scene_files`: the TOML schema of a scene file and its
   readers (:func:`scene_from_dict`, :func:`load_scene`, :func:`resolve_scene`,
   :func:`packaged_scene`).

Every number of a scene file may be an expression (``"pi/4"``,
``"tan(0.05)"``), parsed by :mod:`symvib.expr` (never ``eval``); limiter and
initial positions may use the curve parameters.  Validation happens at
construction and every error names its field: :class:`SceneError`.

Every quantity is in SI units, the coordinate ``q`` in its own (``rad`` or
``m``): :data:`FIELD_UNITS` states each field's, and ``docs/scenes.md`` shows
it (:func:`units_table`).  An angle may carry its unit after a blank
(``alpha0 = "3 deg"``, ``right = "pi/4 rad"``, ``qdot = "90 deg/s"``;
:data:`VALUE_UNITS`), any other field only its own SI unit (``t_max = "10 s"``).

This module is in the numeric wing: it imports neither SymPy nor NumPy.

Examples
--------
>>> s = scene_from_dict({"curve": {"shape": "circle"}, "parameters": {"R": 0.5},
...                      "physics": {"alpha0": 0.05, "restitution": 1},
...                      "limiters": {"right": "pi/4"}, "initial": {"q": "pi/12", "qdot": 7}})
>>> round(s.mu, 6), s.left, round(s.right, 6)
(0.050042, None, 0.785398)
>>> scene_from_dict({"curve": {"shape": "circle"}, "parameters": {"R": 0.5},
...                  "physics": {"mu": 0.1, "restitution": 1.5}, "initial": {"q": 0, "qdot": 1}})
Traceback (most recent call last):
...
symvib.numeric.scene.SceneError: physics.restitution: must be in [0, 1] (1 = ideally elastic, 0 = plastic), got 1.5
>>> scene_from_dict({"curve": {"shape": "circle"}, "parameters": {"R": 0.5},
...                  "physics": {"restitution": 1}, "initial": {"q": 0, "qdot": 1}})
Traceback (most recent call last):
...
symvib.numeric.scene.SceneError: physics.mu: missing: the friction coefficient mu >= 0, or the friction angle ...
"""
from __future__ import annotations

from symvib.numeric.scene_checks import (
    CHECKS,
    CONTACTS,
    MAX_EVENTS,
    MAX_NAME_LENGTH,
    Check,
    SceneError,
    SceneNumbers,
    check_numbers,
    checks,
    declared_domain,
)
from symvib.numeric.scene_files import (
    DEFAULT_MASS,
    MAX_DESCRIPTION_LENGTH,
    SECTIONS,
    STANDARD_GRAVITY,
    TOP_KEYS,
    load_scene,
    packaged_scene,
    resolve_scene,
    scene_from_dict,
)
from symvib.numeric.scene_model import DEFAULT_MAX_EVENTS, DEFAULT_T_MAX, Scene
from symvib.numeric.scene_units import (
    ANGLE_UNIT,
    DRAG_FIELDS,
    FIELD_UNITS,
    FLIGHT_FIELDS,
    STATIC_FRICTION_FIELDS,
    TEXT_FIELDS,
    TRIGONOMETRIC,
    VALUE_UNITS,
    angle_parameters,
    field_unit,
    friction_coefficient,
    units_table,
)

__all__ = ["Scene", "SceneError", "SceneNumbers", "Check", "CHECKS", "load_scene", "resolve_scene", "scene_from_dict",
           "declared_domain", "friction_coefficient", "check_numbers", "DEFAULT_T_MAX", "DEFAULT_MAX_EVENTS",
           "FIELD_UNITS", "STATIC_FRICTION_FIELDS", "DRAG_FIELDS", "FLIGHT_FIELDS",
           "TEXT_FIELDS", "VALUE_UNITS", "field_unit", "units_table", "packaged_scene",
           # handed on as well (callers and tests import them from here):
           "checks", "MAX_EVENTS", "CONTACTS", "MAX_NAME_LENGTH", "angle_parameters", "ANGLE_UNIT", "TRIGONOMETRIC",
           "STANDARD_GRAVITY", "DEFAULT_MASS", "MAX_DESCRIPTION_LENGTH"]

# The tables of a scene file and its top-level keys, under the names they had here.
_SECTIONS, _TOP = SECTIONS, TOP_KEYS
