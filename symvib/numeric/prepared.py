"""A prepared curve: its kernels and the run's regular domain, as the numeric wing receives them.

The prepare step (:mod:`symvib.prepare`, above both wings) loads or generates
a curve's kernel module and, for a user curve, searches its singular points
once per parameter values (SymPy), storing the pieces it finds beside the
module (:func:`store_pieces`, by the module's input hash).  This module is the
numeric side of that record: it reads it (no SymPy), turns it into the run's
domain (:mod:`symvib.regular`) and hands the driver and the sweep a
:class:`Prepared` curve.

Where a singular point lies inside the declared domain (``1/(x - a)``), the
run's domain ends there (physics.md, "Events" 4) and the *same* kernel module
runs it, seen through a :func:`kernel_view`: its ``domain`` and ``q_scale``
are the run's numbers, and ``F_sigma`` is the quadrature of ``F_sigma'`` from
a reference point inside the regular interval (a closed form found for the
whole declared domain need not hold across the point; the quadrature of its
derivative does on the interval).  So a curve started on either side of a
pole generates one module.

Examples
--------
>>> from symvib.numeric.scene import resolve_scene
>>> p = prepared_of(resolve_scene("paper-parabola"))
>>> p.kernels.NAME, p.domain.narrowed, p.ends
('parabola', False, (None, None))
"""
from __future__ import annotations

import hashlib
import json
import math
import os
import types
from dataclasses import dataclass

from symvib import antiderivative, regular, safeio
from symvib.numeric.scene import SceneError, declared_domain
from symvib.paths import UserPathError

__all__ = ["Prepared", "NotPrepared", "prepared_of", "kernels_of", "prepared_from_pieces", "needed_window",
           "read_pieces", "store_pieces", "kernel_view", "RECORD_SUFFIX"]

#: Suffix of the record of a module's singular pieces, beside the module in the kernel cache.
RECORD_SUFFIX = ".regular.json"
#: Version of the record (a record of another is searched again): its layout; 2 since a smooth
#: minimum of ``h`` far below the scan grid's spacing is no longer taken for a cusp; 3 since a
#: cusp's piece is measured against ``h``'s rounding floor next to it, not at the grid's points.
RECORD_FORMAT = 3
#: Most parameter sets a record keeps (the oldest go first): a sweep of a pole's position
#: does not grow it without bound.
MAX_RECORD_ENTRIES = 256
#: Largest record read, in bytes.
MAX_RECORD_BYTES = 4 * 2**20
#: Gauss-Legendre nodes per panel of a narrowed run's ``F_sigma`` (as a generated numeric ``F_sigma``).
F_NODES = antiderivative.NODES


class NotPrepared(SceneError):
    """A user curve whose kernels or singular points are not on record yet: the prepare step
    (``symvib.simulate``, ``symvib.prepare.prepare``) makes them; the numeric wing does not run SymPy."""

    def __init__(self, name: str, what: str):
        super().__init__("curve", f"curve '{name}' is not prepared ({what}): run it through symvib.simulate, "
                                  "symvib.sweep or symvib.prepare.prepare(scene) first (they derive and "
                                  "search it once; the numeric wing does not import SymPy)")


@dataclass(frozen=True)
class Prepared:
    """What a run of a scene receives: the kernels and the run's domain as numbers.

    Attributes
    ----------
    kernels : module
        The generated module, or its :func:`kernel_view` on a narrowed domain.
    domain : symvib.regular.RunDomain
        The run's ends, length scale and ``F_sigma`` reference point.
    ends : tuple
        ``(point, reason)`` of the singular point beyond the left and the right end, or
        ``None`` where the end is the declared domain's (for the status ``reached_singular_point``).
    """

    kernels: object
    domain: regular.RunDomain
    ends: tuple = (None, None)


def _params(scene) -> tuple:
    return tuple((name, float(v)) for name, v in scene.params)


def needed_window(scene, module) -> tuple:
    """The window of ``q`` a search for ``scene`` must cover (:func:`symvib.regular.scan_window`)."""
    lo, hi = declared_domain(scene)
    scale = float(module.q_scale_scalar(*scene.param_values))
    points = [v for v in (scene.q0, scene.left, scene.right) if v is not None]
    return regular.scan_window(lo, hi, scale, points)


def _record_name(module) -> str | None:
    path = getattr(module, "__file__", None)
    if not path:
        return None
    from pathlib import Path

    return Path(path).stem + RECORD_SUFFIX


#: Records already read in this process, by path: ``(stat signature, entries)``.  A loop of runs
#: stats its curve's record instead of reading and checking it again; a record changed on disk
#: (another process added to it, or it was damaged) has another signature and is read again.
_RECORDS: dict = {}


def _read_record(module) -> list:
    """The record's entries (empty when there is none, or it is unreadable or of another module)."""
    from symvib.numeric.kernels import cache_dir

    name = _record_name(module)
    if name is None:
        return []
    path = cache_dir() / name
    try:
        st = os.stat(path, follow_symlinks=False)
    except OSError:
        return []
    signature = (st.st_ino, st.st_size, st.st_mtime_ns, module.INPUT_HASH)
    known = _RECORDS.get(str(path))
    if known is not None and known[0] == signature:
        return known[1]
    try:
        raw = safeio.read_bytes(cache_dir(), name, max_bytes=MAX_RECORD_BYTES, what="kernel cache", private=True)
        data = json.loads(raw.decode("utf-8"))
    except (OSError, UserPathError, ValueError, UnicodeDecodeError):
        return []
    if not isinstance(data, dict) or data.get("format") != RECORD_FORMAT or \
            data.get("input_hash") != module.INPUT_HASH or not isinstance(data.get("entries"), list):
        return []
    entries = [e for e in data["entries"] if _valid_entry(e)]
    _RECORDS[str(path)] = (signature, entries)
    return entries


def _valid_entry(entry) -> bool:
    """An entry as :func:`store_pieces` writes it (numbers, and labels and kinds of :mod:`symvib.regular`)."""
    try:
        params, window, pieces = entry["params"], entry["window"], entry["pieces"]
        ok = all(isinstance(n, str) and isinstance(v, float) for n, v in params)
        ok = ok and len(window) == 2 and all(isinstance(v, float) for v in window)
        return ok and all(isinstance(a, float) and isinstance(b, float) and a <= b and label in regular.LABELS
                          and kind in regular.KINDS for a, b, label, kind in pieces)
    except (KeyError, TypeError, ValueError):
        return False


def read_pieces(scene, module):
    """The singular pieces on record for ``scene``'s parameters over a window covering its start
    and limiters, or None (not searched yet)."""
    params, (wlo, whi) = [list(p) for p in _params(scene)], needed_window(scene, module)
    for entry in _read_record(module):
        (lo, hi) = entry["window"]
        if entry["params"] == params and lo <= wlo and whi <= hi:
            return tuple(tuple(p) for p in entry["pieces"])
    return None


def store_pieces(scene, module, window: tuple, pieces) -> None:
    """Record the singular ``pieces`` of ``module``'s curve for ``scene``'s parameters over ``window``
    (written whole beside the module; a cache that cannot be written only costs a new search)."""
    from symvib.numeric.kernels import cache_dir

    name = _record_name(module)
    if name is None:
        return
    entry = {"params": [list(p) for p in _params(scene)], "window": [float(window[0]), float(window[1])],
             "pieces": [[float(a), float(b), str(label), str(kind)] for a, b, label, kind in pieces]}
    entries = [e for e in _read_record(module) if e["params"] != entry["params"]] + [entry]
    text = json.dumps({"format": RECORD_FORMAT, "input_hash": module.INPUT_HASH,
                       "entries": entries[-MAX_RECORD_ENTRIES:]}, sort_keys=True)
    try:
        safeio.write_text(cache_dir(), name, text, what="kernel cache", private=True)
    except (OSError, UserPathError):
        pass


def prepared_from_pieces(scene, module, pieces) -> Prepared:
    """The run of ``scene`` on the regular interval the singular ``pieces`` leave around its start.

    Raises
    ------
    SceneError
        ``initial.q`` when the start is itself singular; ``limiters.left``/``limiters.right``
        when a limiter lies beyond a singular point (the particle cannot reach it).
    """
    lo, hi = declared_domain(scene)
    r = regular.interval_in(pieces, scene.q0, lo, hi)
    shape, q = scene.shape, scene.shape.q
    if r.at_start:
        raise SceneError("initial.q", f"{scene.q0!r} is a singular point of curve '{shape.name}' "
                                      f"({r.at_start} at {q} = {scene.q0!r}); start inside a regular interval")
    for label, v, ok, end, reason in (("limiters.left", scene.left, lambda v: v > r.lo, r.lo, r.lo_reason),
                                      ("limiters.right", scene.right, lambda v: v < r.hi, r.hi, r.hi_reason)):
        if v is not None and not ok(v):
            raise SceneError(label, f"{v!r} is beyond a singular point of curve '{shape.name}' at {q} = {end!r} "
                                    f"({reason}): the particle cannot get there from {q} = {scene.q0!r}")
    scale = float(module.q_scale_scalar(*scene.param_values))
    run = regular.run_domain(r, scene.q0, scale)
    ends = tuple((point, why) if why else None for point, why in ((r.lo, r.lo_reason), (r.hi, r.hi_reason)))
    return Prepared(kernel_view(module, run) if run.narrowed else module, run, ends)


def _regular(scene, module) -> Prepared:
    """A curve regular on its declared domain: its module as it is."""
    lo, hi = declared_domain(scene)
    scale = float(module.q_scale_scalar(*scene.param_values))
    return Prepared(module, regular.RunDomain(lo, hi, scale, regular.reference_point(lo, hi, scale), False))


def kernels_of(scene):
    """The kernels of :func:`prepared_of` ``(scene)``: a catalogue shape's module as it is, found without
    building the run's domain (a tenth of a millisecond, which a caller that runs many times saves)."""
    if scene.shape.in_catalogue:
        from symvib.numeric.kernels import load

        return load(scene.shape)
    return prepared_of(scene).kernels


def prepared_of(scene, module=None) -> Prepared:
    """The prepared curve of ``scene`` from what is on disk (no SymPy).

    A catalogue shape is regular on its declared domain; a user curve's singular
    points are read from its record (:func:`read_pieces`).

    Raises
    ------
    NotPrepared
        A user curve whose module or record is missing (``symvib.prepare.prepare`` makes them).
    """
    from symvib.numeric.kernels import KernelError, load

    if module is None:
        try:
            module = load(scene.shape)
        except KernelError as err:
            if scene.shape.in_catalogue:
                raise
            raise NotPrepared(scene.shape.name, str(err)) from None
    if scene.shape.in_catalogue:
        return _regular(scene, module)
    pieces = read_pieces(scene, module)
    if pieces is None:
        raise NotPrepared(scene.shape.name, "its singular points are not on record for these parameters")
    return prepared_from_pieces(scene, module, pieces)


# A narrowed run's kernels: the generated module's functions, rebuilt over a namespace of their own
# whose domain, q_scale and F_sigma are the run's.  The templates below read the run's numbers as
# globals of that namespace (numba takes them as compile-time constants).

def _domain(*cp):
    return (RUN_LO, RUN_HI)  # noqa: F821 - a global of the view


def _q_scale_scalar(*cp):
    return RUN_SCALE  # noqa: F821


def _q_scale(*cp):
    return _broadcast(RUN_SCALE, *cp) if cp else RUN_SCALE  # noqa: F821 - the generated module's helper


def _F_p_scalar(q, mu, *cp):
    """Integral of ``F_+'`` from ``RUN_Q_REF`` to ``q``: the rule of a generated numeric ``F_sigma``
    (:mod:`symvib.antiderivative`: pieces at most ``RUN_WIDTH``, each one panel where its Legendre
    tail allows, else walked with halved and doubled panels), the same arithmetic in plain Python
    (``F_+'`` called by name, not passed)."""
    length = q - RUN_Q_REF  # noqa: F821 - globals of the view
    panels = max(1, math.ceil(abs(length) / RUN_WIDTH))  # noqa: F821
    step = length / panels
    total = 0.0
    for k in range(panels):
        left = RUN_Q_REF + k * step  # noqa: F821
        value, error, tol = _F_p_panel_scalar(left, step, mu, *cp)
        if error <= tol or not math.isfinite(error):
            total += value
            continue
        done, width, tries = 0.0, 0.5, 1
        while done < 1.0 and tries < RUN_F_TRIES:  # noqa: F821
            tries += 1
            width = min(width, 1.0 - done)
            value, error, tol = _F_p_panel_scalar(left + done * step, width * step, mu, *cp)
            if error <= tol or not math.isfinite(error) or width <= RUN_F_NARROWEST:  # noqa: F821
                total += value
                done += width
                width = min(1.0, 2.0 * width)
            else:
                width = 0.5 * width
        if done < 1.0:   # the budget spent: the rest of the piece as one panel
            total += _F_p_panel_scalar(left + done * step, (1.0 - done) * step, mu, *cp)[0]
    return total


def _F_p_panel_scalar(left, width, mu, *cp):
    """``(integral, error estimate, tolerance)`` of ``F_+'`` over ``[left, left + width]``: one panel
    of the rule of :mod:`symvib.antiderivative` (as a generated module's ``_F_p_panel_scalar``)."""
    total = 0.0
    size = 0.0
    c1 = 0.0
    c2 = 0.0
    c3 = 0.0
    c4 = 0.0
    for xk, wk, t1, t2, t3, t4 in zip(RUN_GL_X, RUN_GL_W, RUN_GL_T1, RUN_GL_T2, RUN_GL_T3, RUN_GL_T4):  # noqa: F821
        v = dF_p_scalar(left + 0.5 * width * (xk + 1.0), mu, *cp)  # noqa: F821
        total += wk * v
        size += wk * abs(v)
        c1 += t1 * v
        c2 += t2 * v
        c3 += t3 * v
        c4 += t4 * v
    tail = max(abs(c1), abs(c2))
    ratio = min(1.0, math.sqrt(tail / (max(abs(c3), abs(c4)) + 1e-300)))
    flat = 0.5 + 0.5 * math.copysign(1.0, ratio - RUN_F_UNRESOLVED)  # noqa: F821
    real = 0.5 + 0.5 * math.copysign(1.0, tail - flat * RUN_F_FLAT * 0.5 * size)  # noqa: F821
    return (0.5 * width * total, 2.0 * tail * max(ratio ** RUN_F_POWER, flat) * real,  # noqa: F821
            RUN_F_TOL * size)  # noqa: F821


def _twin(fn, names: dict):
    """``fn`` with the globals it names renamed (``dF_p_scalar`` -> ``dF_m_scalar``): one template
    for both branches, each calling its ``F_sigma'`` by name."""
    code = fn.__code__
    return types.FunctionType(code.replace(co_names=tuple(names.get(n, n) for n in code.co_names)),
                              fn.__globals__, fn.__name__.replace("_p", "_m"))


_F_m_scalar = _twin(_F_p_scalar, {"_F_p_panel_scalar": "_F_m_panel_scalar"})
_F_m_panel_scalar = _twin(_F_p_panel_scalar, {"dF_p_scalar": "dF_m_scalar"})


def _F_p(q, mu, *cp):
    return _RUN_NP.vectorize(F_p_scalar)(q, mu, *cp)  # noqa: F821


def _F_m(q, mu, *cp):
    return _RUN_NP.vectorize(F_m_scalar)(q, mu, *cp)  # noqa: F821


#: The view's replacements, by the name they take.
_TEMPLATES = {"domain": _domain, "q_scale_scalar": _q_scale_scalar, "q_scale": _q_scale,
              "F_p_scalar": _F_p_scalar, "F_m_scalar": _F_m_scalar,
              "_F_p_panel_scalar": _F_p_panel_scalar, "_F_m_panel_scalar": _F_m_panel_scalar,
              "F_p": _F_p, "F_m": _F_m}
#: Views already built, by (module name, input hash, run numbers): one object each, so the driver's
#: engine cache holds.
_VIEWS: dict = {}


def kernel_view(module, run: regular.RunDomain):
    """``module`` seen on the run's domain: every function rebuilt over a namespace where
    ``domain``, ``q_scale`` and ``F_sigma`` (a quadrature of the module's ``F_sigma'`` from
    ``run.q_ref``, panels at most ``PANEL * run.scale``) are the run's, so that the kernels
    calling them (``w``, ``qdot2``) follow."""
    import numpy as np

    key = (module.__name__, module.INPUT_HASH, run)
    view = _VIEWS.get(key)
    if view is not None:
        return view
    digest = hashlib.sha256(repr((run.lo, run.hi, run.scale, run.q_ref)).encode()).hexdigest()[:12]
    name = f"{module.__name__}__on_{digest}"
    view = types.ModuleType(name, module.__doc__)
    space = view.__dict__
    for attr, value in vars(module).items():
        if attr not in ("__name__", "__doc__", "__spec__", "__loader__") and not attr.startswith("_symvib_"):
            space[attr] = value
    gl_x, gl_w, t1, t2, t3, t4 = antiderivative.tail_rows(F_NODES)
    width = float(getattr(module, "PANEL", antiderivative.PANEL)) * run.scale
    space.update(RUN_LO=run.lo, RUN_HI=run.hi, RUN_SCALE=run.scale, RUN_Q_REF=run.q_ref, RUN_WIDTH=width,
                 RUN_GL_X=gl_x, RUN_GL_W=gl_w, RUN_GL_T1=t1, RUN_GL_T2=t2, RUN_GL_T3=t3, RUN_GL_T4=t4,
                 RUN_F_TOL=antiderivative.TOL, RUN_F_FLAT=antiderivative.FLAT,
                 RUN_F_UNRESOLVED=antiderivative.UNRESOLVED, RUN_F_POWER=antiderivative.TAIL_POWER,
                 RUN_F_TRIES=antiderivative.TRIES, RUN_F_NARROWEST=antiderivative.NARROWEST,
                 _RUN_NP=np, math=math, Q_REF=run.q_ref, PANEL=float(getattr(module, "PANEL", antiderivative.PANEL)),
                 F_ROUTES={1: "numeric", -1: "numeric"}, __file__=None, RUN_OF=module.__name__)
    functions = {fname: fn for fname, fn in vars(module).items()
                 if isinstance(fn, types.FunctionType) and fn.__module__ == module.__name__}
    functions.update(_TEMPLATES)
    for fname, fn in functions.items():
        new = types.FunctionType(fn.__code__, space, fname, fn.__defaults__, fn.__closure__)
        new.__qualname__, new.__module__, new.__doc__ = fname, name, fn.__doc__
        space[fname] = new
    return _VIEWS.setdefault(key, view)
