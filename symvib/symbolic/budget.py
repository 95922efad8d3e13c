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

import _weakrefset
import os
import signal
import threading
import time
import weakref
from dataclasses import dataclass

import sympy as sp

from symvib import children

__all__ = ["Outcome", "Running", "run", "start", "finish", "simplify", "worker_pool", "SIMPLIFY_SECONDS",
           "CHECK_SIMPLIFY_SECONDS"]

#: Seconds to wait for a killed child to exit.
_JOIN_SECONDS = 5.0
#: Wall-clock budget (seconds) of one simplification in the calling process (:func:`simplify`):
#: a catalogue curve's take well under a second, ``cos(1000000*x)``'s would take hours.
SIMPLIFY_SECONDS = 5.0
#: Wall-clock budget (seconds) of the simplification that verifies an identity (a derivation's
#: back-substitution takes up to about 11 s on the catalogue; a numeric check follows a spent one).
CHECK_SIMPLIFY_SECONDS = 60.0
#: Function applications (``cos(1000000*x)``) of expressions whose simplification ran out of its
#: budget in this process: an expression holding one is not simplified again (the derivation of one
#: curve simplifies dozens of its expressions, and each would spend the whole budget).
_HOPELESS: set = set()
#: Most entries kept in ``_HOPELESS``.
_HOPELESS_SIZE = 1000
#: Seconds between repeated alarms once the budget of :func:`simplify` is spent (should SymPy
#: swallow the first).
_REALARM_SECONDS = 0.1


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
    return finish(start(job, args, seconds=seconds))


@dataclass
class Running:
    """A job started by :func:`start`: its child, the end of its pipe, when it started and its budget."""

    proc: object
    conn: object
    started: float
    seconds: float


def start(job, args: tuple, *, seconds: float) -> Running:
    """Start ``job(*args)`` in a child process (see :func:`run`) and return at once; :func:`finish`
    waits for its outcome.  Several jobs started one after the other run side by side, each
    within its own budget (children are started from the calling thread, by fork where there is one)."""
    started = time.perf_counter()
    ctx = children._context()
    parent, child = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child, args=(child, job, args, os.getpid(), seconds), daemon=True)
    proc.start()
    children.own(proc)  # killed at once if a signal ends this process (children.terminate_as_exception)
    child.close()
    return Running(proc, parent, started, seconds)


def finish(running: Running) -> Outcome:
    """The :class:`Outcome` of a job :func:`start` began: its result, or ``"timeout"`` once
    ``seconds`` have passed since it started (the child is killed then)."""
    proc, parent = running.proc, running.conn
    try:
        left = max(0.0, running.seconds - (time.perf_counter() - running.started))
        if parent.poll(left):
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
        children.disown(proc)
    elapsed = time.perf_counter() - running.started
    if status == "ok" and isinstance(payload, str):
        try:
            payload = _from_srepr(payload)
        except (TypeError, ValueError, SyntaxError, sp.SympifyError) as exc:
            # SymPy's srepr does not round-trip every result (hyper's TupleArg): no result
            status, payload = "error", f"the result does not rebuild from its srepr: {exc}"
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


class _Expired(BaseException):
    """The budget of :func:`simplify` is spent (a BaseException: SymPy's ``except Exception`` lets it by)."""


#: Files whose code Python runs as callbacks it cannot pass an exception out of (a weak
#: reference's callback, as SymPy's caches' ``WeakKeyDictionary`` run, or a finalizer): the alarm
#: raised there would be printed as "Exception ignored" and lost.
_CALLBACK_FILES = frozenset({weakref.__file__, _weakrefset.__file__})


def _expire(signum, frame):
    """The alarm of :func:`simplify`: raise :class:`_Expired`, except inside a weak reference's
    callback or a finalizer (``__del__``), which cannot pass it on; there it returns, and the alarm
    repeated :data:`_REALARM_SECONDS` later raises in SymPy's own code."""
    if frame is not None and (frame.f_code.co_filename in _CALLBACK_FILES or frame.f_code.co_name == "__del__"):
        return
    raise _Expired


def simplify(expr, seconds: float = SIMPLIFY_SECONDS, how=None, *, remember: bool = True):
    """``sympy.simplify(expr)`` (or ``how(expr)``) within ``seconds``, else ``expr`` itself.

    The simplified form is a convenience (shorter kernels, readable equations): where
    SymPy cannot find it in time (``cos(1000000*x)``: its trigonometric rewrites run for
    hours), the unsimplified expression, which is equal, stands.  In the main thread a
    real-time interval timer (SIGALRM) interrupts SymPy in this process, which costs
    nothing when the budget is not spent; elsewhere (a worker thread, a pending timer of
    someone else) the simplification runs in a child process (:func:`run`).  An expression
    that holds a function application of one whose budget ran out is returned as it is
    (``_HOPELESS``): one budget per hopeless curve, not one per expression.

    Parameters
    ----------
    expr : sympy.Expr
    seconds : float
        Wall-clock budget.
    how : callable, optional
        The simplifier (default :func:`sympy.simplify`), a module-level function.
    remember : bool
        Whether a spent budget marks the expression's function applications as hopeless
        for later calls (a verification, which has a numeric fallback, should not make
        the derivation's own forms depend on how long it took).

    Returns
    -------
    sympy.Expr
        The simplified form, or ``expr`` when the budget was spent or SymPy failed.

    Examples
    --------
    >>> x = sp.Symbol("x")
    >>> simplify(sp.sin(x)**2 + sp.cos(x)**2)
    1
    """
    how = how or sp.simplify
    if not isinstance(expr, sp.Basic) or expr.is_Atom:
        return expr
    applied = expr.atoms(sp.Function)
    if applied & _HOPELESS:
        return expr
    if (threading.current_thread() is not threading.main_thread() or not hasattr(signal, "setitimer")
            or signal.getitimer(signal.ITIMER_REAL)[0] > 0):
        outcome = run(_simplify_job, (sp.srepr(expr), how), seconds=seconds)
        if outcome.status == "timeout" and remember:
            _give_up(applied)
        return outcome.value if outcome.status == "ok" else expr
    previous = signal.signal(signal.SIGALRM, _expire)
    try:
        signal.setitimer(signal.ITIMER_REAL, seconds, _REALARM_SECONDS)
        try:
            return how(expr)
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
    except _Expired:
        if remember:
            _give_up(applied)
        return expr
    except Exception:  # noqa: BLE001 - a simplifier that fails leaves the (equal) input
        return expr
    finally:
        signal.signal(signal.SIGALRM, previous)


def _give_up(applied: set) -> None:
    if len(_HOPELESS) + len(applied) > _HOPELESS_SIZE:
        _HOPELESS.clear()
    _HOPELESS.update(applied)


def _simplify_job(expr: str, how):
    return how(sp.sympify(expr))
