"""symvib: vibro-impact dynamics of a heavy particle on rough curves.

Two wings, and the prepare step and the paper's wing above them:

* :mod:`symvib.symbolic` (SymPy): curves, antiderivatives, the derivation, singular points;
* :mod:`symvib.codegen`: the one bridge, derived expressions -> generated kernel modules;
* :mod:`symvib.numeric` (NumPy only): kernels, the engine, the driver, sweeps, figures; it receives
  a prepared curve and imports neither SymPy nor the two modules above;
* :mod:`symvib.prepare`: a curve's kernels generated and its singular points searched once,
  recorded beside the kernels, so a later run needs no SymPy;
* :mod:`symvib.checks`: references, peer integrators, the stability suite, benchmarks;
* :mod:`symvib.paper`: the seed paper's wing: its printed equations audited, its conclusions
  checked against runs, its errata, and the ``symvib paper`` report (Markdown, HTML, PDF).

``import symvib`` imports neither SymPy nor NumPy; the names below load their
module on first use.  The four verbs:

* ``symvib.load_scene(source)``: a scene from a file, a packaged scene's name or a dict;
* ``symvib.simulate(scene)``: a :class:`~symvib.numeric.events.Result` (events, samples,
  dense output ``result.state(t)``, DataFrames ``result.events_frame()``);
* ``symvib.sweep(scene, vary)``: many scenes at once;
* ``symvib.fit(scene, observed, free=("mu", "k"))``: parameters from measured event times or a sampled trajectory;
* ``symvib.derive(curve)``: eqs. 1-2 of a curve (SymPy, imported only here).

>>> import symvib
>>> symvib.derive("circle").eom(+1)
Eq(mu*phidot**2 + phiddot + g*(mu*cos(phi) + sin(phi))/R, 0)
>>> symvib.simulate("paper-parabola", backend="python").status.value
'arrested'
"""
from __future__ import annotations

import importlib

__version__ = "0.1.0"

_LAZY = {
    "load_scene": "symvib.api",
    "simulate": "symvib.api",
    "sweep": "symvib.api",
    "fit": "symvib.api",
    "derive": "symvib.symbolic.derive",
    "graph": "symvib.symbolic.curve",
    "parametric": "symvib.symbolic.curve",
    "shape": "symvib.shapes",
    "CATALOGUE": "symvib.shapes",
    "audit": "symvib.paper.audit",
}

__all__ = sorted(_LAZY)


def __getattr__(name: str):
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'symvib' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
