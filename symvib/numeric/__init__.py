"""The numeric wing (NumPy only): kernels, the engine, the driver, sweeps, figures.

``simulate`` and ``sweep`` of a curve whose kernels exist import neither SymPy
nor mpmath (``tests/test_package.py``); a curve without kernels asks the bridge
(:mod:`symvib.codegen`) lazily.
"""
