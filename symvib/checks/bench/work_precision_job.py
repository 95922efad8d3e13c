"""The job ``symvib bench work-precision``: error against CPU time on the paper scenes.

For the paper scenes (:func:`~symvib.checks.bench.scenes.paper_scenes`) every
setting of :func:`~symvib.checks.bench.settings.work_settings` runs every scene; its
error is the largest event-time or event-position error against the scene's time
reference (:mod:`symvib.checks.bench.paper_references`), its cost the CPU time per
trajectory (:func:`~symvib.checks.bench.timing.cpu_per_run`).  A setting whose event
sequence differs from the reference's on some scene counts as "wrong sequence" there
and gets no error point.  The ratio at equal accuracy is::

    ratio(eps) = min CPU of a peer setting with error <= eps
                 / min CPU of a symvib setting with error <= eps

(settings with a wrong sequence on any paper scene excluded), at the targets
:data:`RATIO_TARGETS` and at the best error a peer reaches.  The job then counts
wrong sequences over random scenes (:mod:`symvib.checks.bench.sequences`) and
writes ``work_precision.png`` (:mod:`~symvib.checks.bench.plot`),
``work_precision.csv``, ``work_precision_runs.csv``, ``wrong_sequences.csv`` and
``summary.md`` (:mod:`~symvib.checks.bench.markdown`).

Examples
--------
>>> rows = [{"method": "symvib", "label": "s16", "wrong": 0, "error": 1e-13, "cpu": 2e-5},
...         {"method": "DOP853", "label": "d7", "wrong": 0, "error": 1e-7, "cpu": 4e-3}]
>>> ratio_at_equal_accuracy(rows, 1e-6)
('d7', 0.004, 's16', 2e-05, 200.0)
"""
from __future__ import annotations

import math
from pathlib import Path

from symvib import safeio
from symvib.checks.bench.markdown import summary_markdown
from symvib.checks.bench.output import OUT_FOLDER, write_csv
from symvib.checks.bench.paper_references import REFERENCE_NAME, reference_events
from symvib.checks.bench.plot import ERROR_FLOOR, plot_work_precision
from symvib.checks.bench.scenes import QUICK_RANDOM, RANDOM_SCENES, paper_scenes
from symvib.checks.bench.sequences import RANDOM_TRUTH_NAME, sequence_counts
from symvib.checks.bench.settings import (
    IVP_METHODS,
    PEER_BUDGET,
    Setting,
    driver_backend,
    run_setting,
    sequence_settings,
    work_settings,
)
from symvib.checks.bench.timing import MIN_TIMING, cpu_per_run, warm_up

__all__ = ["RATIO_TARGETS", "WARM_UP_RTOL", "ratio_at_equal_accuracy", "work_precision"]

#: Accuracy targets of the ratio at equal accuracy (plus the best a peer reaches).
RATIO_TARGETS = (1e-6, 1e-10)
#: The tolerance of the solve_ivp runs that import SciPy and warm its caches before the timings.
WARM_UP_RTOL = 1e-3


def _errors(events, ref) -> tuple:
    from symvib.checks.stability import labels

    same = labels(events) == labels(ref)
    n = min(len(events), len(ref))
    dt = max((abs(e[1] - r[1]) for e, r in zip(events[:n], ref[:n])), default=math.inf)
    dq = max((abs(e[2] - r[2]) for e, r in zip(events[:n], ref[:n])), default=math.inf)
    return same, dt, dq


def ratio_at_equal_accuracy(rows, target: float):
    """``(peer label, peer CPU, symvib label, symvib CPU, ratio)`` at error ``<= target``, or None.

    ``rows`` are summary rows (dicts with ``method``, ``label``, ``wrong``, ``error``, ``cpu``).
    """
    ok = [r for r in rows if r["wrong"] == 0 and r["error"] <= target]
    peers = [r for r in ok if r["method"] != "symvib"]
    ours = [r for r in ok if r["method"] == "symvib"]
    if not peers or not ours:
        return None
    p = min(peers, key=lambda r: r["cpu"])
    s = min(ours, key=lambda r: r["cpu"])
    return p["label"], p["cpu"], s["label"], s["cpu"], p["cpu"] / s["cpu"]


def work_precision(out: Path, *, quick: bool = False, n_random: int | None = None, workers: int = 1,
                   budget: float = PEER_BUDGET, log=print) -> dict:
    """Measure and draw the work-precision diagram (the job ``symvib bench work-precision``).

    Parameters
    ----------
    out : pathlib.Path
        The output folder (its cache files are read and extended).
    quick : bool
        A small run: two paper scenes, few settings, :data:`~symvib.checks.bench.scenes.QUICK_RANDOM`
        random scenes.
    n_random : int, optional
        Random scenes (default :data:`~symvib.checks.bench.scenes.RANDOM_SCENES`, or the quick count).
    workers : int
        Processes for the random scenes (the timings always run here).
    budget : float
        CPU seconds of one peer run.
    log : callable
        Where the progress lines go (default :func:`print`).

    Returns
    -------
    dict
        ``summary`` (one row per setting), ``ratios`` (``(target, ratio or None)``),
        ``sequences`` (:func:`~symvib.checks.bench.sequences.sequence_counts`) and ``backend``.
    """
    safeio.check_root(out, OUT_FOLDER)
    backend = driver_backend()
    scenes = paper_scenes(quick)
    warm = warm_up(scenes, backend)
    log(f"symvib backend: {backend}; first call per curve (compile or load, excluded): "
        + ", ".join(f"{k} {v:.2f} s" for k, v in warm.items()))
    refs = {label: reference_events(s, label=label, cache=out / REFERENCE_NAME) for label, s in scenes}
    for method in IVP_METHODS:  # imports SciPy and warms its caches outside the timings
        run_setting(Setting(method, WARM_UP_RTOL), scenes[0][1], budget=budget)
    runs, summary = [], []
    for st in work_settings(quick):
        errs, cpus, wrong, failed = [], [], 0, 0
        for label, scene in scenes:
            cpu, (status, events, message) = cpu_per_run(lambda: run_setting(st, scene, budget=budget, backend=backend),
                                                         min_total=MIN_TIMING)
            same, dt, dq = _errors(events, refs[label])
            if status == "failed":
                failed += 1
                same = False
            wrong += not same
            err = max(dt, dq)
            if same:
                errs.append(err)
            cpus.append(cpu)
            runs.append({"method": st.method, "setting": st.value, "label": st.label, "scene": label,
                         "events_ref": len(refs[label]), "events": len(events), "same_sequence": same,
                         "status": status, "err_t": dt, "err_q": dq, "cpu_s": cpu, "message": message})
        row = {"method": st.method, "setting": st.value, "label": st.label, "scenes": len(scenes), "wrong": wrong,
               "failed": failed, "error": max(errs) if errs and not wrong else math.inf,
               "error_correct_scenes": max(errs) if errs else math.inf, "cpu": sum(cpus) / len(cpus)}
        summary.append(row)
        log(f"  {st.label:22s} error {row['error_correct_scenes']:9.2e}  CPU/trajectory {row['cpu'] * 1e3:9.3f} ms"
            f"  wrong sequence on {wrong}/{len(scenes)} scenes")
    write_csv(out / "work_precision_runs.csv", runs)
    write_csv(out / "work_precision.csv", summary)
    ratios = []
    peer_ok = [r["error"] for r in summary if r["method"] != "symvib" and r["wrong"] == 0]
    targets = list(RATIO_TARGETS) + ([max(min(peer_ok), ERROR_FLOOR)] if peer_ok else [])
    for target in targets:
        got = ratio_at_equal_accuracy(summary, target)
        ratios.append((target, got))
        if got:
            log(f"ratio at error <= {target:.1e}: {got[0]} {got[1] * 1e3:.3f} ms / {got[2]} {got[3] * 1e3:.4f} ms"
                f" = {got[4]:.0f}")
        else:
            log(f"ratio at error <= {target:.1e}: no peer setting reaches it")
    # Random scenes: wrong event sequences.
    n_random = (QUICK_RANDOM if quick else RANDOM_SCENES) if n_random is None else n_random
    seq = sequence_counts(n_random, sequence_settings(quick), workers, budget, backend, log, out / RANDOM_TRUTH_NAME)
    write_csv(out / "wrong_sequences.csv", seq["rows"])
    plot_work_precision(out / "work_precision.png", summary, backend)
    md = summary_markdown(summary, ratios, seq, backend, warm, scenes)
    safeio.write_file(out / "summary.md", md, what=OUT_FOLDER)
    log(f"wrote {out / 'work_precision.png'}, work_precision.csv, work_precision_runs.csv, wrong_sequences.csv, "
        f"summary.md")
    return {"summary": summary, "ratios": ratios, "sequences": seq, "backend": backend}
