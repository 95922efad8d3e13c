"""Scene files: the TOML schema of a scene, its tables read into a :class:`~symvib.numeric.scene.Scene`.

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
    # mu_s = 0.08               # static friction (rest test), or alpha0_s = ...; >= mu; default: mu
    restitution = 0.8
    # drag = 0.02               # air drag c in F = -c v|v| (kg/m), >= 0; default: 0 (no drag)
    # contact = "unilateral"    # on top of the curve; restitution_curve = 0.5: of a landing (default 0)
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
:mod:`symvib.expr` (never ``eval``), and an angle may carry its unit
(``"3 deg"``; :mod:`symvib.numeric.scene_units`); limiter and initial
positions may use the curve parameters.  :func:`scene_from_dict` reads the
tables (a file's, or a dict of the same), :func:`load_scene` a file,
:func:`packaged_scene` a scene shipped in ``symvib/scenes``, and
:func:`resolve_scene` either of the last two by what the text names.  Every
error names its field (:class:`~symvib.numeric.scene.SceneError`): an unknown
table or key, a curve that is not one, a missing or unreadable value, or any
check of the scene built (:mod:`symvib.numeric.scene_checks`).

This module is the top floor of the scene modules (checks, units, the model,
then this one); callers import its names from :mod:`symvib.numeric.scene`.
It is in the numeric wing: it imports neither SymPy nor NumPy.

Examples
--------
>>> s = scene_from_dict({"curve": {"z": "x**2/(2*p)"}, "parameters": {"p": 1},
...                      "physics": {"alpha0": "3 deg", "restitution": 0.8}, "initial": {"q": 0, "qdot": 1}})
>>> s.shape.kind, round(s.mu, 6)
('graph', 0.052408)
>>> scene_from_dict({"curve": {"shape": "circle"}, "physics": {"mu": 0}, "initial": {}})
Traceback (most recent call last):
...
symvib.numeric.scene.SceneError: parameters: missing section [parameters] (curve 'circle' needs R)
"""
from __future__ import annotations

import numbers
from pathlib import Path

from symvib import expr as _expr
from symvib.numeric.scene_checks import (
    INFINITE,
    MAX_NAME_LENGTH,
    SceneError,
    check_identifier,
    check_name,
    field_key,
    finite,
    show_value,
)
from symvib.numeric.scene_model import DEFAULT_MAX_EVENTS, DEFAULT_T_MAX, Scene
from symvib.numeric.scene_units import friction_coefficient, read_number
from symvib.paths import UserPathError, read_user_toml, safe_stem
from symvib.shapes import CATALOGUE, CLOSED_FORMS, Shape

__all__ = ["scene_from_dict", "load_scene", "resolve_scene", "packaged_scene", "SECTIONS", "TOP_KEYS",
           "STANDARD_GRAVITY", "DEFAULT_MASS", "MAX_DESCRIPTION_LENGTH"]

#: Standard gravity, the default of ``physics.g``.
STANDARD_GRAVITY = 9.81
#: Default mass, kilograms.
DEFAULT_MASS = 1.0
#: Longest scene description, in characters.
MAX_DESCRIPTION_LENGTH = 10_000

#: The tables of a scene file and the keys each takes (``None``: any key, the curve's symbols).
SECTIONS = {
    "curve": {"shape", "x", "z", "q", "name", "domain", "h", "alpha", "q_scale", "params", "closed_form"},
    "parameters": None,  # free names: the curve's symbols
    "physics": {"g", "m", "mu", "alpha0", "mu_s", "alpha0_s", "restitution", "contact", "drag",
                "restitution_curve"},
    "limiters": {"left", "right"},
    "initial": {"q", "qdot"},
    "run": {"t_max", "max_events"},
}
#: The keys of a scene file outside its tables.
TOP_KEYS = {"name", "description"}


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
    check_identifier(q, "curve.q", "the coordinate")
    if "name" in curve:
        check_name(curve["name"], "curve.name")
    # Validate the expressions now (safely), so errors name the field.
    params = curve.get("params")
    names = _curve_symbols(curve, q)
    if params is None:
        params = {n: "positive" for n in names}
    elif isinstance(params, list):
        for i, n in enumerate(params):
            check_identifier(n, f"curve.params[{i}]", "a parameter name")
        params = {n: "positive" for n in params}
    elif not isinstance(params, dict):
        raise SceneError("curve.params", "must be a list of names or a table name -> assumption")
    for n, assumption in params.items():
        check_identifier(n, f"curve.params.{field_key(n)}", "a parameter name")
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
    domain = [end if isinstance(end, str) else show_value(finite(end, f"curve.domain[{i}]"))
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
        finite(end, field)
        return
    if end.strip().lstrip("+-") in INFINITE:
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
        if key not in SECTIONS and key not in TOP_KEYS:
            raise SceneError(field_key(key), f"unknown section or key; known: "
                                             f"{', '.join(sorted(SECTIONS) + sorted(TOP_KEYS))}")
    description = data.get("description", "")
    if not isinstance(description, str) or len(description) > MAX_DESCRIPTION_LENGTH:
        raise SceneError("description", f"must be a string of at most {MAX_DESCRIPTION_LENGTH} characters")
    for section in ("curve", "physics", "initial"):
        if section not in data:
            raise SceneError(section, f"missing section [{section}]")
    for section, keys in SECTIONS.items():
        if section not in data:
            continue
        if not isinstance(data[section], dict):
            raise SceneError(section, f"[{section}] must be a table")
        if keys is not None:
            for key in data[section]:
                if key not in keys:
                    raise SceneError(f"{section}.{field_key(key)}", f"unknown key; known keys of [{section}]: "
                                                         f"{', '.join(sorted(keys))}")
    shape = _shape(data["curve"])
    raw = data.get("parameters", {})
    if shape.params and "parameters" not in data:
        raise SceneError("parameters", f"missing section [parameters] (curve '{shape.name}' needs "
                                       f"{', '.join(shape.params)})")
    values = {}
    for key in raw:
        if key not in shape.params:
            raise SceneError(f"parameters.{field_key(key)}", f"unknown symbol: curve '{shape.name}' has parameters "
                                                  f"{', '.join(shape.params) or 'none'}")
        values[key] = read_number(raw, key, "parameters", shape=shape)
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
    alpha0 = read_number(phys, "alpha0", "physics", shape=shape)
    if alpha0 is not None:
        mu = friction_coefficient(alpha0)
    else:
        mu = read_number(phys, "mu", "physics", shape=shape)
    if "mu_s" in phys and "alpha0_s" in phys:
        raise SceneError("physics", "give mu_s or alpha0_s (mu_s = tan(alpha0_s)), not both")
    alpha0_s = read_number(phys, "alpha0_s", "physics", shape=shape)
    mu_s = read_number(phys, "mu_s", "physics", shape=shape) if alpha0_s is None else None
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
        g=read_number(phys, "g", "physics", default=STANDARD_GRAVITY, shape=shape),
        m=read_number(phys, "m", "physics", default=DEFAULT_MASS, shape=shape),
        mu=mu,
        alpha0=alpha0,
        k=read_number(phys, "restitution", "physics", shape=shape),
        left=read_number(lim, "left", "limiters", symbols=values, shape=shape),
        right=read_number(lim, "right", "limiters", symbols=values, shape=shape),
        q0=read_number(ini, "q", "initial", symbols=values, shape=shape),
        qdot0=read_number(ini, "qdot", "initial", symbols=values, shape=shape),
        t_max=read_number(run, "t_max", "run", default=DEFAULT_T_MAX, shape=shape),
        max_events=max_events,
        contact=phys.get("contact", "bilateral"),
        mu_s=mu_s,
        alpha0_s=alpha0_s,
        drag=read_number(phys, "drag", "physics", default=0.0, shape=shape),
        restitution_curve=read_number(phys, "restitution_curve", "physics", default=0.0, shape=shape),
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
        raise SceneError(field_key(exc.path), exc.reason) from None
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

