"""The old name of :mod:`symvib.paper.seedtex` (the paper's wing, ``symvib/paper/``): the same module.

``import symvib.symbolic.seedtex`` gives the module object of :mod:`symvib.paper.seedtex` itself, so
every name of it, and a change made to it, is seen under both names.
"""
import sys

from symvib.paper import seedtex

sys.modules[__name__] = seedtex
