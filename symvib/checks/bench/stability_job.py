"""The job ``symvib bench stability``: every method on every case of the stability suite.

Each case of :mod:`symvib.checks.stability` runs under every setting of
:data:`~symvib.checks.bench.settings.STABILITY_SETTINGS` within a CPU-time budget,
and its outcome is classified against the case's right one
(:func:`symvib.checks.stability.classify`).  The outcomes go to ``stability.csv``
and ``stability.md`` (:func:`~symvib.checks.bench.markdown.stability_markdown`).
"""
from __future__ import annotations

import time
from pathlib import Path

from symvib import safeio
from symvib.checks.bench.markdown import stability_markdown
from symvib.checks.bench.output import OUT_FOLDER, write_csv
from symvib.checks.bench.settings import PEER_BUDGET, STABILITY_SETTINGS, Setting, driver_backend, run_setting
from symvib.checks.bench.timing import warm_up
from symvib.checks.bench.workers import map_workers

__all__ = ["QUICK_CASES", "MESSAGE_CHARS", "stability"]

#: The cases of a ``--quick`` run.
QUICK_CASES = ("grazing", "cone-edge", "zeno", "plastic-stay", "large-friction")
#: Characters of a run's message kept in the table.
MESSAGE_CHARS = 80


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
                    "cpu_s": cpu, "message": message[:MESSAGE_CHARS]})
    return out


def stability(out: Path, *, quick: bool = False, workers: int = 1, budget: float = PEER_BUDGET, log=print) -> list:
    """Run every method on every stability case; write ``stability.csv`` and ``stability.md``.

    Parameters
    ----------
    out : pathlib.Path
        The output folder.
    quick : bool
        Only the cases of :data:`QUICK_CASES`.
    workers : int
        Processes (one case each at a time).
    budget : float
        CPU seconds of one peer run.
    log : callable
        Where the progress lines and the table go (default :func:`print`).

    Returns
    -------
    list of dict
        One row per case and method (``case``, ``method``, ``outcome``, ``status``, ``events``,
        ``cpu_s``, ``message``).
    """
    from symvib.checks.stability import case, cases, expected

    safeio.check_root(out, OUT_FOLDER)
    backend = driver_backend()
    names = [c.name for c in cases()]
    if quick:
        names = [n for n in names if n in QUICK_CASES]
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
