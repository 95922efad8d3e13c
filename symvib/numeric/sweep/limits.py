"""The sweep's bounds and defaults, and its error.

Every bound is a module constant read when it is checked: assign
``symvib.numeric.sweep.limits.MAX_SCENES`` (and so on) to change one.  The
checks (:func:`symvib.numeric.sweep.spec.check_sizes`) refuse a sweep beyond
them before anything of its size is allocated.

Examples
--------
>>> from symvib.numeric.sweep import limits
>>> limits.NODES_RANGE, limits.DEFAULT_CHUNK
((2, 64), 4096)
>>> SweepError("out", "not a folder").field
'out'
"""
from __future__ import annotations

from symvib.numeric.layout import EventColumn
from symvib.numeric.scene import SceneError

__all__ = ["SweepError", "DEFAULT_CHUNK", "DEFAULT_NODES", "NODES_RANGE", "MAX_SCENES", "MAX_CHUNKS",
           "MAX_LIST_VALUES", "MAX_LOG_EVENTS", "MAX_CHUNK_BYTES", "MAX_EVENT_LOG_BYTES", "MAX_MANIFEST_BYTES"]

#: Scenes per chunk: the unit of writing, resuming and distribution.
DEFAULT_CHUNK = 4096
#: Default Gauss-Legendre nodes per quadrature panel (as :func:`symvib.numeric.driver.simulate`).
DEFAULT_NODES = 16
#: Allowed Gauss-Legendre nodes per panel, inclusive (``symvib.codegen.gauss`` tabulates rules up to this size).
NODES_RANGE = (2, 64)
#: Largest number of scenes a sweep may declare: its joined columns (about 130 bytes a
#: scene with two varied fields) are held in memory by :func:`symvib.numeric.sweep.store.load_sweep`.
MAX_SCENES = 10**8
#: Largest number of chunk files of a sweep (chunk files are numbered with six digits).
MAX_CHUNKS = 10**6
#: Largest number of values of one listed grid axis (``k=0.6,0.8,1``); a
#: ``start:stop:count`` axis is stored as its three numbers, whatever its count.
MAX_LIST_VALUES = 10**5
#: Largest number of events logged per scene (``--log-events``).
MAX_LOG_EVENTS = 10**6
#: Largest memory of one chunk's columns while it is computed, written or read, in bytes.
MAX_CHUNK_BYTES = 2**30
#: Largest event log of a whole sweep (scenes x ``log_events`` x 6 floats), in bytes:
#: :func:`symvib.numeric.sweep.store.load_sweep` joins it in memory.
MAX_EVENT_LOG_BYTES = 2**32
#: Largest manifest read, in bytes (listed axes of MAX_LIST_VALUES values fit many times).
MAX_MANIFEST_BYTES = 2**26
#: Bytes of one float64 or int64 value.
ITEM = 8
#: Values per logged event (the columns :class:`symvib.numeric.layout.EventColumn`).
EVENT_WIDTH = len(EventColumn)


class SweepError(SceneError):
    """A sweep folder, manifest or chunk cannot be used; ``field`` names the file or the option."""
