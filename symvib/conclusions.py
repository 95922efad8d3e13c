"""The old name of :mod:`symvib.paper.conclusions` (the paper's wing, ``symvib/paper/``): the same module.

``import symvib.conclusions`` gives the module object of :mod:`symvib.paper.conclusions` itself, so
every name of it, and a change made to it, is seen under both names.
"""
import sys

from symvib.paper import conclusions

sys.modules[__name__] = conclusions
