"""Trust in input (issue 13): files, paths, expressions and scenes from people symvib does not know.

Every hostile input ends in a one-line error of the project's classes naming
the field or file, or in the correct result; nothing is written outside the
folder the user named (the listings of a temporary folder are compared).
"""
import os
import re
import stat
from pathlib import Path

import pytest

from symvib import paths
from symvib.paths import UserPathError, check_output_dir, check_output_file, inside, read_user_file, safe_stem

ROOT = os.geteuid() == 0 if hasattr(os, "geteuid") else False
SCENES = Path(__file__).resolve().parent.parent / "symvib" / "scenes"
PARABOLA = SCENES / "paper-parabola.toml"


def listing(folder: Path) -> set:
    """Every path under ``folder``, relative to it."""
    return {str(p.relative_to(folder)) for p in folder.rglob("*")}


# --------------------------------------------------------------------------- safe_stem, inside

#: Names a scene or curve may carry, hostile to file systems.
HOSTILE_STEMS = [
    "../../x", "/abs/path", "..", ".", "", "a/b/c", "a\\b", "a\x00b", "a\nb", "a\rb", "a\tb", "κ-ü-∂",
    "x" * 300, ".hidden", "-rf", "~", "~/x", "$HOME", "a b", "con", "a:b", "a*b?", "'\"", "\u2028", "../" * 50,
    "é" * 200, "\ud800", "a;rm -rf /", "..\\..\\x", "a" * 100, "a" * 101,
]


@pytest.mark.parametrize("text", HOSTILE_STEMS, ids=range(len(HOSTILE_STEMS)))
def test_safe_stem_is_a_plain_file_name(text, tmp_path):
    stem = safe_stem(text)
    assert re.fullmatch(r"[A-Za-z0-9_][A-Za-z0-9._-]*", stem), stem
    assert len(stem) <= paths.MAX_STEM_LENGTH
    target = tmp_path / f"{stem}.png"
    assert inside(target, tmp_path)
    target.write_text("x")
    assert listing(tmp_path) == {f"{stem}.png"}


def test_safe_stem_keeps_plain_names_and_distinct_names_apart():
    assert safe_stem("paper-parabola") == "paper-parabola"
    assert safe_stem("a.b_c-1") == "a.b_c-1"
    changed = [safe_stem(t) for t in ("a/b", "a\\b", "a b", "a:b", "a\nb")]
    assert len(set(changed)) == len(changed)
    assert safe_stem("x" * 300) != safe_stem("x" * 301)


@pytest.mark.parametrize("path, folder, expected", [
    ("out/a.png", "out", True), ("out/../a.png", "out", False), ("/abs/a.png", "out", False),
    ("out/sub/../a.png", "out", True), ("out", "out", True), ("outside/a", "out", False),
])
def test_inside(path, folder, expected, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert inside(path, folder) is expected


def test_inside_sees_through_symlinks(tmp_path):
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "link").symlink_to(tmp_path)
    assert not inside(tmp_path / "out" / "link" / "a.png", tmp_path / "out")


# --------------------------------------------------------------------------- read_user_file


def _fifo(tmp_path):
    path = tmp_path / "fifo"
    os.mkfifo(path)
    return path


#: Files that are not small UTF-8 text files: maker -> part of the message.
BAD_FILES = {
    "directory": (lambda d: d, "is a directory"),
    "dev_zero": (lambda d: Path("/dev/zero"), "not a regular file"),
    "dev_null": (lambda d: Path("/dev/null"), "not a regular file"),
    "fifo": (_fifo, "not a regular file"),
    "missing": (lambda d: d / "missing.toml", "no such"),
    "nul_in_name": (lambda d: str(d / "a\x00b.toml"), "NUL|null"),
    "not_utf8": (lambda d: _write(d / "latin.toml", b'name = "caf\xe9"\n'), r"not UTF-8 text \(byte 0xe9 on line 1\)"),
    "utf16": (lambda d: _write(d / "utf16.toml", "name = 1".encode("utf-16")), "not UTF-8"),
    "huge": (lambda d: _write(d / "huge.toml", b"#" * (paths.MAX_INPUT_BYTES + 1)), "bytes"),
    "file_as_folder": (lambda d: _write(d / "f", b"x") / "x.toml", "Not a directory|cannot open"),
}


def _write(path: Path, data: bytes) -> Path:
    path.write_bytes(data)
    return path


@pytest.mark.parametrize("kind", sorted(BAD_FILES))
def test_read_user_file_refuses(kind, tmp_path):
    make, message = BAD_FILES[kind]
    path = make(tmp_path)
    with pytest.raises(UserPathError, match=message) as info:
        read_user_file(path, "scene file")
    text = str(info.value)
    assert "\n" not in text
    assert os.path.basename(str(path)).replace("\x00", "\\x00") in text


def test_read_user_file_reads_at_most_the_cap(tmp_path):
    path = _write(tmp_path / "ok.toml", "é = 1\n".encode())
    assert read_user_file(path) == "é = 1\n"
    with pytest.raises(UserPathError, match="at most 3"):
        read_user_file(path, max_bytes=3)


# --------------------------------------------------------------------------- output paths


@pytest.mark.parametrize("make, message", [
    (lambda d: d, "is a directory"),
    (lambda d: Path("/dev/null"), "not a regular file"),
    (lambda d: d / "missing" / "a.json", "does not exist"),
    (lambda d: _write(d / "f", b"x") / "a.json", "Not a directory|not a folder"),
    (lambda d: "", "empty path"),
    (lambda d: str(d / "a\x00.json"), "NUL"),
    (_fifo, "not a regular file"),
], ids=["dir", "device", "no_parent", "parent_is_file", "empty", "nul", "fifo"])
def test_check_output_file_refuses(make, message, tmp_path):
    with pytest.raises(UserPathError, match=message):
        check_output_file(make(tmp_path), "JSON file")


def test_check_output_file_accepts_new_and_existing_files(tmp_path):
    assert check_output_file(tmp_path / "a.json") == tmp_path / "a.json"
    _write(tmp_path / "b.json", b"{}")
    assert check_output_file(tmp_path / "b.json") == tmp_path / "b.json"


@pytest.mark.parametrize("make, message", [
    (lambda d: _write(d / "f.png", b"x"), "is a file"),
    (lambda d: Path("/dev/null"), "device"),
    (lambda d: _write(d / "f", b"x") / "sub" / "dir", "has .*f, which is a file"),
    (lambda d: "", "empty path"),
    (lambda d: str(d / "a\x00"), "NUL"),
    (_fifo, "device, fifo"),
], ids=["file", "device", "file_above", "empty", "nul", "fifo"])
def test_check_output_dir_refuses(make, message, tmp_path):
    with pytest.raises(UserPathError, match=message):
        check_output_dir(make(tmp_path), "plot folder")


@pytest.mark.skipif(ROOT, reason="root may write anywhere")
def test_unwritable_folders_are_refused(tmp_path):
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(stat.S_IRUSR | stat.S_IXUSR)
    try:
        with pytest.raises(UserPathError, match="not writable"):
            check_output_dir(locked / "new")
        with pytest.raises(UserPathError, match="not writable"):
            check_output_file(locked / "a.json")
    finally:
        locked.chmod(stat.S_IRWXU)


def test_check_output_dir_accepts_a_new_nested_folder_and_creates_nothing(tmp_path):
    assert check_output_dir(tmp_path / "a" / "b") == tmp_path / "a" / "b"
    assert listing(tmp_path) == set()


# --------------------------------------------------------------------------- expressions

from symvib import expr  # noqa: E402
from symvib.expr import ExpressionError, free_names, parse  # noqa: E402

#: Expressions hostile to the parser, or to what comes after it: text -> part of the message.
HOSTILE_EXPRESSIONS = {
    "x" + "+x" * 50_000: "characters long",  # 100 KB: RecursionError in a recursive parser
    "-" * 100_000 + "x": "characters long",  # MemoryError in the parser
    "-" * 60 + "x": "nested deeper",
    "~" * 60 + "x": "nested deeper",
    "- + " * 30 + "x": "nested deeper",
    "(" * 60 + "x" + ")" * 60: "nested deeper",
    "[" * 60 + "]" * 60: "nested deeper",
    "x**2*((((9**64)**64)**64)**64)**64": r"the constant \(\(9\*\*64\)\*\*64\) is larger than 1e\+100",
    "(((9**64)**64)**64)": "larger than 1e",
    "(x**8)**9": "total exponent of 72; at most 64",
    "((x**4)**4)**8": "total exponent of 128",
    "sin((x**16)**16)": "total exponent of 256",
    "x**65": "exponent 65 is larger",
    "9**64**64": "larger than",
    "10**10**10": "larger than 64",
    "x**(2**100)": "larger than 64",
    "9" * 400: "longer than 30 digits",
    "x*" + "9" * 31: "longer than 30 digits",
    "1e400": "not finite",
    "1e101": "larger than 1e",
    "1e308*10": "larger than 1e",
    "exp(1000)": "larger than 1e",
    "cosh(300)*x": "larger than 1e",
    "1/0": "division by zero",
    "x/(1-1)": "division by the constant",
    "x/(pi-pi)": "division by the constant",
    "sqrt(-1)*x": "not a real number",
    "log(0)": "not a real number",
    "acos(2)": "not a real number",
    "__import__('os')": "call of '__import__' is not allowed",
    "__import__('os').system('true')": "attribute access",
    "().__class__.__bases__[0].__subclasses__()": "not allowed",
    "x.real": "Attribute",
    "lambda: 1": "Lambda",
    "[x for x in (1,)]": "ListComp",
    "{x: 1}": "Dict",
    "x if x else 1": "IfExp",
    "(x := 1)": "NamedExpr",
    "x[0]": "Subscript",
    "'a'": "only numbers",
    "b'a'": "only numbers",
    "f'{x}'": "JoinedStr",
    "True": "only numbers",
    "None": "only numbers",
    "...": "only numbers",
    "1j": "only numbers",
    "x < 1": "Compare",
    "x and 1": "BoolOp",
    "not x": "operator Not",
    "x ^ 2": r"use \*\* for powers",
    "x @ x": "MatMult",
    "x // 2": "FloorDiv",
    "x % 2": "Mod",
    "x << 2": "LShift",
    "sin(x, 2)": "takes 1 argument",
    "atan2(x)": "takes 2 arguments",
    "sin(*x)": "takes 1 argument",
    "sin(x=1)": "keyword",
    "sin": "must be called",
    "eval('1')": "call of 'eval'",
    "open('/etc/passwd')": "call of 'open'",
    "exec": "not allowed",
    "_x": "may not start with _",
    "__builtins__": "may not start with _",
    "x;y": "not a valid expression",
    "x\ny": "not a valid expression",
    "x = 1": "not a valid expression",
    "import os": "not a valid expression",
    "": "empty expression",
    "   ": "empty expression",
    "\x00": "not a valid expression|too complex",
    "x # comment": None,  # a comment is just ignored: accepted
}


@pytest.mark.parametrize("text", sorted(HOSTILE_EXPRESSIONS), ids=range(len(HOSTILE_EXPRESSIONS)))
def test_hostile_expressions_are_one_line_errors(text):
    message = HOSTILE_EXPRESSIONS[text]
    if message is None:
        assert free_names(text, field="curve.z") == {"x"}
        return
    with pytest.raises(ExpressionError, match=message) as info:
        free_names(text, field="curve.z")
    assert str(info.value).startswith("curve.z: ")
    assert "\n" not in str(info.value)
    assert info.value.field == "curve.z"


@pytest.mark.parametrize("value, message", [(10 ** 400, "longer than 30 digits"), (True, "got bool"),
                                            ([1], "got list"), (None, "got NoneType"),
                                            (float("inf"), "not finite"), (float("nan"), "not finite"),
                                            (1e200, "larger than 1e")])
def test_non_text_values_are_refused(value, message):
    with pytest.raises(ExpressionError, match=message):
        expr.number(value, field="initial.qdot")


@pytest.mark.parametrize("text, names", [
    ("R*(1 - cos(phi)) + pi", {"R", "phi"}), ("x**2/(2*p)", {"x", "p"}), ("e*x", {"x"}),
    ("(x**8)**8", {"x"}), ("9**64*x", {"x"}), ("x*10**30", {"x"}), ("κ*x", {"κ", "x"}),
    ("-" * 40 + "x", {"x"}), ("(" * 40 + "x" + ")" * 40, {"x"}),
])
def test_free_names_and_limits_that_still_pass(text, names):
    assert free_names(text, field="curve.z") == names


def test_constants_are_folded_in_floats_not_integers():
    # The parse of the nested power takes microseconds: no integer of 10**(61*64**4) digits.
    with pytest.raises(ExpressionError, match="larger than"):
        parse("x**2*((((9**64)**64)**64)**64)**64", symbols=("x",), field="curve.z")
    assert expr.number("9**64", field="f") == pytest.approx(9.0 ** 64)
    assert expr.number("-1e100", field="f") == -1e100
