"""The code generator's jobs: derive a curve and write, or check, its kernel module.

:func:`module_source` derives a curve under the routes and budgets of its :class:`Plan`
(:func:`route_plan`: ``closed_form`` ``"auto"``, ``"required"`` or ``"never"``) and returns the
text of its kernel module (:func:`symvib.codegen.kernel_text.module_text`), checked by the
loader's whitelist; :func:`generate` writes it into a folder, :func:`generate_catalogue` writes
every catalogue shape's (``symvib generate``), and :func:`stale` tells which committed modules no
longer match their inputs or were edited by hand (``symvib generate --check``).
"""
from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass
from pathlib import Path

from symvib import provenance, safeio
from symvib.codegen import gauss
from symvib.codegen.kernel_text import check_param_names, module_text
from symvib.codegen.printers import py_literal
from symvib.kernelformat import DIGEST_PREFIX, verify_text
from symvib.symbolic.derive import derive

__all__ = ["generate", "generate_catalogue", "stale", "DIGEST_PREFIX", "route_plan", "module_source", "Plan",
           "AUTO_SEARCH_SECONDS", "AUTO_ROUTES", "AUTO_ROUTE_SECONDS", "kernel_forms", "module_name", "resolved",
           "file_problems"]


def module_name(name: str) -> str:
    """Python module name for a curve name (``parabola-x`` -> ``parabola_x``)."""
    out = re.sub(r"\W", "_", name)
    return out if out[:1].isalpha() else "c_" + out


def resolved(curve, source, name):
    """``(curve, source, name)`` of a catalogue name, a Shape, or a Curve with its ``source``."""
    from symvib.shapes import Shape, shape

    if isinstance(curve, str):
        curve = shape(curve)
    if isinstance(curve, Shape):
        source = curve.source() if source is None else source
        name = name or curve.module
        curve = curve.curve()
    if source is None:
        raise ValueError("generate() needs the curve's defining data (source) to hash")
    return curve, source, name


#: Budget of the whole closed-form search (s, all routes together) for a curve with
#: ``closed_form = "auto"``: a closed form SymPy finds quickly is taken (checked numerically),
#: and otherwise the numeric ``F_sigma``, so that a new curve's first run waits seconds rather
#: than every route's full budget (:data:`~symvib.symbolic.integrals.ROUTE_SECONDS` each).
AUTO_SEARCH_SECONDS = 4.0
#: Budget of one route under ``closed_form = "auto"`` (s; at most what is left of
#: :data:`AUTO_SEARCH_SECONDS`).
AUTO_ROUTE_SECONDS = 2.0
#: The order of the routes under ``closed_form = "auto"``: the tangent-angle route first, which
#: finds the parabolas' forms in 0.5-1.5 s where ``integrate`` takes 3-6 s on their branch -1.
AUTO_ROUTES = ("tangent-angle", "sympy", "split")


@dataclass(frozen=True)
class Plan:
    """How the derivation of a curve searches ``F_sigma`` in closed form (:func:`route_plan`).

    Attributes
    ----------
    routes : tuple of str
        The closed-form routes, in order (:data:`~symvib.symbolic.integrals.ROUTES`); empty for
        the numeric ``F_sigma`` at once.
    seconds : float
        Budget of one route.
    total : float or None
        Budget of all the routes together (``None``: each route its own ``seconds``).
    check : {"symbolic", "numeric"}
        How a closed form found is checked (:func:`symvib.symbolic.integrals.verify`).
    """

    routes: tuple
    seconds: float
    total: float | None
    check: str


def route_plan(closed_form: str = "auto") -> Plan:
    """The :class:`Plan` of the derivation of a curve whose ``F_sigma`` is found as
    ``closed_form`` says (:data:`symvib.shapes.CLOSED_FORMS`).

    Examples
    --------
    >>> route_plan("never").routes
    ()
    >>> plan = route_plan("auto")
    >>> plan.total == AUTO_SEARCH_SECONDS, plan.check
    (True, 'numeric')
    >>> route_plan("required").total is None
    True
    """
    from symvib.shapes import CLOSED_FORMS
    from symvib.symbolic.integrals import ROUTE_SECONDS, ROUTES

    assert sorted(AUTO_ROUTES) == sorted(ROUTES)
    plans = {"auto": Plan(AUTO_ROUTES, AUTO_ROUTE_SECONDS, AUTO_SEARCH_SECONDS, "numeric"),
             "required": Plan(ROUTES, ROUTE_SECONDS, None, "symbolic"),
             "never": Plan((), ROUTE_SECONDS, None, "symbolic")}
    if closed_form not in plans:
        raise ValueError(f"curve.closed_form: {closed_form!r} is not one of {', '.join(CLOSED_FORMS)}")
    return plans[closed_form]


def kernel_forms(source: dict) -> str:
    """The forms (:data:`symvib.symbolic.derive.FORMS`) of the kernels of the curve ``source``.

    A catalogue shape's module keeps the simplest forms (``"simplest"``: ``generated/`` and the
    paper's equations as they were); a user curve's is derived with its expressions as
    differentiated (``"direct"``), seconds sooner; whoever generates it (``symvib run``,
    ``symvib generate``), one input hash gives one module.

    Examples
    --------
    >>> from symvib.shapes import shape
    >>> kernel_forms(shape("circle").source()), kernel_forms({"name": "circle", "z": "x**4"})
    ('simplest', 'direct')
    """
    from symvib.shapes import CATALOGUE

    catalogue = CATALOGUE.get(source.get("name"))
    return "simplest" if catalogue is not None and catalogue.source() == source else "direct"


def module_source(curve, *, source: dict | None = None, seconds: float | None = None, routes=None,
                  closed_form: str | None = None, origin="<generated module>") -> str:
    """Derive ``curve`` and return the text of its kernel module, checked by the loader's whitelist.

    Arguments as :func:`generate`'s; ``origin`` names the module in errors.  Nothing is written.
    ``closed_form`` (``"auto"``, ``"required"``, ``"never"``: :func:`route_plan`) chooses the routes
    and their budget where ``routes`` and ``seconds`` are not given; ``"required"`` raises a
    ValueError naming ``curve.closed_form`` when a branch has no closed form.  The coefficients
    of eq. 1 are written in the forms :func:`kernel_forms` gives the curve.
    """
    from symvib.symbolic.integrals import ROUTE_SECONDS, ROUTES

    curve, source, _ = resolved(curve, source, None)
    check_param_names(p.name for p in curve.params)  # before the derivation: fail in milliseconds
    py_literal(source)
    closed_form = source.get("closed_form") if closed_form is None else closed_form
    plan = Plan(ROUTES, ROUTE_SECONDS, None, "symbolic") if closed_form is None else route_plan(closed_form)
    if seconds is not None or routes is not None:   # a budget or routes of one's own: every route its seconds
        plan = Plan(plan.routes if routes is None else tuple(routes), plan.seconds if seconds is None else seconds,
                    None, plan.check)
    d = derive(curve, seconds=plan.seconds, routes=plan.routes, total=plan.total, check=plan.check,
               forms=kernel_forms(source))
    missing = [s for s, br in d.branches.items() if br.F.route == "numeric"] if closed_form == "required" else []
    if missing:
        tried = "; ".join(f"{a.route}: {a.outcome}" for a in d.branches[missing[0]].F.attempts)
        raise ValueError(f"curve.closed_form: 'required', but F_sigma of branch {missing[0]:+d} has no closed "
                         f"form within the routes' budgets ({tried}); give closed_form = \"auto\" (the numeric "
                         f"F_sigma) or a longer budget (symvib generate --budget)")
    text = module_text(d, source)
    verify_text(text, origin)  # what a generator writes must pass what a loader checks
    return text


def generate(curve, out_dir, *, name: str | None = None, source: dict | None = None,
             seconds: float | None = None, routes=None) -> Path:
    """Derive ``curve`` and write its kernel module into ``out_dir``; returns the path.

    ``curve`` is a catalogue name, a :class:`~symvib.shapes.Shape` or a
    :class:`~symvib.symbolic.curve.Curve` (then give ``source``, its defining data).
    ``seconds`` and ``routes`` are :func:`~symvib.symbolic.derive.derive`'s (default: every
    route of :data:`~symvib.symbolic.integrals.ROUTES`, :data:`~symvib.symbolic.integrals.ROUTE_SECONDS`
    each); ``routes=()`` takes the numeric route at once, as a curve with no closed-form
    ``F_sigma`` ends up doing after the budgets of every route.  The module is written whole
    or not at all, never through a symbolic link (:func:`symvib.safeio.write_text`).
    """
    curve, source, name = resolved(curve, source, name)
    stem = module_name(name or curve.name)
    out = safeio.check_root(out_dir, "output folder")
    text = module_source(curve, source=source, seconds=seconds, routes=routes, origin=out / f"{stem}.py")
    return safeio.write_text(out, f"{stem}.py", text)


def _generate_one(args):
    shape_name, out_dir = args
    return str(generate(shape_name, out_dir))


def generate_catalogue(out_dir, *, names=None, processes: int | None = None) -> list:
    """Write the kernel module of every catalogue shape (in parallel processes).

    With the whole catalogue, the driver's Gauss-Legendre table
    (:mod:`symvib.codegen.gauss`) is rewritten too.
    """
    import multiprocessing as mproc

    from symvib.shapes import CATALOGUE
    from symvib.symbolic.budget import worker_pool

    names = sorted(CATALOGUE) if names is None else list(names)
    jobs = [(n, str(out_dir)) for n in names]
    table = [] if len(names) < len(CATALOGUE) else [str(gauss.write_table(out_dir))]
    if processes == 1 or len(jobs) == 1:
        return table + [_generate_one(j) for j in jobs]
    with worker_pool(processes or min(len(jobs), mproc.cpu_count())) as pool:
        return table + list(pool.map(_generate_one, jobs))


def stale(out_dir, *, names=None) -> list:
    """Problems with the catalogue modules in ``out_dir`` (empty when all are current).

    A module is stale when it is missing, its input hash differs from the
    current one (the shape's data or the generator changed), or its body does
    not match its recorded digest (edited by hand).  No derivation is run.  With
    the whole catalogue, the Gauss-Legendre table is recomputed and compared.
    """
    from symvib.shapes import CATALOGUE

    out = Path(out_dir)
    names = sorted(CATALOGUE) if names is None else list(names)
    problems = []
    for n in names:
        shape_ = CATALOGUE[n]
        path = out / f"{module_name(shape_.module)}.py"
        if not path.exists():
            problems.append(f"{path}: missing")
            continue
        problems += file_problems(path, provenance.input_hash(shape_.source()))
    expected = {f"{module_name(CATALOGUE[n].module)}.py" for n in names} | {"__init__.py",
                                                                             f"{gauss.TABLE_MODULE}.py"}
    if names == sorted(CATALOGUE):
        problems += gauss.table_problems(out)
        for extra in sorted(p.name for p in out.glob("*.py")):
            if extra not in expected:
                problems.append(f"{out / extra}: not a catalogue shape (remove it)")
    return problems


def file_problems(path: Path, want_hash: str) -> list:
    """Problems with the generated module at ``path``: its body not matching its recorded digest
    (edited by hand), or its ``INPUT_HASH`` not ``want_hash`` (stale)."""
    text = path.read_text(encoding="utf-8")
    first, _, body = text.partition("\n")
    problems = []
    if not first.startswith(DIGEST_PREFIX) or first[len(DIGEST_PREFIX):] != hashlib.sha256(body.encode()).hexdigest():
        problems.append(f"{path}: edited by hand (body digest mismatch)")
    match = re.search(r"^INPUT_HASH = '([0-9a-f]{64})'$", body, re.M)
    if not match or match.group(1) != want_hash:
        problems.append(f"{path}: stale (inputs or generator changed); run `symvib generate`")
    return problems
