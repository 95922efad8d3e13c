"""The event-driven engine: the loop of one scene and of a sweep, and its physics.

Modules, each one concept (physics.md, "Events", for the algorithm):

* :mod:`~symvib.numeric.engine.state`: named state and the kernel interface;
* :mod:`~symvib.numeric.engine.laws`: the mechanics (impact law, rest test,
  Zeno series, energies), each law once;
* :mod:`~symvib.numeric.engine.roots`: root finders;
* :mod:`~symvib.numeric.engine.anchor`: ``G`` carried from a nearby anchor where the
  closed form cancels;
* :mod:`~symvib.numeric.engine.scan`: where the next event is;
* :mod:`~symvib.numeric.engine.timing`: times and friction work by quadrature;
* :mod:`~symvib.numeric.engine.loop`: the event loop and its entry points;
* :mod:`~symvib.numeric.engine.bind`: the engine bound to a curve's kernels,
  as plain Python or compiled by numba;
* :mod:`~symvib.numeric.engine.static`, :mod:`~symvib.numeric.engine.compiled`:
  the kernels as numba sees them (a compile-time constant of one curve, or a
  structure of function pointers for the shared engine).
"""
from symvib.numeric.engine.bind import Engine, bind

__all__ = ["Engine", "bind"]
