"""The symbolic wing (SymPy): curves, antiderivatives, the derivation, the audit.

Nothing in the numeric wing (:mod:`symvib.numeric`) imports this package; the
code generator (:mod:`symvib.codegen`) is the one bridge.
"""
