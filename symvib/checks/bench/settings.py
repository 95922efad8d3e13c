"""The methods and accuracy settings the benchmarks compare, and one setting's run of a scene.

A :class:`Setting` is one method at one accuracy: symvib's driver at a number of
Gauss nodes per panel, :func:`scipy.integrate.solve_ivp` (RK45, DOP853, Radau,
LSODA) at a relative tolerance (``atol = rtol / 100``), or classical RK4 at a fixed
step (the peers of :mod:`symvib.checks.peers`).  :func:`work_settings` are those of
the work-precision diagram, :func:`sequence_settings` those of the random-scene
sequence counts, :data:`STABILITY_SETTINGS` those of the stability table;
:func:`run_setting` runs one of them on one scene.

Examples
--------
>>> [s.label for s in work_settings(quick=True)][:2]
['symvib nodes=2', 'symvib nodes=4']
>>> Setting("RK45", 1e-6).label, Setting("RK4", 1e-3).label
('RK45 rtol=1e-06', 'RK4 dt=0.001')
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Setting", "SYMVIB_NODES", "IVP_METHODS", "RTOLS", "RK4_STEPS", "SEQ_NODES", "SEQ_RTOLS", "SEQ_RK4",
           "PEER_BUDGET", "STABILITY_SETTINGS", "work_settings", "sequence_settings", "run_setting",
           "driver_backend"]

#: Gauss nodes per panel of symvib's driver (its accuracy knob).
SYMVIB_NODES = (1, 2, 3, 4, 6, 8, 12, 16, 24)
IVP_METHODS = ("RK45", "DOP853", "Radau", "LSODA")
#: solve_ivp relative tolerances (atol = rtol / 100, as in symvib.checks.peers).
RTOLS = tuple(10.0 ** -e for e in range(3, 13))
#: RK4 fixed steps, seconds.
RK4_STEPS = (1e-2, 3e-3, 1e-3, 3e-4, 1e-4)
#: Settings of the random-scene sequence counts (fewer: a few hundred scenes each).
SEQ_NODES = (2, 4, 16)
SEQ_RTOLS = (1e-3, 1e-6, 1e-9, 1e-12)
SEQ_RK4 = (1e-2, 1e-3)
#: CPU-time budget of one peer run, seconds.
PEER_BUDGET = 20.0
#: Settings of the stability table: (method, setting).
STABILITY_SETTINGS = (("symvib", 16), ("RK45", 1e-6), ("DOP853", 1e-10), ("Radau", 1e-8), ("LSODA", 1e-8),
                      ("RK4", 1e-3))


@dataclass(frozen=True)
class Setting:
    """One method at one accuracy setting (``nodes`` for symvib, ``rtol`` for solve_ivp, ``dt`` for RK4)."""

    method: str
    value: float

    @property
    def label(self) -> str:
        if self.method == "symvib":
            return f"symvib nodes={int(self.value)}"
        if self.method == "RK4":
            return f"RK4 dt={self.value:g}"
        return f"{self.method} rtol={self.value:g}"


def run_setting(setting: Setting, scene, *, budget: float = PEER_BUDGET, backend: str = "auto"):
    """Run one method on one scene: ``(status, events, message)``, events as ``(kind, t, q, qdot_before)``."""
    if setting.method == "symvib":
        from symvib import simulate

        r = simulate(scene, nodes=int(setting.value), samples=False, backend=backend)
        return r.status.value, [(e.kind.value, e.t, e.q, e.qdot_before) for e in r.events], ""
    from symvib.checks.peers import rk4_events, solve_ivp_events

    if setting.method == "RK4":
        p = rk4_events(scene, setting.value, budget=budget)
    else:
        p = solve_ivp_events(scene, setting.method, setting.value, budget=budget)
    return p.status, [tuple(e[:4]) for e in p.events], p.message


def work_settings(quick: bool = False) -> list:
    """The settings of the work-precision diagram."""
    if quick:
        return ([Setting("symvib", n) for n in (2, 4, 8, 16)]
                + [Setting(m, r) for m in ("RK45", "DOP853") for r in (1e-4, 1e-7, 1e-10)]
                + [Setting("RK4", 3e-3)])
    return ([Setting("symvib", n) for n in SYMVIB_NODES] + [Setting(m, r) for m in IVP_METHODS for r in RTOLS]
            + [Setting("RK4", dt) for dt in RK4_STEPS])


def sequence_settings(quick: bool = False) -> list:
    """The settings of the random-scene sequence counts."""
    if quick:
        return [Setting("symvib", 16), Setting("RK45", 1e-6), Setting("DOP853", 1e-9)]
    return ([Setting("symvib", n) for n in SEQ_NODES] + [Setting(m, r) for m in IVP_METHODS for r in SEQ_RTOLS]
            + [Setting("RK4", dt) for dt in SEQ_RK4])


def driver_backend() -> str:
    """The backend symvib's driver runs on in the benchmarks (``"auto"`` resolved: numba when installed).

    Returns
    -------
    str
        :func:`symvib.numeric.backends.resolve_backend` of ``"auto"``.
    """
    from symvib.numeric.backends import resolve_backend

    return resolve_backend("auto")
