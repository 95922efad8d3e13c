"""The corpus of curves given as expressions (:mod:`symvib.checks.corpus`), end to end.

Every entry is derived, generated (:func:`symvib.codegen.generate.generate`, into the
cache where :func:`symvib.numeric.kernels.load` looks for the shape a run uses),
whitelisted (the loader's :func:`~symvib.numeric.kernels.check_text`), loaded and run
on the plain-Python engine; with ``--runslow`` also on the compiled one (numba, the
engine shared by every curve with the same number of parameters:
:func:`symvib.numeric.engine.bind.bind` with ``shared=True``), which must give the
same events.  Every run must succeed with a closed energy budget.

An entry tagged ``numeric`` has no closed-form ``F_sigma`` (checked when the corpus
was written: every route of :mod:`symvib.symbolic.integrals` runs out of its budget or
fails its check), so its kernels are generated with ``routes=()``: the numeric route
at once, as the default derivation ends up after about a minute of budgets.  The
other entries are derived with every route, and must come out closed.

Cost (this 2-core machine): the entries in :data:`QUICK` took under :data:`QUICK_SECONDS`
each to build, derive, generate and run on the plain engine; the others are marked
``slow`` (up to a minute: ``secant-sqrt`` finds its closed form on the third route).
"""
from __future__ import annotations

import functools
import math

import pytest

from symvib.checks.corpus import CORPUS, entry
from symvib.numeric.backends import backend_available
from symvib.symbolic.integrals import ROUTE_SECONDS

#: Seconds (curve, regular interval, derive + generate, a plain-Python run; one warm process, idle)
#: under which an entry may run in the quick suite.
QUICK_SECONDS = 3.0
#: Entries measured under QUICK_SECONDS that the quick suite runs: every category but ``abs``, and
#: shared antiderivatives (the parabolas, the circles in q) derived once per process.  The others,
#: and the entries of the same kinds left out, are slow.
QUICK = frozenset({
    "parabola-hinted", "parabola-micro", "parabola-huge", "circle-loop", "circle-across-top", "cycloid-micro",
    "quartic", "double-well-bare", "cubic", "pole-well", "hyperbola-graph", "half-power", "cubic-parametric",
})
#: Budget of each closed-form route in the tests (twice the default): a closed form that takes a few
#: seconds on an idle machine must not fall to the numeric route on a loaded one.
ROUTE_BUDGET = 2 * ROUTE_SECONDS
#: The route that closes ``F_sigma`` where the default derivation reaches it only after the budgets of
#: the routes before it (measured: 51 s and 26 s with every route, 6 s and 4 s with this one alone).
ROUTES_OF = {"secant-sqrt": ("tangent-angle",), "tilted-parabola": ("tangent-angle",)}
#: Largest relative residual of a run's energy budget (the driver's own BUDGET_RTOL).
BUDGET_RTOL = 1e-9
#: Agreement of the compiled engine's events with the plain engine's (times and positions).
EVENT_TOL = 1e-12

NUMBA = backend_available("numba")


def _marks(e):
    return () if e.name in QUICK else (pytest.mark.slow,)


ENTRIES = [pytest.param(e.name, marks=_marks(e), id=e.name) for e in CORPUS]


@pytest.fixture(scope="session")
def corpus_cache(tmp_path_factory, request):
    """One kernel cache for the session, shared by the xdist workers (modules are written atomically).

    (Not xdist's ``worker_id`` fixture: ``pip install . && pip install pytest && python -m pytest``
    runs without xdist, where that fixture does not exist.)"""
    base = tmp_path_factory.getbasetemp()
    worker = getattr(request.config, "workerinput", {}).get("workerid", "master")
    folder = (base if worker == "master" else base.parent) / "corpus-kernels"
    folder.mkdir(exist_ok=True)
    return folder


@pytest.fixture
def cache(corpus_cache, monkeypatch):
    monkeypatch.setenv("SYMVIB_CACHE", str(corpus_cache))
    return corpus_cache


@functools.cache
def _scene(name):
    from symvib.numeric.scene import scene_from_dict

    return scene_from_dict(entry(name).scene())


def _kernels(name):
    """Generate (once) and load the kernels of the shape a run of the entry uses."""
    from pathlib import Path

    from symvib import provenance
    from symvib.codegen import generate as codegen
    from symvib.numeric import kernels
    from symvib.prepare import prepare
    from symvib.symbolic.integrals import ROUTES

    e = entry(name)
    shape = _scene(name).shape
    source = shape.source()
    stem = f"{kernels.module_name(shape.module)}_{provenance.input_hash(source)[:16]}"
    if not (kernels.cache_dir() / f"{stem}.py").exists():
        routes = () if "numeric" in e.tags else ROUTES_OF.get(name, ROUTES)
        codegen.generate(shape, kernels.cache_dir(), name=stem, source=source, routes=routes, seconds=ROUTE_BUDGET)
    mod = kernels.load(shape)
    prepare(_scene(name))   # its singular points on record, for the numeric driver
    text = Path(mod.__file__).read_text(encoding="utf-8")
    kernels.check_text(text, mod.__file__, provenance.input_hash(source))   # the loader's check, again
    return shape, mod, text


#: Entries whose run crosses a jump of the curvature (z'' of ``x abs(x)``): the time quadrature
#: meets its tolerance there (the events against an independent integration:
#: tests/test_accuracy.py), the friction work's quadrature of the jumping ``|N|`` does not, and
#: the energy budget says so (status energy_budget_mismatch, a residual of about 3e-8).
KAPPA_JUMP = {"x-abs-x"}
#: The residual such a run may leave (relative to E0).
KAPPA_JUMP_RTOL = 1e-6


def _check(result, name=None):
    if name in KAPPA_JUMP and not result.success:
        assert result.status.value == "energy_budget_mismatch", (result.status, result.stats)
        assert result.energy_budget.relative_residual < KAPPA_JUMP_RTOL
        return
    assert result.success, (result.status, result.stats)
    assert result.energy_budget.relative_residual < BUDGET_RTOL
    assert all(math.isfinite(v) for e in result.events for v in (e.t, e.q, e.qdot_before, e.qdot_after))


@pytest.mark.parametrize("name", ENTRIES)
def test_entry_derives_generates_loads_and_runs(name, cache):
    from symvib import simulate

    e = entry(name)
    shape, mod, text = _kernels(name)
    assert " if " not in text and "==" not in text                   # no conditional (generic_branch)
    closed = all(route != "numeric" for route in mod.F_ROUTES.values())
    assert closed == ("numeric" not in e.tags), mod.F_ROUTES
    result = simulate(_scene(name), backend="python", samples=False)
    _check(result, name)
    assert result.events or result.status.value == "t_max"


def _parameter_count(e):
    return len(e.parameters)


@pytest.mark.slow  # the shared numba engine compiles once per number of parameters and process (40-60 s)
@pytest.mark.skipif(not NUMBA, reason="numba is not installed")
@pytest.mark.parametrize("count", sorted({_parameter_count(e) for e in CORPUS}))
def test_the_compiled_engine_gives_the_events_of_the_plain_one(count, cache, monkeypatch):
    """Every entry with ``count`` parameters on numba (the engine shared by them, one compile), against
    the plain engine; the failures of all of them in one message."""
    from symvib.numeric import backends, driver
    from symvib.numeric.engine.bind import bind

    # simulate() on numba with the engine compiled once per number of parameters, not per curve.
    monkeypatch.setattr(backends, "bind", functools.partial(bind, shared=True))
    monkeypatch.setattr(backends, "_BOUND", {})
    failures = []
    for e in (e for e in CORPUS if _parameter_count(e) == count):
        _kernels(e.name)
        scene = _scene(e.name)
        plain = driver.simulate(scene, backend="python", samples=False)
        compiled = driver.simulate(scene, backend="numba", samples=False)
        why = _difference(plain, compiled)
        if e.name in KAPPA_JUMP and compiled.energy_budget.relative_residual < KAPPA_JUMP_RTOL:
            pass  # the friction work across the curvature's jump (KAPPA_JUMP)
        elif not (compiled.success and compiled.energy_budget.relative_residual < BUDGET_RTOL):
            why.append(f"numba ends {compiled.status.value} (residual {compiled.energy_budget.relative_residual:.2g}; "
                       f"plain: {plain.status.value})")
        failures += [f"{e.name}: {w}" for w in why]
    assert not failures, "; ".join(failures)


def _difference(plain, compiled) -> list:
    """How the compiled run's events differ from the plain run's (empty when they agree)."""
    if compiled.status is not plain.status or [x.kind for x in compiled.events] != [x.kind for x in plain.events]:
        return [f"status/events {compiled.status.value} {len(compiled.events)} against {plain.status.value} "
                f"{len(plain.events)}"]
    for i, (a, b) in enumerate(zip(plain.events, compiled.events)):
        dt, dq = abs(a.t - b.t), abs(a.q - b.q)
        if dt > EVENT_TOL * max(1.0, abs(a.t)) or dq > EVENT_TOL * max(1.0, abs(a.q)):
            return [f"event {i} ({a.kind.value} at t = {a.t:.6g}): t differs by {dt:.2g}, q by {dq:.2g}"]
    return []


#: A scene is on a short (long) length scale when the chord between its limiters is below (above) this.
SHORT_METRES, LONG_METRES = 1e-2, 1e2
#: Points of the numeric checks of the tags (inflection, loop).
TAG_POINTS = 4001


def _range(scene, c, values, run):
    """The interval of ``q`` a run of the scene can use: between its limiters, else its regular
    domain (``run``, the prepare step's), cut at 64 ``q_scale`` from the start where it is infinite."""
    lo, hi = run.lo, run.hi
    reach = 64.0 * float(c.q_scale.subs(values))
    lo = scene.left if scene.left is not None else max(lo, scene.q0 - reach)
    hi = scene.right if scene.right is not None else min(hi, scene.q0 + reach)
    return lo, hi


@pytest.mark.parametrize("name", ENTRIES)
def test_tags_say_what_the_entry_exercises(name):
    import numpy as np
    import sympy as sp

    from symvib.prepare import prepare

    e = entry(name)
    scene = _scene(name)
    c = scene.shape.curve()
    run = prepare(scene).domain
    tags = set(e.tags)
    assert ("graph" in tags) == ("x" not in e.curve)
    assert ("hint" in tags) == bool({"h", "alpha", "q_scale"} & set(e.curve))
    carries_abs = any(x.has(sp.Abs, sp.sign) for x in (c.x, c.z, c.xp, c.zp, c.h, c.alpha, c.hp, c.kappa))
    assert ("abs" in tags) == carries_abs
    values = {p: scene.param_dict[p.name] for p in c.params}
    lo, hi = _range(scene, c, values, run)
    q = np.linspace(lo, hi, TAG_POINTS)[1:-1]
    with np.errstate(all="ignore"):
        kappa = np.broadcast_to(sp.lambdify([c.q], c.kappa.subs(values), "numpy")(q), q.shape)
        turn = np.unwrap(np.arctan2(*(np.broadcast_to(sp.lambdify([c.q], d.subs(values), "numpy")(q), q.shape)
                                      for d in (c.zp, c.xp))))
        xp, zp = (np.broadcast_to(sp.lambdify([c.q], d.subs(values), "numpy")(q), q.shape) for d in (c.xp, c.zp))
    kappa = kappa[np.isfinite(kappa)]
    assert ("inflection" in tags) == bool(np.any(kappa > 0) and np.any(kappa < 0))
    assert ("loop" in tags) == (np.ptp(turn) > np.pi)
    assert ("cut" in tags) == bool(np.any((xp[:-1] < 0) & (np.sign(zp[:-1]) != np.sign(zp[1:]))))
    ends = [v for v in (scene.left, scene.right) if v is not None]
    if len(ends) == 2:
        point = [np.array([float(d.subs(values).subs(c.q, v)) for d in (c.x, c.z)]) for v in ends]
        chord = float(np.hypot(*(point[1] - point[0])))
        assert ("short" in tags) == (chord < SHORT_METRES) and ("long" in tags) == (chord > LONG_METRES)
    else:
        assert not {"short", "long"} & tags


def test_the_corpus_keeps_its_categories():
    tags = [set(e.tags) for e in CORPUS]
    assert len(CORPUS) >= 40 and len({e.name for e in CORPUS}) == len(CORPUS)
    for tag in ("graph", "parametric", "paper", "abs", "loop", "cut", "inflection", "short", "long", "numeric",
                "hint"):
        assert sum(tag in t for t in tags) >= 1, tag
    assert all(("graph" in t) != ("parametric" in t) for t in tags)
