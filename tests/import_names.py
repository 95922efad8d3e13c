"""Helpers of the tests that read imports with :mod:`ast` (``test_house``, ``test_layers``): module names."""
import ast
from pathlib import Path


def own_and_package(path: Path, root: Path) -> tuple:
    """``(module, package)`` dotted names of ``path``, a file of the package folder ``root`` (``symvib/``)."""
    rel = path.relative_to(root)
    own = ".".join(("symvib", *rel.with_suffix("").parts)).removesuffix(".__init__")
    return own, own if rel.name == "__init__.py" else own.rpartition(".")[0]


def imported_module(node: ast.ImportFrom, package: str) -> str:
    """The absolute name of the module a ``from ... import`` in ``package`` reads (relative levels resolved)."""
    if not node.level:
        return node.module or ""
    base = package.split(".")
    base = base[:len(base) - node.level + 1]
    return ".".join(base + ([node.module] if node.module else []))
