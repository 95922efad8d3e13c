"""What several test modules read: the Python examples of the README and of the documents in docs/
(one reader for every section) and ``derivations/nbtool.py`` (the notebooks' tool, imported from its file)."""
import importlib.util
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
DOCS = ROOT / "docs"
NBTOOL = ROOT / "derivations" / "nbtool.py"


def code_blocks(text: str) -> list:
    """The ```python blocks of Markdown ``text``."""
    return re.findall(r"```python\n(.*?)```", text, re.S)


def python_blocks(heading: str, path: Path = README) -> list:
    """The ```python blocks of the section of ``path`` (the README unless given) whose heading line
    starts with ``heading`` (``"## ..."`` or ``"### ..."``), up to the next ``## `` heading; fails the
    test when there are none."""
    text = path.read_text(encoding="utf-8")
    where = path.relative_to(ROOT).as_posix()
    parts = re.split(rf"\n{re.escape(heading)}[^\n]*\n", text, maxsplit=1)
    assert len(parts) == 2, f"{where} has no '{heading}' section"
    blocks = code_blocks(parts[1].split("\n## ", 1)[0])
    assert blocks, f"the '{heading}' section of {where} has no python code block"
    return blocks


def run_section(heading: str, name: str, path: Path = README) -> dict:
    """Run the blocks of the section of ``path`` (the README unless given) in order in one namespace
    (``__name__`` = ``name``); return it."""
    namespace = {"__name__": name}
    anchor = f"{path.relative_to(ROOT).as_posix()}#" + re.sub(
        r"[^a-z0-9 -]", "", heading.lstrip("# ").lower()).replace(" ", "-")
    for block in python_blocks(heading, path):
        exec(compile(block, anchor, "exec"), namespace)  # noqa: S102
    return namespace


def load_nbtool():
    """``derivations/nbtool.py`` as the module ``nbtool`` (one instance for every test module)."""
    if "nbtool" in sys.modules:
        return sys.modules["nbtool"]
    spec = importlib.util.spec_from_file_location("nbtool", NBTOOL)
    module = importlib.util.module_from_spec(spec)
    sys.modules["nbtool"] = module
    spec.loader.exec_module(module)
    return module
