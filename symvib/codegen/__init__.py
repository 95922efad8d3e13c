"""The one bridge between the wings: derived expressions -> generated kernel modules.

:mod:`symvib.codegen.generate` writes a curve's kernel module (``generated/``
for the catalogue, the kernel cache for user curves), whose text :mod:`symvib.codegen.kernel_text`
makes with the printers of :mod:`symvib.codegen.printers`; :mod:`symvib.codegen.jets` writes a
curve's jets module the same way; :mod:`symvib.codegen.gauss`
computes the Gauss rules the numeric wing reads from ``generated/gauss_rules.json``.
"""
