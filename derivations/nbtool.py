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
    python derivations/nbtool.py render [NOTEBOOK ...] [--out DIR]   # executed copies for docs/notebooks/

``run`` executes each notebook top to bottom on a fresh Jupyter kernel
(nbclient + ipykernel, Matplotlib on ``Agg``) in this folder, and exits 1 on
the first error of any notebook; ``--output DIR`` writes the executed copies
(with their outputs and figures) there, never over the stored ones.

``render`` runs them the same way with the plain-Python engine (``SYMVIB_BACKEND=python``:
nothing waits for a compiler) and writes each executed notebook, outputs and figures
included, to ``docs/notebooks/NAME.ipynb`` (GitHub renders it), plus a Markdown export
``NAME.md`` with its figures in ``NAME_files/``.  :func:`rendered_problems` says why a
rendered copy is not current (``tests/test_notebooks_rendered.py``).

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
import json
import os
import re
import sys
import time
from pathlib import Path

#: The folder of the notebooks (this file's folder).
HERE = Path(__file__).resolve().parent
#: Seconds one cell may run before the execution fails (derivations have their own budget).
CELL_TIMEOUT = 300
#: Seconds a fresh kernel may take to start.
STARTUP_TIMEOUT = 120
#: The kernel every notebook runs on.
KERNEL_NAME = "python3"
#: Cell metadata worth keeping (everything else is editor state).
CELL_METADATA = ("tags",)
#: Environment of the kernel: figures render off-screen.
KERNEL_ENV = {"MPLBACKEND": "Agg"}
#: Where ``render`` writes the executed copies.
RENDERED = HERE.parent / "docs" / "notebooks"
#: The engine a rendering runs on: plain Python, so no notebook waits for a numba compile.
RENDER_ENV = {"SYMVIB_BACKEND": "python"}


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
    for cell in nb.get("cells", []):
        out = {k: v for k, v in cell.items() if k not in ("outputs", "execution_count", "metadata", "source")}
        out["metadata"] = {k: v for k, v in cell.get("metadata", {}).items() if k in CELL_METADATA}
        out["source"] = _lines(cell.get("source", ""))
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
    ``env`` (default: this process's environment).  Raises
    ``nbclient.exceptions.CellExecutionError`` on the first cell that fails and
    ``CellTimeoutError`` when one runs longer than ``timeout`` seconds.
    """
    import nbclient
    import nbformat

    path = Path(path)
    nb = nbformat.read(path, as_version=4)
    kernel_env = {**(os.environ if env is None else env), **KERNEL_ENV}
    client = nbclient.NotebookClient(nb, timeout=timeout, startup_timeout=STARTUP_TIMEOUT,
                                     kernel_name=KERNEL_NAME,
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


def _volatile_free(nb: dict) -> dict:
    """An executed notebook without what changes on every run but says nothing (timings, kernel versions)."""
    for cell in nb.get("cells", []):
        cell["metadata"] = {k: v for k, v in cell.get("metadata", {}).items() if k in CELL_METADATA}
    meta = nb.get("metadata", {})
    nb["metadata"] = {k: meta[k] for k in ("kernelspec",) if k in meta}
    nb["metadata"]["language_info"] = {"name": meta.get("language_info", {}).get("name", "python")}
    return nb


def _text(value) -> str:
    return "".join(value) if isinstance(value, list) else str(value)


def markdown_export(nb: dict, name: str, files: Path) -> str:
    """A Markdown page of an executed notebook: its markdown cells, code in fences, text outputs,
    LaTeX and Markdown outputs as they are, and figures written as PNG into ``files``."""
    import base64

    lines = []
    figure = 0
    for cell in nb["cells"]:
        source = _text(cell.get("source", ""))
        if cell["cell_type"] == "markdown":
            lines += [source, ""]
            continue
        if cell["cell_type"] != "code":
            continue
        lines += ["```python", source, "```", ""]
        for out in cell.get("outputs", []):
            kind = out.get("output_type")
            if kind == "stream":
                lines += ["```text", _text(out.get("text", "")).rstrip("\n"), "```", ""]
            elif kind == "error":
                lines += ["```text", f"{out.get('ename')}: {out.get('evalue')}", "```", ""]
            else:
                data = out.get("data", {})
                if "image/png" in data:
                    figure += 1
                    files.mkdir(parents=True, exist_ok=True)
                    png = files / f"figure-{figure:02d}.png"
                    png.write_bytes(base64.b64decode(_text(data["image/png"])))
                    lines += [f"![figure {figure}]({files.name}/{png.name})", ""]
                elif "text/markdown" in data:
                    lines += [_text(data["text/markdown"]), ""]
                elif "text/latex" in data:
                    lines += [_text(data["text/latex"]).strip(), ""]
                elif "text/plain" in data:
                    lines += ["```text", _text(data["text/plain"]), "```", ""]
    head = (f"<!-- Rendered from derivations/{name}.ipynb by `python derivations/nbtool.py render`; "
            "do not edit. -->\n\n")
    return head + "\n".join(lines).rstrip() + "\n"


def render(paths=None, *, out=RENDERED, timeout: float = CELL_TIMEOUT) -> int:
    """Execute notebooks (plain-Python engine) and write their rendered copies; returns the failures."""
    import shutil

    import nbformat

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    failed = 0
    for path in notebooks(paths):
        start = time.perf_counter()
        try:
            nb = execute(path, timeout=timeout, env={**os.environ, **RENDER_ENV})
        except Exception as exc:  # noqa: BLE001 - report every notebook, then fail
            failed += 1
            text = re.sub(r"\x1b\[[0-9;]*m", "", str(exc)).strip()
            print(f"FAIL {path.name} ({time.perf_counter() - start:.1f} s): {type(exc).__name__}\n{text}")
            continue
        data = _volatile_free(json.loads(nbformat.writes(nb)))
        (out / path.name).write_text(json.dumps(data, sort_keys=True, indent=1, ensure_ascii=False) + "\n",
                                     encoding="utf-8")
        files = out / f"{path.stem}_files"
        if files.exists():
            shutil.rmtree(files)
        (out / f"{path.stem}.md").write_text(markdown_export(data, path.stem, files), encoding="utf-8")
        print(f"ok   {path.name} ({time.perf_counter() - start:.1f} s) -> {out / path.name}")
    return failed


def rendered_problems(path, rendered_dir=RENDERED) -> list:
    """Why the rendered copy of notebook ``path`` is not current (empty when it is).

    Current means: it exists, its cells are the stored notebook's (same types and
    sources, in order), every code cell was executed, at least one has an output, no
    output is an error, and its Markdown export exists.
    """
    path = Path(path)
    copy = Path(rendered_dir) / path.name
    if not copy.is_file():
        return [f"no rendered copy {copy.name}"]
    stored = json.loads(path.read_text(encoding="utf-8"))["cells"]
    try:
        shown = json.loads(copy.read_text(encoding="utf-8"))["cells"]
    except (json.JSONDecodeError, KeyError) as exc:
        return [f"rendered copy unreadable: {exc}"]
    found = []
    if [(c["cell_type"], _text(c["source"])) for c in stored] != [(c["cell_type"], _text(c["source"]))
                                                                   for c in shown]:
        found.append("cells differ from the stored notebook (run: python derivations/nbtool.py render)")
    code = [c for c in shown if c["cell_type"] == "code"]
    if any(c.get("execution_count") is None for c in code):
        found.append("a code cell was not executed")
    if not any(c.get("outputs") for c in code):
        found.append("no outputs")
    if any(o.get("output_type") == "error" for c in code for o in c.get("outputs", [])):
        found.append("an output is an error")
    if not copy.with_suffix(".md").is_file():
        found.append(f"no Markdown export {copy.with_suffix('.md').name}")
    return found


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="nbtool.py", description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    for name, text in (("clean", "strip outputs and normalize, in place"),
                       ("check", "exit 1 if a notebook carries outputs or is not normalized"),
                       ("run", "execute every notebook on a fresh kernel; exit 1 on any error"),
                       ("render", "execute every notebook and write rendered copies (docs/notebooks/)")):
        p = sub.add_parser(name, help=text)
        p.add_argument("paths", nargs="*", help="notebooks (default: every *.ipynb in derivations/)")
        if name == "run":
            p.add_argument("--output", help="folder for the executed copies (with outputs)")
        if name == "render":
            p.add_argument("--out", default=str(RENDERED), help="folder of the copies (default: docs/notebooks)")
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
