"""Every example in symvib's docstrings runs and prints what it says (doctest).

The examples of a module that uses an optional extra (xarray, pandas, zarr, dask,
scipy: pyproject's ``[project.optional-dependencies]``) are skipped where that extra
is not installed (``pip install . && python -m pytest`` passes), and run where it is.
"""
import doctest
import importlib
import importlib.util
import pkgutil

import pytest

import symvib

#: Modules whose examples take long (the audit derives and compares every printed equation).
SLOW = {"paper.audit"}
MODULES = sorted(m.name.removeprefix("symvib.") for m in pkgutil.walk_packages(symvib.__path__, "symvib.")
                 if not m.name.startswith("symvib.generated"))
#: The packages of symvib's optional extras (top-level import names).
EXTRAS = ("xarray", "pandas", "zarr", "dask", "scipy")
FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE


def installed(name: str) -> bool:
    """Whether the package ``name`` can be imported here."""
    try:
        return importlib.util.find_spec(name) is not None
    except (ImportError, ValueError):
        return False


def missing_extra(exc: BaseException):
    """The optional extra whose absence raised ``exc`` (an ImportError naming it), else ``None``."""
    if not isinstance(exc, ImportError):
        return None
    named = (getattr(exc, "name", None) or "").split(".")[0]
    for extra in EXTRAS:
        if (named == extra or extra in str(exc)) and not installed(extra):
            return extra
    return None


class ExtrasRunner(doctest.DocTestRunner):
    """A doctest runner that notes an example failing only because an optional extra is missing."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.missing = None

    def report_unexpected_exception(self, out, test, example, exc_info):
        extra = missing_extra(exc_info[1])
        if extra is not None:
            self.missing = self.missing or extra
            return
        super().report_unexpected_exception(out, test, example, exc_info)


def run_examples(module) -> tuple:
    """``(failed, attempted, missing extra or None)`` of the examples of ``module``."""
    runner = ExtrasRunner(optionflags=FLAGS, verbose=False)
    for test in doctest.DocTestFinder().find(module, module.__name__):
        runner.run(test)
    failed, attempted = runner.summarize(verbose=False)
    return failed, attempted, runner.missing


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n in SLOW else n for n in MODULES])
def test_docstring_examples_run(name):
    try:
        module = importlib.import_module(f"symvib.{name}")
    except ImportError as exc:
        if missing_extra(exc) is None:
            raise
        pytest.skip(f"symvib.{name} needs the optional {missing_extra(exc)}")
    if module.__name__ != f"symvib.{name}":
        pytest.skip(f"symvib.{name} is the old name of {module.__name__}, whose examples run under its own name")
    failed, attempted, missing = run_examples(module)
    if missing is not None:
        pytest.skip(f"the examples of symvib.{name} need the optional {missing} (not installed)")
    assert failed == 0, f"{failed} of {attempted} examples of symvib.{name} failed (see above)"


def test_the_examples_are_many():
    # A guard against a module list that silently became empty.
    assert len(MODULES) > 20


def test_an_example_needing_a_missing_extra_is_skipped_not_failed(monkeypatch):
    """Without xarray (as after ``pip install .``), labelled.py's examples are a skip, not a failure."""
    import symvib.numeric.sweep.labelled as labelled

    real = importlib.import_module

    def without_xarray(name, *args, **kwargs):
        if name.split(".")[0] == "xarray":
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return real(name, *args, **kwargs)

    monkeypatch.setattr(importlib, "import_module", without_xarray)
    real_find_spec = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name.split(".")[0] == "xarray" else real_find_spec(name, *a))
    failed, _, missing = run_examples(labelled)
    assert missing == "xarray"
    assert missing_extra(ImportError("a sweep stored as Zarr needs zarr: pip install")) is None  # zarr "installed"
