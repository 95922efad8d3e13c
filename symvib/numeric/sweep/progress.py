"""A one-line progress bar of a sweep: done/total, scenes per second, time left.

Examples
--------
>>> import io
>>> bar = Progress(10, stream=io.StringIO())
>>> bar.update(4)
>>> bar.line().split("]")[1].split(",")[0].strip()
'40.0% 4/10 scenes'
"""
from __future__ import annotations

import math
import sys
import time

__all__ = ["Progress", "PROGRESS_EVERY"]

#: Seconds between progress-bar redraws.
PROGRESS_EVERY = 0.2


class Progress:
    """A one-line progress bar on ``stream``: done/total, scenes per second, time left."""

    WIDTH = 30

    def __init__(self, total: int, *, stream=None, enabled: bool = True, initial: int = 0):
        self.total, self.done, self.start_done = total, initial, initial
        self.stream = sys.stderr if stream is None else stream
        self.enabled = enabled
        self.start = time.perf_counter()
        self.last = -math.inf

    def line(self) -> str:
        elapsed = time.perf_counter() - self.start
        rate = (self.done - self.start_done) / elapsed if elapsed > 0 else 0.0
        left = (self.total - self.done) / rate if rate > 0 else math.inf
        frac = self.done / self.total if self.total else 1.0
        bar = "#" * int(frac * self.WIDTH) + "." * (self.WIDTH - int(frac * self.WIDTH))
        eta = "--:--" if not math.isfinite(left) else time.strftime("%H:%M:%S", time.gmtime(left))
        return f"[{bar}] {frac:6.1%} {self.done}/{self.total} scenes, {rate:,.0f} scenes/s, {eta} left"

    def update(self, n: int, *, final: bool = False) -> None:
        self.done += n
        now = time.perf_counter()
        if not self.enabled or not final and now - self.last < PROGRESS_EVERY:
            return
        self.last = now
        tty = getattr(self.stream, "isatty", lambda: False)()
        self.stream.write(("\r" if tty else "") + self.line() + ("\n" if final or not tty else ""))
        self.stream.flush()
