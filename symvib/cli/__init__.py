"""The ``symvib`` command line, a module a concept.

:mod:`~symvib.cli.command`  the process: :func:`main` (words to a job), :func:`run` (the installed command)
:mod:`~symvib.cli.jobs`     the ``symvib`` parser and its jobs: ``paper``, ``derive``, ``run``, ``fit``, ...
:mod:`~symvib.cli.sweep`    ``symvib sweep``: its parser, its sweep file, :func:`sweep_main`
:mod:`~symvib.cli.bench`    ``symvib bench``: its parser, :func:`bench_main`
:mod:`~symvib.cli.common`   what they share: exit statuses, one-line error messages

``python -m symvib.cli`` is the ``symvib`` command (:mod:`symvib.cli.__main__`).
"""
from symvib.cli.bench import bench_main
from symvib.cli.command import main, run
from symvib.cli.sweep import sweep_main

__all__ = ["main", "run", "sweep_main", "bench_main"]
