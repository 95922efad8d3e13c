"""The ``symvib`` process: :func:`main` hands the words after ``symvib`` to the parser of their job,
reports an error the user caused in one line and ends a job on a signal; :func:`run`, the installed
command, then ends the process without tearing the interpreter down (:func:`leave`).
"""
from __future__ import annotations

import importlib
import logging
import os
import sys

from symvib.cli.bench import bench_main
from symvib.cli.common import EXIT_BAD_INPUT, one_line
from symvib.cli.jobs import FORWARDED, build_parser

__all__ = ["main", "run", "leave"]


def _user_errors() -> tuple:
    """The exception classes a user's input can cause, reported as one line."""
    from symvib.numeric.kernels import KernelError

    return (ValueError, KeyError, OSError, KernelError, RecursionError, MemoryError)


def _one_line_warnings(command: str) -> None:
    """Show a cache-trust warning as one line (``symvib CMD: warning: ...``), not Python's two."""
    import warnings

    from symvib.cachetrust import CacheTrustWarning

    plain = getattr(warnings.formatwarning, "plain", warnings.formatwarning)
    prefix = f"symvib {command}" if command else "symvib"

    def fmt(message, category, filename, lineno, line=None):
        if issubclass(category, CacheTrustWarning):
            return f"{prefix}: warning: {one_line(message)}\n"
        return plain(message, category, filename, lineno, line)

    fmt.plain = plain
    warnings.formatwarning = fmt


def _progress_on_terminal(command: str, stream=None) -> None:
    """Show symvib's progress lines (``logging`` INFO of the ``symvib`` loggers: a new curve's
    derivation) on ``stream`` (stderr) when it is a terminal; piped or captured output gets none,
    so an error stays one line."""
    stream = sys.stderr if stream is None else stream
    logger = logging.getLogger("symvib")
    if not getattr(stream, "isatty", lambda: False)() or any(getattr(h, "symvib_progress", False)
                                                             for h in logger.handlers):
        return
    handler = logging.StreamHandler(stream)
    handler.setFormatter(logging.Formatter(f"symvib {command}: %(message)s" if command else "symvib: %(message)s"))
    handler.symvib_progress = True
    logger.addHandler(handler)
    logger.setLevel(logging.INFO)


def main(argv=None) -> int:
    """Entry point of the ``symvib`` command."""
    argv = sys.argv[1:] if argv is None else list(argv)
    _one_line_warnings(argv[0] if argv and argv[0].isidentifier() else "")
    if argv and argv[0] == "bench":
        command = "bench"
        run = lambda: bench_main(argv[1:])  # noqa: E731
    elif argv and argv[0] in FORWARDED:
        command = argv[0]
        module, function = FORWARDED[command][0].split(":")
        run = lambda: getattr(importlib.import_module(module), function)(argv[1:])  # noqa: E731
    else:
        args = build_parser().parse_args(argv)
        command = args.command
        run = lambda: args.func(args)  # noqa: E731
    import signal

    from symvib.children import Terminated, exit_code, terminate_as_exception

    def ended_by(signum):
        # Child processes were killed when the signal arrived, and the finally blocks on the way
        # here stopped the rest (symvib.children).
        print(f"symvib {command}: {'interrupted' if signum == signal.SIGINT else 'terminated'}", file=sys.stderr)
        return exit_code(signum)

    _progress_on_terminal(command)
    state = None
    try:
        with terminate_as_exception(f"symvib {command}") as state:
            outcome = run()
    except KeyboardInterrupt:
        return ended_by(signal.SIGINT)
    except Terminated:
        return ended_by(signal.SIGTERM)
    except BaseException as exc:
        if state is not None and state.signum is not None:
            # The signal's exception was lost on its way (raised inside a C extension's import it
            # became an ImportError; killed workers broke a pool): the signal is what happened.
            return ended_by(state.signum)
        if not isinstance(exc, _user_errors()):
            raise
        message = exc.args[0] if isinstance(exc, KeyError) and exc.args else exc
        if isinstance(exc, (RecursionError, MemoryError)):
            message = f"input too large or too deeply nested ({type(exc).__name__})"
        elif isinstance(exc, OSError) and not str(exc):
            message = type(exc).__name__
        print(f"symvib {command}: error: {one_line(message)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if state.signum is not None:  # the signal's exception was swallowed: the command did not finish
        return ended_by(state.signum)
    return outcome


def run() -> None:
    """The installed ``symvib`` command: :func:`main`, then :func:`leave` with its exit status.

    ``main`` returns normally, for callers in Python (the tests call it); the command
    itself skips the interpreter's teardown (:func:`leave`).
    """
    leave(main())


def leave(status) -> None:
    """End the process with ``status`` once the command has returned, without tearing the
    interpreter down.

    By the time a command returns, its files are written and closed and its child
    processes stopped (:mod:`symvib.children`); what CPython's teardown does after that is
    free every object one by one, numba's dispatchers and LLVM's modules among them:
    0.15-0.2 s of CPU, 0.2-0.3 s of wall time here, a third of a small sweep's start-up
    (docs/benchmarks.md, "Start-up").  So the exit handlers run (logging's, those of
    the libraries), both streams are flushed, and ``os._exit`` ends the process, as
    pyperformance's ``--exit`` does to time start-up alone.  A stream that cannot be
    flushed (a reader that closed the pipe) turns a success into status 1.
    """
    import atexit

    code = 0 if status is None else status if isinstance(status, int) else 1
    atexit._run_exitfuncs()  # what CPython itself calls at shutdown (a private name of atexit)
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            code = code or 1
    os._exit(code)
