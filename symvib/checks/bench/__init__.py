"""``symvib bench``: work-precision charts and the stability suite.

The jobs of the command line (its options are parsed by :mod:`symvib.cli.bench`,
``symvib bench SUBCOMMAND --help``)::

    symvib bench work-precision --out DIR [--quick] [--random N] [--workers 2]
    symvib bench stability --out DIR [--quick] [--budget S] [--workers 2]
    symvib bench reference [--write] [--out DIR]

Data.  The references the benchmarks compare with ship with the package
(``symvib/checks/data``, read with :mod:`importlib.resources`, see
:mod:`symvib.checks.shipped`): ``time_reference.json`` (the paper scenes) and
``random_truth.json`` (the random scenes).  A reference missing there is
computed on demand and cached in the output folder (``DIR/time_reference.json``,
``DIR/random_truth.json``); nothing is ever written inside the installed package.

``work-precision``
    For the paper scenes (``k = 1`` and ``0.8``) every method and setting runs
    every scene: symvib's driver at ``SYMVIB_NODES`` Gauss nodes (numba backend
    when installed, after a warm-up whose compile time is reported apart),
    :func:`scipy.integrate.solve_ivp` (RK45, DOP853, Radau, LSODA; ``rtol`` 1e-3
    .. 1e-12, ``atol = rtol / 100``), and RK4 at fixed steps.  Its error is the
    largest event-time or event-position error against the 30-digit time reference
    (:mod:`symvib.checks.reference_time`), its cost the CPU time per trajectory
    (:func:`time.process_time`, one thread, the cheapest of ``TIMING_BLOCKS``
    blocks of repeated calls, ``MIN_TIMING`` s in all).  Writes
    ``work_precision.png`` (log-log, one line per method), ``work_precision.csv``
    (one row per setting), ``work_precision_runs.csv`` (one row per setting and
    scene), ``wrong_sequences.csv`` (wrong event sequences over random
    parabola/circle scenes, truth :func:`symvib.checks.reference.phase_reference`
    at 20 digits) and ``summary.md`` with the ratio at equal accuracy.

``stability``
    Every method runs every case of :mod:`symvib.checks.stability` under a CPU-time
    budget; the outcomes go to ``stability.csv`` and ``stability.md``.

``reference``
    Recomputes the time references of the paper scenes (``--write`` stores
    them in ``DIR/time_reference.json``; ``--out symvib/checks/data`` in a
    checkout updates the shipped file).

The modules, one concept each, each importing only those above it in this list:

* :mod:`~symvib.checks.bench.settings` - the methods and accuracy settings
  (:class:`Setting`), one setting's run of a scene (:func:`run_setting`);
* :mod:`~symvib.checks.bench.timing` - CPU time per trajectory, the warm-up the timings leave out;
* :mod:`~symvib.checks.bench.workers` - the jobs shared out over ``--workers`` processes;
* :mod:`~symvib.checks.bench.output` - the output folder's files: JSON caches, CSV tables;
* :mod:`~symvib.checks.bench.scenes` - the paper scenes, the random scenes, a scene's fingerprint;
* :mod:`~symvib.checks.bench.paper_references` - the paper scenes' time references
  (shipped, cached, recomputed: the ``reference`` job);
* :mod:`~symvib.checks.bench.sequences` - wrong event sequences over the random scenes;
* :mod:`~symvib.checks.bench.plot` - the work-precision diagram;
* :mod:`~symvib.checks.bench.markdown` - ``summary.md`` and ``stability.md``;
* :mod:`~symvib.checks.bench.work_precision_job` - the ``work-precision`` job;
* :mod:`~symvib.checks.bench.stability_job` - the ``stability`` job.

This package hands on the names the single module ``symvib/checks/bench.py`` had.

Examples
--------
>>> from symvib.cli import main
>>> main(["bench", "work-precision", "--help"])  # doctest: +SKIP
"""
from __future__ import annotations

from symvib.checks.bench.markdown import stability_markdown
from symvib.checks.bench.paper_references import REFERENCE_NAME, reference_events, references
from symvib.checks.bench.plot import ERROR_FLOOR
from symvib.checks.bench.scenes import (
    QUICK_RANDOM,
    RANDOM_MAX_EVENTS,
    RANDOM_SCENES,
    RANDOM_SEED,
    RESTITUTIONS,
    paper_scenes,
    random_scenes,
    scene_key,
)
from symvib.checks.bench.sequences import RANDOM_DPS, RANDOM_TRUTH_NAME
from symvib.checks.bench.settings import (
    IVP_METHODS,
    PEER_BUDGET,
    RK4_STEPS,
    RTOLS,
    SEQ_NODES,
    SEQ_RK4,
    SEQ_RTOLS,
    STABILITY_SETTINGS,
    SYMVIB_NODES,
    Setting,
    run_setting,
    sequence_settings,
    work_settings,
)
from symvib.checks.bench.stability_job import stability
from symvib.checks.bench.timing import MIN_TIMING, TIMING_BLOCKS, cpu_per_run
from symvib.checks.bench.work_precision_job import RATIO_TARGETS, ratio_at_equal_accuracy, work_precision
from symvib.checks.shipped import DATA_FOLDER, DATA_PACKAGE, shipped

__all__ = ["Setting", "paper_scenes", "reference_events", "random_scenes", "run_setting",
           "ratio_at_equal_accuracy", "scene_key", "shipped", "work_precision", "stability", "references",
           "REFERENCE_NAME", "RANDOM_TRUTH_NAME",
           # handed on as well (the names the module symvib/checks/bench.py had):
           "DATA_PACKAGE", "DATA_FOLDER", "SYMVIB_NODES", "IVP_METHODS", "RTOLS", "RK4_STEPS", "SEQ_NODES", "SEQ_RTOLS",
           "SEQ_RK4", "PEER_BUDGET", "STABILITY_SETTINGS", "work_settings", "sequence_settings", "MIN_TIMING",
           "TIMING_BLOCKS", "cpu_per_run", "RESTITUTIONS", "RANDOM_SCENES", "QUICK_RANDOM", "RANDOM_MAX_EVENTS",
           "RANDOM_SEED", "RANDOM_DPS", "RATIO_TARGETS", "ERROR_FLOOR", "stability_markdown"]
