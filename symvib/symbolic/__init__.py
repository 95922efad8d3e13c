"""The symbolic wing (SymPy): curves, antiderivatives, the derivation, singular points.

Nothing in the numeric wing (:mod:`symvib.numeric`) imports this package; the
code generator (:mod:`symvib.codegen`) is the one bridge.  The audit of the
paper's printed equations, built on the derivation, lives in the paper's wing
(:mod:`symvib.paper.audit`, with the seed paper's text, :mod:`symvib.paper.seed`).
"""
