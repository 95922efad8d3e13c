"""The old name of :mod:`symvib.paper.texmathml` (the paper's wing, ``symvib/paper/``): the same module.

``import symvib.texmathml`` gives the module object of :mod:`symvib.paper.texmathml` itself, so
every name of it, and a change made to it, is seen under both names.
"""
import sys

from symvib.paper import texmathml

sys.modules[__name__] = texmathml
