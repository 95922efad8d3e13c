"""A sweep's scenes as rows: the engine's scene rows and parameter rows of a chunk, checked.

Every row starts as the base scene's row (:func:`symvib.numeric.scenerow.scene_row`,
columns :class:`symvib.numeric.layout.SceneRow`) with the varied fields set,
and is checked by the scene's own checks (:data:`symvib.numeric.scene.CHECKS`,
applied element-wise to the columns): a bad row raises the
:class:`~symvib.numeric.scene.SceneError` a scene file with that value raises,
naming the field, with ``(sweep row N)`` appended: the row's number in the sweep.

Examples
--------
>>> from symvib.numeric.scene import resolve_scene
>>> from symvib.numeric.sweep.axes import parse_axis
>>> base = resolve_scene("paper-parabola")
>>> axes = (parse_axis(base, "restitution", "0.5,1.5", random=False),)
>>> scene_rows(base, axes, [np.array([0.5, 1.5])])
Traceback (most recent call last):
...
symvib.numeric.scene.SceneError: physics.restitution: must be in [0, 1] (1 = ideally elastic, 0 = plastic), ...
"""
from __future__ import annotations

import numpy as np

from symvib.numeric.layout import SceneRow
from symvib.numeric.scene import SceneError, SceneNumbers, checks, declared_domain, friction_coefficient
from symvib.numeric.scenerow import scene_row
from symvib.numeric.sweep.axes import FIELDS

__all__ = ["scene_rows", "check_rows"]


def _where(axes, values, rows, i: int) -> str:
    """Which scene of the sweep row ``i`` of a chunk is: its sweep row number, else its varied values."""
    if rows is not None:
        return f"sweep row {int(rows[i])}"
    return "varied values " + ", ".join(f"{a.field} = {float(np.asarray(v)[i]):g}" for a, v in zip(axes, values))


def scene_rows(scene, axes, values, rows=None) -> tuple:
    """The engine's rows for varied ``values`` (one array per axis) of ``scene``.

    Parameters
    ----------
    scene : Scene
        The base scene: fields not varied keep its values.
    axes : sequence of Axis
        The varied fields (:class:`symvib.numeric.sweep.axes.Axis`).
    values : sequence of ndarray
        Each axis's values, one per row.
    rows : ndarray, optional
        The rows' numbers in the sweep (named in an error); without them an error names
        the varied values.

    Returns
    -------
    scene_rows, param_rows : ndarray
        C-contiguous ``(n, len(SceneRow))`` and ``(n, number of curve parameters)``.

    Raises
    ------
    SceneError
        For the first check a row fails (:func:`check_rows`), naming the field and the row.
    """
    n = len(values[0]) if values else 0
    where = lambda i: _where(axes, values, rows, i)  # noqa: E731
    out = np.repeat(scene_row(scene)[None, :], n, axis=0)
    names = [name for name, _ in scene.params]
    params = np.repeat(np.array(scene.param_values, dtype=float)[None, :], n, axis=0)
    for axis, v in zip(axes, values):
        v = np.asarray(v, dtype=float)
        if axis.field.startswith("parameters."):
            params[:, names.index(axis.field.split(".", 1)[1])] = v
            continue
        if axis.field in ("physics.alpha0", "physics.alpha0_s"):
            v = _friction_coefficients(v, axis.field, where)
        out[:, FIELDS[axis.field]] = v
        if axis.field == "limiters.left":
            out[:, SceneRow.has_left] = 1.0
        elif axis.field == "limiters.right":
            out[:, SceneRow.has_right] = 1.0
    if scene.mu_s is None and not {a.field for a in axes} & {"physics.mu_s", "physics.alpha0_s"}:
        out[:, SceneRow.mu_s] = out[:, SceneRow.mu]   # the scene gives no static friction: mu_s follows mu
    check_rows(scene, out, params, vary_params=any(a.field.startswith("parameters.") for a in axes), where=where)
    return np.ascontiguousarray(out), np.ascontiguousarray(params)


def _friction_coefficients(alpha0: np.ndarray, field: str, where) -> np.ndarray:
    """``mu = tan(alpha0)`` (or ``mu_s = tan(alpha0_s)``) per row, by the scene's own conversion
    (:func:`~symvib.numeric.scene.friction_coefficient`)."""
    out = np.empty_like(alpha0)
    for i, a in enumerate(alpha0):
        try:
            out[i] = friction_coefficient(a, field)
        except SceneError as exc:
            raise SceneError(exc.field, f"{exc.reason} ({where(i)})") from None
    return out


def check_rows(scene, rows: np.ndarray, params: np.ndarray, *, vary_params: bool = True, where=None) -> None:
    """Make the checks of :func:`symvib.numeric.scene.check_numbers` on every row, in the same order.

    ``rows`` are scene rows (columns :class:`~symvib.numeric.layout.SceneRow`),
    ``params`` the curve's parameter values per row.  The curve's domain is
    evaluated once, or per row when ``vary_params``.  ``where(i)`` says which scene
    row ``i`` is (default ``row i``).

    Raises
    ------
    SceneError
        The scene's message for the first failing check (of its first failing
        row), with ``(where(i))`` appended.
    """
    where = where or (lambda i: f"row {i}")
    count = rows.shape[0]
    names = [name for name, _ in scene.params]

    def domain():
        if not vary_params:
            return declared_domain(scene)
        ends = np.array([declared_domain(scene, p) for p in params]).reshape(count, 2)
        return ends[:, 0], ends[:, 1]

    columns = {name: rows[:, SceneRow[name]] for name in SceneNumbers.NAMES if name != "contact"}
    columns["has_left"], columns["has_right"] = columns["has_left"] != 0, columns["has_right"] != 0
    events = columns["max_events"]
    if np.all((events % 1 == 0) & (np.abs(events) < 2**62)):   # whole numbers: shown as a scene file's integer
        columns["max_events"] = events.astype(np.int64)
    numbers = SceneNumbers(params={n: params[:, j] for j, n in enumerate(names)}, kinds=dict(scene.shape.params),
                           domain=domain, contact=scene.contact, **columns)
    for c in checks(numbers):
        if c.test is None:
            ok = np.isfinite(np.asarray(c.value(numbers), dtype=float))
        else:
            ok = c.test(numbers)
        if c.when is not None:
            ok = np.logical_or(ok, np.logical_not(c.when(numbers)))
        bad = np.flatnonzero(~np.broadcast_to(ok, (count,)))
        if bad.size:
            i = int(bad[0])
            raise SceneError(c.field, f"{c.message(numbers.row(i))} ({where(i)})")
