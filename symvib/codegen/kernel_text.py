"""The one bridge: derivation -> plain NumPy kernel module.

:func:`module_text` turns a :class:`~symvib.symbolic.derive.Derivation` into the source
of a Python module that needs only NumPy (and :mod:`math` for the scalar
path): one function per kernel and per branch, common subexpressions
eliminated (:func:`sympy.cse`), and no conditional: every ``Piecewise`` is
replaced by its generic branch before cse
(:func:`~symvib.symbolic.branches.generic_branch`: the branches SymPy adds on
equalities such as ``Eq(cos(phi), 0)`` hold on a set of measure zero, a singular
point or a removable value), ``sign(f)`` prints as ``math.copysign(1.0, f)`` /
``numpy.copysign(1.0, f)`` and ``Abs`` as ``abs`` / ``numpy.abs`` (a power of ``Abs(u)``
in a denominator as one of ``u sign(u)``, so that a removable value such as ``q**2 /
|q|`` at 0 is finite: :func:`~symvib.symbolic.branches.removable_form`); a condition that is an
inequality is a :class:`~symvib.symbolic.branches.CurveError`.  Functions
broadcast over NumPy arrays of ``q``, the state and the parameters; every
kernel also has a ``*_scalar`` twin built on :mod:`math`, which is several
times faster for one float (root finding in the driver).

Kernels (argument order in each docstring and in ``SIGNATURES``); ``cp`` are
the curve parameters in declaration order, ``_p``/``_m`` the branches
``s = +1``/``-1``:

============================  =========================================================
``x z h alpha kappa``         geometry, ``(q, *cp)``
``dx dz dh dalpha``           ``x' z' h' alpha'``, ``(q, *cp)``
``F_p dF_p ddF_p``            ``F_s`` (eq. 2), its integrand and derivative, ``(q, mu, *cp)``
``w_p qdot2_p``               ``w(q; C)`` and ``qdot**2`` (eq. 2), ``(q, C, g, mu, *cp)``
``qddot_p``                   eq. 1 solved for ``qddot``, ``(q, qdot, g, mu, *cp)``
``N_w``                       normal force per mass ``kappa w + g cos(alpha)``, ``(q, w, g, *cp)``
``F_N P_mu Ek Ep E``          energy analysis (physics.md), state form ``(q, qdot, ...)``
``domain q_scale``            the regular interval of ``q`` and its scale, ``(*cp)``
============================  =========================================================

The constant ``ALPHA_CUT`` (:attr:`~symvib.symbolic.curve.Curve.alpha_cut`) is ``True``
when the kernel ``alpha`` is ``atan2(z', x')``, no continuous closed form having been
found: it jumps by ``2 pi`` where ``x' < 0`` and ``z'`` changes sign, so the engine
must not integrate across such a point as if ``alpha`` were continuous.

On the numeric route ``F_s`` integrates ``dF_s`` from ``Q_REF`` by the rule of
:mod:`symvib.antiderivative`: pieces no wider than ``PANEL * q_scale``, each one
16-point Gauss-Legendre panel where the Legendre tail of ``dF_s`` on it says that
is enough (``TOL``, 1e-15 of its integral of ``|dF_s|``), else walked with halved
and doubled panels (``_F_p_panel_scalar`` is one panel: its integral, error
estimate and tolerance), so that a narrow feature of a curve whose ``q_scale`` is
1 (a Gaussian well, a sine track of small width) is resolved where it is: ``F_s``
within a few rounding errors of the integral of ``|dF_s|``.  ``F_p_scalar``
calls its ``dF_p_scalar`` by name and decides without a conditional (the
whitelist has none: ``math.copysign`` steps, ``range`` of 0 or 1); ``F_p`` is
``F_p_scalar`` at every point of the broadcast arguments.

The output is deterministic (no timings, sorted data), so generating twice
gives the same bytes; the header records the inputs' hash
(:mod:`symvib.provenance`), and a digest of the body so hand edits show.

Examples
--------
>>> from symvib.symbolic.derive import derive
>>> text = module_text(derive("circle"), {"name": "circle"})
>>> "def F_p(q, mu, R):" in text and "import sympy" not in text
True
"""
from __future__ import annotations

import builtins
import hashlib
import keyword

import sympy as sp

from symvib import antiderivative, provenance
from symvib.codegen.printers import BROADCAST, Math, NumPy, doc_text, function, generic, py_literal
from symvib.kernelformat import DIGEST_PREFIX
from symvib.symbolic.branches import CurveError
from symvib.symbolic.derive import Derivation
from symvib.symbolic.symbols import C, g, mu

__all__ = ["module_text", "check_param_names", "kernel_exprs", "KERNEL_FUNCTIONS", "KERNEL_CONSTANTS",
           "KERNEL_RESERVED", "QUAD_NODES", "PANEL"]

#: Gauss-Legendre nodes per panel of a numeric-route antiderivative (:mod:`symvib.antiderivative`).
QUAD_NODES = antiderivative.NODES
#: Widest panel of a numeric-route antiderivative, in units of ``q_scale``.
PANEL = antiderivative.PANEL
#: Functions every kernel module defines (each also as ``<name>_scalar``).
KERNEL_FUNCTIONS = frozenset({
    "x", "z", "h", "alpha", "kappa", "dx", "dz", "dh", "dalpha", "N_w", "F_N", "P_mu", "Ek", "Ep", "E",
    "q_scale", "domain", *(f"{k}_{b}" for k in ("F", "dF", "ddF", "w", "qdot2", "qddot", "node")
                              for b in ("p", "m"))})
#: Constants every kernel module defines.
KERNEL_CONSTANTS = frozenset({"NAME", "COORDINATE", "PARAMS", "F_ROUTES", "Q_REF", "PANEL", "INPUT_HASH",
                              "SYMPY_VERSION", "GENERATOR_VERSION", "SOURCE", "SIGNATURES", "ALPHA_CUT"})
#: Names a curve parameter may not have in a kernel module: its arguments, modules and
#: module-level names (a parameter is a Python argument of every kernel, so it would shadow them).
KERNEL_RESERVED = frozenset({"q", "qdot", "w", "numpy", "math"} | KERNEL_FUNCTIONS
                            | {f"{k}_scalar" for k in KERNEL_FUNCTIONS} | KERNEL_CONSTANTS)

_Q = sp.Symbol("q", real=True)
_QDOT = sp.Symbol("qdot", real=True)
_W = sp.Symbol("w", real=True)
_BRANCH = {1: "p", -1: "m"}


def kernel_exprs(d: Derivation) -> list:
    """(name, argument names, expression, one-line description) of every closed-form kernel."""
    c = d.curve
    cp = tuple(p.name for p in c.params)
    to_kernel = {c.q: _Q, c.qdot: _QDOT}
    K = lambda e: sp.sympify(e).xreplace(to_kernel)  # noqa: E731
    geo = ("q", *cp)
    out = [
        ("x", geo, K(c.x), "x(q): horizontal position"),
        ("z", geo, K(c.z), "z(q): height"),
        ("h", geo, K(c.h), "h(q) = sqrt(x'^2 + z'^2): metric, ds = h dq"),
        ("alpha", geo, K(c.alpha), "alpha(q): tangent angle, h sin(alpha) = z', h cos(alpha) = x'"),
        ("kappa", geo, K(c.kappa), "kappa(q) = alpha'/h: curvature"),
        ("dx", geo, K(c.xp), "x'(q)"),
        ("dz", geo, K(c.zp), "z'(q)"),
        ("dh", geo, K(c.hp), "h'(q)"),
        ("dalpha", geo, K(c.alphap), "alpha'(q)"),
    ]
    for s, br in d.branches.items():
        b = _BRANCH[s]
        sign = "+" if s > 0 else "-"
        f = K(br.F.integrand)
        out.append((f"dF_{b}", ("q", "mu", *cp), f,
                    f"F_{sign}'(q) = exp({sign}2 mu alpha) (z' {sign} mu x'): integrand of eq. 2"))
        out.append((f"ddF_{b}", ("q", "mu", *cp), sp.diff(f, _Q), f"F_{sign}''(q)"))
        if br.F.closed:
            out.append((f"F_{b}", ("q", "mu", *cp), K(br.F.expr),
                        f"F_{sign}(q): antiderivative of eq. 2 (route: {br.F.route})"))
        out.append((f"w_{b}", ("q", "C", "g", "mu", *cp),
                    K(sp.exp(-2 * s * mu * c.alpha)) * (C - 2 * g * sp.Symbol(f"__F_{b}")),
                    f"w(q; C) = exp({'-' if s > 0 else ''}2 mu alpha) [C - 2 g F_{sign}(q)] (eq. 2, s = {s:+d})"))
        out.append((f"qdot2_{b}", ("q", "C", "g", "mu", *cp),
                    K(sp.exp(-2 * s * mu * c.alpha) / c.h**2) * (C - 2 * g * sp.Symbol(f"__F_{b}")),
                    f"qdot^2(q; C) = w / h^2 (eq. 2, s = {s:+d})"))
        out.append((f"qddot_{b}", ("q", "qdot", "g", "mu", *cp), K(br.qddot(c.qdot)),
                    f"qddot = -A qdot^2 - B (eq. 1, s = {s:+d})"))
        # What the driver's time quadrature needs at a node, fused so that shared
        # subexpressions are computed once: F_s' = e^2 (z' + s mu x') with
        # e = exp(s mu alpha), then h, e, kappa, cos(alpha).
        e1 = sp.Symbol("_e0")
        out.append((f"node_{b}", ("q", "mu", *cp),
                    ({e1: K(sp.exp(s * mu * c.alpha))},
                     sp.Tuple(e1**2 * K(c.zp + s * mu * c.xp), K(c.h), e1, K(c.kappa), K(c.xp / c.h))),
                    f"(F_{sign}', h, exp({sign}mu alpha), kappa, cos(alpha)) at once, for the time quadrature"))
    e = d.energies
    out += [
        ("N_w", ("q", "w", "g", *cp), K(c.kappa) * _W + g * K(sp.cos(c.alpha)),
         "N = kappa w + g cos(alpha): normal force per unit mass"),
        ("F_N", ("q", "qdot", "g", "m", *cp), K(e["F_N"]), "F_N = m (kappa v^2 + g cos(alpha))"),
        ("P_mu", ("q", "qdot", "g", "m", "mu", *cp), K(e["P_mu"]), "P_mu = -mu |F_N| |v|: power of friction"),
        ("Ek", ("q", "qdot", "m", *cp), K(e["Ek"]), "Ek = m v^2 / 2"),
        ("Ep", ("q", "g", "m", *cp), K(e["Ep"]), "Ep = m g z"),
        ("E", ("q", "qdot", "g", "m", *cp), K(e["E"]), "E = Ek + Ep"),
        ("q_scale", cp, c.q_scale, "characteristic length of q"),
    ]
    return out


def _literal(values) -> str:
    return "(" + ", ".join(repr(float(v)) for v in values) + ",)"

_QUAD_HELPERS = '''
_GL_X = {x}
_GL_W = {w}
_GL_T1 = {t1}
_GL_T2 = {t2}
_GL_T3 = {t3}
_GL_T4 = {t4}
_F_TOL = {tol!r}
_F_FLAT = {flat!r}
_F_UNRESOLVED = {unresolved!r}
_F_POWER = {power!r}
_F_TRIES = {tries!r}
_F_NARROWEST = {narrowest!r}
'''

# One panel of a numeric F_s, and F_s itself (symvib.antiderivative), per branch: formatted with
# {b} (p or m), {args} (q, mu, cp), {pargs} (left, width, mu, cp), {cargs} (mu, cp), {ref}, {scale}.
# The scalar F_s calls its panel and dF by name (not as functions passed in): numba caches a
# compiled function on disk only without such values, so the compiled engine is found again.
# No conditional, no comparison (the whitelist, symvib.kernelformat): 0.5 + 0.5 copysign(1, x) is
# 1 where x >= 0 and 0 where x < 0 (and 0 or 1 for NaN), and range(n) with n 0 or 1 is a branch.
_PANEL_TEMPLATE = '''def _F_{b}_panel_scalar({pargs}):
    \"\"\"(integral, error estimate, tolerance) of dF_{b} over [left, left + width]: one panel of
    Gauss-Legendre nodes, the error from the Legendre tail of dF_{b} (symvib.antiderivative).

    Arguments: ({pargs}). Floats only (math).\"\"\"
    total = 0.0
    size = 0.0
    c1 = 0.0
    c2 = 0.0
    c3 = 0.0
    c4 = 0.0
    for xk, wk, t1, t2, t3, t4 in zip(_GL_X, _GL_W, _GL_T1, _GL_T2, _GL_T3, _GL_T4):
        v = dF_{b}_scalar(left + 0.5 * width * (xk + 1.0), {cargs})
        total += wk * v
        size += wk * abs(v)
        c1 += t1 * v
        c2 += t2 * v
        c3 += t3 * v
        c4 += t4 * v
    tail = max(abs(c1), abs(c2))
    ratio = min(1.0, math.sqrt(tail / (max(abs(c3), abs(c4)) + 1e-300)))
    flat = 0.5 + 0.5 * math.copysign(1.0, ratio - _F_UNRESOLVED)
    real = 0.5 + 0.5 * math.copysign(1.0, tail - flat * _F_FLAT * 0.5 * size)
    return 0.5 * width * total, 2.0 * tail * max(ratio ** _F_POWER, flat) * real, _F_TOL * size'''

_F_TEMPLATE = '''def F_{b}_scalar({args}):
    \"\"\"{doc} Floats only (math).\"\"\"
    q_ref = {ref}
    length = q - q_ref
    panels = max(1, math.ceil(abs(length) / (PANEL * q_scale_scalar({scale}))))
    step = length / panels
    total = 0.0
    for k in range(panels):
        left = q_ref + k * step
        value, error, tol = _F_{b}_panel_scalar(left, step, {cargs})
        passed = max(0.5 + 0.5 * math.copysign(1.0, tol - error), 1.0 - int(math.isfinite(error)))
        total += passed * value
        done = passed
        width = 0.5
        tries = int((_F_TRIES - 1) * (1.0 - passed))
        for attempt in range(tries):
            todo = int(0.5 - 0.5 * math.copysign(1.0, done - 1.0))
            for once in range(todo):
                width = min(width, 1.0 - done)
                value, error, tol = _F_{b}_panel_scalar(left + done * step, width * step, {cargs})
                passed = max(0.5 + 0.5 * math.copysign(1.0, tol - error), 1.0 - int(math.isfinite(error)),
                             0.5 + 0.5 * math.copysign(1.0, _F_NARROWEST - width))
                total += passed * value
                done += passed * width
                width = min(1.0, width * (0.5 + 1.5 * passed))
        todo = int(0.5 - 0.5 * math.copysign(1.0, done - 1.0))
        for once in range(todo):
            total += _F_{b}_panel_scalar(left + done * step, (1.0 - done) * step, {cargs})[0]
    return total'''

_F_ARRAY_TEMPLATE = '''def F_{b}({args}):
    \"\"\"{doc}\"\"\"
    points = numpy.broadcast({args})
    values = [F_{b}_scalar(*[float(v) for v in point]) for point in points]
    return numpy.reshape(numpy.array(values, dtype=float), points.shape) * 1.0'''


def module_text(d: Derivation, source: dict) -> str:
    """The full text of the kernel module for derivation ``d``.

    ``source`` is the curve's defining data (hashed into the header).
    """
    c = d.curve
    cp = check_param_names(p.name for p in c.params)
    kernels = kernel_exprs(d)
    numeric = {s: not br.F.closed for s, br in d.branches.items()}
    F_sub = {}
    for s in (1, -1):
        b = _BRANCH[s]
        F_sub[sp.Symbol(f"__F_{b}")] = sp.Function(f"F_{b}")(_Q, mu, *c.params)
    np_printer, math_printer = NumPy(), Math()
    parts = []
    signatures = {}
    for name, args, expr, doc in kernels:
        expr = generic(expr, f"curve '{c.name}': kernel {name}")
        if not isinstance(expr, tuple):
            expr = expr.xreplace(F_sub)
        signatures[name] = args
        argdoc = f"{doc}.\n\n    Arguments: ({', '.join(args)})."
        parts.append(function(name, args, expr, argdoc, np_printer))
        parts.append(function(name + "_scalar", args, expr, argdoc + " Floats only (math).", math_printer))
    # Numeric-route antiderivatives.
    needs_quad = any(numeric.values())
    for s in (1, -1):
        if numeric[s] and not d.branches[s].F.q_ref.is_finite:
            raise CurveError(f"curve.domain: the reference point {d.branches[s].F.q_ref} of the numeric "
                             "antiderivative is not finite")
    for s in (1, -1):
        if not numeric[s]:
            continue
        b = _BRANCH[s]
        sign = "+" if s > 0 else "-"
        args = ("q", "mu", *cp)
        signatures[f"F_{b}"] = args
        call_args = ", ".join(("mu", *cp))
        ref_s = math_printer.doprint(d.branches[s].F.q_ref.xreplace({c.q: _Q}))
        scale = ", ".join(cp)
        doc = (f"F_{sign}(q): integral of dF_{b} from Q_REF (numeric route: no closed form; the rule of "
               f"symvib.antiderivative).\n\n    Arguments: ({', '.join(args)}).")
        fill = {"b": b, "args": ", ".join(args), "pargs": ", ".join(("left", "width", "mu", *cp)),
                "cargs": call_args, "ref": ref_s, "scale": scale}
        parts.append(_F_ARRAY_TEMPLATE.format(doc=doc + " F_" + b + "_scalar at every point (broadcasts).",
                                              **fill))
        parts.append(_F_TEMPLATE.format(doc=doc, **fill))
        parts.append(_PANEL_TEMPLATE.format(**fill))
    # Domain as numbers.
    lo, hi = c.domain
    dom = lambda e, p: "math.inf" if e == sp.oo else "-math.inf" if e == -sp.oo else p.doprint(e)  # noqa: E731
    signatures["domain"] = cp
    parts.append(f"def domain({', '.join(cp)}):\n    \"\"\"Open interval of q where the curve is regular.\n\n"
                 f"    Arguments: ({', '.join(cp)}).\"\"\"\n"
                 f"    return ({dom(lo, math_printer)}, {dom(hi, math_printer)})")
    routes = {s: br.F.route for s, br in d.branches.items()}
    header = _header(d, source, routes)
    consts = [
        f"NAME = {source.get('name', c.name)!r}",
        f"COORDINATE = {c.q.name!r}",
        f"PARAMS = {cp!r}",
        f"F_ROUTES = {{1: {routes[1]!r}, -1: {routes[-1]!r}}}",
        f"Q_REF = {float(d.branches[1].F.q_ref.subs({p: 1 for p in c.params})) if needs_quad else 0.0!r}",
        f"PANEL = {PANEL!r}",
        f"ALPHA_CUT = {bool(c.alpha_cut)!r}",
        f"INPUT_HASH = {provenance.input_hash(source)!r}",
        f"SYMPY_VERSION = {sp.__version__!r}",
        f"GENERATOR_VERSION = {provenance.GENERATOR_VERSION!r}",
        f"SOURCE = {py_literal(source)}",
        "SIGNATURES = {\n" + "".join(f"    {k!r}: {v!r},\n" for k, v in sorted(signatures.items())) + "}",
    ]
    quad = ""
    if needs_quad:
        x, w, t1, t2, t3, t4 = antiderivative.tail_rows(QUAD_NODES)
        quad = _QUAD_HELPERS.format(x=_literal(x), w=_literal(w), t1=_literal(t1), t2=_literal(t2),
                                    t3=_literal(t3), t4=_literal(t4), tol=antiderivative.TOL,
                                    flat=antiderivative.FLAT, unresolved=antiderivative.UNRESOLVED,
                                    power=antiderivative.TAIL_POWER, tries=antiderivative.TRIES,
                                    narrowest=antiderivative.NARROWEST)
    body = (header + "import math\n\nimport numpy\n\n" + "\n".join(consts) + "\n" + BROADCAST + quad
            + "\n\n" + "\n\n\n".join(parts) + "\n")
    digest = hashlib.sha256(body.encode()).hexdigest()
    return f"{DIGEST_PREFIX}{digest}\n" + body


def check_param_names(names) -> tuple:
    """The parameter names as a tuple, if each can be a Python argument of a kernel.

    A name must be an ASCII identifier (Python folds other identifiers by NFKC,
    so two parameters could become one argument), not a keyword, not start with
    ``_`` (the kernels' temporaries) and not be a builtin or one of
    :data:`KERNEL_RESERVED`.

    Raises
    ------
    CurveError
        Naming ``curve.params`` and the offending name.
    """
    names = tuple(names)
    for name in names:
        why = ("is not an ASCII identifier" if not (isinstance(name, str) and name.isascii() and name.isidentifier())
               else "is a Python keyword" if keyword.iskeyword(name)
               else "starts with '_' (kept for the kernels' temporaries)" if name.startswith("_")
               else "is reserved in kernel modules" if name in KERNEL_RESERVED or hasattr(builtins, name)
               else "")
        if why:
            raise CurveError(f"curve.params: parameter name {name!r} {why}; rename it")
    return names


def _header(d: Derivation, source: dict, routes: dict) -> str:
    c = d.curve
    lines = [
        f'"""Kernels of the curve {doc_text(repr(source.get("name", c.name)), "named in NAME")}: '
        'generated by `symvib generate`; do not edit.',
        "",
        f"Curve ({c.kind}): x = {c.x}, z = {c.z}, coordinate {c.q} (passed as q),",
        f"parameters {', '.join(p.name for p in c.params) or 'none'}, domain ({c.domain[0]}, {c.domain[1]}).",
        f"Geometry: h = {c.h}, alpha = {c.alpha}, kappa = {c.kappa}.",
        ("ALPHA_CUT: alpha is atan2(z', x'), which jumps by 2 pi where x' < 0 and z' changes sign."
         if c.alpha_cut else "ALPHA_CUT = False: alpha is continuous wherever the curve is regular."),
        "",
        "Phase trajectory (eq. 2), branch s = +1 (p) and -1 (m):",
        "    w(q; C) = exp(-2 s mu alpha) [C - 2 g F_s(q)],  qdot^2 = w / h^2.",
    ]
    for s in (1, -1):
        F = d.branches[s].F
        text = str(F.expr) if F.closed else f"numeric quadrature of {F.integrand} from {F.q_ref}"
        lines.append(f"F_{_BRANCH[s]} (route {routes[s]}): {text}")
    lines += [
        "",
        f"SymPy {sp.__version__}; generator {provenance.GENERATOR_VERSION}; "
        f"input hash {provenance.input_hash(source)}.",
        "Each function's docstring gives its argument order; SIGNATURES lists them all.",
        '"""',
    ]
    # Only the first line opens and only the last closes the docstring; user text in the
    # lines between is shown only when it cannot end it (doc_text).
    body = [lines[0]] + [doc_text(line, "(not shown: see SOURCE)") for line in lines[1:-1]]
    return "\n".join(_wrap(line) for line in body) + '\n"""\n'


def _wrap(line: str, width: int = 100) -> str:
    if len(line) <= width:
        return line
    return "\n    ".join(line[i:i + width] for i in range(0, len(line), width))
