"""The scene model: :class:`Scene`, a curve, its parameters, friction, limiters and an initial state.

A :class:`Scene` is immutable and always valid: it runs every check of
:mod:`symvib.numeric.scene_checks` when it is built, so a wrong value is a
:class:`~symvib.numeric.scene.SceneError` naming its field, and a copy with
fields changed (:meth:`Scene.replace`) is checked again.  Its numbers are SI
(:mod:`symvib.numeric.scene_units`); friction is the coefficient ``mu``, with
the friction angle ``alpha0`` kept when the scene was given one, and static
friction the coefficient ``mu_s >= mu`` of the rest test (or its angle
``alpha0_s``), equal to ``mu`` unless given (:attr:`Scene.mu_static`).
:meth:`Scene.to_dict` writes it back as the tables of a scene file, which
:func:`symvib.numeric.scene.scene_from_dict` reads
(:mod:`symvib.numeric.scene_files`).

This module is in the numeric wing: it imports neither SymPy nor NumPy.

Examples
--------
>>> from symvib.shapes import shape
>>> s = Scene(name="demo", shape=shape("circle"), params=(("R", 0.5),), g=9.81, m=1.0, mu=0.05, k=1.0,
...           left=None, right=0.8, q0=0.25, qdot0=7.0)
>>> s.replace(qdot0=8.0).qdot0, s.to_dict()["limiters"]
(8.0, {'right': 0.8})
>>> s.replace(k=1.5)
Traceback (most recent call last):
...
symvib.numeric.scene.SceneError: physics.restitution: must be in [0, 1] (1 = ideally elastic, 0 = plastic), got 1.5
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

from symvib.numeric.scene_checks import (
    TRIAL_NUMBERS,
    SceneError,
    SceneNumbers,
    check_name,
    check_numbers,
    finite,
)
from symvib.numeric.scene_units import friction_coefficient
from symvib.shapes import Shape

__all__ = ["Scene", "DEFAULT_T_MAX", "DEFAULT_MAX_EVENTS"]

#: Default time bound of a run, in seconds.
DEFAULT_T_MAX = 1000.0
#: Default bound on the number of events of a run.
DEFAULT_MAX_EVENTS = 100_000

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


def _static_friction_dict(s: Scene) -> dict:
    """``{}`` when the scene gives no static friction (``mu_s`` follows ``mu``), ``{"alpha0_s": ...}``
    when its ``mu_s`` is ``tan(alpha0_s)``, else ``{"mu_s": ...}``."""
    if s.mu_s is None:
        return {}
    if s.alpha0_s is not None and friction_coefficient(s.alpha0_s, "physics.alpha0_s") == s.mu_s:
        return {"alpha0_s": s.alpha0_s}
    return {"mu_s": s.mu_s}


@dataclass(frozen=True)
class Scene:
    """A validated scene (immutable).  Build with :func:`~symvib.numeric.scene.load_scene`,
    :func:`~symvib.numeric.scene.scene_from_dict` or :meth:`replace`.

    Attributes
    ----------
    name : str
    shape : Shape
        The curve (a catalogue shape or a user curve's data).
    params : tuple of (str, float)
        Values of the curve parameters, in the curve's order.
    g, m, mu, k : float
        Gravity, mass, (kinetic) friction coefficient ``mu = tan(alpha0)``, restitution.
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
        of increasing ``q``), :data:`~symvib.numeric.scene_checks.CONTACTS`.
    mu_s : float or None
        The static friction coefficient of the rest test (physics.md, "Events" 2),
        ``mu_s >= mu``; ``None`` (the default): equal to ``mu``, also after
        ``replace(mu=...)``.  :attr:`mu_static` is the value the rest test uses.
    alpha0_s : float or None
        The static friction angle, ``mu_s = tan(alpha0_s)``, kept when the scene was
        given one (a scene given both must have them agree).
    drag : float
        The air drag coefficient ``c`` of the force ``-c v |v|`` (kg/m, ``>= 0``; physics.md,
        "Air drag"); ``gamma = c / m`` enters the equations.  Default 0: no drag, and the
        scene runs, writes and reads as before drag existed.
    restitution_curve : float
        Newton's restitution of the normal velocity when a flying particle lands on the
        curve (unilateral contact; physics.md, "Flight and landing" 4), in ``[0, 1]``;
        default 0 (no bounce).
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
    mu_s: float | None = None
    alpha0_s: float | None = field(default=None, compare=False)
    drag: float = 0.0
    restitution_curve: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "restitution_curve", check_restitution_curve(self.restitution_curve))
        if self.alpha0_s is not None:
            mu_s = friction_coefficient(self.alpha0_s, "physics.alpha0_s")
            if self.mu_s is None:
                object.__setattr__(self, "mu_s", mu_s)
            elif finite(self.mu_s, "physics.mu_s") != mu_s:
                raise SceneError("physics.alpha0_s", f"gives mu_s = tan(alpha0_s) = {mu_s!r}, but mu_s = "
                                                     f"{float(self.mu_s)!r} is given too: give one of them")
        _validate(self)

    @property
    def mu_static(self):
        """The static friction coefficient the rest test uses: ``mu_s``, or ``mu`` when the
        scene gives none (physics.md, "Events" 2)."""
        return self.mu if self.mu_s is None else self.mu_s

    @property
    def param_values(self) -> tuple:
        """The parameter values in the curve's order (kernel argument order)."""
        return tuple(v for _, v in self.params)

    @property
    def param_dict(self) -> dict:
        return dict(self.params)

    def replace(self, **changes) -> Scene:
        """A copy with fields changed (validated again).

        ``params`` may be given as a dict of the names to change.  A scene without
        ``mu_s`` keeps none: its static friction follows a new ``mu``.
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
        if "mu_s" in changes and "alpha0_s" not in changes:
            changes["alpha0_s"] = None
        if "alpha0_s" in changes and changes["alpha0_s"] is not None and "mu_s" not in changes:
            changes["mu_s"] = friction_coefficient(changes["alpha0_s"], "physics.alpha0_s")
        return dataclasses.replace(self, **changes)

    def with_numbers(self, **values) -> Scene:
        """A copy with some of ``mu``, ``k``, ``qdot0``, ``q0``, ``left``, ``right`` changed (numbers; a
        fit's trial points), checked by every check of the scene's numbers
        (:func:`~symvib.numeric.scene_checks.check_numbers`) but without rebuilding the rest (the
        curve, its parameters, the sections): the copy is the one :meth:`replace` makes, and a value
        it refuses (NaN, out of range, a limiter past ``q0`` or out of the curve's domain) is refused
        with the same :class:`SceneError` naming the field.  A limiter the scene does not have cannot
        be set here.
        """
        unknown = set(values) - set(TRIAL_NUMBERS)
        if unknown:
            raise TypeError(f"with_numbers: only {', '.join(TRIAL_NUMBERS)}, got {sorted(unknown)[0]!r}")
        new = object.__new__(Scene)
        state = dict(self.__dict__)
        for name, v in values.items():
            if name in ("left", "right") and state[name] is None:
                raise SceneError(f"limiters.{name}", "the scene has no such limiter to move")
            state[name] = float(v)
        if "mu" in values:      # (as replace(mu=...): the friction angle no longer describes mu)
            state["alpha0"] = None
        new.__dict__.update(state)
        check_numbers(SceneNumbers.of(new))
        return new

    def to_dict(self) -> dict:
        """The scene as TOML-ready data: ``scene_from_dict(s.to_dict()) == s``.

        A catalogue shape is written by name, any other curve by the keys of a
        scene file's ``[curve]`` (``z``, ``x``, ``q``, ``name``, ``domain``,
        ``h``, ``alpha``, ``q_scale``, ``params``), so user curves round-trip too
        (sweep manifests and Dask tasks carry scenes this way).  The friction
        angle ``alpha0`` is written when the scene was given one (so it survives
        the round trip), else ``mu``; likewise ``alpha0_s`` or ``mu_s``, and neither
        when the scene gives no static friction (its file and outputs stay as they were).
        """
        sh = self.shape
        out = {"name": self.name, "curve": _curve_dict(sh), "parameters": dict(self.params),
               "physics": {"g": self.g, "m": self.m, **_friction_dict(self), **_static_friction_dict(self),
                           "restitution": self.k},
               "initial": {"q": self.q0, "qdot": self.qdot0},
               "run": {"t_max": self.t_max, "max_events": self.max_events}}
        out["physics"]["contact"] = self.contact
        if self.drag != 0.0:   # (a scene without drag writes what it wrote before drag existed)
            out["physics"]["drag"] = self.drag
        if self.restitution_curve != 0.0:
            out["physics"]["restitution_curve"] = self.restitution_curve
        limiters = {k: v for k, v in (("left", self.left), ("right", self.right)) if v is not None}
        if limiters:
            out["limiters"] = limiters
        return out


def check_restitution_curve(value) -> float:
    """``physics.restitution_curve`` as a float in ``[0, 1]`` (physics.md, "Flight and landing" 4),
    else a :class:`SceneError` naming the field.

    Examples
    --------
    >>> check_restitution_curve(0.5)
    0.5
    >>> try:
    ...     check_restitution_curve(2)
    ... except SceneError as exc:
    ...     print(exc.field)
    physics.restitution_curve
    """
    v = finite(value, "physics.restitution_curve")
    if not 0.0 <= v <= 1.0:
        raise SceneError("physics.restitution_curve",
                         f"must be in [0, 1] (the restitution of a landing on the curve; 0: no bounce), got {v!r}")
    return v


def _validate(s: Scene) -> None:
    check_name(s.name, "name")
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
    _check_drag(s.drag)


def _check_drag(value) -> None:
    """``physics.drag``: a finite number ``>= 0`` (kg/m), else a :class:`SceneError` naming it."""
    if not finite(value, "physics.drag") >= 0.0:
        raise SceneError("physics.drag", f"the drag coefficient c (F = -c v|v|, kg/m) must be >= 0, got {value!r}")
