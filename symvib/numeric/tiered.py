"""The tiered engine: a curve a process runs many times is compiled in the background.

A run on ``backend="auto"`` takes the compiled engine where numba's disk cache holds it
already and the plain-Python engine otherwise (:func:`symvib.numeric.backends.run_backend`):
a single run never waits for a compiler.  A loop of runs of one curve (an optimizer, a Monte
Carlo study) would then stay on the plain engine, 20 to 50 times slower than the compiled
one.  So once a process has run a curve's plain engine :data:`TIER_CALLS` times for at least
:data:`TIER_SECONDS` in all, it starts **one** child process that compiles the curve's
engine into numba's disk cache (what a ``backend="numba"`` run leaves: the specialized
binding's ``simulate`` entry and its marker, :func:`symvib.numeric.engine.bind.is_compiled`),
and its runs go on with the plain engine meanwhile.  Each later run asks the child whether
it has ended (``waitpid`` without waiting: no file is read while it compiles); the first run
after a clean end loads the compiled engine from disk (about a second), every run after it
uses it.  The engines give the same events (``tests/test_backends.py``).

The child is tethered (:func:`symvib.children.tether`: it dies with its parent, whatever its
parent's death) and killed when its parent exits (:func:`stop_children`, at exit: the exit
does not wait for a compile), or when it has run :data:`TIER_TIMEOUT` seconds. A child that
fails, or whose compiled engine numba could not write to its cache, leaves this process on
the plain engine for that curve for good, with one :class:`TierWarning` line.
``$SYMVIB_TIER=off``, ``$SYMVIB_BACKEND`` and an explicit ``backend=`` start no child. The
start and the end of a compile are logged at INFO on the logger ``symvib.numeric.tiered``;
which engine ran a run is ``Result.stats["backend"]``.

Why the specialized binding: compiling its ``simulate`` entry on empty caches took 18.3-20.4 s
of CPU against 18.9-19.2 s for the shared binding's (docs/benchmarks.md, "The tiered engine"),
the same within the noise; it then runs faster, and later processes take it with no tier at all (its marker).

Examples
--------
>>> tier_enabled({"SYMVIB_TIER": "off"}), tier_enabled({})
(False, True)
"""
from __future__ import annotations

import atexit
import importlib.util
import logging
import os
import sys
import threading
import time
import warnings

__all__ = ["TIER_ENV", "TIER_CALLS", "TIER_SECONDS", "TierWarning", "tier_enabled", "ready", "ran",
           "stop_children", "children_of_tiers"]

#: Environment variable that turns the tiered engine off (``off``, ``0``, ``no`` or ``false``).
TIER_ENV = "SYMVIB_TIER"
#: Values of :data:`TIER_ENV` that turn it off, and that leave it on (any other value also turns it
#: off, with a :class:`TierWarning` naming the variable: a misspelt "of" must not start compiles).
TIER_OFF = ("off", "0", "no", "false")
TIER_ON = ("", "on", "1", "yes", "true")
#: Plain runs of one curve before a compile may start: a notebook's few runs, or a command's
#: one, never start one (the compile takes a core for about 20 s); a loop passes it at once.
TIER_CALLS = 50
#: Seconds of plain-engine time (summed over a curve's runs in this process) before a compile
#: starts: about 200 paper-parabola runs (4-5 ms each here).  A compile costs about 20 s of a
#: second core; a loop that has run a second is likely to run on, and the earlier the child
#: starts the sooner the loop is 20-50 times faster; the core is lost only where a loop stops
#: within the next 20 s.  (Measured effect on a 100,000-run loop: docs/benchmarks.md.)
TIER_SECONDS = 1.0
#: Seconds a compile child may run before it is killed and the curve stays on the plain engine, with
#: a :class:`TierWarning`: about 10 times the longest compile measured under load (75 s of wall,
#: docs/benchmarks.md).  A child forked from a process whose other threads held a lock at the fork
#: (a logging handler's, a user's thread pool's) can wait on it for ever; nothing hangs in the parent
#: (it never waits for the child), but without this bound the loop would wait in vain.
TIER_TIMEOUT = 900.0

_log = logging.getLogger(__name__)


class TierWarning(RuntimeWarning):
    """A background compile failed: this process stays on the plain engine for that curve."""


def tier_enabled(environ=os.environ) -> bool:
    """Whether background compiles may start: not with ``$SYMVIB_TIER=off`` (or a value not in
    :data:`TIER_ON`, with a warning) nor a forced ``$SYMVIB_BACKEND``."""
    value = environ.get(TIER_ENV, "").strip().lower()
    if value not in TIER_ON + TIER_OFF:
        warnings.warn(f"symvib: ${TIER_ENV}={value!r:.40} is not one of {', '.join(v for v in TIER_ON if v)} or "
                      f"{', '.join(TIER_OFF)}; the tiered engine stays off", TierWarning, stacklevel=2)
        return False
    return value not in TIER_OFF and not environ.get("SYMVIB_BACKEND")


class _Tier:
    """One curve's tier in this process: its plain runs, its compile child, its state."""

    __slots__ = ("module", "label", "owner", "calls", "seconds", "child", "pipe", "state", "started")

    def __init__(self, module, label):
        self.module, self.label, self.owner = module, label, os.getpid()
        self.calls, self.seconds = 0, 0.0
        self.child = self.pipe = None
        self.state = "plain"   # plain -> compiling -> compiled | failed; or plain -> off
        self.started = 0.0


#: Tiers by the identity of their kernel module (the module is kept: an id is not reused meanwhile).
_TIERS: dict = {}
_LOCK = threading.Lock()


def _own(module) -> _Tier | None:
    """The tier of ``module`` in this process (a forked process's copies of its parent's are not its own)."""
    tier = _TIERS.get(id(module))
    return tier if tier is not None and tier.module is module and tier.owner == os.getpid() else None


def _tier(module, label=None) -> _Tier:
    tier = _own(module)
    if tier is None:
        tier = _TIERS[id(module)] = _Tier(module, label or getattr(module, "__name__", "curve"))
    return tier


def ready(module) -> bool | None:
    """Whether the curve's compiled engine may run now, as its tier knows: True once its child
    ended cleanly; False while it compiles or after it failed; None where no child started
    (then the disk cache decides, :func:`symvib.numeric.engine.bind.is_compiled`)."""
    tier = _own(module)
    if tier is None or tier.state in ("plain", "off"):
        return None
    if tier.state == "compiling":
        with _LOCK:
            if tier.state == "compiling":
                _poll(tier)
    return tier.state == "compiled"


def ran(module, seconds: float, label: str, call) -> None:
    """Count one plain run of ``module``'s curve (``seconds`` of engine time); start its compile
    child once the thresholds are passed.

    ``call()`` runs the curve's compiled engine once on the run's arguments (the driver's
    :func:`~symvib.numeric.backends.compile_by_running`): the child compiles by calling it so
    (numba compiles a function at its first call, then marks it cached).
    """
    tier = _tier(module, label)
    tier.calls += 1
    tier.seconds += seconds
    if tier.state != "plain" or tier.calls < TIER_CALLS or tier.seconds < TIER_SECONDS:
        return
    with _LOCK:
        if tier.state == "plain":
            _start(tier, call)


def _context():
    """The fork start method (the child inherits the loaded kernels; nothing is pickled), or None."""
    import multiprocessing as mp  # (here: a plain run that never starts a child does not import it)

    return mp.get_context("fork") if "fork" in mp.get_all_start_methods() else None


def _start(tier: _Tier, call) -> None:
    """Start the compile child of ``tier`` (or fail at once where none can start)."""
    ctx = _context()
    if (not tier_enabled() or not getattr(tier.module, "__file__", None) or ctx is None
            or importlib.util.find_spec("numba") is None):
        tier.state = "off"   # silently: turned off, a view compiled per process, no fork or no numba
        return
    receive, send = ctx.Pipe(duplex=False)
    child = ctx.Process(target=_compile, args=(os.getpid(), tier.module, call, send),
                        name=f"symvib-compile-{tier.label}", daemon=True)
    try:
        child.start()
    except OSError as exc:
        _fail(tier, f"its process could not start ({exc})")
        return
    send.close()
    tier.child, tier.pipe, tier.state, tier.started = child, receive, "compiling", time.monotonic()
    _log.info("symvib: compiling the engine of curve '%s' in the background (process %d) after %d plain runs "
              "(%.1f s); runs go on with the plain engine meanwhile", tier.label, child.pid, tier.calls,
              tier.seconds)


def _compile(parent: int, module, call, send) -> None:
    """The child: tethered to ``parent``, compile the curve's engine into numba's disk cache.

    Exits 0 when the engine ran compiled (numba then wrote it to its cache); any failure is
    sent to the parent as one line and the child exits 1, printing nothing.
    """
    from symvib.children import tether

    tether(parent)
    try:
        call()
    except BaseException as exc:   # noqa: BLE001 - whatever it is, the parent says it in one line
        send.send(f"{type(exc).__name__}: {exc}".splitlines()[0] if str(exc) else type(exc).__name__)
        send.close()
        sys.exit(1)
    send.close()


def _poll(tier: _Tier) -> None:
    """Look whether ``tier``'s child ended (no wait); on its end, reap it and settle the tier."""
    child = tier.child
    if child.exitcode is None:   # waitpid(WNOHANG)
        if time.monotonic() - tier.started > TIER_TIMEOUT:
            child.kill()
            child.join()
            tier.pipe.close()
            _fail(tier, f"it did not end within {TIER_TIMEOUT:g} s and was killed")
        return
    from symvib.numeric.engine.bind import is_compiled

    try:
        reason = tier.pipe.recv() if tier.pipe.poll() else None
    except EOFError:   # closed without a word: it ended cleanly, or was killed
        reason = None
    tier.pipe.close()
    child.join()
    if child.exitcode == 0 and is_compiled(tier.module):
        tier.state = "compiled"
        _log.info("symvib: the compiled engine of curve '%s' is ready (compiled in %.1f s); later runs use it",
                  tier.label, time.monotonic() - tier.started)
        return
    if child.exitcode == 0:
        reason = f"numba could not write the compiled engine to its cache ({os.environ.get('NUMBA_CACHE_DIR')})"
    _fail(tier, reason or f"its process ended with status {child.exitcode}")


def _fail(tier: _Tier, reason: str) -> None:
    tier.state = "failed"
    warnings.warn(f"symvib: the background compile of curve '{tier.label}' failed: {reason}; this process "
                  "stays on the plain engine for it", TierWarning, stacklevel=2)


def children_of_tiers() -> list:
    """The compile children started in this process that are still running (their ``Process``)."""
    return [t.child for t in list(_TIERS.values())
            if t.owner == os.getpid() and t.child is not None and t.child.exitcode is None]


def stop_children() -> None:
    """Kill the compile children still running and reap them (at exit: the exit does not wait for them)."""
    for child in children_of_tiers():
        child.kill()
        child.join()


atexit.register(stop_children)
