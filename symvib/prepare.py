"""The prepare step: a scene's curve made ready for the numeric wing, once (above both wings).

:func:`prepare` is what ``symvib.simulate``, ``symvib.sweep`` and the command
line call before the numeric wing runs:

1. the curve's kernel module is loaded, or generated once for a new user
   curve (:func:`load_kernels`: the code generator, SymPy);
2. for a user curve, its singular points (poles, cusps, corners, the ends of a
   ``sqrt``) are searched once per parameter values over a window covering the
   start and the limiters (:func:`symvib.symbolic.singular.singular_pieces`),
   and recorded beside the module by its input hash
   (:func:`symvib.numeric.prepared.store_pieces`);
3. the record gives the run's regular domain, length scale and ``F_sigma``
   reference point as numbers (:mod:`symvib.regular`), and the numeric wing
   receives a :class:`~symvib.numeric.prepared.Prepared` curve.

A later process finds module and record on disk and imports no SymPy
(:func:`symvib.numeric.prepared.prepared_of`); a catalogue shape is regular
on its domain and needs neither.  The numeric wing imports nothing from
:mod:`symvib.symbolic` or :mod:`symvib.codegen`: every climb goes through here.

Examples
--------
>>> from symvib.numeric.scene import scene_from_dict
>>> s = scene_from_dict({"curve": {"name": "pole", "z": "x**2 + 1/(x - 0.3)"},
...     "physics": {"mu": 0.1, "restitution": 0.5}, "initial": {"q": 0.5, "qdot": 0.0}})
>>> p = prepare(s)
>>> p.domain.narrowed, p.ends[0][0], p.ends[0][1], p.ends[1]
(True, 0.3, 'z is not finite', None)
"""
from __future__ import annotations

import logging

from symvib.numeric import jet_kernels as _jet_kernels
from symvib.numeric import prepared as _prepared
from symvib.numeric.kernels import load

__all__ = ["prepare", "load_kernels", "load_jets"]

#: Progress of slow steps: shown on a terminal by the command line.
_log = logging.getLogger("symvib.prepare")


def _module_text(shape, source: dict, origin) -> str:
    """The generated module's text for a user curve (the bridge: imports SymPy)."""
    from symvib.codegen import generate as codegen

    return codegen.module_source(shape, source=source, closed_form=shape.closed_form, origin=origin)


def load_kernels(shape):
    """The kernel module of ``shape`` (a name, a :class:`~symvib.shapes.Shape` or its data),
    generated and cached on first use of a user curve (:func:`symvib.numeric.kernels.load`)."""
    return load(shape, generate=_module_text)


def _jets_text(shape, source: dict, origin) -> str:
    """The jets module's text for a user curve (the bridge: imports SymPy)."""
    from symvib.codegen.jets import jets_text

    return jets_text(shape, source=source)


def load_jets(shape):
    """The jets module of ``shape`` (:mod:`symvib.codegen.jets`), generated and cached on first use
    of a user curve (:func:`symvib.numeric.jet_kernels.load_jets`); the numeric wing asks for it only
    when it differentiates a run that needs it (physics.md, "Sensitivities" 8 and 9)."""
    return _jet_kernels.load_jets(shape, generate=_jets_text)


# The numeric wing loads a user curve's jets when a sensitivity needs them; it does not import this
# module, so the generator is handed down here, once.
_jet_kernels.register_generator(_jets_text)

#: Symbolic curves already built, by shape source (the singular search of a second parameter set
#: in the same process reuses it).
_CURVES: dict = {}


def _curve(shape):
    import json

    key = json.dumps(shape.source(), sort_keys=True)
    return _CURVES.get(key) or _CURVES.setdefault(key, shape.curve())


def prepare(scene) -> _prepared.Prepared:
    """The :class:`~symvib.numeric.prepared.Prepared` curve a run of ``scene`` receives.

    Parameters
    ----------
    scene : symvib.numeric.scene.Scene

    Returns
    -------
    Prepared
        The kernels (the module, or its view on a narrowed domain) and the run's domain.

    Raises
    ------
    SceneError
        ``initial.q`` when the start is a singular point; ``limiters.left``/``limiters.right``
        when a limiter lies beyond one.
    """
    shape = scene.shape
    try:
        return _prepared.prepared_of(scene)   # on disk already (always, for a catalogue shape)
    except _prepared.NotPrepared:
        pass
    # (seconds: SymPy's import, the singular points, and for a new curve its derivation)
    _log.info("preparing curve %r: its singular points and kernels", shape.name)
    module = load_kernels(shape)
    pieces = _prepared.read_pieces(scene, module)
    if pieces is None:
        from symvib.symbolic.singular import singular_pieces

        window = _prepared.needed_window(scene, module)
        values = tuple(sorted((name, float(v)) for name, v in scene.params))
        pieces = singular_pieces(_curve(shape), values, *window)
        _prepared.store_pieces(scene, module, window, pieces)
    return _prepared.prepared_from_pieces(scene, module, pieces)
