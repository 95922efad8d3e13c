"""The physical symbols shared by every derivation (physics.md notation).

Curve parameters (``p``, ``R``, ...) and the generalized coordinate belong to
the curve; these belong to the physics and are reserved: a curve may not use
their names.
"""
from __future__ import annotations

import sympy as sp

#: Gravitational acceleration.
g = sp.Symbol("g", positive=True)
#: Mass of the particle.
m = sp.Symbol("m", positive=True)
#: Coulomb friction coefficient ``mu = tan(alpha0)``.  Declared positive so that
#: SymPy integrates ``exp(2 sigma mu alpha)`` without case splits; ``mu = 0`` is
#: reached as a limit, which every derivation checks is continuous.
mu = sp.Symbol("mu", positive=True)
#: Integration constant of a phase trajectory (eq. 2).
C = sp.Symbol("C", real=True)
#: Sign of the velocity, +1 or -1 (the paper's upper and lower signs).
sigma = sp.Symbol("sigma", real=True, nonzero=True)
#: Squared speed along the curve, ``w = v**2``.
w = sp.Symbol("w", nonnegative=True)

#: Names a curve may not use for its own symbols.
RESERVED = frozenset({"g", "m", "mu", "C", "sigma", "w", "alpha0", "k"})

#: LaTeX names used when printing.
LATEX_NAMES = {sigma: r"\sigma", mu: r"\mu", C: "C", w: "w"}
