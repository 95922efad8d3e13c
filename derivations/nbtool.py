"""Keep the notebooks in ``derivations/`` diffable, and run them.

The notebooks are stored as plain Jupyter notebooks (nbformat 4) *without
outputs*: execution counts null, outputs empty, only the ``kernelspec`` and the
language name kept in the metadata, and the JSON normalized (sorted keys,
1-space indent, one source line per JSON string, trailing newline).  A diff of
a notebook is then a diff of its source, and it still opens in Jupyter as is.

Commands (paths default to every ``*.ipynb`` next to this file)::

    python derivations/nbtool.py clean [NOTEBOOK ...]   # strip outputs, normalize (in place)
    python derivations/nbtool.py check [NOTEBOOK ...]   # exit 1 if one is not stored clean
    python derivations/nbtool.py run [NOTEBOOK ...] [--output DIR] [--timeout SECONDS]
    python derivations/nbtool.py render [NOTEBOOK ...] [--out DIR]   # pages for docs/notebooks/

``run`` executes each notebook top to bottom on a fresh Jupyter kernel
(nbclient + ipykernel, Matplotlib on ``Agg``) in this folder, and exits 1 on
the first error of any notebook; ``--output DIR`` writes the executed copies
(with their outputs and figures) there, never over the stored ones.

``render`` runs them the same way with the plain-Python engine (``SYMVIB_BACKEND=python``:
nothing waits for a compiler) and writes each executed notebook as one Markdown page,
``docs/notebooks/NAME.md``, with its figures as PNG files in ``docs/notebooks/NAME_files/``.
:func:`rendered_problems` says why a rendered page is not current
(``tests/test_notebooks_rendered.py``).

Why a page and figure files, and no executed ``.ipynb``: a figure is stored once, as the
PNG that the page links (an executed notebook would hold the same figure again as base64,
a third larger, and rewrite it whole on each render); a figure that did not change is the
same file and adds nothing to the history, and a page diffs as text.  GitHub shows a
Markdown page at once, with its math and figures, where it renders a large notebook
slowly or not at all.  The notebooks themselves are in ``derivations/`` (``run --output``
writes executed copies for Jupyter).  PNG, not SVG: an SVG figure holds every plotted point as
path text, 3.4 times the PNG's bytes in a checkout for the explorer's figures.

A render is deterministic: the same notebook rendered twice on the same code and machine
gives byte-identical files.  Each kernel starts with a fixed environment of its own (a
fresh ``IPYTHONDIR`` whose config makes PNG figures without the ``Software`` text chunk,
a ``matplotlibrc`` of the render's instead of the user's, ``PYTHONHASHSEED=0``, a fresh
``$SYMVIB_CACHE``: kernels of user curves are generated as on a first run); nbclient
records no cell timings and merges stream outputs (``coalesce_streams``: ipykernel
flushes ``print`` output in chunks whose borders depend on timing); the page holds no
metadata, ids, execution counts or dates, only a digest of the notebook's cells; figures
are numbered in order.  What the notebooks print must not depend on the clock or the
machine either (no wall times, no absolute paths): ``tests/test_notebooks_rendered.py``
renders one twice and compares.  One thing stays outside: ``derive`` tries its routes under
wall-clock budgets, so on a machine loaded several times over a route that takes a second
may time out and a page show another route; render on a quiet machine.

``clean`` and ``check`` need only the standard library (``check`` also
validates against the nbformat schema when :mod:`nbformat` is installed);
``run`` needs ``nbclient`` and ``ipykernel`` (``pip install ".[test]"``).
This script does not import symvib.

Examples
--------
>>> nb = {"cells": [{"cell_type": "code", "execution_count": 3, "id": "a", "metadata": {},
...                   "outputs": [{"output_type": "stream", "name": "stdout", "text": "1"}],
...                   "source": "print(1)\\nx = 2"}],
...       "metadata": {"kernelspec": {"name": "python3", "display_name": "Python 3",
...                                   "language": "python"}},
...       "nbformat": 4, "nbformat_minor": 5}
>>> problems(dumps(nb))
['code cell 1 carries outputs', 'code cell 1 has execution count 3', 'not normalized']
>>> problems(dumps(normalize(nb)))
[]
"""
from __future__ import annotations

import argparse
import base64
import hashlib
import json
import os
import re
import shutil
import sys
import tempfile
import time
from pathlib import Path

#: The folder of the notebooks (this file's folder).
HERE = Path(__file__).resolve().parent
#: Seconds one cell may run before the execution fails (derivations have their own budget): a guard
#: against a hung kernel, not a speed test.  The parabola's 30-digit reference cell took more than 300 s
#: at load 6 on the 2-core machine (2026-11-26), so the guard is well above what load does to a cell.
CELL_TIMEOUT = 1200
#: Seconds a fresh kernel may take to start.
STARTUP_TIMEOUT = 120
#: The kernel every notebook runs on.
KERNEL_NAME = "python3"
#: Cell metadata worth keeping (everything else is editor state).
CELL_METADATA = ("tags",)
#: Hex digits of the id :func:`normalize` gives a cell that has none (as Jupyter's own: 8).
CELL_ID_DIGITS = 8
#: Environment of the kernel: figures render off-screen.
KERNEL_ENV = {"MPLBACKEND": "Agg"}
#: Where ``render`` writes the pages.
RENDERED = HERE.parent / "docs" / "notebooks"
#: The environment a rendering runs in: the plain-Python engine (no notebook waits for a numba
#: compile) and a fixed hash seed (SymPy's set and dict orders are then those of every render).
RENDER_ENV = {"SYMVIB_BACKEND": "python", "PYTHONHASHSEED": "0"}
#: The kernel's IPython configuration in a render (``IPYTHONDIR/profile_default``): PNG figures
#: without the ``Software`` text chunk (Matplotlib's version) and compressed as tightly as zlib can.
KERNEL_CONFIG = """\
c.InlineBackend.figure_formats = {"png"}
c.InlineBackend.print_figure_kwargs = {"bbox_inches": "tight", "metadata": {"Software": None},
                                       "pil_kwargs": {"optimize": True}}
c.InlineBackend.rc = {}
c.HistoryManager.enabled = False
"""
#: The Matplotlib configuration of a render (``$MATPLOTLIBRC``), in place of the user's.
MATPLOTLIBRC = "backend: Agg\nsvg.hashsalt: symvib\n"
#: The figure types a page takes from an output, best first, with the extension of their file.
FIGURE_TYPES = {"image/png": "png", "image/svg+xml": "svg"}
#: PNG chunks a rendered figure may hold (text and time chunks would be metadata that churns).
PNG_CHUNKS = {b"IHDR", b"PLTE", b"tRNS", b"pHYs", b"IDAT", b"IEND"}


def notebooks(paths=None) -> list:
    """The notebooks named, or every ``*.ipynb`` in this folder (sorted)."""
    if paths:
        return [Path(p) for p in paths]
    return sorted(HERE.glob("*.ipynb"))


def _lines(source) -> list:
    text = "".join(source) if isinstance(source, list) else source
    return text.splitlines(keepends=True)


def normalize(nb: dict) -> dict:
    """The notebook with outputs stripped and only durable metadata kept (a new dict)."""
    cells = []
    for index, cell in enumerate(nb.get("cells", [])):
        out = {k: v for k, v in cell.items() if k not in ("outputs", "execution_count", "metadata", "source")}
        out["metadata"] = {k: v for k, v in cell.get("metadata", {}).items() if k in CELL_METADATA}
        out["source"] = _lines(cell.get("source", ""))
        if "id" not in out:   # (nbformat 4.5 requires one; derived from the cell, so cleaning twice agrees)
            text = f"{index}:{''.join(out['source'])}"
            out["id"] = hashlib.sha256(text.encode("utf-8")).hexdigest()[:CELL_ID_DIGITS]
        if cell.get("cell_type") == "code":
            out["outputs"] = []
            out["execution_count"] = None
        cells.append(out)
    meta = nb.get("metadata", {})
    metadata = {}
    if "kernelspec" in meta:
        metadata["kernelspec"] = meta["kernelspec"]
    if "language_info" in meta:
        metadata["language_info"] = {"name": meta["language_info"].get("name", "python")}
    return {"cells": cells, "metadata": metadata, "nbformat": nb.get("nbformat", 4),
            "nbformat_minor": nb.get("nbformat_minor", 5)}


def dumps(nb: dict) -> str:
    """The stored text: sorted keys, 1-space indent, trailing newline."""
    return json.dumps(nb, sort_keys=True, indent=1, ensure_ascii=False) + "\n"


def problems(text: str) -> list:
    """Why a notebook's stored text is not clean (empty when it is)."""
    try:
        nb = json.loads(text)
    except json.JSONDecodeError as exc:
        return [f"not JSON: {exc}"]
    if nb.get("nbformat") != 4:
        return [f"nbformat {nb.get('nbformat')!r}, expected 4"]
    found = []
    for i, cell in enumerate(nb.get("cells", []), 1):
        if "id" not in cell:
            found.append(f"cell {i} has no id")
        if cell.get("cell_type") != "code":
            continue
        if cell.get("outputs"):
            found.append(f"code cell {i} carries outputs")
        if cell.get("execution_count") is not None:
            found.append(f"code cell {i} has execution count {cell['execution_count']}")
    try:
        import nbformat
    except ImportError:
        pass
    else:
        try:
            nbformat.validate(nbformat.reads(text, as_version=4))
        except Exception as exc:  # noqa: BLE001 - any schema failure is a problem to report
            found.append(f"invalid notebook: {str(exc).splitlines()[0]}")
    if text != dumps(normalize(nb)):
        found.append("not normalized")
    return found


def clean(paths=None) -> list:
    """Strip and normalize notebooks in place; returns the paths that changed."""
    changed = []
    for path in notebooks(paths):
        text = path.read_text(encoding="utf-8")
        new = dumps(normalize(json.loads(text)))
        if new != text:
            path.write_text(new, encoding="utf-8")
            changed.append(path)
    return changed


def check(paths=None) -> dict:
    """``{path: [problem, ...]}`` for every notebook that is not stored clean."""
    out = {}
    for path in notebooks(paths):
        found = problems(path.read_text(encoding="utf-8"))
        if found:
            out[path] = found
    return out


def execute(path, *, timeout: float = CELL_TIMEOUT, env: dict | None = None):
    """Run a notebook top to bottom on a fresh kernel; returns the executed notebook.

    The kernel starts in the notebook's folder with ``MPLBACKEND=Agg`` added to
    ``env`` (default: this process's environment).  No cell timings are recorded and each
    cell's stream outputs are merged, one per stream.  Raises
    ``nbclient.exceptions.CellExecutionError`` on the first cell that fails and
    ``CellTimeoutError`` when one runs longer than ``timeout`` seconds.
    """
    import nbclient
    import nbformat

    path = Path(path)
    nb = nbformat.read(path, as_version=4)
    kernel_env = {**(os.environ if env is None else env), **KERNEL_ENV}
    client = nbclient.NotebookClient(nb, timeout=timeout, startup_timeout=STARTUP_TIMEOUT,
                                     kernel_name=KERNEL_NAME, record_timing=False, coalesce_streams=True,
                                     resources={"metadata": {"path": str(path.parent.resolve())}})
    client.execute(env=kernel_env)
    return nb


def run(paths=None, *, output=None, timeout: float = CELL_TIMEOUT) -> int:
    """Execute notebooks, print one line each; returns the number that failed."""
    failed = 0
    for path in notebooks(paths):
        start = time.perf_counter()
        try:
            nb = execute(path, timeout=timeout)
        except Exception as exc:  # noqa: BLE001 - report every notebook, then fail
            failed += 1
            text = re.sub(r"\x1b\[[0-9;]*m", "", str(exc)).strip()
            print(f"FAIL {path.name} ({time.perf_counter() - start:.1f} s): {type(exc).__name__}\n{text}")
            continue
        print(f"ok   {path.name} ({time.perf_counter() - start:.1f} s)")
        if output is not None:
            import nbformat

            Path(output).mkdir(parents=True, exist_ok=True)
            nbformat.write(nb, Path(output) / path.name)
    return failed


def _text(value) -> str:
    return "".join(value) if isinstance(value, list) else str(value)


def cells_digest(cells) -> str:
    """16 hex digits of SHA-256 over the cells' types and sources: what a page records of its notebook."""
    pairs = [[c["cell_type"], _text(c.get("source", ""))] for c in cells]
    text = json.dumps(pairs, ensure_ascii=False, separators=(",", ":"))
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


def _header(name: str, digest: str) -> str:
    return (f"<!-- Rendered from derivations/{name}.ipynb (cells {digest}) by "
            "`python derivations/nbtool.py render`; do not edit. -->\n\n")


def _cell_block(cell) -> str:
    """A cell's own text on the page: a markdown cell as it is, a code cell in a ``python`` fence."""
    source = _text(cell.get("source", ""))
    return source if cell["cell_type"] == "markdown" else f"```python\n{source}\n```"


def markdown_export(nb: dict, name: str, files: Path) -> str:
    """A Markdown page of an executed notebook: its markdown cells, code in fences, text outputs,
    LaTeX and Markdown outputs as they are, and each figure written once, as a file in ``files``
    (``figure-01.png``, ... in order) that the page links.

    The page starts with a comment naming the notebook and the digest of its cells
    (:func:`cells_digest`); it holds nothing else of the run (no metadata, ids, counts or
    dates).  An error output is refused (``ValueError``): a page shows a notebook that ran.
    """
    lines = []
    figure = 0
    for i, cell in enumerate(nb["cells"], 1):
        if cell["cell_type"] not in ("markdown", "code"):
            continue
        lines += [_cell_block(cell), ""]
        for out in cell.get("outputs", []):
            kind = out.get("output_type")
            if kind == "stream":
                lines += ["```text", _text(out.get("text", "")).rstrip("\n"), "```", ""]
                continue
            if kind == "error":
                raise ValueError(f"{name}: cell {i} failed: {out.get('ename')}: {out.get('evalue')}")
            data = out.get("data", {})
            image = next((t for t in FIGURE_TYPES if t in data), None)
            if image is not None:
                figure += 1
                files.mkdir(parents=True, exist_ok=True)
                file = files / f"figure-{figure:02d}.{FIGURE_TYPES[image]}"
                body = _text(data[image])
                file.write_bytes(base64.b64decode(body) if image == "image/png" else body.encode("utf-8"))
                lines += [f"![figure {figure}]({files.name}/{file.name})", ""]
            elif "text/markdown" in data:
                lines += [_text(data["text/markdown"]), ""]
            elif "text/latex" in data:
                lines += [_text(data["text/latex"]).strip(), ""]
            elif "text/plain" in data:
                lines += ["```text", _text(data["text/plain"]), "```", ""]
    return _header(name, cells_digest(nb["cells"])) + "\n".join(lines).rstrip() + "\n"


def render_environment(folder) -> dict:
    """The variables a rendering kernel runs with, its configuration files written into ``folder``:
    :data:`RENDER_ENV`, a fresh ``IPYTHONDIR`` holding :data:`KERNEL_CONFIG` (no user's profile
    or startup files), ``MATPLOTLIBRC`` (:data:`MATPLOTLIBRC`, not the user's) and a fresh
    ``SYMVIB_CACHE`` (user curves' kernels generated as on a first run)."""
    folder = Path(folder)
    profile = folder / "ipython" / "profile_default"
    profile.mkdir(parents=True, exist_ok=True)
    (profile / "ipython_kernel_config.py").write_text(KERNEL_CONFIG, encoding="utf-8")
    (folder / "matplotlibrc").write_text(MATPLOTLIBRC, encoding="utf-8")
    (folder / "kernels").mkdir(mode=0o700, exist_ok=True)
    return {**RENDER_ENV, "IPYTHONDIR": str(folder / "ipython"), "MATPLOTLIBRC": str(folder / "matplotlibrc"),
            "SYMVIB_CACHE": str(folder / "kernels")}


def render(paths=None, *, out=RENDERED, timeout: float = CELL_TIMEOUT) -> int:
    """Execute notebooks in :func:`render_environment` and write their pages; returns the failures."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    failed = 0
    with tempfile.TemporaryDirectory(prefix="nbtool-render-") as scratch:
        env = {**os.environ, **render_environment(scratch)}
        for path in notebooks(paths):
            start = time.perf_counter()
            try:
                nb = execute(path, timeout=timeout, env=env)
                files = out / f"{path.stem}_files"
                with tempfile.TemporaryDirectory(prefix="figures-", dir=scratch) as staged:
                    page = markdown_export(nb, path.stem, Path(staged) / files.name)
                    if files.exists():
                        shutil.rmtree(files)
                    if (Path(staged) / files.name).exists():
                        shutil.copytree(Path(staged) / files.name, files)
            except Exception as exc:  # noqa: BLE001 - report every notebook, then fail
                failed += 1
                text = re.sub(r"\x1b\[[0-9;]*m", "", str(exc)).strip()
                print(f"FAIL {path.name} ({time.perf_counter() - start:.1f} s): {type(exc).__name__}\n{text}")
                continue
            (out / f"{path.stem}.md").write_text(page, encoding="utf-8")
            print(f"ok   {path.name} ({time.perf_counter() - start:.1f} s) -> {out / path.stem}.md")
    return failed


def png_chunks(data: bytes) -> list:
    """The chunk types of a PNG file, in order (``ValueError`` when it is not one)."""
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError("not a PNG file")
    chunks, at = [], 8
    while at + 8 <= len(data):
        size = int.from_bytes(data[at:at + 4], "big")
        chunks.append(data[at + 4:at + 8])
        at += 12 + size
    return chunks


def figure_problems(file) -> list:
    """Why a figure file is not as a render writes it: a PNG with text or time chunks (metadata
    that changes with the Matplotlib version or the clock), an SVG with a date."""
    file = Path(file)
    data = file.read_bytes()
    if file.suffix == ".png":
        try:
            extra = sorted({c.decode("latin-1") for c in png_chunks(data)} - {c.decode() for c in PNG_CHUNKS})
        except ValueError as exc:
            return [f"{file.name}: {exc}"]
        return [f"{file.name} carries PNG chunks {', '.join(extra)}"] if extra else []
    if file.suffix == ".svg":
        return [f"{file.name} carries a date"] if b"<dc:date>" in data else []
    return [f"{file.name}: not a figure type of a page"]


def rendered_problems(path, rendered_dir=RENDERED) -> list:
    """Why the rendered page of notebook ``path`` is not current (empty when it is).

    Current means: ``NAME.md`` exists and records the digest of the stored notebook's cells
    (:func:`cells_digest`: the same cells, types and sources, in order); every cell's text
    is on the page, in order (no hand edit of a page goes unseen); each figure it links is a
    file of ``NAME_files/``, every file there is linked once, and none carries metadata
    (:func:`figure_problems`).
    """
    path = Path(path)
    rendered_dir = Path(rendered_dir)
    page_path = rendered_dir / f"{path.stem}.md"
    if not page_path.is_file():
        return [f"no rendered page {page_path.name}"]
    cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
    page = page_path.read_text(encoding="utf-8")
    found = []
    if not page.startswith(_header(path.stem, cells_digest(cells))):
        found.append("cells differ from the stored notebook (run: python derivations/nbtool.py render)")
    at = 0
    for i, cell in enumerate(cells, 1):
        block = _cell_block(cell)
        where = page.find(block, at)
        if where < 0:
            found.append(f"cell {i} is not on the page as it is in the notebook")
            break
        at = where + len(block)
    files = rendered_dir / f"{path.stem}_files"
    linked = re.findall(r"^!\[figure \d+\]\(([^)]+)\)$", page, re.M)
    for link in linked:
        if not (rendered_dir / link).is_file():
            found.append(f"figure {link} is missing")
    present = sorted(files.iterdir()) if files.is_dir() else []
    stored = [f"{files.name}/{f.name}" for f in present]
    unlinked = sorted(set(stored) - set(linked))
    if unlinked:
        found.append(f"figure files the page does not link: {', '.join(unlinked)}")
    if len(set(linked)) != len(linked):
        found.append("a figure is linked twice")
    for file in present:
        found += figure_problems(file)
    return found


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="nbtool.py", description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    for name, text in (("clean", "strip outputs and normalize, in place"),
                       ("check", "exit 1 if a notebook carries outputs or is not normalized"),
                       ("run", "execute every notebook on a fresh kernel; exit 1 on any error"),
                       ("render", "execute every notebook and write its page (docs/notebooks/)")):
        p = sub.add_parser(name, help=text)
        p.add_argument("paths", nargs="*", help="notebooks (default: every *.ipynb in derivations/)")
        if name == "run":
            p.add_argument("--output", help="folder for the executed copies (with outputs)")
        if name == "render":
            p.add_argument("--out", default=str(RENDERED), help="folder of the pages (default: docs/notebooks)")
        if name in ("run", "render"):
            p.add_argument("--timeout", type=float, default=CELL_TIMEOUT, help="seconds per cell")
    args = parser.parse_args(argv)
    missing = [p for p in args.paths if not Path(p).is_file()]
    if missing:
        print(f"nbtool: no such notebook: {missing[0]}", file=sys.stderr)
        return 2
    if args.command == "clean":
        for path in clean(args.paths):
            print(f"cleaned {path}")
        return 0
    if args.command == "check":
        found = check(args.paths)
        for path, why in found.items():
            print(f"{path}: {'; '.join(why)}")
        if found:
            print("run: python derivations/nbtool.py clean", file=sys.stderr)
        return 1 if found else 0
    if args.command == "render":
        return 1 if render(args.paths, out=args.out, timeout=args.timeout) else 0
    return 1 if run(args.paths, output=args.output, timeout=args.timeout) else 0


if __name__ == "__main__":
    sys.exit(main())
