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
symvib.scene.SceneError: physics.restitution: must be in [0, 1] (1 = ideally elastic, 0 = plastic), got 1.5
"""
from __future__ import annotations

import dataclasses
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from . import expr as _expr
from .shapes import CATALOGUE, Shape

__all__ = ["Scene", "SceneError", "load_scene", "scene_from_dict", "DEFAULT_T_MAX", "DEFAULT_MAX_EVENTS"]

#: Default time bound of a run, in seconds.
DEFAULT_T_MAX = 1000.0
#: Default bound on the number of events of a run.
DEFAULT_MAX_EVENTS = 100_000
#: Standard gravity, the default of ``physics.g``.
STANDARD_GRAVITY = 9.81
#: Default mass, kilograms.
DEFAULT_MASS = 1.0

_SECTIONS = {
    "curve": {"shape", "x", "z", "q", "name", "domain", "h", "alpha", "q_scale", "params"},
    "parameters": None,  # free names: the curve's symbols
    "physics": {"g", "m", "mu", "alpha0", "restitution"},
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
    if CATALOGUE.get(sh.name) == sh:
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
        contact = getattr(self, "contact", None)  # physics.contact, where the driver's Scene has it
        if contact is not None:
            out["physics"]["contact"] = contact
        limiters = {k: v for k, v in (("left", self.left), ("right", self.right)) if v is not None}
        if limiters:
            out["limiters"] = limiters
        return out


def _finite(value, field):
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SceneError(field, f"must be a number, got {value!r}")
    if not math.isfinite(value):
        raise SceneError(field, f"must be finite, got {value}")
    return float(value)


def _validate(s: Scene) -> None:
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
            raise SceneError(f"parameters.{n}", f"must be positive, got {v}")
    if not _finite(s.g, "physics.g") > 0:
        raise SceneError("physics.g", f"must be positive, got {s.g}")
    if not _finite(s.m, "physics.m") > 0:
        raise SceneError("physics.m", f"must be positive, got {s.m}")
    if _finite(s.mu, "physics.mu") < 0:
        raise SceneError("physics.mu", f"friction coefficient must be >= 0, got {s.mu}")
    k = _finite(s.k, "physics.restitution")
    if not 0.0 <= k <= 1.0:
        raise SceneError("physics.restitution", f"must be in [0, 1] (1 = ideally elastic, 0 = plastic), got {k}")
    for side in ("left", "right"):
        v = getattr(s, side)
        if v is not None:
            _finite(v, f"limiters.{side}")
    if s.left is not None and s.right is not None and not s.left < s.right:
        raise SceneError("limiters", f"left limiter ({s.left}) must be left of the right one ({s.right})")
    q0 = _finite(s.q0, "initial.q")
    _finite(s.qdot0, "initial.qdot")
    if s.left is not None and q0 < s.left:
        raise SceneError("initial.q", f"{q0} is outside the limiters: left of the left limiter at {s.left}")
    if s.right is not None and q0 > s.right:
        raise SceneError("initial.q", f"{q0} is outside the limiters: right of the right limiter at {s.right}")
    lo, hi = _domain(s)
    for label, v in (("limiters.left", s.left), ("limiters.right", s.right), ("initial.q", q0)):
        if v is not None and not lo < v < hi:
            raise SceneError(label, f"{v} is outside the curve's regular domain ({lo:.6g}, {hi:.6g})")
    if not _finite(s.t_max, "run.t_max") > 0:
        raise SceneError("run.t_max", f"must be positive, got {s.t_max}")
    if isinstance(s.max_events, bool) or not isinstance(s.max_events, int) or s.max_events < 1:
        raise SceneError("run.max_events", f"must be a positive integer, got {s.max_events!r}")


def _domain(s: Scene) -> tuple:
    values = dict(s.params)
    out = []
    for i, end in enumerate(s.shape.domain):
        text = str(end).strip()
        if text.lstrip("+-") in ("oo", "inf"):
            out.append(-math.inf if text.startswith("-") else math.inf)
        else:
            out.append(_expr.number(text, field=f"curve.domain[{i}]", symbols=values))
    return tuple(out)


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
    # Validate the expressions now (safely), so errors name the field.
    params = curve.get("params")
    names = _curve_symbols(curve, q)
    if params is None:
        params = {n: "positive" for n in names}
    elif isinstance(params, list):
        params = {n: "positive" for n in params}
    elif not isinstance(params, dict):
        raise SceneError("curve.params", "must be a list of names or a table name -> assumption")
    unknown = sorted(set(names) - set(params))
    if unknown:
        raise SceneError("curve", f"unknown symbol(s) {', '.join(unknown)} in the curve expressions "
                                  f"(declared parameters: {', '.join(params) or 'none'})")
    domain = curve.get("domain", ["-oo", "oo"])
    if not (isinstance(domain, list) and len(domain) == 2):
        raise SceneError("curve.domain", "must be a list [low, high] of expressions")
    return Shape(name=curve.get("name", "user-curve"), kind=kind, q=q, z=curve["z"], x=curve.get("x"),
                 params=dict(params), domain=tuple(str(d) for d in domain), h=curve.get("h"),
                 alpha=curve.get("alpha"), q_scale=str(curve.get("q_scale", "1")))


def _curve_symbols(curve: dict, q: str) -> list:
    """The free symbols of a user curve's expressions (parsed safely)."""
    import ast

    names = set()
    for key in ("x", "z", "h", "alpha", "q_scale"):
        text = curve.get(key)
        if text is None:
            continue
        try:
            tree = ast.parse(text.strip(), mode="eval")
        except SyntaxError as exc:
            raise SceneError(f"curve.{key}", f"not a valid expression: {exc.msg}") from None
        found = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}
        found = {n for n in found if n not in _expr.FUNCTIONS and n not in _expr.CONSTANTS}
        try:
            _expr.parse(text, symbols=found, field=f"curve.{key}")
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
            raise SceneError(key, f"unknown section or key; known: {', '.join(sorted(_SECTIONS) + sorted(_TOP))}")
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
                    raise SceneError(f"{section}.{key}", f"unknown key; known keys of [{section}]: "
                                                         f"{', '.join(sorted(keys))}")
    shape = _shape(data["curve"])
    raw = data.get("parameters", {})
    if shape.params and "parameters" not in data:
        raise SceneError("parameters", f"missing section [parameters] (curve '{shape.name}' needs "
                                       f"{', '.join(shape.params)})")
    values = {}
    for key in raw:
        if key not in shape.params:
            raise SceneError(f"parameters.{key}", f"unknown symbol: curve '{shape.name}' has parameters "
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
    )


def load_scene(path) -> Scene:
    """Read and validate a scene TOML file."""
    path = Path(path)
    try:
        with path.open("rb") as fh:
            data = tomllib.load(fh)
    except FileNotFoundError:
        raise SceneError(str(path), "no such file") from None
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(str(path), f"not valid TOML: {exc}") from None
    return scene_from_dict(data, name=data.get("name", path.stem))
