"""The package's layers: symbolic (SymPy) -> codegen (the one bridge) -> numeric (NumPy only).

Every import of every module under ``symvib/numeric/`` and ``symvib/codegen/`` is read with
:mod:`ast` (inside functions too) and checked against the layers; the few known climbs are listed
here, each with its reason, so that a new one fails; the numeric wing has none (the prepare step,
:mod:`symvib.prepare`, above both wings, makes what it receives).  What both wings share (the
format of a generated module, :mod:`symvib.kernelformat`; the Gauss-Legendre computation,
:mod:`symvib.quadrature_rules`; a run's regular domain from singular pieces, :mod:`symvib.regular`)
lives on the ground floor, ``symvib/``.  The paper's wing, :mod:`symvib.paper`, stands above both wings:
neither imports it.
"""
import ast
from pathlib import Path

import pytest
from import_names import imported_module, own_and_package

import symvib

PACKAGE = Path(symvib.__file__).resolve().parent

#: Function-level imports of ``symvib.numeric`` by the code generator: ``(file, function) -> reason``
#: (none at module level, ever).
CODEGEN_TO_NUMERIC: dict = {}


def _imports(path: Path, root: Path | None = None) -> list:
    """``(imported module, enclosing function or None, line)`` of every import in ``path`` (a file
    of the package folder ``root``), relative imports resolved; ``from M import name`` also yields
    ``M.name`` (it may be a submodule)."""
    _, package = own_and_package(path, root or PACKAGE)
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    out = []

    def visit(node, function):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                visit(child, function or child.name)   # a nested function counts as its outermost one
                continue
            if isinstance(child, ast.Import):
                out.extend((alias.name, function, child.lineno) for alias in child.names)
            elif isinstance(child, ast.ImportFrom):
                module = imported_module(child, package)
                out.append((module, function, child.lineno))
                out.extend((f"{module}.{alias.name}", function, child.lineno) for alias in child.names)
            visit(child, function)

    visit(tree, None)
    return out


def _climbs(folder: str, target: str) -> list:
    """``(file, function or None, line)`` of every import of ``target`` (or below it) in ``folder``."""
    found = set()
    for path in sorted((PACKAGE / folder).rglob("*.py")):
        rel = path.relative_to(PACKAGE).as_posix()
        for module, function, line in _imports(path):
            if module == target or module.startswith(target + "."):
                found.add((rel, function, line))
    return sorted(found, key=lambda f: (f[0], f[2]))


def test_the_scan_sees_imports_in_functions_and_relative_ones(tmp_path):
    root = tmp_path / "symvib"
    (root / "numeric").mkdir(parents=True)
    (root / "numeric" / "x.py").write_text(
        "import symvib.codegen.gauss\n"
        "def f():\n    def g():\n        from ..codegen import generate\n"
        "    from .. import codegen\n")
    found = _imports(root / "numeric" / "x.py", root)
    assert ("symvib.codegen.gauss", None, 1) in found
    assert ("symvib.codegen", "f", 4) in found and ("symvib.codegen.generate", "f", 4) in found
    assert ("symvib.codegen", "f", 5) in found


@pytest.mark.parametrize("target", ["symvib.codegen", "symvib.symbolic", "symvib.prepare", "symvib.paper", "sympy"])
def test_the_numeric_wing_never_climbs(target):
    """The numeric wing receives a prepared curve (symvib.prepare, above both wings, derives and
    searches it): no import of the code generator, the symbolic wing or SymPy, not even in a function."""
    found = _climbs("numeric", target) if target.startswith("symvib.") else _climbs_any("numeric", target)
    assert not found, (f"the numeric wing imports {target} (what both need goes on the ground floor, symvib/; "
                       "what needs SymPy goes through symvib.prepare):\n"
                       + "\n".join(f"symvib/{rel}:{line} in {fn or 'the module'}" for rel, fn, line in found))


def test_the_symbolic_wing_imports_nothing_numeric():
    found = _climbs("symbolic", "symvib.numeric")
    assert not found, "symvib/symbolic imports symvib.numeric:\n" + "\n".join(f"symvib/{r}:{ln}" for r, _, ln in found)


@pytest.mark.parametrize("wing", ["symbolic", "codegen"])
def test_the_paper_wing_stands_above_the_symbolic_wing_and_the_code_generator(wing):
    """The audit uses the derivation, not the other way round: neither symvib/symbolic nor
    symvib/codegen imports symvib.paper."""
    found = [f"symvib/{rel}:{line}" for rel, _, line in _climbs(wing, "symvib.paper")]
    assert not found, f"symvib/{wing} imports the paper's wing:\n" + "\n".join(found)


def _climbs_any(folder: str, target: str) -> list:
    """As :func:`_climbs`, for a module outside the package (``sympy``)."""
    found = set()
    for path in sorted((PACKAGE / folder).rglob("*.py")):
        rel = path.relative_to(PACKAGE).as_posix()
        found |= {(rel, function, line) for module, function, line in _imports(path)
                  if module == target or module.startswith(target + ".")}
    return sorted(found, key=lambda f: (f[0], f[2]))


def test_the_code_generator_imports_nothing_numeric_at_module_level():
    found = _climbs("codegen", "symvib.numeric")
    at_import = [f"symvib/{rel}:{line}" for rel, function, line in found if function is None]
    assert not at_import, ("symvib/codegen imports symvib.numeric at module level (the format of a generated "
                           "module is symvib.kernelformat):\n" + "\n".join(at_import))
    new = [f"symvib/{rel}:{line}: in {function}" for rel, function, line in found
           if function is not None and (rel, function) not in CODEGEN_TO_NUMERIC]
    assert not new, "symvib/codegen imports symvib.numeric in a function not listed:\n" + "\n".join(new)


@pytest.mark.parametrize("name", ["kernelformat", "quadrature_rules", "regular"])
def test_the_ground_floor_imports_no_wing(name):
    found = [module for module, _, _ in _imports(PACKAGE / f"{name}.py")
             if module.split(".")[:2] in (["symvib", "numeric"], ["symvib", "codegen"], ["symvib", "symbolic"])
             or module.split(".")[0] == "sympy"]
    assert not found, f"symvib/{name}.py imports {found}"
