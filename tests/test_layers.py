"""The package's layers: symbolic (SymPy) -> codegen (the one bridge) -> numeric (NumPy only).

Every import of every module under ``symvib/numeric/`` and ``symvib/codegen/`` is read with
:mod:`ast` (inside functions too) and checked against the layers; the few known climbs are listed
here, each with its reason, so that a new one fails.  What both wings share (the format of a
generated module, :mod:`symvib.kernelformat`; the Gauss-Legendre computation,
:mod:`symvib.quadrature_rules`) lives on the ground floor, ``symvib/``.
"""
import ast
from pathlib import Path

import pytest
from import_names import imported_module, own_and_package

import symvib

PACKAGE = Path(symvib.__file__).resolve().parent

#: Imports of ``symvib.codegen`` by the numeric wing: ``(file, function) -> reason``.
NUMERIC_TO_CODEGEN = {
    ("numeric/kernels.py", "_generate"): "the bridge: a user curve not generated yet is derived and generated",
}
#: Imports of ``symvib.symbolic`` by the numeric wing: ``(file, function) -> reason``.
#: The prepare step (issue 25) removes these.
NUMERIC_TO_SYMBOLIC = {
    ("numeric/driver.py", "_singular_end"): "a singular end of the domain is found symbolically",
    ("numeric/driver.py", "_run_shape"): "a singular end of the domain is found symbolically",
    ("numeric/sweep/runner.py", "_refuse_singular_domain"): "a sweep refuses a singular domain symbolically",
}
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


@pytest.mark.parametrize(("target", "known"), [("symvib.codegen", NUMERIC_TO_CODEGEN),
                                               ("symvib.symbolic", NUMERIC_TO_SYMBOLIC)])
def test_the_numeric_wing_climbs_only_where_known(target, known):
    found = _climbs("numeric", target)
    new = [f"symvib/{rel}:{line}: import of {target} in {function or 'the module'}"
           for rel, function, line in found if (rel, function) not in known]
    assert not new, (f"the numeric wing imports {target} (put what both need on the ground floor, symvib/):\n"
                     + "\n".join(new))
    gone = set(known) - {(rel, function) for rel, function, _ in found}
    assert not gone, f"known climbs no longer there (remove them from the list): {sorted(gone)}"


def test_the_code_generator_imports_nothing_numeric_at_module_level():
    found = _climbs("codegen", "symvib.numeric")
    at_import = [f"symvib/{rel}:{line}" for rel, function, line in found if function is None]
    assert not at_import, ("symvib/codegen imports symvib.numeric at module level (the format of a generated "
                           "module is symvib.kernelformat):\n" + "\n".join(at_import))
    new = [f"symvib/{rel}:{line}: in {function}" for rel, function, line in found
           if function is not None and (rel, function) not in CODEGEN_TO_NUMERIC]
    assert not new, "symvib/codegen imports symvib.numeric in a function not listed:\n" + "\n".join(new)


@pytest.mark.parametrize("name", ["kernelformat", "quadrature_rules"])
def test_the_ground_floor_imports_no_wing(name):
    found = [module for module, _, _ in _imports(PACKAGE / f"{name}.py")
             if module.split(".")[:2] in (["symvib", "numeric"], ["symvib", "codegen"], ["symvib", "symbolic"])
             or module.split(".")[0] == "sympy"]
    assert not found, f"symvib/{name}.py imports {found}"
