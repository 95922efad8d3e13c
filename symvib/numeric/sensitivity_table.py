"""The record of a run's exact derivatives and its tables (physics.md, "Sensitivities").

:func:`symvib.numeric.sensitivity.sensitivities` computes a :class:`Sensitivities`;
this module holds it: the derivatives of every event's time, position and speeds and of
the final state, per parameter, with the reasons where there are none, as arrays, a long
table (:meth:`Sensitivities.rows`, :meth:`Sensitivities.to_dataframe`) or an
``xarray.Dataset`` with an event and a parameter dimension (:meth:`Sensitivities.to_xarray`).

Examples
--------
>>> import numpy as np
>>> empty = Sensitivities(("mu",), (), np.zeros((0, 1)), np.zeros((0, 1)), np.zeros((0, 1)),
...                       np.zeros((0, 1)), (), {}, {})
>>> empty.rows()
[]
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Sensitivities"]


@dataclass(frozen=True)
class Sensitivities:
    """Derivatives of a run's events and final state (an immutable record).

    Attributes
    ----------
    wrt : tuple of str
        The parameters, in the order of the columns.
    events : tuple of Event
        The run's events (rows).
    t, q, v_before, v_after : ndarray, shape (events, parameters)
        Derivatives of each event's time, position and speed ``v = h qdot`` just before
        and after it; NaN where the event is not differentiable.
    reasons : tuple of str
        Per event, why its row is NaN (empty where it is differentiable).
    final : dict
        ``t_final``, ``q_final``, ``friction_work``, ``impact_loss`` (and ``landing_loss`` on a
        unilateral curve) -> derivatives, shape (parameters,); NaN when the run did not end on an
        event or an event before is not differentiable.
    notes : dict
        Parameter -> why its whole column is NaN (a start at rest has no derivative in ``qdot0``).
    """

    wrt: tuple
    events: tuple
    t: np.ndarray
    q: np.ndarray
    v_before: np.ndarray
    v_after: np.ndarray
    reasons: tuple
    final: dict
    notes: dict

    def rows(self) -> list:
        """One dict per event and parameter: ``event``, ``kind``, ``wrt``, ``dt``, ``dq``,
        ``dv_before``, ``dv_after``, ``reason`` (a long table, as a DataFrame wants it)."""
        out = []
        for i, event in enumerate(self.events):
            for j, name in enumerate(self.wrt):
                out.append({"event": i, "kind": event.kind.value, "wrt": name, "dt": float(self.t[i, j]),
                            "dq": float(self.q[i, j]), "dv_before": float(self.v_before[i, j]),
                            "dv_after": float(self.v_after[i, j]), "reason": self.reasons[i]})
        return out

    def to_xarray(self):
        """The derivatives as an ``xarray.Dataset`` with an ``event`` and a ``wrt`` dimension
        (``dt``, ``dq``, ``dv_before``, ``dv_after``; the event's ``kind`` and ``reason`` as
        coordinates) and the final state's as variables over ``wrt`` (extra ``symvib[xarray]``).

        Examples
        --------
        >>> from symvib import simulate
        >>> ds = simulate("paper-parabola").sensitivities(wrt=("mu", "k")).to_xarray()  # doctest: +SKIP
        >>> float(ds.dt.sel(wrt="mu").isel(event=-1)) == float(ds.t_final.sel(wrt="mu"))  # doctest: +SKIP
        True
        """
        try:
            import xarray as xr
        except ImportError:
            raise ImportError("Sensitivities.to_xarray needs xarray: pip install 'symvib[xarray]'") from None
        dims = ("event", "wrt")
        coords = {"event": np.arange(len(self.events)), "wrt": list(self.wrt),
                  "kind": ("event", [e.kind.value for e in self.events]),
                  "t": ("event", [e.t for e in self.events]), "reason": ("event", list(self.reasons))}
        data = {"dt": (dims, self.t), "dq": (dims, self.q), "dv_before": (dims, self.v_before),
                "dv_after": (dims, self.v_after)}
        data.update({name: ("wrt", values) for name, values in self.final.items()})
        return xr.Dataset(data, coords=coords, attrs={name: why for name, why in self.notes.items()})

    def to_dataframe(self):
        """:meth:`rows` as a pandas DataFrame (extra ``symvib[pandas]``)."""
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("Sensitivities.to_dataframe needs pandas: pip install 'symvib[pandas]'") from None
        return pd.DataFrame(self.rows())
