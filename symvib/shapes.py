"""The catalogue of named curve shapes, as data.

Adding a shape is adding one :class:`Shape` entry to :data:`CATALOGUE`: its
expressions (strings, parsed safely), parameters, domain, and optionally
simpler verified forms of ``h`` and ``alpha``.  No new control flow.

This module is imported by both wings: it holds only strings, and the SymPy
curve is built lazily by :meth:`Shape.curve`.

Examples
--------
>>> sorted(CATALOGUE)[:3]
['catenary', 'circle', 'cycloid']
>>> shape("cycloid").curve().alpha
phi/2
"""
from __future__ import annotations

from dataclasses import dataclass, field

__all__ = ["Shape", "CATALOGUE", "shape", "PAPER_SHAPES", "PAPER_SCENES", "CLOSED_FORMS"]

#: How a user curve's ``F_sigma`` (the antiderivative of eq. 2) is found when its kernels are first
#: generated (``curve.closed_form``): ``"auto"`` tries the closed-form routes on a short budget and
#: takes the numeric ``F_sigma`` at once where they do not answer quickly; ``"required"`` gives every
#: route its full budget and fails when none finds one; ``"never"`` takes the numeric ``F_sigma``
#: at once (:func:`symvib.codegen.generate.route_plan`).
CLOSED_FORMS = ("auto", "required", "never")


@dataclass(frozen=True)
class Shape:
    """A named curve shape.

    Attributes
    ----------
    name : str
        Catalogue key (also the generated module's name, with ``-`` -> ``_``).
    kind : {"graph", "parametric"}
    q : str
        Coordinate name.
    z : str
        ``z(q)`` (for a graph, ``f(x)``).
    x : str or None
        ``x(q)`` for a parametric shape.
    params : dict of str -> str
        Parameter names and assumptions.
    defaults : dict of str -> float
        Typical parameter values (examples, sampling, the paper's scenes).
    domain : (str, str)
        Open interval of ``q`` where the parametrization is regular.
    h, alpha : str or None
        Simpler verified forms of the metric and tangent angle.
    q_scale : str
        Characteristic length of ``q``.
    doc : str
        One line for listings and generated-module headers.
    closed_form : {"auto", "required", "never"}
        How ``F_sigma`` is found when a user curve's kernels are generated (:data:`CLOSED_FORMS`);
        part of the defining data only when not ``"auto"``.
    """

    name: str
    kind: str
    q: str
    z: str
    x: str | None = None
    params: dict = field(default_factory=dict)
    defaults: dict = field(default_factory=dict)
    domain: tuple = ("-oo", "oo")
    h: str | None = None
    alpha: str | None = None
    q_scale: str = "1"
    doc: str = ""
    q_unit: str = ""
    closed_form: str = "auto"

    def __post_init__(self):
        if self.closed_form not in CLOSED_FORMS:
            raise ValueError(f"curve.closed_form: {self.closed_form!r} is not one of {', '.join(CLOSED_FORMS)}")

    @property
    def unit(self) -> str:
        """Unit of the coordinate: ``q_unit``, else m for a graph and rad otherwise."""
        return self.q_unit or ("m" if self.kind == "graph" else "rad")

    @property
    def in_catalogue(self) -> bool:
        """Whether this is a catalogue shape as shipped: regular on its domain, its
        kernels committed in ``generated/`` (a user curve of the same name is not)."""
        return CATALOGUE.get(self.name) == self

    @property
    def module(self) -> str:
        """Name of the generated kernel module."""
        return self.name.replace("-", "_")

    def curve(self):
        """The symbolic :class:`~symvib.symbolic.curve.Curve` (imports SymPy)."""
        from symvib.symbolic import curve as _curve

        common = dict(params=self.params, name=self.name, domain=self.domain, h=self.h,
                      alpha=self.alpha, q_scale=self.q_scale)
        if self.kind == "graph":
            return _curve.graph(self.z, x=self.q, **common)
        return _curve.parametric(self.x, self.z, q=self.q, **common)

    def source(self) -> dict:
        """The defining data, as plain strings (hashed by the code generator)."""
        source = {"name": self.name, "kind": self.kind, "q": self.q, "x": self.x, "z": self.z,
                  "params": dict(self.params), "domain": list(self.domain), "h": self.h,
                  "alpha": self.alpha, "q_scale": self.q_scale}
        if self.closed_form != "auto":   # (so a curve's hash, and its cached kernels, stay as they were)
            source["closed_form"] = self.closed_form
        return source


CATALOGUE: dict[str, Shape] = {s.name: s for s in (
    Shape(
        name="parabola", kind="parametric", q="phi",
        x="p*tan(phi)", z="p*tan(phi)**2/2",
        params={"p": "positive"}, defaults={"p": 1.0},
        domain=("-pi/2", "pi/2"), h="p/cos(phi)**3", alpha="phi",
        doc="parabola x^2 = 2 p z in its tangent angle phi (paper figs. 5-11)",
    ),
    Shape(
        name="parabola-x", kind="graph", q="x", z="x**2/(2*p)",
        params={"p": "positive"}, defaults={"p": 1.0}, q_scale="p",
        doc="parabola z = x^2 / (2 p) as a graph in x",
    ),
    Shape(
        name="cycloid", kind="parametric", q="phi",
        x="R*(phi + sin(phi))", z="R*(1 - cos(phi))",
        params={"R": "positive"}, defaults={"R": 0.05},
        domain=("-pi", "pi"), h="2*R*cos(phi/2)", alpha="phi/2",
        doc="cycloid in its rolling angle phi, cusps at phi = +-pi (paper figs. 12-18)",
    ),
    Shape(
        name="circle", kind="parametric", q="phi",
        x="R*sin(phi)", z="R*(1 - cos(phi))",
        params={"R": "positive"}, defaults={"R": 0.5},
        h="R", alpha="phi",
        doc="circle of radius R, phi from the lowest point (paper figs. 19-26)",
    ),
    Shape(
        name="catenary", kind="graph", q="x", z="a*(cosh(x/a) - 1)",
        params={"a": "positive"}, defaults={"a": 1.0},
        h="cosh(x/a)", alpha="atan(sinh(x/a))", q_scale="a",
        doc="catenary z = a (cosh(x/a) - 1); F_sigma has no closed form",
    ),
    Shape(
        name="ellipse", kind="parametric", q="theta",
        x="a*sin(theta)", z="b*(1 - cos(theta))",
        params={"a": "positive", "b": "positive"}, defaults={"a": 1.0, "b": 0.5},
        domain=("-pi/2", "pi/2"), alpha="atan(b*tan(theta)/a)",
        doc="lower half of the ellipse with semi-axes a (horizontal), b (vertical), eccentric angle theta",
    ),
    Shape(
        name="quartic", kind="graph", q="x", z="x**4/(4*c**3)",
        params={"c": "positive"}, defaults={"c": 1.0}, q_scale="c",
        doc="quartic well z = x^4 / (4 c^3): zero curvature at the bottom",
    ),
)}

#: The shapes the paper treats, in its order.
PAPER_SHAPES = ("parabola", "cycloid", "circle")
#: The paper's scenes, in its order (files ``symvib/scenes/NAME.toml``): the one list the paper
#: job (:mod:`symvib.paper`), its conclusions (:mod:`symvib.paper.conclusions`) and the benchmarks read.
PAPER_SCENES = ("paper-parabola", "paper-cycloid", "paper-circle-3.8", "paper-circle-7")


def shape(name: str) -> Shape:
    """Look up a catalogue shape; the error lists the known names."""
    try:
        return CATALOGUE[name]
    except KeyError:
        raise KeyError(f"unknown shape {name!r}; known shapes: {', '.join(sorted(CATALOGUE))}") from None
