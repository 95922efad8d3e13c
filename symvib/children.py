"""Child processes that die with their parent and never outlive their budget.

A SymPy child of :mod:`symvib.symbolic.budget` or a worker of ``symvib paper``'s
pool must not survive the process that started it: a ``timeout``, a supervisor
or a user sends SIGKILL or SIGTERM to that process alone (not its group), and
a child re-parented to init would run on, unbounded.  So every child calls
:func:`tether` first thing:

* ``prctl(PR_SET_PDEATHSIG, SIGKILL)`` (Linux, through :mod:`ctypes`): the kernel
  kills the child when its parent dies, whatever the parent's death;
* a watchdog thread polling :func:`os.getppid` every :data:`WATCHDOG_SECONDS`,
  the portable fallback (a re-parented child sees another parent id);
* with a budget, ``RLIMIT_CPU`` a little above it (:data:`CPU_MARGIN_SECONDS`):
  the kernel ends the child even when its parent is alive but stopped.

:func:`worker_pool` is a process pool whose workers are tethered, and which
kills them when the ``with`` block is left by an exception (Ctrl-C, SIGTERM made
an exception by :func:`terminate_as_exception`) instead of waiting for their jobs.

Examples
--------
>>> with worker_pool(1) as pool:
...     pool.submit(abs, -3).result()
3
"""
from __future__ import annotations

import contextlib
import math
import multiprocessing as mp
import os
import signal
import sys
import threading

__all__ = ["tether", "worker_pool", "Terminated", "terminate_as_exception", "WATCHDOG_SECONDS",
           "CPU_MARGIN_SECONDS", "EXIT_INTERRUPTED", "EXIT_TERMINATED"]

#: Seconds between two checks of the watchdog thread for a parent that died.
WATCHDOG_SECONDS = 0.2
#: CPU seconds a budgeted child may use beyond its budget before the kernel ends it (``RLIMIT_CPU``);
#: the parent kills it at the budget itself, so this only bounds a child whose parent cannot.
CPU_MARGIN_SECONDS = 2
#: Exit status after Ctrl-C (128 + SIGINT), as a shell reports it.
EXIT_INTERRUPTED = 128 + signal.SIGINT
#: Exit status after SIGTERM (128 + SIGTERM).
EXIT_TERMINATED = 128 + signal.SIGTERM
#: Seconds to wait for a killed worker to exit.
_JOIN_SECONDS = 5.0
#: ``prctl`` option that sets the signal a process receives when its parent dies (linux/prctl.h).
_PR_SET_PDEATHSIG = 1


def _context():
    methods = mp.get_all_start_methods()
    return mp.get_context("fork" if "fork" in methods else "spawn")


def _death_signal() -> bool:
    """Ask the kernel for SIGKILL when the parent dies (Linux); whether it was set."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        return libc.prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) == 0
    except (OSError, AttributeError):  # no libc or no prctl: the watchdog thread alone
        return False


def _die():
    """End this process at once (no cleanup: the parent is gone and nobody waits for a result)."""
    try:
        os.kill(os.getpid(), signal.SIGKILL)
    finally:  # pragma: no cover - SIGKILL does not return
        os._exit(1)


def _watch(parent: int) -> None:
    while True:
        if os.getppid() != parent:
            _die()
        threading.Event().wait(WATCHDOG_SECONDS)


def tether(parent: int, cpu_seconds: float | None = None) -> None:
    """Make this (child) process die with ``parent`` and, with ``cpu_seconds``, within that much CPU time.

    Parameters
    ----------
    parent : int
        The process id of the parent, read by the parent before it started the child (a
        parent that died before the child runs this is noticed here, not missed).
    cpu_seconds : float, optional
        The child's budget: ``RLIMIT_CPU`` is set to it plus :data:`CPU_MARGIN_SECONDS`
        (rounded up to whole seconds), after which the kernel ends the child (SIGXCPU,
        then SIGKILL one second later).
    """
    # A forked child inherits the parent's Python handlers: SIGTERM would raise Terminated here, in
    # whatever the child was doing (an import, a job), and print its traceback on the shared stderr
    # when the parent's pool shuts it down.  A child just ends on SIGTERM.
    with contextlib.suppress(ValueError):  # (not the main thread: nothing was inherited there)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
    _death_signal()
    if os.getppid() != parent:
        _die()
    threading.Thread(target=_watch, args=(parent,), name="symvib-parent-watchdog", daemon=True).start()
    if cpu_seconds is not None:
        _limit_cpu(cpu_seconds)


def _limit_cpu(seconds: float) -> None:
    try:
        import resource
    except ImportError:  # pragma: no cover - not on POSIX: the parent's kill and the watchdog remain
        return
    used = resource.getrusage(resource.RUSAGE_SELF)
    soft = math.ceil(used.ru_utime + used.ru_stime + seconds + CPU_MARGIN_SECONDS)
    _, hard = resource.getrlimit(resource.RLIMIT_CPU)
    if hard != resource.RLIM_INFINITY and hard <= soft:
        soft = hard - 1 if hard > 1 else hard
    else:
        hard = soft + 1
    with contextlib.suppress(ValueError, OSError):
        resource.setrlimit(resource.RLIMIT_CPU, (soft, hard))


def _stop(pool) -> None:
    """Cancel the jobs of a :class:`~concurrent.futures.ProcessPoolExecutor` and kill its workers now."""
    kill = getattr(pool, "kill_workers", None)  # Python 3.14
    if kill is not None:
        with contextlib.suppress(Exception):
            kill()
        return
    workers = list((getattr(pool, "_processes", None) or {}).values())  # shutdown() forgets them
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in workers:
        with contextlib.suppress(Exception):
            proc.kill()
    for proc in workers:
        with contextlib.suppress(Exception):
            proc.join(_JOIN_SECONDS)


class _Pool:
    """A process pool used as a context manager: on an exception its workers are killed, not awaited."""

    def __init__(self, pool):
        self._pool = pool

    def __getattr__(self, name):
        return getattr(self._pool, name)

    def __enter__(self):
        return self

    def __exit__(self, kind, value, trace):
        if kind is None:
            self._pool.shutdown(wait=True)
        else:
            _stop(self._pool)
        return False


def worker_pool(workers: int, method: str | None = None):
    """A process pool whose workers die with this process (:func:`tether`).

    Not :class:`multiprocessing.Pool`: its daemonic workers may not start the budgeted
    child processes of :func:`symvib.symbolic.budget.run`.  Use it in a ``with`` block:
    leaving the block normally waits for the jobs; leaving it by an exception (Ctrl-C,
    :class:`Terminated`) cancels them and kills the workers.

    Parameters
    ----------
    workers : int
        Worker processes.
    method : str, optional
        The start method (``"spawn"``, ``"fork"``); default ``fork`` where there is one.

    Returns
    -------
    context manager
        A :class:`concurrent.futures.ProcessPoolExecutor` (``submit``, ``map``, ...).
    """
    from concurrent.futures import ProcessPoolExecutor

    context = _context() if method is None else mp.get_context(method)
    pool = ProcessPoolExecutor(workers, mp_context=context, initializer=tether, initargs=(os.getpid(),))
    return _Pool(pool)


class Terminated(BaseException):
    """SIGTERM, raised in the main thread so that ``finally`` blocks stop child processes."""


def _raise_terminated(signum, frame):
    raise Terminated(f"terminated (signal {signum})")


@contextlib.contextmanager
def terminate_as_exception():
    """Within the block, SIGTERM raises :class:`Terminated` in the main thread (elsewhere: no change).

    The default action of SIGTERM ends the process without running ``finally`` blocks or
    context managers, so a pool would not be shut down; as an exception it unwinds the stack.
    The previous handler is restored on leaving.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGTERM, _raise_terminated)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
