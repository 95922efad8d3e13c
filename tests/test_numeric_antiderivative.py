"""A numeric ``F_sigma`` (no closed form) is right to rounding whatever the width of the curve's features.

The rule (:mod:`symvib.antiderivative`) refines a piece of ``PANEL * q_scale`` where the Legendre
tail of ``F_s'`` says one 16-point panel is not enough.  Before it, a curve whose ``q_scale`` is 1
(the default of a user curve) with a feature of width ``b`` was under-resolved: ``F_+(-0.197)`` of a
Gaussian well of ``b = 0.1`` was off by 6e-10 and runs on it ended ``tolerance_not_met``.  Here the
generated kernels (array and scalar forms) and a narrowed run's view are held to a 30-digit
quadrature, the smooth catalogue curves to one panel a piece, and seeded runs on narrow curves to
the independent arc-length integrator (:mod:`symvib.checks.accuracy`).
"""
import math

import mpmath
import numpy as np
import pytest

from symvib import antiderivative, regular
from symvib.numeric import kernels
from symvib.numeric.prepared import kernel_view
from symvib.prepare import load_kernels

#: Agreement required with the 30-digit reference, relative to the integral of ``|F_s'|`` from ``Q_REF``.
F_RTOL = 1e-13
#: The curves (graphs ``z(x)``, so ``alpha = atan(z')``), as a user writes them: ``q_scale`` 1.
GAUSS = {"name": "gauss-well", "kind": "graph", "q": "x", "z": "-a*exp(-(x/b)**2)",
         "params": {"a": "positive", "b": "positive"}, "closed_form": "never"}
SINE = {"name": "sine-track", "kind": "graph", "q": "x", "z": "a*(1 - cos(x/b))",
        "params": {"a": "positive", "b": "positive"}, "closed_form": "never"}
#: z'(x) of each, in mpmath.
SLOPES = {"gauss-well": lambda x, a, b: 2 * a * x / b**2 * mpmath.exp(-(x / b) ** 2),
          "sine-track": lambda x, a, b: a / b * mpmath.sin(x / b)}
#: (curve, a, b): Gaussian wells of depth b (slope up to 0.86) and sine tracks of amplitude b/2.
CASES = [(GAUSS, 0.1, 0.1), (GAUSS, 0.05, 0.05), (GAUSS, 0.02, 0.02), (GAUSS, 0.2, 0.1),
         (SINE, 0.025, 0.05), (SINE, 0.01, 0.02)]
#: Friction coefficients (at 0 both branches are one integral: taken once).
MU = (0.0, 0.05, 0.35)


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    path = tmp_path_factory.mktemp("kernels")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv(kernels.CACHE_ENV, str(path))
        yield path


def _points(b):
    """Points across the domain: in the feature, on its flanks, pieces away (both sides of Q_REF = 0)."""
    return sorted({-2.3, -0.61, -0.197, -3.1 * b, -0.4 * b, 0.0, 0.27 * b, 1.3 * b, 2.9 * b, 0.45, 1.9})


def _edges(lo, hi, b, periodic):
    """Breaks for the reference quadrature from ``lo`` to ``hi``: every ``b/2`` where the curve has a
    feature (everywhere on a sine track, within ``8 b`` of a Gaussian's centre), every 0.25 elsewhere
    (where a Gaussian's slope is below ``exp(-64)``)."""
    out, x = [lo], lo
    step = 1 if hi > lo else -1
    while (hi - x) * step > 0:
        near = periodic or abs(x) < 8 * b or abs(x + step * 0.25) < 8 * b
        x = x + step * (0.5 * b if near else 0.25)
        x = hi if (x - hi) * step > 0 else x
        out.append(x)
    return out


def _reference(slope, a, b, s, mu, points):
    """``F_s(q)`` from 0 at ``points`` at 30 digits (mpmath's tanh-sinh rule on the breaks of
    :func:`_edges`), and the integral of ``|F_s'|`` (the scale of its error: a 64-point rule in double
    precision on the same breaks is enough for that)."""
    periodic = slope is SLOPES["sine-track"]
    x64, w64 = np.polynomial.legendre.leggauss(64)
    with mpmath.workdps(30):
        am, bm, mum = mpmath.mpf(a), mpmath.mpf(b), mpmath.mpf(mu)

        def dF(x):
            zp = slope(x, am, bm)
            return mpmath.exp(2 * s * mum * mpmath.atan(zp)) * (zp + s * mum)

        def size_of(lo, hi):
            u = lo + (hi - lo) * (x64 + 1) / 2
            zp = np.array([float(slope(mpmath.mpf(v), am, bm)) for v in u])
            return abs(hi - lo) / 2 * float(np.sum(w64 * np.abs(np.exp(2 * s * mu * np.arctan(zp)) * (zp + s * mu))))

        out = {0.0: (0.0, 0.0)}
        for side in (sorted(p for p in points if p > 0), sorted((p for p in points if p < 0), reverse=True)):
            F, size, last = mpmath.mpf(0), 0.0, 0.0
            for p in side:
                edges = _edges(last, p, b, periodic)
                F += mpmath.quad(dF, [mpmath.mpf(e) for e in edges])
                size += sum(size_of(e0, e1) for e0, e1 in zip(edges[:-1], edges[1:]))
                out[p] = (float(F), size)
                last = p
        return out


@pytest.mark.parametrize("curve, a, b", CASES, ids=[f"{c['name']}-a{a}-b{b}" for c, a, b in CASES])
def test_numeric_F_of_narrow_features_matches_30_digits(cache, curve, a, b):
    k = load_kernels(curve)
    assert k.F_ROUTES == {1: "numeric", -1: "numeric"} and k.Q_REF == 0.0 and k.q_scale_scalar(a, b) == 1.0
    points = _points(b)
    worst = 0.0
    for s, F, F_scalar in ((1, k.F_p, k.F_p_scalar), (-1, k.F_m, k.F_m_scalar)):
        for mu in MU[s < 0:]:
            ref = _reference(SLOPES[curve["name"]], a, b, s, mu, points)
            array = F(np.array(points), mu, a, b)
            assert array.shape == (len(points),)
            for q, got in zip(points, array):
                want, size = ref[q]
                scalar = F_scalar(q, mu, a, b)
                assert scalar == got, (q, s, mu)    # the array form is the scalar one at every point
                err = abs(scalar - want) / max(size, 1e-300)
                worst = max(worst, err)
                assert err <= F_RTOL, f"{curve['name']} a={a} b={b} s={s:+d} mu={mu} q={q}: {err:.2e}"
    assert worst > 0.0   # (the points are not all at Q_REF)


def test_one_panel_a_piece_was_off_by_1e_10_on_a_narrow_gaussian(cache):
    """What the rule fixes: one 16-point panel of 0.25 over a Gaussian of width 0.1 errs by 9e-11."""
    k = load_kernels(GAUSS)
    a, b, mu, q = 0.2, 0.1, 0.3, -0.197
    ref, _ = _reference(SLOPES["gauss-well"], a, b, 1, mu, [q])[q]
    x, w = np.polynomial.legendre.leggauss(antiderivative.NODES)
    pieces = math.ceil(abs(q) / antiderivative.PANEL)
    step = q / pieces
    old = sum(0.5 * step * sum(wk * k.dF_p_scalar(i * step + 0.5 * step * (xk + 1.0), mu, a, b)
                               for xk, wk in zip(x, w)) for i in range(pieces))
    assert abs(old - ref) > 5e-11
    assert abs(k.F_p_scalar(q, mu, a, b) - ref) < 1e-15


class _Counter:
    """Counts the panels a generated F_s takes (its ``_F_<b>_panel_scalar``, called by name)."""

    def __init__(self, module, b):
        self.name = f"_F_{b}_panel_scalar"
        self.module, self.fn, self.calls = module, getattr(module, self.name), 0

    def __enter__(self):
        def counted(*args):
            self.calls += 1
            return self.fn(*args)

        setattr(self.module, self.name, counted)
        return self

    def __exit__(self, *exc):
        setattr(self.module, self.name, self.fn)


@pytest.mark.parametrize("name", ["catenary", "ellipse", "quartic"])
def test_smooth_catalogue_curves_take_one_panel_a_piece(name):
    """The cost on the catalogue's numeric curves stays the old rule's: no piece is refined."""
    from symvib.shapes import shape

    k = load_kernels(name)
    assert "numeric" in k.F_ROUTES.values()
    cp = [shape(name).defaults[p] for p in k.PARAMS]
    width = antiderivative.PANEL * k.q_scale_scalar(*cp)
    lo, hi = k.domain(*cp)
    for b in ("p", "m"):
        for mu in (0.0, 0.05, 0.3):
            for q in np.linspace(max(lo, -3.0) * 0.98, min(hi, 3.0) * 0.98, 13):
                with _Counter(k, b) as c:
                    getattr(k, f"F_{b}_scalar")(float(q), mu, *cp)
                assert c.calls == max(1, math.ceil(abs(q - k.Q_REF) / width)), (name, b, mu, q)


def test_a_narrow_feature_is_refined_where_it_is(cache):
    k = load_kernels(GAUSS)
    a, b, mu = 0.05, 0.05, 0.1
    with _Counter(k, "p") as near:
        k.F_p_scalar(0.25, mu, a, b)          # one piece: the well's right flank
    assert 4 < near.calls < 60
    with _Counter(k, "p") as far:
        k.F_p_scalar(1.75, mu, a, b)          # seven pieces: the flank, then six of the flat far out
    assert far.calls == near.calls + 6


def test_a_budget_spent_leaves_no_gap(cache):
    """A piece that spends its panels (rounding that never passes) is finished by one panel: the
    result stays within the old rule's accuracy, and every call ends."""
    k = load_kernels(SINE)
    a, b = 0.05, 0.1
    with _Counter(k, "p") as c, pytest.MonkeyPatch.context() as mp:
        mp.setattr(k, "_F_TOL", -1.0)        # no panel passes on its estimate: only the narrowest do
        mp.setattr(k, "_F_FLAT", -1.0)
        mp.setattr(k, "_F_TRIES", 40)
        value = k.F_p_scalar(0.2, 0.1, a, b)
    assert c.calls == 40 + 1
    ref, _ = _reference(SLOPES["sine-track"], a, b, 1, 0.1, [0.2])[0.2]
    assert abs(value - ref) < 1e-9


def test_a_non_finite_integrand_is_not_refined(cache):
    k = load_kernels(GAUSS)
    with _Counter(k, "p") as c:
        value = k.F_p_scalar(0.6, 0.1, math.inf, 0.05)   # an infinite depth: F' is inf or nan at the nodes
    assert not math.isfinite(value) and c.calls == 3


def test_a_narrowed_view_takes_the_same_rule(cache):
    """A narrowed run's F_sigma (a view's template, plain Python) is the generated rule, bit for bit."""
    k = load_kernels(GAUSS)
    a, b = 0.05, 0.05
    view = kernel_view(k, regular.RunDomain(-5.0, 5.0, 1.0, 0.0, True))
    for q in _points(b):
        for mu in MU:
            assert view.F_p_scalar(q, mu, a, b) == k.F_p_scalar(q, mu, a, b)
            assert view.F_m_scalar(q, mu, a, b) == k.F_m_scalar(q, mu, a, b)
    # from another reference point: differences of the module's F
    view = kernel_view(k, regular.RunDomain(-5.0, 5.0, 1.0, -0.13, True))
    ref = _reference(SLOPES["gauss-well"], a, b, 1, 0.2, [-0.13, 0.11])
    got = view.F_p_scalar(0.11, 0.2, a, b)
    want = ref[0.11][0] - ref[-0.13][0]
    assert abs(got - want) <= F_RTOL * (ref[0.11][1] + ref[-0.13][1])


def test_the_compiled_rule_is_the_same_arithmetic(cache):
    """numba compiles the generated walk (no conditional, calls by name) to the same bits."""
    pytest.importorskip("numba")
    from symvib.numeric.engine.bind import compiled_kernels

    k = load_kernels(GAUSS)
    compiled = compiled_kernels(k, len(k.PARAMS))
    F_p, F_m = compiled[0], compiled[1]
    a, b = 0.05, 0.05
    for q in _points(b):
        for mu in MU:
            assert F_p(q, mu, a, b) == k.F_p_scalar(q, mu, a, b)
            assert F_m(q, mu, a, b) == k.F_m_scalar(q, mu, a, b)


# --- runs on narrow curves ------------------------------------------------------------------------
#: Seeded scenes on narrow Gaussian wells and sine tracks (curves as a user writes them, q_scale 1).
RUN_SEED, RUN_SCENES = 8, 31
#: The ones among them that ended ``tolerance_not_met`` with one 16-point panel a piece.
WERE_NOT_MET = (0, 5, 6, 14, 15, 17, 25, 26, 30)


def narrow_scenes(seed: int, n: int) -> list:
    """``n`` seeded scenes alternating between a Gaussian well ``-a exp(-(x/b)^2)`` (``a`` 0.5 .. 2
    ``b``) and a sine track ``a (1 - cos(x/b))`` (``a`` 0.2 .. 0.8 ``b``), ``b`` one of 0.1, 0.05,
    0.02, limiters a few ``b`` away, random ``mu``, ``k`` and start."""
    rng = np.random.default_rng(seed)
    out = []
    for j in range(n):
        gauss = j % 2 == 0
        b = float(rng.choice([0.1, 0.05, 0.02]))
        if gauss:
            a = float(rng.uniform(0.5, 2.0) * b)
            left, right = -float(rng.uniform(1.5, 3.0)) * b, float(rng.uniform(1.5, 3.0)) * b
        else:
            a = float(rng.uniform(0.2, 0.8) * b)
            left, right = -float(rng.uniform(1.0, 5.0)) * b, float(rng.uniform(1.0, 5.0)) * b
        curve = GAUSS if gauss else SINE
        q0 = float(rng.uniform(left, right) * 0.8)
        speed = float(rng.uniform(0.5, 4.0) * np.sqrt(9.81 * b))
        mu = round(float(rng.uniform(0.0, 0.5)), 4)
        k = round(float(rng.uniform(0.3, 1.0)), 4)
        out.append({"name": f"narrow-{seed}-{j}",
                    "curve": {"name": curve["name"].replace("-", "-narrow-"), "z": curve["z"],
                              "closed_form": "never"},
                    "parameters": {"a": round(a, 6), "b": b},
                    "physics": {"g": 9.81, "m": 0.2, "mu": mu, "restitution": k},
                    "limiters": {"left": round(left, 6), "right": round(right, 6)},
                    "initial": {"q": round(q0, 6), "qdot": round(speed, 6)},
                    "run": {"t_max": 3.0, "max_events": 30}})
    return out


@pytest.mark.parametrize("index", WERE_NOT_MET)
def test_runs_on_narrow_curves_agree_with_the_independent_integrator(cache, index):
    """Each of these ended ``tolerance_not_met`` at its first or second interval (``F_sigma`` off by
    1e-10 .. 1e-6); now it ends as the arc-length integrator (DOP853) says, every event within 1e-11 s."""
    pytest.importorskip("scipy")
    import symvib
    from symvib.checks.accuracy import compare, reference_for

    scene = narrow_scenes(RUN_SEED, RUN_SCENES)[index]
    result = symvib.simulate(scene, backend="python", samples=False)
    assert result.success and result.status.value in ("arrested", "rest_on_limiter", "t_max", "max_events")
    reference = reference_for(scene)
    verdict = compare(result, reference.run, split_at=reference.split_at)
    assert verdict.verdict == "agree", verdict.detail
    assert verdict.max_dt < 1e-11    # (the DOP853 pair itself spreads by up to 1e-12 on these)
