"""Trust in generated code (issue 13): user text never runs, kernel modules are verified before import.

A curve's name, expressions, parameter names and domain reach the text of a
generated kernel module; none of it may close a string or docstring and run.
"""
import importlib.util
import os

import pytest

from symvib import kernels

#: What a hostile name's payload writes when it runs (the tests assert it never appears).
MARKER_NAME = "PAYLOAD_RAN"

#: Names that try to close the module's docstring, a string or a line, with text that is not ASCII.
HOSTILE_NAMES = {
    "closes_docstring": 'a""";open({marker!r},"w").write("x");"""',
    "closes_docstring_newline": 'a"""\nopen({marker!r},"w").write("x")\n"""',
    "triple_single": "a''';open({marker!r},'w').write('x');'''",
    "backslash": "a\\\\b\\",
    "newline_hash": "a\n# b\nimport os; open({marker!r},'w')",
    "hash": "a # open({marker!r},'w')",
    "unicode": "κ-ü-∂ «»\u2028\u2029",
    "nul": "a\x00b",
    "quotes": "a'\"b\"'c",
}

BOWL = {"kind": "graph", "q": "x", "z": "x**2/(2*p)", "params": {"p": "positive"}}


@pytest.fixture
def cache(tmp_path, monkeypatch):
    folder = tmp_path / "cache"
    monkeypatch.setenv(kernels.CACHE_ENV, str(folder))
    monkeypatch.setattr(kernels, "_LOADED", {})
    return folder


@pytest.mark.xfail(strict=True, reason="issue 13 step 1: reproduction; fixed in step 2")
@pytest.mark.parametrize("label", ["closes_docstring"])
def test_hostile_name_payload_never_runs_repro(label, cache, tmp_path):
    marker = tmp_path / MARKER_NAME
    name = HOSTILE_NAMES[label].format(marker=str(marker))
    module = kernels.load({**BOWL, "name": name})
    assert module.NAME == name
    assert not marker.exists()
