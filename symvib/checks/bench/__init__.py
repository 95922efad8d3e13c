"""``symvib bench``: work-precision charts and the stability suite.

The jobs of the command line (its options are parsed by :mod:`symvib.cli`,
``symvib bench SUBCOMMAND --help``)::

    symvib bench work-precision --out DIR [--quick] [--random N] [--workers 2]
    symvib bench stability --out DIR [--quick] [--budget S] [--workers 2]
    symvib bench reference [--write] [--out DIR]

Data.  The references the benchmarks compare with ship with the package
(``symvib/checks/data``, read with :mod:`importlib.resources`, see
:func:`shipped`): ``time_reference.json`` (the paper scenes) and
``random_truth.json`` (the random scenes).  A reference missing there is
computed on demand and cached in the output folder (``DIR/time_reference.json``,
``DIR/random_truth.json``); nothing is ever written inside the installed package.

``work-precision``
    For the paper scenes (``k = 1`` and ``0.8``) every method and setting
    runs every scene; its error is the largest event-time or event-position
    error against the 30-digit time reference (:mod:`symvib.checks.reference_time`,
    shipped in ``symvib/checks/data/time_reference.json``), its cost the CPU time
    per trajectory (:func:`time.process_time`, one thread, the cheapest of
    ``TIMING_BLOCKS`` blocks of repeated calls, ``MIN_TIMING`` s in all).  A
    setting whose event sequence differs from the reference's on some scene
    counts as "wrong sequence" there and gets no error point.  Methods: symvib's driver at ``SYMVIB_NODES`` Gauss nodes
    (numba backend when installed, after a warm-up whose compile time is
    reported apart), :func:`scipy.integrate.solve_ivp` (RK45, DOP853, Radau,
    LSODA; ``rtol`` 1e-3 .. 1e-12, ``atol = rtol / 100``), and RK4 at fixed
    steps.  Writes ``work_precision.png`` (log-log, one line per method),
    ``work_precision.csv`` (one row per setting), ``work_precision_runs.csv``
    (one row per setting and scene), ``wrong_sequences.csv`` and
    ``summary.md`` with the ratio at equal accuracy, which is::

        ratio(eps) = min CPU of a peer setting with error <= eps
                     / min CPU of a symvib setting with error <= eps

    (settings with a wrong sequence on any paper scene excluded).  It also
    counts wrong event sequences over random parabola/circle scenes (random
    ``qdot0``, ``mu``, ``k``, limiters; truth :func:`symvib.checks.reference.phase_reference`
    at 20 digits, cached; scenes needing more than ``RANDOM_MAX_EVENTS`` events
    are left out).

``stability``
    Every method runs every case of :mod:`symvib.checks.stability` under a CPU-time
    budget; the outcomes go to ``stability.csv`` and ``stability.md``.

``reference``
    Recomputes the time references of the paper scenes (``--write`` stores
    them in ``DIR/time_reference.json``; ``--out symvib/checks/data`` in a
    checkout updates the shipped file).

Examples
--------
>>> from symvib.cli import main
>>> main(["bench", "work-precision", "--help"])  # doctest: +SKIP
"""
from __future__ import annotations

import math
import time
from pathlib import Path

from symvib import safeio
from symvib.checks.bench.output import OUT_FOLDER, write_csv
from symvib.checks.bench.paper_references import REFERENCE_NAME, reference_events, references
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
from symvib.checks.bench.sequences import RANDOM_DPS, RANDOM_TRUTH_NAME, sequence_counts
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
    driver_backend,
    run_setting,
    sequence_settings,
    work_settings,
)
from symvib.checks.bench.timing import MIN_TIMING, TIMING_BLOCKS, cpu_per_run, warm_up
from symvib.checks.bench.workers import map_workers
from symvib.checks.shipped import DATA_FOLDER, DATA_PACKAGE, shipped

__all__ = ["Setting", "paper_scenes", "reference_events", "random_scenes", "run_setting",
           "ratio_at_equal_accuracy", "scene_key", "shipped", "work_precision", "stability", "references",
           "REFERENCE_NAME", "RANDOM_TRUTH_NAME",
           # handed on as well (the shipped data's place, symvib.checks.shipped):
           "DATA_PACKAGE", "DATA_FOLDER", "SYMVIB_NODES", "IVP_METHODS", "RTOLS", "RK4_STEPS", "SEQ_NODES", "SEQ_RTOLS",
           "SEQ_RK4", "PEER_BUDGET", "STABILITY_SETTINGS", "work_settings", "sequence_settings", "MIN_TIMING",
           "TIMING_BLOCKS", "cpu_per_run", "RESTITUTIONS", "RANDOM_SCENES", "QUICK_RANDOM", "RANDOM_MAX_EVENTS",
           "RANDOM_SEED", "RANDOM_DPS"]

#: Accuracy targets of the ratio at equal accuracy (plus the best a peer reaches).
RATIO_TARGETS = (1e-6, 1e-10)
#: Smallest error drawn (errors below are plotted here).
ERROR_FLOOR = 1e-16


# --- measuring ------------------------------------------------------------------------------------
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
    """Measure and draw the work-precision diagram; returns the summary (see the module docstring)."""
    safeio.check_root(out, OUT_FOLDER)
    backend = driver_backend()
    scenes = paper_scenes(quick)
    warm = warm_up(scenes, backend)
    log(f"symvib backend: {backend}; first call per curve (compile or load, excluded): "
        + ", ".join(f"{k} {v:.2f} s" for k, v in warm.items()))
    refs = {label: reference_events(s, label=label, cache=out / REFERENCE_NAME) for label, s in scenes}
    for method in IVP_METHODS:  # imports SciPy and warms its caches outside the timings
        run_setting(Setting(method, 1e-3), scenes[0][1], budget=budget)
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
    _plot(out / "work_precision.png", summary, backend)
    md = _summary_markdown(summary, ratios, seq, backend, warm, scenes)
    safeio.write_file(out / "summary.md", md, what=OUT_FOLDER)
    log(f"wrote {out / 'work_precision.png'}, work_precision.csv, work_precision_runs.csv, wrong_sequences.csv, "
        f"summary.md")
    return {"summary": summary, "ratios": ratios, "sequences": seq, "backend": backend}


_STYLE = {"symvib": ("k", "o"), "RK45": ("tab:blue", "s"), "DOP853": ("tab:orange", "^"),
          "Radau": ("tab:green", "v"), "LSODA": ("tab:red", "D"), "RK4": ("tab:purple", "x")}


def _plot(path: Path, summary, backend) -> None:
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.4, 4.4), dpi=100)
    ax = fig.subplots()
    for method, (color, marker) in _STYLE.items():
        pts = [(max(r["error"], ERROR_FLOOR), r["cpu"] * 1e3) for r in summary
               if r["method"] == method and math.isfinite(r["error"])]
        if not pts:
            continue
        name = f"symvib ({backend})" if method == "symvib" else method if method == "RK4" else f"solve_ivp {method}"
        ax.plot(*zip(*pts), marker=marker, color=color, label=name, ms=4, lw=1.2)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.invert_xaxis()
    ax.set_xlabel("max event-time / position error (vs 30-digit time reference)")
    ax.set_ylabel("CPU time per trajectory [ms]")
    ax.set_title("Work-precision, paper scenes (k = 1, 0.8)", fontsize=10)
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    with safeio.replacing(safeio.check_root(path.parent, OUT_FOLDER), path.name, what=OUT_FOLDER) as fh:
        fig.savefig(fh, format="png")


def _summary_markdown(summary, ratios, seq, backend, warm, scenes) -> str:
    lines = [f"symvib backend: **{backend}** (first call per curve, excluded from the timings: "
             + ", ".join(f"{k} {v:.2f} s" for k, v in warm.items()) + ").",
             f"Scenes: {', '.join(label for label, _ in scenes)}.", "",
             "| ratio at error <= | cheapest peer setting | its CPU / trajectory | cheapest symvib setting "
             "| its CPU / trajectory | ratio |", "| --- | --- | --- | --- | --- | --- |"]
    for target, got in ratios:
        if got:
            lines.append(f"| {target:.1e} | {got[0]} | {got[1] * 1e3:.3f} ms | {got[2]} | {got[3] * 1e3:.4f} ms "
                         f"| {got[4]:.0f} |")
        else:
            lines.append(f"| {target:.1e} | none reaches it | | | | |")
    lines += ["", "| setting | max error (all sequences right) | CPU / trajectory | wrong sequence (paper scenes) |",
              "| --- | --- | --- | --- |"]
    for r in summary:
        err = f"{r['error']:.1e}" if math.isfinite(r["error"]) else "-"
        lines.append(f"| {r['label']} | {err} | {r['cpu'] * 1e3:.3f} ms | {r['wrong']}/{r['scenes']} |")
    lines += ["", f"Wrong event sequences over {seq['usable']} random parabola/circle scenes "
              f"({seq['left_out']} more were left out: over {RANDOM_MAX_EVENTS} events, or the reference failed):", "",
              "| setting | wrong sequence | failed or out of budget |", "| --- | --- | --- |"]
    for r in seq["rows"]:
        lines.append(f"| {r['label']} | {r['wrong']}/{r['scenes']} | {r['failed']} |")
    return "\n".join(lines) + "\n"


# --- stability --------------------------------------------------------------------------------------
def _stability_task(args):
    name, exp, settings, budget, backend = args
    from symvib.checks.stability import case, classify

    scene = case(name).scene
    out = []
    for method, value in settings:
        st = Setting(method, value)
        start = time.process_time()
        try:
            status, events, message = run_setting(st, scene, budget=budget, backend=backend)
        except Exception as exc:  # noqa: BLE001 - a crash is an outcome
            status, events, message = "failed", [], f"{type(exc).__name__}: {exc}"
        cpu = time.process_time() - start
        outcome = classify(exp, status, events, message)
        out.append({"case": name, "method": st.label, "outcome": outcome, "status": status, "events": len(events),
                    "cpu_s": cpu, "message": message[:80]})
    return out


def stability(out: Path, *, quick: bool = False, workers: int = 1, budget: float = PEER_BUDGET, log=print) -> list:
    """Run every method on every stability case; write ``stability.csv`` and ``stability.md``."""
    from symvib.checks.stability import case, cases, expected

    safeio.check_root(out, OUT_FOLDER)
    backend = driver_backend()
    names = [c.name for c in cases()]
    if quick:
        names = [n for n in names if n in ("grazing", "cone-edge", "zeno", "plastic-stay", "large-friction")]
    settings = STABILITY_SETTINGS
    warm = warm_up([(n, case(n).scene) for n in names], backend)
    log(f"symvib backend: {backend}; first call per curve (compile or load): "
        + ", ".join(f"{k} {v:.2f} s" for k, v in warm.items()))
    log(f"budget per run {budget:g} s CPU; computing the right outcomes")
    exps = {n: expected(n) for n in names}
    tasks = [(n, exps[n], settings, budget, backend) for n in names]
    results = map_workers(_stability_task, tasks, workers)
    rows = [r for group in results for r in group]
    write_csv(out / "stability.csv", rows)
    md = stability_markdown(rows, names, [Setting(m, v).label for m, v in settings])
    safeio.write_file(out / "stability.md", md, what=OUT_FOLDER)
    log(md)
    log(f"wrote {out / 'stability.csv'}, {out / 'stability.md'}")
    return rows


def stability_markdown(rows, names, methods) -> str:
    """The stability table: one row per case, one column per method."""
    from symvib.checks.stability import case

    cell = {(r["case"], r["method"]): r["outcome"] for r in rows}
    lines = ["| case | " + " | ".join(methods) + " |", "| --- |" + " --- |" * len(methods)]
    for n in names:
        marks = []
        for m in methods:
            o = cell.get((n, m), "")
            marks.append("**correct**" if o == "correct" else o)
        lines.append(f"| {case(n).title} | " + " | ".join(marks) + " |")
    return "\n".join(lines) + "\n"
