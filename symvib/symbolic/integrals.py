"""The antiderivative ``F_sigma`` of the phase trajectory (physics.md, eq. 2).

On a branch ``s = sigma * sign(N)`` the squared speed is

    w(q) = exp(-2 s mu alpha(q)) * [C - 2 g F_s(q)],
    F_s(q) = Integral exp(2 s mu alpha) * (z' + s mu x') dq.

Whether SymPy finds ``F_s`` depends on the curve and on how the integrand is
written, it can take minutes, and it has returned wrong antiderivatives.  So
:func:`antiderivative` tries a chain of routes, each in a child process under
a time budget (:mod:`symvib.symbolic.budget`), and accepts a closed form only after it
is differentiated back and checked:

``sympy``
    ``integrate`` on the integrand as derived.
``split``
    the integrand expanded into terms, each integrated on its own, also in
    exponential form.
``tangent-angle``
    change of variable to the tangent angle ``a = alpha(q)``:
    ``F = Integral exp(2 s mu a) (sin a + s mu cos a) rho(a) da`` with the
    radius of curvature ``rho = h / alpha'`` written in ``a``.
``numeric``
    no closed form: ``F`` is the integral from a reference point ``q_ref``,
    evaluated by quadrature in the generated kernels.

Default budget: :data:`ROUTE_SECONDS` per route and :data:`VERIFY_SECONDS` for
the symbolic part of a check, so one branch takes at most about
``3 * ROUTE_SECONDS + VERIFY_SECONDS`` seconds (40 s) before the numeric
route stands in.  A ``total`` budget bounds all the routes together (a new curve's
first run, :func:`symvib.codegen.generate.route_plan`), and ``check="numeric"`` accepts a
closed form on its numeric checks alone (the derivative at 30 digits at random points and
``F(b) - F(a)`` against a quadrature), without the symbolic substitution.

Examples
--------
>>> from symvib.shapes import shape
>>> F = antiderivative(shape("circle").curve(), +1)
>>> F.route, F.closed
('sympy', True)
"""
from __future__ import annotations

import random
import time
from dataclasses import dataclass, replace

import mpmath
import sympy as sp

from symvib.symbolic import budget
from symvib.symbolic.angle import reference_point
from symvib.symbolic.curve import Curve
from symvib.symbolic.identity import CHECK_DIGITS, CHECK_TOLERANCE, numeric_zero, sample_points
from symvib.symbolic.symbols import mu

__all__ = ["Attempt", "Antiderivative", "antiderivative", "antiderivatives", "integrand", "ROUTES", "ROUTE_SECONDS",
           "VERIFY_SECONDS", "CHECKS", "SHORTEST_ROUTE_SECONDS"]

#: Closed-form routes, tried in this order.
ROUTES = ("sympy", "split", "tangent-angle")
#: Default budget of one route, in seconds.
ROUTE_SECONDS = 10.0
#: Default budget for SymPy to simplify ``F' - integrand`` to zero, in seconds.
VERIFY_SECONDS = 10.0
#: How a closed form is checked: ``"symbolic"`` tries SymPy's substitution after the numeric checks
#: (:func:`verify`), ``"numeric"`` stops after them.
CHECKS = ("symbolic", "numeric")
#: A route is started only when at least this much of a ``total`` budget is left, in seconds.
SHORTEST_ROUTE_SECONDS = 0.25
#: Random points at which a closed form is differentiated back at 30 digits.
VERIFY_POINTS = 6
#: Pairs of points at which ``F(b) - F(a)`` is compared with a quadrature (catches jumps).
CONTINUITY_PAIRS = 3
#: Range of ``mu`` used by the numeric checks.
MU_RANGE = (0.01, 0.5)
#: ``mu`` at which continuity of the frictionless limit is checked in double precision.
MU_TINY = 1e-12

_CACHE: dict = {}


@dataclass(frozen=True)
class Attempt:
    """One route tried: its name, what came of it and how long it took."""

    route: str
    outcome: str
    seconds: float


@dataclass(frozen=True)
class Antiderivative:
    """``F_s(q)`` for one branch, with its provenance.

    Attributes
    ----------
    s : int
        Branch, +1 or -1.
    integrand : sympy.Expr
        ``exp(2 s mu alpha) (z' + s mu x')``.
    expr : sympy.Expr
        The closed form, or ``Integral(integrand, (u, q_ref, q))`` on the numeric route.
    route : str
        ``"sympy"``, ``"split"``, ``"tangent-angle"`` or ``"numeric"``.
    verification : str
        How the closed form was checked (``"symbolic"``: SymPy reduced
        ``F' - integrand`` to 0; ``"numeric"``: below 1e-25 at 30 digits at
        random points), and that ``F(b) - F(a)`` matches a quadrature.
    attempts : tuple of Attempt
    q_ref : sympy.Expr
        Lower limit of the numeric route's integral.
    mu_regular : bool
        ``True`` when ``expr`` is finite and continuous as ``mu -> 0``.
    """

    s: int
    integrand: sp.Expr
    expr: sp.Expr
    route: str
    verification: str
    attempts: tuple
    q_ref: sp.Expr
    mu_regular: bool = True

    @property
    def closed(self) -> bool:
        """``True`` when a verified closed form was found."""
        return self.route != "numeric"


def integrand(curve: Curve, s: int) -> sp.Expr:
    """``F_s'(q) = exp(2 s mu alpha) (z' + s mu x')`` (physics.md)."""
    return sp.exp(2 * s * mu * curve.alpha) * (curve.zp + s * mu * curve.xp)


# --- jobs run in child processes (module level, srepr arguments) -------------------
def _job_sympy(f: str, q: str):
    expr = sp.sympify(f)
    return sp.integrate(expr, _find(expr, q))


def _job_split(f: str, q: str):
    expr = sp.sympify(f)
    var = _find(expr, q)
    total = sp.Integer(0)
    for term in sp.Add.make_args(sp.expand(expr)):
        result = sp.integrate(term, var)
        if result.has(sp.Integral):
            result = sp.integrate(term.rewrite(sp.exp), var)
            if result.has(sp.Integral):
                return result
        total += result
    return total


def _job_tangent(f: str, alpha: str, h: str, alphap: str, q: str, s: int):
    alpha_e, h_e, alphap_e = sp.sympify(alpha), sp.sympify(h), sp.sympify(alphap)
    var = _find(alpha_e, q)
    a = sp.Dummy("a", real=True)
    solutions = sp.solve(sp.Eq(alpha_e, a), var)
    if not solutions:
        raise ValueError("alpha(q) = a has no explicit solution for q")
    q_of_a = solutions[0]
    rho = sp.simplify((h_e / alphap_e).subs(var, q_of_a))
    # |cos a| and the like: on a regular arc the sign is fixed, so take the one
    # at a = alpha(q_ref); a wrong choice fails the derivative check later.
    a0 = alpha_e.subs(var, 0) if alpha_e.subs(var, 0).is_finite else sp.Rational(1, 10)
    rho = rho.replace(sp.Abs, lambda arg: arg * sp.sign(arg.subs(a, a0) if arg.subs(a, a0) != 0 else 1))
    fa = sp.exp(2 * s * mu * a) * (sp.sin(a) + s * mu * sp.cos(a)) * rho
    # The whole product first: expanding can split an integrable combination
    # (the parabola's (tan a + s mu) sec(a)**2 exp(2 s mu a)) into terms that are not.
    for form in (fa, sp.exp(2 * s * mu * a) * sp.simplify(fa / sp.exp(2 * s * mu * a)), sp.expand(fa)):
        Fa = sp.integrate(form, a)
        if not Fa.has(sp.Integral):
            return Fa.subs(a, alpha_e)
    return Fa


def _job_simplify_zero(e: str):
    return sp.Integer(1) if sp.simplify(sp.sympify(e)) == 0 else sp.Integer(0)


def _find(expr, name):
    for sym in expr.free_symbols:
        if sym.name == name:
            return sym
    return sp.Symbol(name, real=True)


# --- checks ----------------------------------------------------------------------------
def _random_values(curve: Curve, rng: random.Random) -> dict:
    values = {p: sp.Float(0.5 + 1.5 * rng.random(), CHECK_DIGITS) for p in curve.params}
    values[mu] = sp.Float(MU_RANGE[0] + (MU_RANGE[1] - MU_RANGE[0]) * rng.random(), CHECK_DIGITS)
    return values


def _continuous(F: sp.Expr, f: sp.Expr, curve: Curve, seed: int = 3) -> bool:
    """``F(b) - F(a)`` equals a 30-digit quadrature of ``f`` over ``[a, b]``."""
    rng = random.Random(seed)
    with mpmath.workdps(CHECK_DIGITS):
        for _ in range(CONTINUITY_PAIRS):
            values = _random_values(curve, rng)
            a, b = sample_points(curve, 2, seed=rng.randrange(10**6),
                                 values={p: values[p] for p in curve.params})
            Fn = sp.lambdify(curve.q, F.subs(values), "mpmath")
            fn = sp.lambdify(curve.q, f.subs(values), "mpmath")
            exact = mpmath.quad(fn, [a, b])
            got = Fn(b) - Fn(a)
            if not abs(got - exact) <= CHECK_TOLERANCE * max(1, abs(exact), abs(Fn(a))):
                return False
    return True


def verify(F: sp.Expr, f: sp.Expr, curve: Curve, *, seconds: float = VERIFY_SECONDS,
           check: str = "symbolic") -> str | None:
    """Differentiate ``F`` back and compare with ``f``; ``None`` if it fails.

    Returns ``"symbolic"`` or ``"numeric"`` (how ``F' = f`` was shown), after
    also checking ``F(b) - F(a)`` against a quadrature at random pairs.  With
    ``check="numeric"`` the symbolic substitution is not tried (``"numeric"`` or ``None``).
    """
    residual = sp.diff(F, curve.q) - f
    if not numeric_zero(residual, curve, extra={mu: MU_RANGE}, points=VERIFY_POINTS):
        return None
    if not _continuous(F, f, curve):
        return None
    if check == "numeric":
        return "numeric"
    outcome = budget.run(_job_simplify_zero, (sp.srepr(residual),), seconds=seconds)
    return "symbolic" if outcome.status == "ok" and outcome.value == 1 else "numeric"


def regularize(F: sp.Expr, q: sp.Symbol) -> tuple:
    """Remove a ``q``-independent pole at ``mu = 0`` from an antiderivative.

    ``F`` is defined up to a constant, and its derivative is regular at
    ``mu = 0``, so any principal part in ``mu`` cannot depend on ``q``: it is
    dropped.  Returns ``(F_regular, regular)`` where ``regular`` tells whether
    the result has a finite value at ``mu = 0`` that needs no cancellation.

    >>> t = sp.Symbol("t", real=True)
    >>> F, regular = regularize(sp.exp(mu * t) / mu, t)   # the pole 1/mu is dropped
    >>> sp.simplify(F - (sp.exp(mu * t) - 1) / mu), sp.limit(F, mu, 0), regular
    (0, t, False)
    """
    try:
        pole = sp.series(F, mu, 0, 0).removeO()
    except Exception:  # noqa: BLE001 - series can fail on exotic forms; treat as irregular
        return F, False
    if pole == 0:
        return F, True
    if pole.has(q):
        return F, False
    return F - pole, False


def antiderivative(curve: Curve, s: int, *, seconds: float = ROUTE_SECONDS,
                   routes=ROUTES) -> Antiderivative:
    """Find ``F_s`` for ``curve`` by the first route that yields a verified closed form.

    Parameters
    ----------
    curve : Curve
    s : {+1, -1}
        Branch (sign of the friction term).
    seconds : float
        Budget of each route (child process killed when it is spent).
    routes : sequence of str
        Closed-form routes to try, a subset of :data:`ROUTES`.

    Returns
    -------
    Antiderivative
        Always; with ``route="numeric"`` when no route succeeds.
    """
    return antiderivatives(curve, (s,), seconds=seconds, routes=routes)[s]


def antiderivatives(curve: Curve, branches=(1, -1), *, seconds: float = ROUTE_SECONDS,
                    routes=ROUTES, total: float | None = None, check: str = "symbolic") -> dict:
    """:func:`antiderivative` of each branch in ``branches``, ``{s: Antiderivative}``.

    Every route is tried on every branch still without a closed form, in the order of
    ``routes``; the branches' attempts at one route run side by side (a child process each,
    on cores of their own), so a curve whose routes all spend their budgets waits for them
    once, not once per branch.  ``total`` (seconds), when given, bounds all the routes
    together: a route gets ``seconds`` or what is left of ``total``, whichever is less, so a
    route that ends early leaves its time to the next, and none starts with less than
    :data:`SHORTEST_ROUTE_SECONDS` left.  ``check`` (:data:`CHECKS`)
    is how a closed form found is checked (:func:`verify`).
    """
    unknown = set(routes) - set(ROUTES)
    if unknown:
        raise ValueError(f"unknown route(s) {sorted(unknown)}; known: {', '.join(ROUTES)}")
    if check not in CHECKS:
        raise ValueError(f"check: {check!r} is not one of {', '.join(CHECKS)}")
    out, todo = {}, {}
    for s in branches:
        if s not in (1, -1):
            raise ValueError(f"branch s must be +1 or -1, got {s!r}")
        f = integrand(curve, s)
        key = (sp.srepr(f), sp.srepr(curve.alpha), tuple(routes), seconds, total, check)
        if key in _CACHE:
            # The reference point depends on the domain: one integrand on (0.3, oo) and on
            # (-oo, -0.3) shares the symbolic work but not q_ref.
            out[s] = _with_q_ref(_CACHE[key], reference_point(curve), curve.q)
        else:
            todo[s] = (f, key, [])
    deadline = None if total is None else time.perf_counter() + total
    for i, route in enumerate(routes):
        waiting = [s for s in todo if s not in out]
        if not waiting:
            break
        allowed = seconds
        if deadline is not None:   # at most what is left of the total budget
            allowed = min(seconds, deadline - time.perf_counter())
            if allowed < SHORTEST_ROUTE_SECONDS:   # too little for this route, and so for the rest
                for s in waiting:
                    todo[s][2].extend(Attempt(r, f"not tried: the total budget of {total:g} s is spent", 0.0)
                                      for r in routes[i:])
                break
        started = {s: budget.start(*_route_job(route, todo[s][0], curve, s), seconds=allowed) for s in waiting}
        for s in waiting:
            f, _, attempts = todo[s]
            found = _judge(s, route, started[s], budget.finish(started[s]), f, curve, check, attempts)
            if found is not None:
                out[s] = found
    q = curve.q
    for s, (f, key, attempts) in todo.items():
        if s not in out:
            u = sp.Dummy("u", real=True)
            q_ref = reference_point(curve)
            out[s] = Antiderivative(s=s, integrand=f, expr=sp.Integral(f.subs(q, u), (u, q_ref, q)),
                                    route="numeric", verification="quadrature", attempts=tuple(attempts),
                                    q_ref=q_ref)
        _CACHE[key] = out[s]
    return out


def _judge(s: int, route: str, running, outcome, f: sp.Expr, curve: Curve, check: str, attempts: list):
    """The :class:`Antiderivative` a route's ``outcome`` gives, after its check, or ``None``; the
    attempt is appended to ``attempts`` either way."""
    if outcome.status == "timeout":
        attempts.append(Attempt(route, f"timeout after {running.seconds:.3g} s", outcome.seconds))
        return None
    if outcome.status == "error":
        attempts.append(Attempt(route, f"error: {outcome.value}", outcome.seconds))
        return None
    F = outcome.value
    if F.has(sp.Integral) or F.has(sp.Piecewise):
        attempts.append(Attempt(route, "no closed form", outcome.seconds))
        return None
    F = _tidy(F)
    how = verify(F, f, curve, check=check)
    elapsed = time.perf_counter() - running.started
    if how is None:
        attempts.append(Attempt(route, "rejected: derivative check failed", elapsed))
        return None
    F_reg, regular = regularize(F, curve.q)
    attempts.append(Attempt(route, f"closed form, verified {how}", elapsed))
    return Antiderivative(s=s, integrand=f, expr=F_reg, route=route, verification=how, attempts=tuple(attempts),
                          q_ref=reference_point(curve), mu_regular=regular)


def _route_job(route: str, f: sp.Expr, curve: Curve, s: int) -> tuple:
    """``(job, args)`` of one closed-form route for the integrand ``f`` of branch ``s``."""
    q = curve.q
    if route == "sympy":
        return _job_sympy, (sp.srepr(f), q.name)
    if route == "split":
        return _job_split, (sp.srepr(f), q.name)
    return _job_tangent, (sp.srepr(f), sp.srepr(curve.alpha), sp.srepr(curve.h), sp.srepr(curve.alphap), q.name, s)


def _with_q_ref(result: Antiderivative, q_ref: sp.Expr, q: sp.Symbol) -> Antiderivative:
    """``result`` measured from ``q_ref`` (a numeric route integrates from it)."""
    if result.q_ref == q_ref:
        return result
    if result.route == "numeric":
        u = result.expr.limits[0][0]
        return replace(result, q_ref=q_ref, expr=sp.Integral(result.expr.function, (u, q_ref, q)))
    return replace(result, q_ref=q_ref)


def _tidy(F: sp.Expr) -> sp.Expr:
    """A shorter equivalent form when one is cheap to find."""
    candidates = [F]
    for op in (sp.factor_terms, lambda e: sp.collect(sp.expand(e), sp.exp(sp.Wild("w")), evaluate=True),
               sp.powsimp):
        try:
            candidates.append(op(F))
        except Exception:  # noqa: BLE001 - tidying is optional
            pass
    return min(candidates, key=sp.count_ops)


def frictionless_gap(F: Antiderivative, curve: Curve, values: dict, points: int = 5) -> float:
    """Largest relative gap between ``F(q) - F(q0)`` at ``mu = MU_TINY`` and at ``mu -> 0``.

    Evaluated in double precision through :func:`sympy.lambdify`, so it shows
    whether a form cancels catastrophically as ``mu -> 0``; at ``mu = 0``
    ``F(q) - F(q0) = z(q) - z(q0)`` (energy conservation).
    """
    import math

    fx = sp.lambdify([curve.q, mu, *curve.params], F.expr, "math")
    zx = sp.lambdify([curve.q, *curve.params], curve.z, "math")
    ps = [float(values[p]) for p in curve.params]
    qs = [float(v) for v in sample_points(curve, points + 1, seed=11, values=values)]
    q0, worst = qs[0], 0.0
    for qv in qs[1:]:
        got = fx(qv, MU_TINY, *ps) - fx(q0, MU_TINY, *ps)
        want = zx(qv, *ps) - zx(q0, *ps)
        worst = max(worst, abs(got - want) / max(abs(want), math.ulp(1.0)))
    return worst
