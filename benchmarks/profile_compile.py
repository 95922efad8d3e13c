"""Where the compile of the curve's engine goes: numba's front end per function, LLVM per phase.

Run from the project folder, with empty caches (the compile is what is measured)::

    SYMVIB_CACHE=$(mktemp -d) NUMBA_CACHE_DIR=$(mktemp -d) python benchmarks/profile_compile.py [simulate|sweep]

Binds the paper parabola's specialized engine and calls one entry once, with numba's
``numba:compile`` events timed (CPU) per function, exclusive of the functions it compiled on
the way (type inference compiles a callee when it first meets a call), and numba's LLVM steps
timed in total: the per-function passes (``add_ir_module``), the module optimization
(``_optimize_final_module``) and the machine code (``finalize_object``).  It prints the total,
the LLVM phases, the functions with the most exclusive time and their number of
specializations, and the size of the largest modules the optimizer saw (instructions before
it).  The timers cost about 1 % (no cProfile).
"""
from __future__ import annotations

import collections
import sys
import time

from numba.core import codegen, event

STACK: list = []
EXCLUSIVE: collections.Counter = collections.Counter()
COUNT: collections.Counter = collections.Counter()
PHASES: collections.Counter = collections.Counter()
SIZES: dict = {}


class _Compiles(event.Listener):
    def on_start(self, ev):
        STACK.append([ev.data["dispatcher"].py_func.__name__, time.process_time(), 0.0])

    def on_end(self, ev):
        name, start, inner = STACK.pop()
        spent = time.process_time() - start
        EXCLUSIVE[name] += spent - inner
        COUNT[name] += 1
        if STACK:
            STACK[-1][2] += spent


def _timed(cls, name, phase, size=False):
    original = getattr(cls, name)

    def timed(self, *args, **kwargs):
        if size:
            SIZES[self.name] = sum(1 for f in self._final_module.functions if not f.is_declaration
                                   for b in f.blocks for _ in b.instructions)
        start = time.process_time()
        try:
            return original(self, *args, **kwargs)
        finally:
            PHASES[phase] += time.process_time() - start

    setattr(cls, name, timed)


def main(which: str) -> None:
    event.register("numba:compile", _Compiles())
    _timed(codegen.CPUCodeLibrary, "add_ir_module", "per-function passes (add_ir_module)")
    _timed(codegen.CPUCodeLibrary, "_optimize_final_module", "module optimization", size=True)
    _timed(codegen.JITCodeLibrary, "_finalize_specific", "machine code (finalize_object)")

    import numpy as np

    import symvib
    from symvib.numeric import driver
    from symvib.numeric.engine.bind import bind
    from symvib.prepare import prepare

    scene = symvib.load_scene("paper-parabola")
    module = prepare(scene).kernels
    cp, row, R = tuple(scene.param_values), driver.scene_row(scene), driver.rules(driver.NODES)
    start = time.process_time()
    engine = bind(module, "numba")
    if which == "simulate":
        engine.simulate(cp, row, R, True)
    else:
        engine.sweep(np.array([row]), np.array([cp]), R, 4)
    total = time.process_time() - start
    print(f"{which} entry of paper-parabola: {total:.1f} s of CPU; functions compiled {len(COUNT)}, "
          f"specializations {sum(COUNT.values())}")
    for phase, seconds in PHASES.items():
        print(f"  LLVM {phase}: {seconds:.2f} s")
    print(f"  numba front end and the rest: {total - sum(PHASES.values()):.2f} s")
    print("most exclusive time (s, specializations):")
    for name, seconds in EXCLUSIVE.most_common(20):
        print(f"  {name:24s} {seconds:6.2f}  {COUNT[name]}")
    print(f"modules optimized: {len(SIZES)}, {sum(SIZES.values())} instructions in all; the largest:")
    for name, size in sorted(SIZES.items(), key=lambda kv: -kv[1])[:6]:
        print(f"  {size:7d} {name[:70]}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "simulate")
