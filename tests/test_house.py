"""House rules of the package: every ``__all__`` name exists, and no module imports another's private names."""
import ast
import importlib
import pkgutil
from pathlib import Path

import pytest
from import_names import imported_module, own_and_package

import symvib

PACKAGE = Path(symvib.__file__).resolve().parent
#: Every module of the package (the generated kernel modules included: they are imported, not scanned).
MODULES = sorted(m.name for m in pkgutil.walk_packages(symvib.__path__, "symvib."))
#: Private imports allowed across modules: ``(importing file, imported module, name)``.
#: Private imports waiting to be made public (none: codegen/jets.py imports the printers' and the
#: generator's names public, from symvib.codegen.printers, .kernel_text and .generate).
PENDING_PRIVATE_IMPORTS: set = set()


@pytest.mark.parametrize("name", MODULES)
def test_every_name_in_all_exists(name):
    module = importlib.import_module(name)
    missing = [n for n in getattr(module, "__all__", ()) if not hasattr(module, n)]
    assert not missing, f"{name}.__all__ names what the module does not define: {missing}"


@pytest.mark.parametrize("module, names", [("generate", {"generate", "module_source", "stale"}),
                                           ("kernel_text", {"module_text", "KERNEL_FUNCTIONS"}),
                                           ("printers", {"NumPy", "Math", "function"})])
def test_star_import_of_the_code_generator(module, names):
    namespace = {}
    exec(f"from symvib.codegen.{module} import *", namespace)  # noqa: S102 - the import is the test
    assert names <= namespace.keys()


def _sources():
    """The package's own source files (the generated kernel modules live outside ``symvib/``)."""
    return sorted(p for p in PACKAGE.rglob("*.py") if "generated" not in p.relative_to(PACKAGE).parts)


def _private_imports(path: Path, root: Path = PACKAGE) -> list:
    """``(line, imported module, name)`` of every ``from M import _name`` in ``path`` (a file of the
    package folder ``root``) with M another module."""
    own, package = own_and_package(path, root)
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), filename=str(path))):
        if not isinstance(node, ast.ImportFrom) or node.module == "__future__":
            continue
        module = imported_module(node, package)
        if module == own:
            continue
        for alias in node.names:
            if alias.name.startswith("_") and not alias.name.startswith("__"):
                out.append((node.lineno, module, alias.name))
    return out


def test_the_scan_finds_a_private_import(tmp_path):
    """The scan itself: absolute and relative private imports are found, a private alias is not."""
    fake = tmp_path / "symvib" / "checks"
    fake.mkdir(parents=True)
    (fake / "x.py").write_text("from symvib.symbolic.derive import _pm\nfrom ..paper import _y as y\n"
                               "from symvib.symbolic import curve as _curve\n", encoding="utf-8")
    assert _private_imports(fake / "x.py", tmp_path / "symvib") == [(1, "symvib.symbolic.derive", "_pm"),
                                                                    (2, "symvib.paper", "_y")]


def test_no_module_imports_private_names_of_another():
    found = []
    for path in _sources():
        rel = path.relative_to(PACKAGE).as_posix()
        for line, module, name in _private_imports(path):
            if (rel, module, name) not in PENDING_PRIVATE_IMPORTS:
                found.append(f"symvib/{rel}:{line}: from {module} import {name}")
    assert not found, ("private names imported across modules (make them public, documented, or move them):\n"
                       + "\n".join(found))
