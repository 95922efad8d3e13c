"""The old name of :mod:`symvib.paper.seed` (the paper's wing, ``symvib/paper/``): the same module.

``import symvib.symbolic.seed`` gives the module object of :mod:`symvib.paper.seed` itself, so
every name of it, and a change made to it, is seen under both names.
"""
import sys

from symvib.paper import seed

sys.modules[__name__] = seed
