"""Every example in symvib's docstrings runs and prints what it says (doctest)."""
import doctest
import importlib
import pkgutil

import pytest

import symvib

#: Modules whose examples take long (the audit derives and compares every printed equation).
SLOW = {"symbolic.audit"}
MODULES = sorted(m.name.removeprefix("symvib.") for m in pkgutil.walk_packages(symvib.__path__, "symvib.")
                 if not m.name.startswith("symvib.generated"))


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n in SLOW else n for n in MODULES])
def test_docstring_examples_run(name):
    module = importlib.import_module(f"symvib.{name}")
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE, verbose=False)
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples of symvib.{name} failed (see above)"


def test_the_examples_are_many():
    # A guard against a module list that silently became empty.
    assert len(MODULES) > 20
