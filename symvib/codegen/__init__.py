"""The one bridge between the wings: derived expressions -> generated kernel modules.

:mod:`symvib.codegen.generate` writes a curve's kernel module (``generated/``
for the catalogue, the kernel cache for user curves); :mod:`symvib.codegen.gauss`
computes the Gauss rules the numeric wing reads from ``generated/gauss_rules.json``.
"""
