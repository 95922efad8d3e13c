"""The old name of :mod:`symvib.paper.audit` (the paper's wing, ``symvib/paper/``): the same module.

``import symvib.symbolic.audit`` gives the module object of :mod:`symvib.paper.audit` itself, so
every name of it, and a change made to it, is seen under both names;
``python -m symvib.symbolic.audit`` runs ``python -m symvib.paper.audit``.
"""
import sys

if __name__ == "__main__":  # pragma: no cover - prints the errata of the equations
    import runpy

    runpy.run_module("symvib.paper.audit", run_name="__main__", alter_sys=True)
else:
    from symvib.paper import audit

    sys.modules[__name__] = audit
