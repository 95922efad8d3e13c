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
    alpha0 = 0.05               # friction angle (mu = tan alpha0), or mu = ..., not both
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

This module is in the numeric wing: it imports neither SymPy nor NumPy.

Examples
--------
>>> s = scene_from_dict({"curve": {"shape": "circle"}, "parameters": {"R": 0.5},
...                      "physics": {"alpha0": 0.05, "restitution": 1},
...                      "limiters": {"right": "pi/4"}, "initial": {"q": "pi/12", "qdot": 7}})
>>> round(s.mu, 6), s.left, round(s.right, 6)
(0.050042, None, 0.785398)
>>> scene_from_dict({"curve": {"shape": "circle"}, "parameters": {"R": 0.5},
...                  "physics": {"restitution": 1.5}, "initial": {"q": 0, "qdot": 1}})
Traceback (most recent call last):
...
symvib.numeric.scene.SceneError: physics.restitution: must be in [0, 1] (1 = ideally elastic, 0 = plastic), got 1.5
"""
from __future__ import annotations

import dataclasses
import math
import numbers
from dataclasses import dataclass, field
from pathlib import Path

from symvib import expr as _expr
from symvib.paths import UserPathError, read_user_toml, safe_stem
from symvib.shapes import CATALOGUE, Shape

__all__ = ["Scene", "SceneError", "load_scene", "scene_from_dict", "DEFAULT_T_MAX", "DEFAULT_MAX_EVENTS"]

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
    "curve": {"shape", "x", "z", "q", "name", "domain", "h", "alpha", "q_scale", "params"},
    "parameters": None,  # free names: the curve's symbols
    "physics": {"g", "m", "mu", "alpha0", "restitution", "contact"},
    "limiters": {"left", "right"},
    "initial": {"q", "qdot"},
    "run": {"t_max", "max_events"},
}
_TOP = {"name", "description"}


class SceneError(ValueError):
    """A scene was rejected; ``field`` names where (``"physics.restitution"``)."""

    def __init__(self, field: str, reason: str):
        self.field = field
        self.reason = reason
        super().__init__(f"{field}: {reason}")


#: Keys of ``Shape.source()`` that a scene file's ``[curve]`` table takes (``kind`` is implied by ``x``).
_CURVE_KEYS = ("name", "x", "z", "q", "domain", "h", "alpha", "q_scale", "params")


def _curve_dict(sh: Shape) -> dict:
    """The ``[curve]`` table of a shape: its catalogue name, or its expressions."""
    if sh.in_catalogue:
        return {"shape": sh.name}
    source = sh.source()
    return {k: source[k] for k in _CURVE_KEYS if source.get(k) is not None}


def _friction_dict(s: "Scene") -> dict:
    """``{"alpha0": ...}`` when the scene's ``mu`` is ``tan(alpha0)``, else ``{"mu": ...}``."""
    if s.alpha0 is not None and math.tan(s.alpha0) == s.mu:
        return {"alpha0": s.alpha0}
    return {"mu": s.mu}


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

    def replace(self, **changes) -> "Scene":
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
            changes["mu"] = math.tan(_finite(changes["alpha0"], "physics.alpha0"))
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
    for n, v in s.params:
        _finite(v, f"parameters.{n}")
        if s.shape.params.get(n, "positive") == "positive" and not v > 0:
            raise SceneError(f"parameters.{n}", f"must be positive, got {_show(v)}")
    if not _finite(s.g, "physics.g") > 0:
        raise SceneError("physics.g", f"must be positive, got {_show(s.g)}")
    if not _finite(s.m, "physics.m") > 0:
        raise SceneError("physics.m", f"must be positive, got {_show(s.m)}")
    if _finite(s.mu, "physics.mu") < 0:
        raise SceneError("physics.mu", f"friction coefficient must be >= 0, got {_show(s.mu)}")
    k = _finite(s.k, "physics.restitution")
    if not 0.0 <= k <= 1.0:
        raise SceneError("physics.restitution",
                         f"must be in [0, 1] (1 = ideally elastic, 0 = plastic), got {_show(k)}")
    for side in ("left", "right"):
        v = getattr(s, side)
        if v is not None:
            _finite(v, f"limiters.{side}")
    if s.left is not None and s.right is not None and not s.left < s.right:
        raise SceneError("limiters", f"left limiter ({_show(s.left)}) must be left of the right one "
                                     f"({_show(s.right)})")
    q0 = _finite(s.q0, "initial.q")
    _finite(s.qdot0, "initial.qdot")
    if s.left is not None and q0 < s.left:
        raise SceneError("initial.q", f"{_show(q0)} is outside the limiters: left of the left limiter at "
                                      f"{_show(s.left)}")
    if s.right is not None and q0 > s.right:
        raise SceneError("initial.q", f"{_show(q0)} is outside the limiters: right of the right limiter at "
                                      f"{_show(s.right)}")
    lo, hi = _domain(s)
    for label, v in (("limiters.left", s.left), ("limiters.right", s.right), ("initial.q", q0)):
        if v is not None and not lo < v < hi:
            raise SceneError(label, f"{_show(v)} is outside the curve's regular domain ({lo:.6g}, {hi:.6g})")
    if not _finite(s.t_max, "run.t_max") > 0:
        raise SceneError("run.t_max", f"must be positive, got {_show(s.t_max)}")
    if s.contact not in CONTACTS:
        raise SceneError("physics.contact", f"must be one of {', '.join(map(repr, CONTACTS))}, got {_show(s.contact)}")
    if isinstance(s.max_events, bool) or not isinstance(s.max_events, int) or s.max_events < 1:
        raise SceneError("run.max_events", f"must be a positive integer, got {_show(s.max_events)}")
    if s.max_events > MAX_EVENTS:
        raise SceneError("run.max_events", f"at most {MAX_EVENTS} (scene.MAX_EVENTS), got {_show(s.max_events)}")


#: Texts of an infinite end of a curve's domain (with an optional sign).
_INFINITE = ("oo", "inf")


def _domain(s: Scene) -> tuple:
    """The curve's domain as floats; a SceneError naming ``curve.domain[i]`` (or ``curve.domain``
    when the ends are reversed), before any limiter or initial position is compared with it."""
    values = dict(s.params)
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


def _number(section: dict, key: str, prefix: str, symbols=None, default=None):
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
    try:
        return _expr.number(value, field=field_, symbols=symbols)
    except _expr.ExpressionError as exc:
        raise SceneError(exc.field, exc.reason) from None


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
                 alpha=curve.get("alpha"), q_scale=str(curve.get("q_scale", "1")))


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
        values[key] = _number(raw, key, "parameters")
    params = tuple((n, values[n]) if n in values else (n, None) for n in shape.params)
    for n, v in params:
        if v is None:
            raise SceneError(f"parameters.{n}", f"missing: curve '{shape.name}' needs a value for {n}")
    phys = data["physics"]
    if "mu" in phys and "alpha0" in phys:
        raise SceneError("physics", "give mu or alpha0 (mu = tan(alpha0)), not both")
    alpha0 = _number(phys, "alpha0", "physics")
    if alpha0 is not None:
        if not 0 <= alpha0 < math.pi / 2:
            raise SceneError("physics.alpha0", f"friction angle must be in [0, pi/2) radians, got {alpha0}")
        mu = math.tan(alpha0)
    else:
        mu = _number(phys, "mu", "physics", default=0.0)
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
        g=_number(phys, "g", "physics", default=STANDARD_GRAVITY),
        m=_number(phys, "m", "physics", default=DEFAULT_MASS),
        mu=mu,
        alpha0=alpha0,
        k=_number(phys, "restitution", "physics"),
        left=_number(lim, "left", "limiters", symbols=values),
        right=_number(lim, "right", "limiters", symbols=values),
        q0=_number(ini, "q", "initial", symbols=values),
        qdot0=_number(ini, "qdot", "initial", symbols=values),
        t_max=_number(run, "t_max", "run", default=DEFAULT_T_MAX),
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
