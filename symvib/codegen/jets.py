"""The jets of a curve: the derivatives exact sensitivities need beyond the kernel module (physics.md, "Sensitivities").

A curve's kernel module (:mod:`symvib.codegen.kernel_text`) holds what a run needs: ``x', z', h,
h', alpha, alpha', kappa``, ``F_s`` and its first two derivatives.  Differentiating a run's events
(:mod:`symvib.numeric.sensitivity`) needs two more families, written here into a companion
module of their own so that the kernel modules, their generator and its hash stay as they are:

* ``jet3(q, *cp)``: ``(x''', z''', kappa')``: ``kappa'`` is the slope of the normal force along
  the trajectory at a sign change of ``N`` (physics.md, "Sensitivities" 8);
* ``param_jet_<j>(q, *cp)``: the derivatives with respect to the ``j``-th curve parameter ``a`` at
  fixed ``q`` of ``(x, z, x', z', x'', z'', alpha, alpha', h, h', kappa)``, and
  ``dF_p_param_<j>(q, mu, *cp)``, ``dF_m_param_<j>``: of ``F_s' = exp(2 s mu alpha) (z' + s mu x')``
  (physics.md, "Sensitivities" 9).

Functions are named by the parameter's position (``PARAM_JETS`` maps each name to its index),
so no user text becomes an identifier; parameter names are checked as the kernel module's are
(:func:`symvib.codegen.kernel_text.check_param_names`) and the curve's name reaches the docstring
only where it cannot end it.  The printing (common subexpressions eliminated, no conditional)
is the kernel generator's own (:mod:`symvib.codegen.printers`).  The module is sealed like a
kernel module (its body's digest on the first line) and records ``INPUT_HASH``, the jets hash of the curve
(:func:`symvib.provenance.jets_hash`: the kernel module's inputs and this file's source).
Catalogue curves' jets are committed in ``generated/jets/`` (``symvib generate`` writes and
``--check`` checks them); a user curve's are generated on first need and cached beside its
kernels (:func:`symvib.prepare.load_jets`).

Examples
--------
>>> text = jets_text("circle")
>>> "def param_jet_0(q, R):" in text and "import sympy" not in text
True
"""
from __future__ import annotations

import hashlib
from pathlib import Path

import sympy as sp

from symvib import provenance, safeio
from symvib.codegen.generate import file_problems, module_name, resolved
from symvib.codegen.kernel_text import check_param_names
from symvib.codegen.printers import BROADCAST, NumPy, doc_text, function, generic, py_literal
from symvib.kernelformat import DIGEST_PREFIX, verify_text
from symvib.symbolic.symbols import mu

__all__ = ["jets_text", "write_jets", "generate_jets_catalogue", "stale_jets", "JET3", "PARAM_JET", "JETS_FOLDER",
           "jet_exprs"]

#: Folder of the catalogue's jets modules inside ``generated/`` (not a ``*.py`` of ``generated/``
#: itself, which :func:`symvib.codegen.generate.stale` keeps for the catalogue's kernel modules).
JETS_FOLDER = "jets"
#: What ``jet3`` returns, in order.
JET3 = ("d3x", "d3z", "dkappa")
#: What ``param_jet_<j>`` returns, in order: each differentiated with respect to the parameter at fixed ``q``.
PARAM_JET = ("x", "z", "dx", "dz", "d2x", "d2z", "alpha", "dalpha", "h", "dh", "kappa")

_Q = sp.Symbol("q", real=True)
_BRANCH = {1: "p", -1: "m"}


def jet_exprs(curve) -> list:
    """``(name, argument names, expression, description)`` of every jets kernel of ``curve`` (a
    :class:`~symvib.symbolic.curve.Curve`), ``q`` already the kernels' ``q``; a tuple kernel's
    expression is an :class:`sympy.Tuple` in the order of :data:`JET3` / :data:`PARAM_JET`."""
    c = curve
    cp = tuple(p.name for p in c.params)
    K = lambda e: sp.sympify(e).xreplace({c.q: _Q})  # noqa: E731
    geo = ("q", *cp)
    q = c.q
    out = [("jet3", geo, sp.Tuple(K(sp.diff(c.x, q, 3)), K(sp.diff(c.z, q, 3)), K(sp.diff(c.kappa, q))),
             "(x''', z''', kappa'): third derivatives and the slope of the curvature")]
    for j, a in enumerate(c.params):
        base = (c.x, c.z, c.xp, c.zp, sp.diff(c.xp, q), sp.diff(c.zp, q), c.alpha, c.alphap, c.h, c.hp, c.kappa)
        out.append((f"param_jet_{j}", geo, sp.Tuple(*(K(sp.diff(e, a)) for e in base)),
                    f"d/d{a.name} at fixed q of ({', '.join(PARAM_JET)})"))
        for s, b in _BRANCH.items():
            f = sp.exp(2 * s * mu * c.alpha) * (c.zp + s * mu * c.xp)
            out.append((f"dF_{b}_param_{j}", ("q", "mu", *cp), K(sp.diff(f, a)),
                        f"d/d{a.name} at fixed q of F_{'+' if s > 0 else '-'}' = exp({'' if s > 0 else '-'}2 mu "
                        f"alpha) (z' {'+' if s > 0 else '-'} mu x')"))
    return out


def jets_text(curve, *, source: dict | None = None, name: str | None = None) -> str:
    """The text of the jets module of ``curve`` (a catalogue name, a :class:`~symvib.shapes.Shape`,
    or a :class:`~symvib.symbolic.curve.Curve` with its ``source``), checked by the loader's whitelist.

    Raises
    ------
    CurveError
        Naming ``curve.params`` for a parameter name a kernel may not have, or the kernel whose
        expression cannot be printed without a conditional.
    """
    curve, source, _ = resolved(curve, source, name)
    cp = check_param_names(p.name for p in curve.params)
    py_literal(source)
    printer = NumPy()
    parts, signatures = [], {}
    for fname, args, expr, doc in jet_exprs(curve):
        field = f"curve '{curve.name}': jet {fname}"
        if isinstance(expr, sp.Tuple):
            expr = sp.Tuple(*(generic(e, field) for e in expr))
        else:
            expr = generic(expr, field)
        signatures[fname] = args
        parts.append(function(fname, args, expr, f"{doc_text(doc, fname)}.\n\n    Arguments: ({', '.join(args)}).",
                              printer))
    shown = doc_text(repr(source.get("name", curve.name)), "named in NAME")
    header = (f'"""Jets of the curve {shown}: generated by `symvib generate` (symvib.codegen.jets); do not edit.\n\n'
              "jet3: (x''', z''', kappa'); param_jet_<j>: d/d(parameter j) at fixed q of\n"
              f"({', '.join(PARAM_JET)}); dF_p_param_<j>, dF_m_param_<j>: d/d(parameter j) of F_s'.\n"
              "PARAM_JETS maps each parameter's name to j; SIGNATURES gives every function's arguments.\n"
              '"""\n')
    consts = [
        f"NAME = {source.get('name', curve.name)!r}",
        f"CURVE_PARAMS = {cp!r}",
        f"PARAM_JETS = {py_literal({n: j for j, n in enumerate(cp)})}",
        f"JET3 = {JET3!r}",
        f"PARAM_JET = {PARAM_JET!r}",
        f"INPUT_HASH = {provenance.jets_hash(source)!r}",
        f"SYMPY_VERSION = {sp.__version__!r}",
        "SIGNATURES = {\n" + "".join(f"    {k!r}: {v!r},\n" for k, v in sorted(signatures.items())) + "}",
    ]
    body = header + "import numpy\n\n" + "\n".join(consts) + "\n" + BROADCAST + "\n\n" + "\n\n\n".join(parts) + "\n"
    text = f"{DIGEST_PREFIX}{hashlib.sha256(body.encode()).hexdigest()}\n" + body
    verify_text(text, "<jets module>")
    return text


def write_jets(curve, out_dir, *, source: dict | None = None, name: str | None = None) -> Path:
    """Write the jets module of ``curve`` into ``out_dir`` as ``<module name>.py`` (whole or not at
    all, never through a link: :func:`symvib.safeio.write_text`); returns the path."""
    curve_, source_, name_ = resolved(curve, source, name)
    text = jets_text(curve_, source=source_, name=name_)
    out = safeio.check_root(out_dir, "output folder")
    return safeio.write_text(out, f"{module_name(name_ or curve_.name)}.py", text)


def generate_jets_catalogue(generated, *, names=None) -> list:
    """Write the jets module of every catalogue shape (or of ``names``) into ``generated/jets/``."""
    from symvib.shapes import CATALOGUE

    folder = Path(generated) / JETS_FOLDER
    folder.mkdir(exist_ok=True)
    return [write_jets(n, folder) for n in (sorted(CATALOGUE) if names is None else names)]


def stale_jets(generated, *, names=None) -> list:
    """Problems with the catalogue's jets modules in ``generated/jets/`` (empty when all are current):
    missing, made from other inputs (the shape, the kernel generator or this module changed), or
    edited by hand.  No derivation runs."""
    from symvib.shapes import CATALOGUE

    folder = Path(generated) / JETS_FOLDER
    problems = []
    for n in sorted(CATALOGUE) if names is None else names:
        shape_ = CATALOGUE[n]
        path = folder / f"{module_name(shape_.module)}.py"
        if not path.exists():
            problems.append(f"{path}: missing")
            continue
        problems += file_problems(path, provenance.jets_hash(shape_.source()))
    return problems
