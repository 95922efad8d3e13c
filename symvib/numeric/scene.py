"""Scenes: a curve, its parameters, friction, limiters and an initial state.

A scene loads from TOML (:mod:`tomllib`) with this schema::

    name = "paper-parabola"
    [curve]
    shape = "parabola"          # a catalogue shape, or expressions instead:
    # z = "x**2/(2*p)"          # graph, coordinate x (or q = "...")
    # x = "R*(phi + sin(phi))"  # parametric: x, z and the coordinate name q
    # z = "R*(1 - cos(phi))"
    # q = "phi"
    [parameters]                # values of the curve's symbols
    p = 1.0
    [physics]
    g = 9.81
    m = 0.2
    alpha0 = 0.05               # friction angle (mu = tan alpha0), or mu = ...: one of them, not both
    restitution = 0.8
    [limiters]                  # positions in the coordinate q; either may be absent
    left = "-pi/6"
    right = "pi/4"
    [initial]
    q = 0.0
    qdot = 7.0
    [run]                       # optional bounds
    t_max = 1000.0
    max_events = 100000

Every number may be an expression (``"pi/4"``, ``"tan(0.05)"``), parsed by
:mod:`symvib.expr` (never ``eval``); limiter and initial positions may use the
curve parameters.  Validation happens at construction and every error names
its field: :class:`SceneError`.

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

import dataclasses
import math
import numbers
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from symvib import expr as _expr
from symvib.paths import UserPathError, read_user_toml, safe_stem
from symvib.shapes import CATALOGUE, CLOSED_FORMS, Shape

__all__ = ["Scene", "SceneError", "SceneNumbers", "Check", "CHECKS", "load_scene", "resolve_scene", "scene_from_dict",
           "declared_domain", "friction_coefficient", "check_numbers", "DEFAULT_T_MAX", "DEFAULT_MAX_EVENTS",
           "FIELD_UNITS", "TEXT_FIELDS", "VALUE_UNITS", "field_unit", "units_table", "packaged_scene"]

#: Default time bound of a run, in seconds.
DEFAULT_T_MAX = 1000.0
#: Default bound on the number of events of a run.
DEFAULT_MAX_EVENTS = 100_000
#: Largest ``run.max_events`` accepted: the engine's event log grows with the events (48 bytes
#: each, so 4.8 GB at this bound) and its counter is an int64.
MAX_EVENTS = 10**8
#: Values of ``physics.contact`` (physics.md, "Assumptions"): ``bilateral`` (the default, the
#: paper's model: a bead on a wire, held on both sides, N may change sign) or ``unilateral``
#: (a particle on the surface, supported only along the normal n: the run ends when N reaches 0).
CONTACTS = ("bilateral", "unilateral")
#: Standard gravity, the default of ``physics.g``.
STANDARD_GRAVITY = 9.81
#: Default mass, kilograms.
DEFAULT_MASS = 1.0
#: Longest scene or curve name, in characters.
MAX_NAME_LENGTH = 200
#: Longest scene description, in characters.
MAX_DESCRIPTION_LENGTH = 10_000

_SECTIONS = {
    "curve": {"shape", "x", "z", "q", "name", "domain", "h", "alpha", "q_scale", "params", "closed_form"},
    "parameters": None,  # free names: the curve's symbols
    "physics": {"g", "m", "mu", "alpha0", "restitution", "contact"},
    "limiters": {"left", "right"},
    "initial": {"q", "qdot"},
    "run": {"t_max", "max_events"},
}
_TOP = {"name", "description"}

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
    "physics.restitution": "1",
    "limiters.left": "[q]",
    "limiters.right": "[q]",
    "initial.q": "[q]",
    "initial.qdot": "[q]/s",
    "run.t_max": "s",
    "run.max_events": "1",
}
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


class SceneError(ValueError):
    """A scene was rejected; ``field`` names where (``"physics.restitution"``)."""

    def __init__(self, field: str, reason: str):
        self.field = field
        self.reason = reason
        super().__init__(f"{field}: {reason}")


#: Keys of ``Shape.source()`` that a scene file's ``[curve]`` table takes (``kind`` is implied by ``x``).
_CURVE_KEYS = ("name", "x", "z", "q", "domain", "h", "alpha", "q_scale", "params", "closed_form")


def _curve_dict(sh: Shape) -> dict:
    """The ``[curve]`` table of a shape: its catalogue name, or its expressions."""
    if sh.in_catalogue:
        return {"shape": sh.name}
    source = sh.source()
    return {k: source[k] for k in _CURVE_KEYS if source.get(k) is not None}


def _friction_dict(s: Scene) -> dict:
    """``{"alpha0": ...}`` when the scene's ``mu`` is ``tan(alpha0)``, else ``{"mu": ...}``."""
    if s.alpha0 is not None:
        try:
            if friction_coefficient(s.alpha0) == s.mu:
                return {"alpha0": s.alpha0}
        except SceneError:
            pass
    return {"mu": s.mu}


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
    alpha0 = _finite(alpha0, field)
    if not 0 <= alpha0 < math.pi / 2:
        raise SceneError(field, f"friction angle must be in [0, pi/2) radians, got {alpha0}")
    return math.tan(alpha0)


@dataclass(frozen=True)
class Scene:
    """A validated scene (immutable).  Build with :func:`load_scene`,
    :func:`scene_from_dict` or :meth:`replace`.

    Attributes
    ----------
    name : str
    shape : Shape
        The curve (a catalogue shape or a user curve's data).
    params : tuple of (str, float)
        Values of the curve parameters, in the curve's order.
    g, m, mu, k : float
        Gravity, mass, friction coefficient ``mu = tan(alpha0)``, restitution.
    left, right : float or None
        Limiter positions in ``q``.
    q0, qdot0 : float
        Initial state.
    t_max : float
    max_events : int
    contact : {"bilateral", "unilateral"}
        Whether the curve holds the particle on both sides (a bead on a wire) or
        only pushes it along the normal ``n = (-sin alpha, cos alpha)`` (a particle
        on top of a graph; for a parametric curve, on the left of the direction
        of increasing ``q``), :data:`CONTACTS`.
    """

    name: str
    shape: Shape
    params: tuple
    g: float
    m: float
    mu: float
    k: float
    left: float | None
    right: float | None
    q0: float
    qdot0: float
    t_max: float = DEFAULT_T_MAX
    max_events: int = DEFAULT_MAX_EVENTS
    alpha0: float | None = field(default=None, compare=False)
    contact: str = "bilateral"

    def __post_init__(self):
        _validate(self)

    @property
    def param_values(self) -> tuple:
        """The parameter values in the curve's order (kernel argument order)."""
        return tuple(v for _, v in self.params)

    @property
    def param_dict(self) -> dict:
        return dict(self.params)

    def replace(self, **changes) -> Scene:
        """A copy with fields changed (validated again).

        ``params`` may be given as a dict of the names to change.
        """
        if isinstance(changes.get("params"), dict):
            merged = dict(self.params)
            unknown = set(changes["params"]) - set(merged)
            if unknown:
                raise SceneError(f"parameters.{sorted(unknown)[0]}",
                                 f"not a parameter of curve '{self.shape.name}' (it has: {', '.join(merged)})")
            merged.update(changes["params"])
            changes["params"] = tuple(merged.items())
        if "mu" in changes and "alpha0" not in changes:
            changes["alpha0"] = None
        if "alpha0" in changes and changes["alpha0"] is not None and "mu" not in changes:
            changes["mu"] = friction_coefficient(changes["alpha0"])
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict:
        """The scene as TOML-ready data: ``scene_from_dict(s.to_dict()) == s``.

        A catalogue shape is written by name, any other curve by the keys of a
        scene file's ``[curve]`` (``z``, ``x``, ``q``, ``name``, ``domain``,
        ``h``, ``alpha``, ``q_scale``, ``params``), so user curves round-trip too
        (sweep manifests and Dask tasks carry scenes this way).  The friction
        angle ``alpha0`` is written when the scene was given one (so it survives
        the round trip), else ``mu``.
        """
        sh = self.shape
        out = {"name": self.name, "curve": _curve_dict(sh), "parameters": dict(self.params),
               "physics": {"g": self.g, "m": self.m, **_friction_dict(self), "restitution": self.k},
               "initial": {"q": self.q0, "qdot": self.qdot0},
               "run": {"t_max": self.t_max, "max_events": self.max_events}}
        out["physics"]["contact"] = self.contact
        limiters = {k: v for k, v in (("left", self.left), ("right", self.right)) if v is not None}
        if limiters:
            out["limiters"] = limiters
        return out


def _show(value) -> str:
    """A number as plain text for messages (``2.0``, never ``np.float64(2.0)``)."""
    if isinstance(value, numbers.Integral) and not isinstance(value, bool):
        text = str(int(value))
        return text if len(text) <= _expr.MAX_INT_DIGITS else f"an integer of {len(text)} digits"
    if isinstance(value, numbers.Real):
        return repr(float(value))
    text = repr(value)
    return text if len(text) <= MAX_NAME_LENGTH else text[:MAX_NAME_LENGTH] + "..."


def _finite(value, field):
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise SceneError(field, f"must be a number, got {_show(value)}")
    try:
        result = float(value)
    except OverflowError:
        raise SceneError(field, f"number too large: {_show(value)}") from None
    if not math.isfinite(result):
        raise SceneError(field, f"must be finite, got {_show(value)}")
    return result


def _check_name(value, field):
    """A scene or curve name: one line of printable text of at most MAX_NAME_LENGTH characters."""
    if not isinstance(value, str):
        raise SceneError(field, f"must be a string, got {type(value).__name__}")
    if not value.strip():
        raise SceneError(field, "must not be empty")
    if len(value) > MAX_NAME_LENGTH:
        raise SceneError(field, f"is {len(value)} characters long; at most {MAX_NAME_LENGTH} are accepted")
    if not value.isprintable():
        raise SceneError(field, f"must be one line of printable text, got {_show(value)}")


def _key(key) -> str:
    """A TOML key as it may appear in a field name: one printable line, not too long."""
    text = str(key)
    if not text.isprintable():
        text = repr(text)[1:-1]
    return text if len(text) <= MAX_NAME_LENGTH else text[:MAX_NAME_LENGTH] + "..."


def _check_identifier(value, field, what):
    """A coordinate or parameter name: a plain identifier that is not a function or constant."""
    if not isinstance(value, str):
        raise SceneError(field, f"{what} must be a string, got {type(value).__name__}")
    if not value.isidentifier() or value.startswith("_") or len(value) > MAX_NAME_LENGTH:
        raise SceneError(field, f"{what} must be an identifier (letters, digits, _; not starting with _ or "
                                f"a digit; at most {MAX_NAME_LENGTH} characters), got {_show(value)}")
    if value in _expr.FUNCTIONS or value in _expr.CONSTANTS:
        raise SceneError(field, f"{what} {value!r} is the name of a function or constant")


def _validate(s: Scene) -> None:
    _check_name(s.name, "name")
    if not isinstance(s.shape, Shape):
        raise SceneError("curve", "must be a catalogue shape or a curve definition")
    declared = list(s.shape.params)
    given = [n for n, _ in s.params]
    for n in given:
        if n not in declared:
            raise SceneError(f"parameters.{n}", f"unknown symbol: curve '{s.shape.name}' has parameters "
                                                f"{', '.join(declared) or 'none'}")
    for n in declared:
        if n not in given:
            raise SceneError(f"parameters.{n}", f"missing: curve '{s.shape.name}' needs a value for {n}")
    check_numbers(SceneNumbers.of(s))


class SceneNumbers:
    """The numbers of one scene, or of many as columns, as :data:`CHECKS` read them.

    For one scene (:meth:`of`) every attribute is the scene's value (``left``
    and ``right`` may be ``None``; ``has_left`` says whether there is one) and
    ``domain`` is computed when a check first reads it
    (:func:`declared_domain`), so its errors come in their order.  For many
    scenes (a sweep's rows, :mod:`symvib.numeric.sweep.rows`) the attributes
    are NumPy columns of equal length or single values, and ``domain`` is
    ``(lo, hi)`` as values or columns.

    Parameters
    ----------
    params : dict
        Parameter name -> value (or column).
    kinds : dict
        Parameter name -> assumption (``"positive"``, ...), the curve's.
    domain : tuple or callable
        ``(lo, hi)``, or a function returning it (called once, when first read).
    """

    NAMES = ("g", "m", "mu", "k", "has_left", "left", "has_right", "right", "q0", "qdot0", "t_max",
             "max_events", "contact")

    def __init__(self, *, params: dict, kinds: dict, domain, **values):
        missing = set(self.NAMES) - set(values)
        if missing or set(values) - set(self.NAMES):
            raise TypeError(f"SceneNumbers takes {', '.join(self.NAMES)}")
        self.__dict__.update(values)
        self.params, self.kinds, self._domain = params, kinds, domain

    @classmethod
    def of(cls, s: Scene) -> SceneNumbers:
        """The numbers of scene ``s`` (its domain computed on first use)."""
        return cls(params=dict(s.params), kinds=dict(s.shape.params), domain=lambda: declared_domain(s),
                   g=s.g, m=s.m, mu=s.mu, k=s.k, has_left=s.left is not None, left=s.left,
                   has_right=s.right is not None, right=s.right, q0=s.q0, qdot0=s.qdot0, t_max=s.t_max,
                   max_events=s.max_events, contact=s.contact)

    @property
    def domain(self) -> tuple:
        """``(lo, hi)``: the curve's declared domain for these parameter values."""
        if callable(self._domain):
            self._domain = self._domain()
        return self._domain

    def row(self, i: int) -> SceneNumbers:
        """The numbers of scene ``i`` of columns (single values are shared by every row)."""
        def pick(v):
            return v[i] if hasattr(v, "__len__") and not isinstance(v, str) else v

        return SceneNumbers(params={n: pick(v) for n, v in self.params.items()}, kinds=self.kinds,
                            domain=lambda: tuple(pick(v) for v in self.domain),
                            **{n: pick(getattr(self, n)) for n in self.NAMES})


@dataclass(frozen=True)
class Check:
    """One check of a scene's numbers: where it applies, what it tests and what it says.

    ``value``, ``test`` and ``when`` take a :class:`SceneNumbers`.  They use
    arithmetic, comparisons, ``&`` and ``|`` only, so they hold for one scene
    and, element-wise, for columns of many (a sweep's rows).  ``test`` ``None``
    means: ``value`` must be a finite number (for one scene the type is checked
    too, :func:`_finite`).  ``reason`` gives the message for one scene: a text
    (then ``", got VALUE"`` follows) or a function of its numbers.
    """

    field: str
    value: Callable
    test: Callable | None = None
    reason: str | Callable = "must be finite"
    when: Callable | None = None

    def message(self, n: SceneNumbers) -> str:
        """The reason this check fails for the one scene ``n``."""
        if callable(self.reason):
            return self.reason(n)
        return f"{self.reason}, got {_show(self.value(n))}"


def _positive_integer(v):
    """``v >= 1`` and whole: a Python ``int`` for one scene, whole numbers in a float column."""
    if isinstance(v, numbers.Number) or not hasattr(v, "dtype"):
        return isinstance(v, numbers.Integral) and not isinstance(v, bool) and v >= 1
    return (v % 1 == 0) & (v >= 1)


def _attr(name: str) -> Callable:
    return lambda n: getattr(n, name)


def _finite_check(field: str, name: str, when=None) -> Check:
    return Check(field, _attr(name), when=when)


def _limit_reason(side: str) -> Callable:
    where = "left of the left" if side == "left" else "right of the right"
    return lambda n: (f"{_show(float(n.q0))} is outside the limiters: {where} limiter at "
                      f"{_show(getattr(n, side))}")


def _domain_check(field: str, name: str, when=None) -> Check:
    def test(n):
        lo, hi = n.domain
        v = getattr(n, name)
        return (lo < v) & (v < hi)

    def reason(n):
        lo, hi = n.domain
        v = getattr(n, name)
        return f"{_show(float(v) if name == 'q0' else v)} is outside the curve's regular domain ({lo:.6g}, {hi:.6g})"

    return Check(field, _attr(name), test, reason, when)


def _parameter_checks(n: SceneNumbers) -> list:
    out = []
    for name in n.params:
        value = (lambda name: lambda n: n.params[name])(name)
        out.append(Check(f"parameters.{name}", value))
        if n.kinds.get(name, "positive") == "positive":
            out.append(Check(f"parameters.{name}", value, lambda n, value=value: value(n) > 0, "must be positive"))
    return out


_has_left, _has_right = _attr("has_left"), _attr("has_right")

#: The checks of a scene's numbers after its parameters', in the order they are made
#: (:func:`check_numbers`); a sweep applies the same to its rows (:mod:`symvib.numeric.sweep.rows`).
CHECKS = (
    _finite_check("physics.g", "g"),
    Check("physics.g", _attr("g"), lambda n: n.g > 0, "must be positive"),
    _finite_check("physics.m", "m"),
    Check("physics.m", _attr("m"), lambda n: n.m > 0, "must be positive"),
    _finite_check("physics.mu", "mu"),
    Check("physics.mu", _attr("mu"), lambda n: n.mu >= 0, "friction coefficient must be >= 0"),
    _finite_check("physics.restitution", "k"),
    Check("physics.restitution", lambda n: float(n.k), lambda n: (n.k >= 0) & (n.k <= 1),
          "must be in [0, 1] (1 = ideally elastic, 0 = plastic)"),
    _finite_check("limiters.left", "left", when=_has_left),
    _finite_check("limiters.right", "right", when=_has_right),
    Check("limiters", _attr("left"), lambda n: n.left < n.right,
          lambda n: f"left limiter ({_show(n.left)}) must be left of the right one ({_show(n.right)})",
          when=lambda n: n.has_left & n.has_right),
    _finite_check("initial.q", "q0"),
    _finite_check("initial.qdot", "qdot0"),
    Check("initial.q", _attr("q0"), lambda n: n.q0 >= n.left, _limit_reason("left"), when=_has_left),
    Check("initial.q", _attr("q0"), lambda n: n.q0 <= n.right, _limit_reason("right"), when=_has_right),
    _domain_check("limiters.left", "left", when=_has_left),
    _domain_check("limiters.right", "right", when=_has_right),
    _domain_check("initial.q", "q0"),
    _finite_check("run.t_max", "t_max"),
    Check("run.t_max", _attr("t_max"), lambda n: n.t_max > 0, "must be positive"),
    Check("physics.contact", _attr("contact"), lambda n: n.contact in CONTACTS,
          lambda n: f"must be one of {', '.join(map(repr, CONTACTS))}, got {_show(n.contact)}"),
    Check("run.max_events", _attr("max_events"), lambda n: _positive_integer(n.max_events),
          "must be a positive integer"),
    Check("run.max_events", _attr("max_events"), lambda n: n.max_events <= MAX_EVENTS,
          f"at most {MAX_EVENTS} (scene.MAX_EVENTS)"),
)


def checks(n: SceneNumbers) -> list:
    """Every check of the numbers ``n``, in order: the parameters', then :data:`CHECKS`."""
    return _parameter_checks(n) + list(CHECKS)


def check_numbers(n: SceneNumbers) -> None:
    """Make every check (:func:`checks`) of one scene's numbers; the first that fails raises.

    Raises
    ------
    SceneError
        Naming the field of the first failing check.

    Examples
    --------
    >>> s = scene_from_dict({"curve": {"shape": "parabola"}, "parameters": {"p": 1},
    ...     "physics": {"mu": 0, "restitution": 1}, "initial": {"q": 0, "qdot": 1}})
    >>> n = SceneNumbers.of(s)
    >>> n.k = 1.5
    >>> check_numbers(n)
    Traceback (most recent call last):
    ...
    symvib.numeric.scene.SceneError: physics.restitution: must be in [0, 1] (1 = ideally elastic, 0 = plastic), got 1.5
    """
    for c in checks(n):
        if c.when is not None and not c.when(n):
            continue
        if c.test is None:
            _finite(c.value(n), c.field)
        elif not c.test(n):
            raise SceneError(c.field, c.message(n))


#: Texts of an infinite end of a curve's domain (with an optional sign).
_INFINITE = ("oo", "inf")


def declared_domain(s: Scene, values=None) -> tuple:
    """The curve's declared domain ``(lo, hi)`` as floats, for the scene's parameter values
    or for ``values`` (the parameters' values in the curve's order).

    Raises
    ------
    SceneError
        Naming ``curve.domain[i]`` (or ``curve.domain`` when the ends are
        reversed), before any limiter or initial position is compared with it.

    Examples
    --------
    >>> s = scene_from_dict({"curve": {"shape": "cycloid"}, "parameters": {"R": 1},
    ...     "physics": {"mu": 0, "restitution": 1}, "initial": {"q": 0, "qdot": 1}})
    >>> [round(v, 6) for v in declared_domain(s)]
    [-3.141593, 3.141593]
    """
    names = [n for n, _ in s.params]
    values = dict(s.params) if values is None else dict(zip(names, (float(v) for v in values)))
    out = []
    for i, end in enumerate(s.shape.domain):
        text = str(end).strip()
        if text.lstrip("+-") in _INFINITE:
            out.append(-math.inf if text.startswith("-") else math.inf)
            continue
        try:
            out.append(_expr.number(text, field=f"curve.domain[{i}]", symbols=values))
        except _expr.ExpressionError as exc:
            raise SceneError(exc.field, exc.reason) from None
    lo, hi = out
    if not lo < hi:
        raise SceneError("curve.domain", f"the low end ({lo:.6g}) must be below the high end ({hi:.6g})")
    return lo, hi


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


#: The unit of an angle-valued curve parameter (its values may carry ``deg``, as any angle's).
ANGLE_UNIT = "rad"
#: Functions whose argument is an angle: a parameter found only in their arguments is one.
TRIGONOMETRIC = frozenset({"sin", "cos", "tan"})


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
        raise SceneError(field_, f"unknown unit {_show(given)}; this field is in {unit} and takes "
                                 f"{', '.join(accepted)}")
    if unit == "1":
        raise SceneError(field_, f"takes no unit (a dimensionless number), got the unit {_show(given)}")
    if unit is None:
        hint = (" (a curve parameter is an angle when the curve uses it only inside "
                f"{', '.join(sorted(TRIGONOMETRIC))} or its alpha)") if field_.startswith("parameters.") else ""
        raise SceneError(field_, f"takes no unit, got {_show(given)}; units are accepted on angles only "
                                 f"({', '.join(VALUE_UNITS['rad'])}){hint}")
    angles = ", ".join(VALUE_UNITS["rad"])
    if re.fullmatch(_UNIT_NAME, unit):
        raise SceneError(field_, f"unknown unit {_show(given)}: this field is in {unit} (SI), the one unit it "
                                 f"takes; other units are accepted on angles only ({angles})")
    raise SceneError(field_, f"takes no unit, got {_show(given)}: write the number in {unit} (SI); units are "
                             f"accepted on angles only ({angles})")


def _number(section: dict, key: str, prefix: str, symbols=None, default=None, shape: Shape | None = None):
    if key not in section:
        return default
    value = section[key]
    field_ = f"{prefix}.{key}"
    if isinstance(value, bool):
        raise SceneError(field_, f"must be a number, got {value!r}")
    if isinstance(value, (int, float)):
        return _finite(value, field_)
    if not isinstance(value, str):
        raise SceneError(field_, f"must be a number or an expression string, got {type(value).__name__}")
    text, factor = _split_unit(value, field_, field_unit(field_, shape) if shape is not None else None, symbols)
    try:
        number = _expr.number(text, field=field_, symbols=symbols)
    except _expr.ExpressionError as exc:
        raise SceneError(exc.field, exc.reason) from None
    return number if factor == 1.0 else _finite(number * factor, field_)


def _shape(curve: dict) -> Shape:
    if "shape" in curve:
        extra = set(curve) - {"shape"}
        if extra:
            raise SceneError(f"curve.{sorted(extra)[0]}", "give either shape = \"...\" or expressions, not both")
        name = curve["shape"]
        if not isinstance(name, str):
            raise SceneError("curve.shape", f"must be a string naming a catalogue shape, got {type(name).__name__}; "
                                            f"known shapes: {', '.join(sorted(CATALOGUE))}")
        if name not in CATALOGUE:
            raise SceneError("curve.shape", f"unknown shape {name!r}; known shapes: {', '.join(sorted(CATALOGUE))}")
        return CATALOGUE[name]
    if "z" not in curve:
        raise SceneError("curve", "needs shape = \"<catalogue name>\" or at least z = \"<expression>\"")
    for key, value in curve.items():
        if key != "params" and key != "domain" and not isinstance(value, str):
            raise SceneError(f"curve.{key}", f"must be a string, got {type(value).__name__}")
    closed_form = curve.get("closed_form", "auto")
    if closed_form not in CLOSED_FORMS:
        raise SceneError("curve.closed_form", f"must be one of {', '.join(map(repr, CLOSED_FORMS))} (how F_sigma is "
                                              f"found: closed-form routes briefly, all of them, or none), "
                                              f"not {closed_form!r}")
    kind = "parametric" if "x" in curve else "graph"
    q = curve.get("q", "q" if kind == "parametric" else "x")
    _check_identifier(q, "curve.q", "the coordinate")
    if "name" in curve:
        _check_name(curve["name"], "curve.name")
    # Validate the expressions now (safely), so errors name the field.
    params = curve.get("params")
    names = _curve_symbols(curve, q)
    if params is None:
        params = {n: "positive" for n in names}
    elif isinstance(params, list):
        for i, n in enumerate(params):
            _check_identifier(n, f"curve.params[{i}]", "a parameter name")
        params = {n: "positive" for n in params}
    elif not isinstance(params, dict):
        raise SceneError("curve.params", "must be a list of names or a table name -> assumption")
    for n, assumption in params.items():
        _check_identifier(n, f"curve.params.{_key(n)}", "a parameter name")
        if not isinstance(assumption, str):
            raise SceneError(f"curve.params.{n}", f"the assumption must be a string, got {type(assumption).__name__}")
    if q in params:
        raise SceneError(f"curve.params.{q}", f"the coordinate {q!r} cannot also be a parameter")
    unknown = sorted(set(names) - set(params))
    if unknown:
        raise SceneError("curve", f"unknown symbol(s) {', '.join(unknown)} in the curve expressions "
                                  f"(declared parameters: {', '.join(params) or 'none'})")
    domain = curve.get("domain", ["-oo", "oo"])
    if not (isinstance(domain, list) and len(domain) == 2):
        raise SceneError("curve.domain", "must be a list [low, high] of expressions")
    for i, end in enumerate(domain):
        _domain_end(end, f"curve.domain[{i}]", params)
    domain = [end if isinstance(end, str) else _show(_finite(end, f"curve.domain[{i}]"))
              for i, end in enumerate(domain)]
    return Shape(name=curve.get("name", "user-curve"), kind=kind, q=q, z=curve["z"], x=curve.get("x"),
                 params=dict(params), domain=tuple(str(d) for d in domain), h=curve.get("h"),
                 alpha=curve.get("alpha"), q_scale=str(curve.get("q_scale", "1")), closed_form=closed_form)


def _domain_end(end, field, params) -> None:
    """Check one end of a user curve's domain: ``oo``/``-oo``, a finite number, or an
    expression of the curve's parameters (its value is checked with the scene's values)."""
    if isinstance(end, bool) or not isinstance(end, (str, numbers.Real)):
        raise SceneError(field, f"must be a number or an expression string, got {type(end).__name__}")
    if not isinstance(end, str):
        _finite(end, field)
        return
    if end.strip().lstrip("+-") in _INFINITE:
        return
    try:
        _expr.parse(end, symbols=tuple(params), field=field)
    except _expr.ExpressionError as exc:
        raise SceneError(exc.field, exc.reason) from None


def _curve_symbols(curve: dict, q: str) -> list:
    """The free symbols of a user curve's expressions (parsed safely, :func:`symvib.expr.free_names`)."""
    names = set()
    for key in ("x", "z", "h", "alpha", "q_scale"):
        text = curve.get(key)
        if text is None:
            continue
        try:
            found = set(_expr.free_names(text, field=f"curve.{key}"))
        except _expr.ExpressionError as exc:
            raise SceneError(exc.field, exc.reason) from None
        if key in ("x", "z") and q not in found and key == "z" and "x" not in curve:
            raise SceneError("curve.z", f"does not depend on the coordinate '{q}'")
        names |= found
    names.discard(q)
    return sorted(names)


def scene_from_dict(data: dict, *, name: str | None = None) -> Scene:
    """Build and validate a scene from parsed TOML data (see the module docstring)."""
    if not isinstance(data, dict):
        raise SceneError("scene", "must be a table")
    for key in data:
        if key not in _SECTIONS and key not in _TOP:
            raise SceneError(_key(key), f"unknown section or key; known: {', '.join(sorted(_SECTIONS) + sorted(_TOP))}")
    description = data.get("description", "")
    if not isinstance(description, str) or len(description) > MAX_DESCRIPTION_LENGTH:
        raise SceneError("description", f"must be a string of at most {MAX_DESCRIPTION_LENGTH} characters")
    for section in ("curve", "physics", "initial"):
        if section not in data:
            raise SceneError(section, f"missing section [{section}]")
    for section, keys in _SECTIONS.items():
        if section not in data:
            continue
        if not isinstance(data[section], dict):
            raise SceneError(section, f"[{section}] must be a table")
        if keys is not None:
            for key in data[section]:
                if key not in keys:
                    raise SceneError(f"{section}.{_key(key)}", f"unknown key; known keys of [{section}]: "
                                                         f"{', '.join(sorted(keys))}")
    shape = _shape(data["curve"])
    raw = data.get("parameters", {})
    if shape.params and "parameters" not in data:
        raise SceneError("parameters", f"missing section [parameters] (curve '{shape.name}' needs "
                                       f"{', '.join(shape.params)})")
    values = {}
    for key in raw:
        if key not in shape.params:
            raise SceneError(f"parameters.{_key(key)}", f"unknown symbol: curve '{shape.name}' has parameters "
                                                  f"{', '.join(shape.params) or 'none'}")
        values[key] = _number(raw, key, "parameters", shape=shape)
    params = tuple((n, values[n]) if n in values else (n, None) for n in shape.params)
    for n, v in params:
        if v is None:
            raise SceneError(f"parameters.{n}", f"missing: curve '{shape.name}' needs a value for {n}")
    phys = data["physics"]
    if "mu" in phys and "alpha0" in phys:
        raise SceneError("physics", "give mu or alpha0 (mu = tan(alpha0)), not both")
    if "mu" not in phys and "alpha0" not in phys:
        raise SceneError("physics.mu", "missing: the friction coefficient mu >= 0, or the friction angle alpha0 "
                                       "(mu = tan(alpha0)); mu = 0 for a frictionless curve")
    alpha0 = _number(phys, "alpha0", "physics", shape=shape)
    if alpha0 is not None:
        mu = friction_coefficient(alpha0)
    else:
        mu = _number(phys, "mu", "physics", shape=shape)
    if "restitution" not in phys:
        raise SceneError("physics.restitution", "missing: the restitution coefficient k in [0, 1]")
    lim = data.get("limiters", {})
    ini = data["initial"]
    for key in ("q", "qdot"):
        if key not in ini:
            raise SceneError(f"initial.{key}", "missing")
    run = data.get("run", {})
    max_events = run.get("max_events", DEFAULT_MAX_EVENTS)
    if isinstance(max_events, float) and max_events.is_integer():
        max_events = int(max_events)
    return Scene(
        name=name or data.get("name", "scene"),
        shape=shape,
        params=params,
        g=_number(phys, "g", "physics", default=STANDARD_GRAVITY, shape=shape),
        m=_number(phys, "m", "physics", default=DEFAULT_MASS, shape=shape),
        mu=mu,
        alpha0=alpha0,
        k=_number(phys, "restitution", "physics", shape=shape),
        left=_number(lim, "left", "limiters", symbols=values, shape=shape),
        right=_number(lim, "right", "limiters", symbols=values, shape=shape),
        q0=_number(ini, "q", "initial", symbols=values, shape=shape),
        qdot0=_number(ini, "qdot", "initial", symbols=values, shape=shape),
        t_max=_number(run, "t_max", "run", default=DEFAULT_T_MAX, shape=shape),
        max_events=max_events,
        contact=phys.get("contact", "bilateral"),
    )


def load_scene(path) -> Scene:
    """Read and validate a scene TOML file.

    Raises
    ------
    SceneError
        When the file is missing, not a regular file, larger than
        ``symvib.paths.MAX_INPUT_BYTES``, not UTF-8 or not TOML (``field`` is
        then the path), or not a valid scene.
    """
    path = Path(path)
    try:
        data = read_user_toml(path, "scene file")
    except UserPathError as exc:
        raise SceneError(_key(exc.path), exc.reason) from None
    stem = path.stem if path.stem.isprintable() and len(path.stem) <= MAX_NAME_LENGTH else safe_stem(path.stem)
    return scene_from_dict(data, name=data.get("name", stem))


def resolve_scene(text: str) -> Scene:
    """The scene of a file path, or of a packaged scene's name (``"paper-parabola"``).

    Raises
    ------
    SceneError
        When ``text`` is neither an existing file nor a packaged scene, or the scene is not valid.
    """
    path = Path(text)
    if path.exists() or text.endswith(".toml"):
        return load_scene(path)
    return packaged_scene(text)


def packaged_scene(name: str) -> Scene:
    """The packaged scene ``name`` (a file of ``symvib/scenes``), whatever the current folder holds.

    Raises
    ------
    SceneError
        When there is no packaged scene of that name.
    """
    from importlib import resources

    packaged = resources.files("symvib") / "scenes" / f"{name}.toml"
    if not packaged.is_file():
        raise SceneError(name, "no such scene file (nor a packaged scene of that name)")
    with resources.as_file(packaged) as p:
        return load_scene(p)
