"""Run a SymPy computation under a wall-clock budget, in a child process.

SymPy's ``integrate`` and ``simplify`` can run for minutes and cannot be
interrupted from another thread, so every open-ended symbolic step of a
derivation runs in a forked child (``spawn`` where ``fork`` is unavailable)
that is killed when its budget is spent.  Expressions cross the process
boundary as ``srepr`` text, which round-trips exactly.  The child is tethered
(:func:`symvib.children.tether`): it dies with its parent, and the kernel ends it
a little after its budget in CPU time even when its parent cannot.

Examples
--------
>>> import sympy as sp
>>> outcome = run(_integrate_job, (sp.srepr(sp.cos(sp.Symbol("t"))), "t"), seconds=20)
>>> outcome.status, outcome.value
('ok', sin(t))
"""
from __future__ import annotations

import os
import time
from dataclasses import dataclass

import sympy as sp

from symvib import children

__all__ = ["Outcome", "run", "worker_pool"]

#: Seconds to wait for a killed child to exit.
_JOIN_SECONDS = 5.0


@dataclass(frozen=True)
class Outcome:
    """What a budgeted job returned.

    ``status`` is ``"ok"``, ``"timeout"`` or ``"error"``; ``value`` is the
    SymPy result for ``"ok"`` and the error text for ``"error"``.
    """

    status: str
    value: object
    seconds: float


def worker_pool(workers: int):
    """A process pool whose workers may run derivations (:func:`symvib.children.worker_pool`).

    Not :class:`multiprocessing.Pool`: its daemonic workers may not start the budgeted
    child processes of :func:`run`.  The workers die with this process.
    """
    return children.worker_pool(workers)


def _child(conn, job, args, parent, seconds):
    children.tether(parent, seconds)
    try:
        result = job(*args)
        conn.send(("ok", sp.srepr(result) if isinstance(result, sp.Basic) else result))
    except BaseException as exc:  # noqa: BLE001 - report anything to the parent
        conn.send(("error", f"{type(exc).__name__}: {exc}"))
    finally:
        conn.close()


def run(job, args: tuple, *, seconds: float) -> Outcome:
    """Run ``job(*args)`` in a child process for at most ``seconds``.

    ``job`` must be a module-level function; SymPy arguments should be passed
    as ``srepr`` strings.  A SymPy result comes back as an expression.
    """
    start = time.perf_counter()
    ctx = children._context()
    parent, child = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child, args=(child, job, args, os.getpid(), seconds), daemon=True)
    proc.start()
    child.close()
    try:
        if parent.poll(seconds):
            try:
                status, payload = parent.recv()
            except EOFError:
                status, payload = "error", "the worker exited without a result"
        else:
            status, payload = "timeout", None
    finally:
        parent.close()
        if proc.is_alive():
            proc.kill()
        proc.join(_JOIN_SECONDS)
    elapsed = time.perf_counter() - start
    if status == "ok" and isinstance(payload, str):
        payload = _from_srepr(payload)
    return Outcome(status, payload, elapsed)


def _from_srepr(text: str):
    # srepr output is SymPy constructor calls produced by SymPy itself in the
    # child process (never user text), so sympify reconstructs it exactly.
    return sp.sympify(text)


def _integrate_job(integrand: str, variable: str):
    """Example job: integrate an srepr'd expression in a variable."""
    expr = sp.sympify(integrand)
    var = next(s for s in expr.free_symbols if s.name == variable)
    return sp.integrate(expr, var)
