"""Checks of a scene: :class:`SceneError` and every check that names a field.

A scene is refused with a :class:`SceneError` whose ``field`` says where
(``"physics.restitution"``) and whose ``reason`` says why.  This module holds
that error, the checks of names and identifiers (:func:`check_name`,
:func:`check_identifier`), of numbers (:func:`finite`), and the checks of a
scene's numbers (:data:`CHECKS`, made in order by :func:`check_numbers`), which
read a :class:`SceneNumbers`: one scene's values, or columns of many (a
sweep's rows, :mod:`symvib.numeric.sweep.rows`).  The curve's declared domain,
which the limiters and the initial position must lie inside, is evaluated here
too (:func:`declared_domain`).

It is the ground floor of the scene modules: it imports none of them.  The
scene itself is :class:`symvib.numeric.scene.Scene`, which runs these checks
when it is built; a scene's numbers carry no units here (they are SI,
:mod:`symvib.numeric.scene_units`).

This module is in the numeric wing: it imports neither SymPy nor NumPy.

Examples
--------
>>> finite(9, "physics.g")
9.0
>>> finite(float("inf"), "physics.g")
Traceback (most recent call last):
...
symvib.numeric.scene.SceneError: physics.g: must be finite, got inf
"""
from __future__ import annotations

import math
import numbers
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from types import SimpleNamespace

from symvib import expr as _expr

__all__ = ["SceneError", "SceneNumbers", "Check", "CHECKS", "checks", "check_numbers", "declared_domain",
           "finite", "show_value", "check_name", "check_identifier", "field_key", "MAX_EVENTS", "CONTACTS",
           "MAX_NAME_LENGTH", "INFINITE"]

#: Largest ``run.max_events`` accepted: the engine's event log grows with the events (48 bytes
#: each, so 4.8 GB at this bound) and its counter is an int64.
MAX_EVENTS = 10**8
#: Values of ``physics.contact`` (physics.md, "Assumptions"): ``bilateral`` (the default, the
#: paper's model: a bead on a wire, held on both sides, N may change sign) or ``unilateral``
#: (a particle on the surface, supported only along the normal n: the run ends when N reaches 0).
CONTACTS = ("bilateral", "unilateral")
#: Longest scene or curve name, in characters.
MAX_NAME_LENGTH = 200
#: Texts of an infinite end of a curve's domain (with an optional sign).
INFINITE = ("oo", "inf")


class SceneError(ValueError):
    """A scene was rejected; ``field`` names where (``"physics.restitution"``)."""

    def __init__(self, field: str, reason: str):
        self.field = field
        self.reason = reason
        super().__init__(f"{field}: {reason}")


# Its home is the module every caller imports it from (and tracebacks name): symvib.numeric.scene.
SceneError.__module__ = "symvib.numeric.scene"


def show_value(value) -> str:
    """A number as plain text for messages (``2.0``, never ``np.float64(2.0)``)."""
    if isinstance(value, numbers.Integral) and not isinstance(value, bool):
        text = str(int(value))
        return text if len(text) <= _expr.MAX_INT_DIGITS else f"an integer of {len(text)} digits"
    if isinstance(value, numbers.Real):
        return repr(float(value))
    text = repr(value)
    return text if len(text) <= MAX_NAME_LENGTH else text[:MAX_NAME_LENGTH] + "..."


def finite(value, field) -> float:
    """``value`` as a float, when it is a finite real number (not a bool); else a :class:`SceneError`
    naming ``field``."""
    if type(value) is float and math.isfinite(value):    # (the common case, without the ABC checks below)
        return value
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise SceneError(field, f"must be a number, got {show_value(value)}")
    try:
        result = float(value)
    except OverflowError:
        raise SceneError(field, f"number too large: {show_value(value)}") from None
    if not math.isfinite(result):
        raise SceneError(field, f"must be finite, got {show_value(value)}")
    return result


def check_name(value, field):
    """A scene or curve name: one line of printable text of at most MAX_NAME_LENGTH characters."""
    if not isinstance(value, str):
        raise SceneError(field, f"must be a string, got {type(value).__name__}")
    if not value.strip():
        raise SceneError(field, "must not be empty")
    if len(value) > MAX_NAME_LENGTH:
        raise SceneError(field, f"is {len(value)} characters long; at most {MAX_NAME_LENGTH} are accepted")
    if not value.isprintable():
        raise SceneError(field, f"must be one line of printable text, got {show_value(value)}")


def field_key(key) -> str:
    """A TOML key as it may appear in a field name: one printable line, not too long."""
    text = str(key)
    if not text.isprintable():
        text = repr(text)[1:-1]
    return text if len(text) <= MAX_NAME_LENGTH else text[:MAX_NAME_LENGTH] + "..."


def check_identifier(value, field, what):
    """A coordinate or parameter name: a plain identifier that is not a function or constant."""
    if not isinstance(value, str):
        raise SceneError(field, f"{what} must be a string, got {type(value).__name__}")
    if not value.isidentifier() or value.startswith("_") or len(value) > MAX_NAME_LENGTH:
        raise SceneError(field, f"{what} must be an identifier (letters, digits, _; not starting with _ or "
                                f"a digit; at most {MAX_NAME_LENGTH} characters), got {show_value(value)}")
    if value in _expr.FUNCTIONS or value in _expr.CONSTANTS:
        raise SceneError(field, f"{what} {value!r} is the name of a function or constant")


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

    NAMES = ("g", "m", "mu", "mu_s", "k", "has_left", "left", "has_right", "right", "q0", "qdot0", "t_max",
             "max_events", "contact")

    def __init__(self, *, params: dict, kinds: dict, domain, **values):
        missing = set(self.NAMES) - set(values)
        if missing or set(values) - set(self.NAMES):
            raise TypeError(f"SceneNumbers takes {', '.join(self.NAMES)}")
        self.__dict__.update(values)
        self.params, self.kinds, self._domain = params, kinds, domain

    @classmethod
    def of(cls, s) -> SceneNumbers:
        """The numbers of scene ``s``, a :class:`~symvib.numeric.scene.Scene` (its domain computed on first use)."""
        return cls(params=dict(s.params), kinds=dict(s.shape.params), domain=lambda: declared_domain(s),
                   g=s.g, m=s.m, mu=s.mu, mu_s=s.mu_static, k=s.k, has_left=s.left is not None, left=s.left,
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
    too, :func:`finite`).  ``reason`` gives the message for one scene: a text
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
        return f"{self.reason}, got {show_value(self.value(n))}"


def _positive_integer(v):
    """``v >= 1`` and whole: a Python ``int`` for one scene, whole numbers in a float column."""
    if isinstance(v, numbers.Number) or not hasattr(v, "dtype"):
        return isinstance(v, numbers.Integral) and not isinstance(v, bool) and v >= 1
    return (v % 1 == 0) & (v >= 1)


def _attr(name: str) -> Callable:
    return lambda n: getattr(n, name)


def _finite_check(field: str, name: str, when=None) -> Check:
    return Check(field, _attr(name), when=when)


def _static_friction_reason(n: SceneNumbers) -> str:
    """Why ``mu_s < mu`` is refused, and what to change."""
    return (f"static friction coefficient {show_value(n.mu_s)} is below the kinetic mu = {show_value(n.mu)}: "
            f"static friction below kinetic is not a Coulomb contact (at rest where mu_s < |tan alpha| < mu "
            f"the particle would start to slide, and kinetic friction stop it at once); give mu_s >= mu, "
            f"lower mu, or leave mu_s out (it is then equal to mu)")


def _limit_reason(side: str) -> Callable:
    where = "left of the left" if side == "left" else "right of the right"
    return lambda n: (f"{show_value(float(n.q0))} is outside the limiters: {where} limiter at "
                      f"{show_value(getattr(n, side))}")


def _domain_check(field: str, name: str, when=None) -> Check:
    def test(n):
        lo, hi = n.domain
        v = getattr(n, name)
        return (lo < v) & (v < hi)

    def reason(n):
        lo, hi = n.domain
        v = getattr(n, name)
        return (f"{show_value(float(v) if name == 'q0' else v)} is outside the curve's regular domain "
                f"({lo:.6g}, {hi:.6g})")

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
    _finite_check("physics.mu_s", "mu_s"),
    Check("physics.mu_s", _attr("mu_s"), lambda n: n.mu_s >= 0, "static friction coefficient must be >= 0"),
    Check("physics.mu_s", _attr("mu_s"), lambda n: n.mu_s >= n.mu, _static_friction_reason),
    _finite_check("physics.restitution", "k"),
    Check("physics.restitution", lambda n: float(n.k), lambda n: (n.k >= 0) & (n.k <= 1),
          "must be in [0, 1] (1 = ideally elastic, 0 = plastic)"),
    _finite_check("limiters.left", "left", when=_has_left),
    _finite_check("limiters.right", "right", when=_has_right),
    Check("limiters", _attr("left"), lambda n: n.left < n.right,
          lambda n: f"left limiter ({show_value(n.left)}) must be left of the right one ({show_value(n.right)})",
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
          lambda n: f"must be one of {', '.join(map(repr, CONTACTS))}, got {show_value(n.contact)}"),
    Check("run.max_events", _attr("max_events"), lambda n: _positive_integer(n.max_events),
          "must be a positive integer"),
    Check("run.max_events", _attr("max_events"), lambda n: n.max_events <= MAX_EVENTS,
          f"at most {MAX_EVENTS} (scene.MAX_EVENTS)"),
)


def checks(n: SceneNumbers) -> list:
    """Every check of the numbers ``n``, in order: the parameters', then :data:`CHECKS`."""
    return list(_checks_of(tuple((name, n.kinds.get(name, "positive")) for name in n.params)))


@lru_cache(maxsize=256)
def _checks_of(parameters: tuple) -> tuple:
    """:func:`checks` of numbers whose parameters are ``(name, kind)`` in order (the checks read the numbers
    they are given: built once per set of parameters)."""
    kinds = dict(parameters)
    return tuple(_parameter_checks(SimpleNamespace(params=kinds, kinds=kinds))) + CHECKS


def check_numbers(n: SceneNumbers) -> None:
    """Make every check (:func:`checks`) of one scene's numbers; the first that fails raises.

    Raises
    ------
    SceneError
        Naming the field of the first failing check.

    Examples
    --------
    >>> from symvib.numeric.scene import scene_from_dict
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
            finite(c.value(n), c.field)
        elif not c.test(n):
            raise SceneError(c.field, c.message(n))


#: The numbers a fit's trial point may change (``Scene.with_numbers``).
TRIAL_NUMBERS = ("mu", "k", "qdot0", "q0", "left", "right")


def declared_domain(s, values=None) -> tuple:
    """The curve's declared domain ``(lo, hi)`` as floats, for the parameter values of the scene ``s``
    (a :class:`~symvib.numeric.scene.Scene`) or for ``values`` (the parameters' values in the curve's order).

    Raises
    ------
    SceneError
        Naming ``curve.domain[i]`` (or ``curve.domain`` when the ends are
        reversed), before any limiter or initial position is compared with it.

    Examples
    --------
    >>> from symvib.numeric.scene import scene_from_dict
    >>> s = scene_from_dict({"curve": {"shape": "cycloid"}, "parameters": {"R": 1},
    ...     "physics": {"mu": 0, "restitution": 1}, "initial": {"q": 0, "qdot": 1}})
    >>> [round(v, 6) for v in declared_domain(s)]
    [-3.141593, 3.141593]
    """
    names = [n for n, _ in s.params]
    pairs = tuple(s.params) if values is None else tuple(zip(names, (float(v) for v in values)))
    domain = tuple(str(end) for end in s.shape.domain)
    try:   # the values bit for bit (0.0 and -0.0 apart), as the key of a loop's repeated parse
        key = tuple((n, float(v).hex()) for n, v in pairs)
    except (TypeError, ValueError):
        return _domain_at(domain, dict(pairs))
    return _remembered_domain(domain, key)


@lru_cache(maxsize=256)
def _remembered_domain(domain: tuple, key: tuple) -> tuple:
    """:func:`_domain_at` remembered by the parameters' exact values (``(name, float.hex)``):
    a loop of runs of one curve parses its domain once."""
    return _domain_at(domain, {n: float.fromhex(h) for n, h in key})


def _domain_at(domain: tuple, values: dict) -> tuple:
    """The ends ``domain`` (text) as floats at the parameter ``values`` (:func:`declared_domain`)."""
    out = []
    for i, end in enumerate(domain):
        text = str(end).strip()
        if text.lstrip("+-") in INFINITE:
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
