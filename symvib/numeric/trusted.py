"""The checks that make a run's numbers a result: finite, and an energy budget that closes
(physics.md, "Energies").

:func:`checked_status` is applied by the driver (:mod:`symvib.numeric.driver`) to every run and
to the columns of a sweep, and by the paths that run beside the engine (air drag,
:mod:`symvib.numeric.drag_run`; flights, :mod:`symvib.numeric.flights`), which import it from
here rather than from the driver that calls them.
"""
from __future__ import annotations

import math

import numpy as np

from symvib.numeric.layout import ERROR_CODES, StatusCode

__all__ = ["BUDGET_RTOL", "checked_status", "MATH_MESSAGES", "math_error"]

#: Largest relative residual of the energy budget (physics.md, "Energies") a trusted run may
#: end with: ``|E0 - E_final - W_friction - W_impacts|`` over the largest of those four
#: magnitudes.  Each term is exact to rounding or to the quadrature (about 1e-15 relative per
#: interval at 16 nodes, so at most about 1e-10 after the default 100,000 events; the catalogue
#: scenes and the test suite end below 1e-13), while a missed or misplaced event (a turning
#: point, a branch flip, a normal-force zero) or an overflow leaves a residual of the order of
#: the energy it mislays.  A run beyond it ends with status ``energy_budget_mismatch``.
BUDGET_RTOL = 1e-9


def checked_status(status, t_final, q_final, qdot_final, E0, E_final, friction_work, impact_loss):
    """The engine's status code after the checks of a trusted result (physics.md, "Energies").

    A run whose final state or energy sums are not finite ends ``NON_FINITE``;
    one whose energy budget ``E0 - E_final = W_friction + W_impacts`` misses by
    more than :data:`BUDGET_RTOL` of the largest of those terms ends
    ``ENERGY_BUDGET_MISMATCH``; any other status is kept.  Works on one run (numbers)
    or on the columns of a sweep (arrays).

    Returns
    -------
    int or ndarray of int
        Codes of :class:`symvib.numeric.layout.StatusCode`.

    Examples
    --------
    >>> checked_status(StatusCode.ARRESTED, 1.0, 0.0, 0.0, 4.9, 0.1, 2.8, 2.0) == StatusCode.ARRESTED
    True
    >>> checked_status(StatusCode.T_MAX, 1.0, 0.0, 0.0, 4.9, 0.0, 9.9, 0.0) == StatusCode.ENERGY_BUDGET_MISMATCH
    True
    >>> checked_status(StatusCode.ARRESTED, math.nan, 0.0, 0.0, 4.9, 0.0, 4.9, 0.0) == StatusCode.NON_FINITE
    True
    """
    if np.ndim(status) == 0:  # one run: the same test in plain floats (no array machinery)
        values = [float(v) for v in (t_final, q_final, qdot_final, E0, E_final, friction_work, impact_loss)]
        if not all(math.isfinite(v) for v in values):
            return int(StatusCode.NON_FINITE)
        e0, e1, wf, wi = values[3:]
        closes = abs(e0 - e1 - wf - wi) <= BUDGET_RTOL * max(abs(e0), abs(e1), abs(wf), abs(wi))
        return int(status) if closes or int(status) in ERROR_CODES else int(StatusCode.ENERGY_BUDGET_MISMATCH)
    code = np.asarray(status, dtype=np.int64)
    E0, E_final, Wf, Wimp = (np.asarray(v, dtype=float) for v in (E0, E_final, friction_work, impact_loss))
    finite = np.ones(code.shape, dtype=bool)
    for v in (t_final, q_final, qdot_final, E0, E_final, Wf, Wimp):
        finite &= np.isfinite(v)
    with np.errstate(invalid="ignore", over="ignore"):
        residual = np.abs(E0 - E_final - Wf - Wimp)
        scale = np.maximum(np.maximum(np.abs(E0), np.abs(E_final)), np.maximum(np.abs(Wf), np.abs(Wimp)))
        closes = residual <= BUDGET_RTOL * scale
    out = np.where(~finite, StatusCode.NON_FINITE, np.where(closes | np.isin(code, ERROR_CODES), code,
                                                       StatusCode.ENERGY_BUDGET_MISMATCH))
    return out.astype(np.int64)


#: Messages of the exceptions Python's ``math`` raises where compiled code returns inf or NaN.
MATH_MESSAGES = ("math range error", "math domain error", "float division by zero", "division by zero",
                  "Numerical result out of range", "float modulo", "integer division or modulo by zero")


def math_error(exc: BaseException) -> bool:
    """Whether ``exc`` is a floating-point failure of the plain-Python engine (not a bug)."""
    if isinstance(exc, ArithmeticError):
        return True  # OverflowError, ZeroDivisionError, FloatingPointError
    return isinstance(exc, ValueError) and any(m in str(exc) for m in MATH_MESSAGES)
