"""A corpus of curves given as expressions, as a researcher writes them in a scene file.

Each :class:`Entry` is a scene's ``curve`` table (expressions, never a catalogue name),
its parameter values, a scene that runs on it and tags saying what it exercises: the
paper's three curves in user form, ``Abs``/``sign``/``sqrt``-of-square cases,
inflection points, loops (a tangent angle over more than ``2 pi``), short and long
length scales, curves whose ``F_sigma`` has no closed form.  The tests derive,
generate, whitelist, load and run every entry (``tests/test_corpus.py``), and the
random accuracy check draws its curves from here (:mod:`symvib.checks.accuracy`).

Tags (``tests/test_corpus.py`` checks each against the curve and its scene): ``graph`` /
``parametric``; ``paper`` (a paper curve in user form); ``abs`` (the geometry carries
``Abs`` or ``sign``); ``loop`` (the tangent turns by more than ``pi`` over the range the
scene can use: between its limiters, else 64 ``q_scale`` around the start); ``cut`` (over
that range the tangent points along ``-x``, where ``atan2(z', x')`` jumps by ``2 pi``:
the continuous tangent angle matters, :func:`symvib.symbolic.angle.tangent_angle`);
``inflection`` (the curvature changes sign over that range); ``short`` / ``long`` (the
chord between the limiters is below 1 cm / above 100 m); ``numeric`` (no closed-form
``F_sigma``: every route of :mod:`symvib.symbolic.integrals` ran out of its default budget
or failed its check when the corpus was last measured, so a default derivation takes
about a minute; the tests derive these with the numeric route at once); ``hint`` (the
curve gives ``h``, ``alpha`` or ``q_scale``).

Examples
--------
>>> len(CORPUS) >= 40, len({e.name for e in CORPUS}) == len(CORPUS)
(True, True)
>>> entry("paper-parabola-user").curve["x"]
'p*tan(phi)'
"""
from __future__ import annotations

from dataclasses import dataclass, field

__all__ = ["Entry", "CORPUS", "entry", "tagged"]

#: Default physics of a corpus scene (SI units).
_PHYSICS = {"g": 9.81, "m": 0.2, "mu": 0.05, "restitution": 0.8}


@dataclass(frozen=True)
class Entry:
    """One curve of the corpus and a scene on it.

    Attributes
    ----------
    name : str
    curve : dict
        The scene's ``curve`` table (``z``; ``x`` and ``q`` for a parametric curve;
        optional ``domain``, ``h``, ``alpha``, ``q_scale``, ``params``).
    parameters : dict
        Values of the curve's parameters.
    limiters : dict
        ``left`` / ``right`` (either may be missing).
    initial : dict
        ``q`` and ``qdot``.
    tags : tuple of str
    physics : dict
        Overrides of the default physics.
    run : dict
        ``t_max`` / ``max_events``.
    """

    name: str
    curve: dict
    parameters: dict
    limiters: dict
    initial: dict
    tags: tuple
    physics: dict = field(default_factory=dict)
    run: dict = field(default_factory=lambda: {"t_max": 5.0, "max_events": 200})

    def scene(self, **changes) -> dict:
        """The scene as a dict of its tables (``changes`` replace whole tables)."""
        out = {"name": f"corpus-{self.name}", "curve": {"name": self.name, **self.curve},
               "parameters": dict(self.parameters), "physics": {**_PHYSICS, **self.physics},
               "limiters": dict(self.limiters), "initial": dict(self.initial), "run": dict(self.run)}
        out.update(changes)
        return out


def _g(name, z, parameters, limiters, initial, tags, **kw):
    return Entry(name, {"z": z, **kw.pop("curve", {})}, parameters, limiters, initial, ("graph", *tags), **kw)


def _p(name, x, z, q, parameters, limiters, initial, tags, **kw):
    return Entry(name, {"x": x, "z": z, "q": q, **kw.pop("curve", {})}, parameters, limiters, initial,
                 ("parametric", *tags), **kw)


CORPUS = (
    # The paper's three curves, as a user writes them.
    _p("paper-parabola-user", "p*tan(phi)", "p*tan(phi)**2/2", "phi", {"p": 1.0},
       {"left": "-pi/6", "right": "pi/4"}, {"q": 0.0, "qdot": 7.0}, ("paper", "abs"),
       curve={"domain": ["-pi/2", "pi/2"]}),
    _p("paper-parabola-bare", "tan(phi)", "tan(phi)**2/2", "phi", {},
       {"left": -0.5, "right": 0.7}, {"q": 0.0, "qdot": 3.0}, ("paper", "abs"),
       curve={"domain": ["-pi/2", "pi/2"]}),
    _p("paper-cycloid-user", "R*(phi + sin(phi))", "R*(1 - cos(phi))", "phi", {"R": 0.5},
       {"left": "-pi/2", "right": "pi/2"}, {"q": 0.0, "qdot": 6.0}, ("paper",),
       curve={"domain": ["-pi", "pi"]}),
    _p("paper-circle-user", "R*sin(phi)", "R*(1 - cos(phi))", "phi", {"R": 0.5},
       {"left": "-pi/4", "right": "pi/3"}, {"q": 0.0, "qdot": 7.0}, ("paper",)),
    # Graphs.
    _g("parabola", "x**2/(2*p)", {"p": 1.0}, {"left": -0.5, "right": 0.6}, {"q": 0.0, "qdot": 3.0}, ()),
    _g("parabola-hinted", "x**2/(2*p)", {"p": 0.5}, {"left": -0.4, "right": 0.4}, {"q": 0.1, "qdot": 2.0},
       ("hint",), curve={"alpha": "atan(x/p)", "h": "sqrt(1 + x**2/p**2)", "q_scale": "p"}),
    _g("bowl", "R - sqrt(R**2 - x**2)", {"R": 0.5}, {"left": -0.2, "right": 0.35}, {"q": 0.1, "qdot": 3.0},
       (), curve={"domain": ["-R", "R"]}),
    _g("catenary", "a*(cosh(x/a) - 1)", {"a": 0.8}, {"left": -0.6, "right": 0.5}, {"q": 0.0, "qdot": 3.0},
       ("numeric",)),
    _g("quartic", "x**4/(4*a**3)", {"a": 0.5}, {"left": -0.6, "right": 0.6}, {"q": 0.0, "qdot": 2.0}, ("numeric",)),
    _g("double-well", "a*((x/b)**2 - 1)**2", {"a": 0.05, "b": 0.4}, {"left": -0.8, "right": 0.8},
       {"q": -0.4, "qdot": 1.5}, ("inflection", "numeric")),
    _g("double-well-bare", "(x**2 - 1)**2/4", {}, {}, {"q": -1.0, "qdot": 2.5}, ("inflection", "numeric")),
    _g("cubic", "x**3/3 - a**2*x", {"a": 0.5}, {"left": -0.9, "right": 0.9}, {"q": 0.5, "qdot": 1.0},
       ("inflection", "numeric")),
    _g("sine-track", "a*(1 - cos(x/b))", {"a": 0.1, "b": 0.2}, {}, {"q": 0.0, "qdot": 2.3},
       ("inflection", "numeric"), run={"t_max": 2.0, "max_events": 200}),
    _g("sine-track-short", "a*(1 - cos(x/b))", {"a": 0.001, "b": 0.002}, {"left": -0.004, "right": 0.0045},
       {"q": 0.0, "qdot": 0.3}, ("inflection", "numeric", "short", "hint"), run={"t_max": 2.0, "max_events": 200},
       curve={"q_scale": "b"}),  # q_scale 1 (the default) spans 80 bumps: sampling and panels need b
    _g("tilted-parabola", "x**2/(2*p) + c*x", {"p": 1.0, "c": 0.3}, {"left": -0.8, "right": 0.5},
       {"q": 0.0, "qdot": 2.0}, ()),
    _g("tan-wall", "a*tan(x/b)", {"a": 0.2, "b": 1.0}, {"left": -1.0, "right": 1.0}, {"q": 0.0, "qdot": 1.0},
       ("numeric", "inflection"), curve={"domain": ["-pi*b/2", "pi*b/2"]}),
    _g("pole-well", "-a/x", {"a": 0.1}, {"left": 0.3, "right": 2.0}, {"q": 1.0, "qdot": 0.5},
       ("numeric",), curve={"domain": [0, "oo"]}),
    _g("abs-cubed", "abs(x)**3/(3*a**2)", {"a": 0.5}, {"left": -0.7, "right": 0.7}, {"q": 0.2, "qdot": 2.0},
       ("abs", "numeric")),
    _g("x-abs-x", "x*abs(x)/(2*a) + x**2/(2*a)", {"a": 0.5}, {"left": -0.5, "right": 0.6},
       {"q": 0.3, "qdot": 1.0}, ("abs", "numeric")),
    _g("hyperbola-graph", "sqrt(x**2 + a**2) - a", {"a": 0.3}, {"left": -0.6, "right": 0.7},
       {"q": 0.0, "qdot": 2.5}, ("numeric",)),
    _g("gaussian-well", "-a*exp(-(x/b)**2)", {"a": 0.2, "b": 0.3}, {"left": -0.5, "right": 0.5},
       {"q": 0.0, "qdot": 2.0}, ("inflection", "numeric")),
    _g("log-cosh", "a*log(cosh(x/a))", {"a": 0.4}, {"left": -0.8, "right": 0.8}, {"q": 0.0, "qdot": 2.0}, ("numeric",)),
    _g("exponential-slope", "a*exp(x/a)", {"a": 0.5}, {"left": -1.0}, {"q": 0.5, "qdot": -1.0}, ("numeric",)),
    _g("witch", "a*x**2/(x**2 + b**2)", {"a": 0.3, "b": 0.5}, {"left": -0.6, "right": 0.6},
       {"q": 0.0, "qdot": 1.5}, ("inflection", "numeric")),
    _g("quadratic-quartic", "a*x**2 + b*x**4", {"a": 0.5, "b": 2.0}, {"left": -0.5, "right": 0.5},
       {"q": 0.0, "qdot": 2.0}, ("numeric",)),
    _g("tanh-step", "a*tanh(x/b)", {"a": 0.2, "b": 0.3}, {"left": -0.6, "right": 0.6}, {"q": 0.0, "qdot": 1.0},
       ("inflection", "numeric")),
    _g("washboard", "a*sin(x/b) + c*x", {"a": 0.02, "b": 0.05, "c": 0.2}, {"left": -0.4, "right": 0.4},
       {"q": 0.0, "qdot": 1.0}, ("inflection", "numeric")),
    _g("dome", "-sqrt(R**2 - x**2)", {"R": 0.5}, {"left": -0.3, "right": 0.3}, {"q": 0.0, "qdot": 1.0}, (),
       curve={"domain": ["-R", "R"]}),
    _g("half-power", "a*x**(3/2)", {"a": 0.5}, {"left": 0.2, "right": 1.5}, {"q": 1.0, "qdot": 1.0}, ("numeric",),
       curve={"domain": [0, "oo"]}),  # the curvature is infinite at 0: the left limiter keeps the run off it
    _g("parabola-micro", "x**2/(2*p)", {"p": 1e-5}, {"left": -4e-6, "right": 5e-6}, {"q": 0.0, "qdot": 0.01},
       ("short",)),
    _g("parabola-huge", "x**2/(2*p)", {"p": 800.0}, {"left": -300.0, "right": 350.0},
       {"q": 0.0, "qdot": 60.0}, ("long",), run={"t_max": 200.0, "max_events": 100}),
    _g("bowl-micro", "R - sqrt(R**2 - x**2)", {"R": 2e-6}, {"left": -1e-6, "right": 1.2e-6},
       {"q": 0.0, "qdot": 0.01}, ("short",), curve={"domain": ["-R", "R"]}),
    # Parametric curves.
    _p("circle-loop", "R*sin(q)", "R*(1 - cos(q))", "q", {"R": 0.5}, {}, {"q": 0.0, "qdot": 12.0},
       ("loop", "cut"), run={"t_max": 3.0, "max_events": 50}),
    _p("circle-across-top", "R*sin(q)", "R*(1 - cos(q))", "q", {"R": 0.5}, {"left": 2.8, "right": 3.5},
       {"q": 3.0, "qdot": 2.0}, ("cut",)),
    _p("ellipse-loop", "a*sin(q)", "b*(1 - cos(q))", "q", {"a": 0.5, "b": 0.3}, {}, {"q": 0.0, "qdot": 14.0},
       ("loop", "cut", "numeric"), run={"t_max": 3.0, "max_events": 50}),
    _p("hyperbola-cosh", "sinh(q)", "cosh(q)", "q", {}, {"left": -0.5, "right": 0.7}, {"q": 0.0, "qdot": 3.0},
       ("numeric",)),
    _p("hyperbola-scaled", "a*sinh(q)", "a*cosh(q)", "q", {"a": 0.5}, {"left": -0.8, "right": 0.6},
       {"q": 0.0, "qdot": 3.0}, ("numeric",)),
    _p("secant-sqrt", "sin(q)*sqrt(tan(q)**2 + 1)", "tan(q)**2/2", "q", {}, {"left": -0.6, "right": 0.6},
       {"q": 0.0, "qdot": 2.0}, ("abs",), curve={"domain": ["-pi/2", "pi/2"]}),
    _p("sqrt-square-x", "sqrt(q**2)*q", "q**4", "q", {}, {"left": 0.2, "right": 0.9},
       {"q": 0.5, "qdot": 1.0}, ("abs", "numeric"), curve={"domain": [0, "oo"]}),
    _p("prolate-trochoid", "q - a*sin(q)", "a*(1 - cos(q))", "q", {"a": 1.5}, {}, {"q": 0.0, "qdot": 3.0},
       ("loop", "cut", "numeric"), run={"t_max": 3.0, "max_events": 50}),
    _p("cubic-parametric", "q**3 + q", "q**2", "q", {}, {"left": -0.7, "right": 0.8}, {"q": 0.0, "qdot": 2.0},
       ("inflection", "numeric")),
    _p("spiral-arc", "exp(b*q)*sin(q)", "exp(b*q)*(1 - cos(q))", "q", {"b": 0.1}, {"left": -1.0, "right": 1.2},
       {"q": 0.0, "qdot": 4.0}, ("numeric",)),
    _p("circle-radius-param", "R*sin(t)", "-R*cos(t)", "t", {"R": 2.0}, {"left": -0.5, "right": 0.5},
       {"q": 0.2, "qdot": 0.0}, ()),
    _p("cycloid-micro", "R*(phi + sin(phi))", "R*(1 - cos(phi))", "phi", {"R": 3e-6},
       {"left": "-pi/2", "right": "pi/2"}, {"q": 0.0, "qdot": 3000.0}, ("paper", "short"),
       curve={"domain": ["-pi", "pi"]}),
    _p("circle-huge", "R*sin(phi)", "R*(1 - cos(phi))", "phi", {"R": 600.0},
       {"left": -0.4, "right": 0.5}, {"q": 0.0, "qdot": 0.1}, ("long",),
       run={"t_max": 500.0, "max_events": 100}),
)


def entry(name: str) -> Entry:
    """The corpus entry called ``name``."""
    for e in CORPUS:
        if e.name == name:
            return e
    raise KeyError(f"corpus: unknown curve {name!r}; known: {', '.join(e.name for e in CORPUS)}")


def tagged(*tags: str, without: tuple = ()) -> tuple:
    """The entries that carry every tag in ``tags`` and none in ``without``."""
    return tuple(e for e in CORPUS if set(tags) <= set(e.tags) and not set(without) & set(e.tags))
