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
import weakref

__all__ = ["tether", "worker_pool", "Terminated", "terminate_as_exception", "own", "disown", "WATCHDOG_SECONDS",
           "CPU_MARGIN_SECONDS", "GRACE_SECONDS", "EXIT_INTERRUPTED", "EXIT_TERMINATED"]

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
#: Seconds a process interrupted or terminated within :func:`terminate_as_exception` has to leave the
#: block; past them the exception was swallowed on its way (raised inside a C extension's import it
#: becomes an ``ImportError``; inside a finalizer it is ignored), and the process exits at once.
GRACE_SECONDS = 3.0
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
    # Likewise SIGINT, and the parent's registry of children (a forked copy: its processes are not ours).
    with contextlib.suppress(ValueError):  # (not the main thread: nothing was inherited there)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        if signal.getsignal(signal.SIGINT) is _on_signal:
            signal.signal(signal.SIGINT, signal.default_int_handler)
    _OWNED.clear()
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


#: Children this process kills at once when a signal ends it (:func:`terminate_as_exception`): objects
#: with a ``kill()`` method (a pool's workers, a budgeted child); weakly held.
_OWNED: weakref.WeakSet = weakref.WeakSet()


def own(child):
    """Register ``child`` (anything with ``kill()``) to be killed the moment SIGTERM or SIGINT arrives
    within :func:`terminate_as_exception`, before any ``finally`` block runs; returns it."""
    _OWNED.add(child)
    return child


def disown(child) -> None:
    """Forget a child registered by :func:`own` (it ended, or was stopped)."""
    _OWNED.discard(child)


def _kill_owned() -> None:
    for child in list(_OWNED):
        with contextlib.suppress(Exception):
            child.kill()


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
        own(self)

    def __getattr__(self, name):
        return getattr(self._pool, name)

    def __enter__(self):
        return self

    def __exit__(self, kind, value, trace):
        try:
            if kind is None:
                self._pool.shutdown(wait=True)
            else:
                _stop(self._pool)
        finally:
            disown(self)
        return False

    def kill(self) -> None:
        """SIGKILL every worker now (nothing awaited: safe in a signal handler)."""
        for proc in list((getattr(self._pool, "_processes", None) or {}).values()):
            with contextlib.suppress(Exception):
                proc.kill()


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


class _Signals:
    """What :func:`terminate_as_exception` saw: ``signum`` of the first SIGTERM or SIGINT, else ``None``."""

    def __init__(self, label):
        self.label = label
        self.signum = None
        self.timer = None


#: The state of the innermost :func:`terminate_as_exception` block (``None`` outside one).
_ACTIVE: _Signals | None = None


def exit_code(signum: int) -> int:
    """The exit status after ``signum`` (:data:`EXIT_INTERRUPTED` or :data:`EXIT_TERMINATED`)."""
    return EXIT_INTERRUPTED if signum == signal.SIGINT else EXIT_TERMINATED


def _force_exit(state: _Signals) -> None:
    what = "interrupted" if state.signum == signal.SIGINT else "terminated"
    with contextlib.suppress(Exception):
        _kill_owned()
        print(f"{state.label}: {what}", file=sys.stderr, flush=True)
    os._exit(exit_code(state.signum))


def _on_signal(signum, frame):
    state = _ACTIVE
    if state is not None and state.signum is None:
        state.signum = signum
        # The children go first, here: the exception below may be swallowed on its way.
        _kill_owned()
        state.timer = threading.Timer(GRACE_SECONDS, _force_exit, (state,))
        state.timer.daemon = True
        state.timer.start()
    if signum == signal.SIGINT:
        raise KeyboardInterrupt
    raise Terminated(f"terminated (signal {signum})")


@contextlib.contextmanager
def terminate_as_exception(label: str = "symvib"):
    """Within the block, SIGTERM raises :class:`Terminated` and SIGINT ``KeyboardInterrupt`` in the
    main thread, after killing the children registered by :func:`own` (elsewhere: no change).

    The default action of SIGTERM ends the process without running ``finally`` blocks or
    context managers, so a pool would not be shut down; as an exception it unwinds the stack.
    An exception raised by a signal handler can be lost on its way (inside a C extension's
    import it becomes an ``ImportError``, inside a finalizer it is ignored), so the children
    are killed in the handler itself, the block's state records the signal (``signum``; the
    caller reports it even when the exception never arrived), and a process that has not
    left the block :data:`GRACE_SECONDS` after the signal prints ``"<label>: interrupted"``
    (or ``terminated``) and exits at once with :func:`exit_code`.  A SIGINT that is ignored
    (a shell's background job) stays ignored.  The previous handlers are restored on leaving.

    Yields
    ------
    state
        Its ``signum`` is the first SIGTERM or SIGINT received in the block, else ``None``.
    """
    global _ACTIVE
    state = _Signals(label)
    if threading.current_thread() is not threading.main_thread():
        yield state
        return
    outer = _ACTIVE
    previous_term = signal.signal(signal.SIGTERM, _on_signal)
    previous_int = signal.getsignal(signal.SIGINT)
    if previous_int is signal.default_int_handler:
        signal.signal(signal.SIGINT, _on_signal)
    _ACTIVE = state
    try:
        yield state
    finally:
        _ACTIVE = outer
        if state.timer is not None:
            state.timer.cancel()
        signal.signal(signal.SIGTERM, previous_term)
        if previous_int is signal.default_int_handler:
            signal.signal(signal.SIGINT, previous_int)
