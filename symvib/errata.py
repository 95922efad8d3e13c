"""The old name of :mod:`symvib.paper.errata` (the paper's wing, ``symvib/paper/``): the same module.

``import symvib.errata`` gives the module object of :mod:`symvib.paper.errata` itself, so
every name of it, and a change made to it, is seen under both names;
``python -m symvib.errata`` runs ``python -m symvib.paper.errata``.
"""
import sys

if __name__ == "__main__":  # pragma: no cover - writes docs/errata.md
    import runpy

    runpy.run_module("symvib.paper.errata", run_name="__main__", alter_sys=True)
else:
    from symvib.paper import errata

    sys.modules[__name__] = errata
