"""A scene as the engine's row of floats (columns :class:`symvib.numeric.layout.SceneRow`).

The driver, the dense output and the sweep's rows all hand the engine a scene
this way; it lives below them so that none imports another to reach it.

Examples
--------
>>> from symvib.numeric.scene import scene_from_dict
>>> s = scene_from_dict({"curve": {"shape": "parabola"}, "parameters": {"p": 1},
...     "physics": {"mu": 0.1, "restitution": 0.8}, "limiters": {"right": 0.5}, "initial": {"q": 0, "qdot": 2}})
>>> row = scene_row(s)
>>> row[SceneRow.mu].item(), row[SceneRow.has_left].item(), row[SceneRow.right].item()
(0.1, 0.0, 0.5)
"""
from __future__ import annotations

import numpy as np

from symvib.numeric.layout import SceneRow

__all__ = ["scene_row"]


def scene_row(scene) -> np.ndarray:
    """``scene`` as the engine's row of floats (columns :class:`symvib.numeric.layout.SceneRow`;
    the deadline column, which only the plain engine's wall-clock limit sets, stays 0)."""
    row = np.zeros(len(SceneRow))
    row[SceneRow.g], row[SceneRow.m], row[SceneRow.mu], row[SceneRow.k] = scene.g, scene.m, scene.mu, scene.k
    row[SceneRow.has_left] = scene.left is not None
    row[SceneRow.left] = 0.0 if scene.left is None else scene.left
    row[SceneRow.has_right] = scene.right is not None
    row[SceneRow.right] = 0.0 if scene.right is None else scene.right
    row[SceneRow.q0], row[SceneRow.qdot0] = scene.q0, scene.qdot0
    row[SceneRow.t_max], row[SceneRow.max_events] = scene.t_max, scene.max_events
    row[SceneRow.unilateral] = scene.contact == "unilateral"
    row[SceneRow.mu_s] = scene.mu_static
    return row
