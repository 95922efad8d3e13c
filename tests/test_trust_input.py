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
from symvib.numeric.figures import FIGURE_NAMES
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
    "exec(x)": "call of .exec. is not allowed",
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


# --------------------------------------------------------------------------- scenes

import copy  # noqa: E402

from symvib.numeric.scene import MAX_NAME_LENGTH, SceneError, load_scene, scene_from_dict  # noqa: E402

BIG = 10 ** 400  # a 401-digit TOML integer


def bowl_scene(**over):
    """A valid user-curve scene, with ``section__key=value`` changes (``None`` deletes)."""
    data = {"name": "bowl", "curve": {"z": "x**2/(2*p)", "name": "bowl"}, "parameters": {"p": 1.0},
            "physics": {"g": 9.81, "m": 0.2, "alpha0": 0.05, "restitution": 0.8},
            "limiters": {"left": -1, "right": 1}, "initial": {"q": 0.5, "qdot": 0.0}}
    for key, value in over.items():
        parts = key.split("__")
        table = data
        for part in parts[:-1]:
            table = table[part]
        if value is None:
            table.pop(parts[-1], None)
        else:
            table[parts[-1]] = copy.deepcopy(value)
    return data


#: Hostile or careless scenes: changes -> (field the error names, part of the message).
BAD_SCENES = {
    "shape_list": (dict(curve={"shape": ["parabola"]}), "curve.shape", "must be a string"),
    "shape_int": (dict(curve={"shape": 5}), "curve.shape", "must be a string"),
    "shape_table": (dict(curve={"shape": {"a": 1}}), "curve.shape", "must be a string"),
    "shape_unknown": (dict(curve={"shape": "../../etc/passwd"}), "curve.shape", "unknown shape"),
    "big_qdot": (dict(initial__qdot=BIG), "initial.qdot", "too large: an integer of 401 digits"),
    "big_q": (dict(initial__q=BIG), "initial.q", "too large"),
    "big_param": (dict(parameters__p=BIG), "parameters.p", "too large"),
    "big_limiter": (dict(limiters__right=BIG), "limiters.right", "too large"),
    "big_g": (dict(physics__g=BIG), "physics.g", "too large"),
    "big_m": (dict(physics__m=-BIG), "physics.m", "too large"),
    "big_restitution": (dict(physics__restitution=BIG), "physics.restitution", "too large"),
    "big_t_max": (dict(run={"t_max": BIG}), "run.t_max", "too large"),
    "big_text": (dict(initial__qdot="9" * 400), "initial.qdot", "longer than 30 digits"),
    "nan_qdot": (dict(initial__qdot=float("nan")), "initial.qdot", "must be finite"),
    "inf_param": (dict(parameters__p=float("inf")), "parameters.p", "must be finite"),
    "domain_reversed": (dict(curve__domain=["1", "-1"]), "curve.domain", "low end"),
    "domain_equal": (dict(curve__domain=[0, 0]), "curve.domain", "low end"),
    "domain_name": (dict(curve__domain=["a", "1"]), "curve.domain[0]", "name 'a' is not allowed"),
    "domain_coordinate": (dict(curve__domain=["-1", "x"]), "curve.domain[1]", "name 'x' is not allowed"),
    "domain_div0": (dict(curve__domain=["1/0", "2"]), "curve.domain[0]", "division by zero"),
    "domain_bool": (dict(curve__domain=[True, 2]), "curve.domain[0]", "got bool"),
    "domain_nan": (dict(curve__domain=[float("nan"), 2]), "curve.domain[0]", "finite"),
    "domain_list": (dict(curve__domain=[[0], 2]), "curve.domain[0]", "got list"),
    "domain_three": (dict(curve__domain=[0, 1, 2]), "curve.domain", "list"),
    "domain_string": (dict(curve__domain="-1:1"), "curve.domain", "list"),
    "domain_attack": (dict(curve__domain=["__import__('os')", "1"]), "curve.domain[0]", "not allowed"),
    "domain_huge": (dict(curve__domain=["-(9**64)**64", "1"]), "curve.domain[0]", "larger than"),
    "domain_param_negative": (dict(curve__domain=["p", "-p"]), "curve.domain", "low end"),
    "domain_sqrt": (dict(curve__domain=["sqrt(-p)", "1"]), "curve.domain[0]", "cannot evaluate"),
    "name_int": (dict(name=5), "name", "must be a string"),
    "name_long": (dict(name="x" * (MAX_NAME_LENGTH + 1)), "name", "characters long"),
    "name_newline": (dict(name="a\nb"), "name", "printable"),
    "name_nul": (dict(name="a\x00b"), "name", "printable"),
    "name_empty": (dict(name=""), "name", "empty"),
    "name_escape": (dict(name="\x1b[2J"), "name", "printable"),
    "curve_name_list": (dict(curve__name=["a"]), "curve.name", "must be a string"),
    "curve_name_long": (dict(curve__name="c" * 1000), "curve.name", "characters long"),
    "curve_name_newline": (dict(curve__name='a"""\nimport os'), "curve.name", "printable"),
    "q_digit": (dict(curve__q="1x"), "curve.q", "identifier"),
    "q_dunder": (dict(curve__q="__class__"), "curve.q", "identifier"),
    "q_function": (dict(curve__q="sin"), "curve.q", "function or constant"),
    "q_constant": (dict(curve__q="pi"), "curve.q", "function or constant"),
    "q_space": (dict(curve__q="x y"), "curve.q", "identifier"),
    "q_int": (dict(curve__q=5), "curve.q", "must be a string"),
    "param_dunder": (dict(curve__params=["_p"]), "curve.params[0]", "identifier"),
    "param_int": (dict(curve__params=[1]), "curve.params[0]", "must be a string"),
    "param_space": (dict(curve__params={"a b": "positive"}), "curve.params.a b", "identifier"),
    "param_is_q": (dict(curve__params=["p", "x"]), "curve.params.x", "coordinate"),
    "param_assumption": (dict(curve__params={"p": 1}), "curve.params.p", "assumption"),
    "z_dunder_name": (dict(curve__z="__builtins__*x"), "curve.z", "may not start with _"),
    "z_attack": (dict(curve__z="__import__('os').system('true')"), "curve.z", "attribute access"),
    "z_100kb": (dict(curve__z="x" + "+x" * 50_000), "curve.z", "characters long"),
    "z_unary": (dict(curve__z="-" * 100_000 + "x"), "curve.z", "characters long"),
    "z_nested_power": (dict(curve__z="x**2*((((9**64)**64)**64)**64)**64"), "curve.z", "larger than"),
    "z_power_product": (dict(curve__z="((x**4)**4)**8"), "curve.z", "total exponent"),
    "z_not_string": (dict(curve__z=2), "curve.z", "must be a string"),
    "z_lambda": (dict(curve__z="(lambda: x)()"), "curve.z", "not allowed"),
    "limiter_attack": (dict(limiters__left="().__class__"), "limiters.left", "not allowed"),
    "qdot_list": (dict(initial__qdot=[1]), "initial.qdot", "got list"),
    "unknown_section": (dict(exec={"x": 1}), "exec", "unknown section"),
    "description_table": (dict(description={"a": 1}), "description", "must be a string"),
    "description_long": (dict(description="d" * 10_001), "description", "at most 10000"),
    "unknown_section_newline": ({"a\nb": 1}, "a\\nb", "unknown section"),
    "unknown_key_newline": ({"physics__x\ny": 1}, "physics.x\\ny", "unknown key"),
    "unknown_parameter_long": ({"parameters__" + "k" * 1000: 1}, "parameters." + "k" * MAX_NAME_LENGTH + "...",
                               "unknown symbol"),
    "param_newline": (dict(curve__params={"a\nb": "positive"}), "curve.params.a\\nb", "identifier"),
}


@pytest.mark.parametrize("case", sorted(BAD_SCENES))
def test_bad_scenes_are_one_line_scene_errors(case):
    over, field, message = BAD_SCENES[case]
    data = bowl_scene(**over)
    if "shape" in data["curve"]:
        data["curve"] = {"shape": data["curve"]["shape"]}
    with pytest.raises(SceneError, match=message) as info:
        scene_from_dict(data)
    assert info.value.field == field
    text = str(info.value)
    assert text.startswith(f"{field}: ")
    assert "\n" not in text and "np." not in text and len(text) < 2000


@pytest.mark.parametrize("domain, q0", [(["0.3", "oo"], 0.5), (["-oo", "oo"], 0.0), ([-2, 2], 0.5),
                                        (["-p", "p"], 0.5), (["-inf", "+inf"], 0.5)])
def test_good_domains_are_accepted(domain, q0):
    s = scene_from_dict(bowl_scene(curve__domain=domain, initial__q=q0, limiters__left=None,
                                   limiters__right=None))
    assert s.q0 == q0


def test_domain_below_initial_q_blames_initial_q_only_when_the_domain_is_sound():
    with pytest.raises(SceneError) as info:
        scene_from_dict(bowl_scene(curve__domain=["0.3", "oo"], initial__q=0.0, limiters__left=None))
    assert info.value.field == "initial.q"


def test_numpy_numbers_are_accepted_and_shown_plainly():
    np = pytest.importorskip("numpy")
    s = scene_from_dict(bowl_scene())
    assert s.replace(g=np.float64(2.0), max_events=100).g == 2.0
    with pytest.raises(SceneError, match=r"^physics\.g: must be positive, got -2\.0$"):
        s.replace(g=np.float64(-2.0))
    with pytest.raises(SceneError, match=r"^physics\.restitution: .* got 2\.0$"):
        s.replace(k=np.float32(2.0))
    with pytest.raises(SceneError, match=r"^initial\.q: 5\.0 is outside the limiters: right of the right "
                                         r"limiter at 1\.0$"):
        s.replace(q0=np.float64(5.0))
    assert s.replace(m=np.int64(3)).m == 3.0


#: Scene files that are not scene files: maker -> part of the message.
BAD_SCENE_FILES = {
    "directory": (lambda d: d, "is a directory"),
    "dev_zero": (lambda d: Path("/dev/zero"), "not a regular file"),
    "fifo": (_fifo, "not a regular file"),
    "missing": (lambda d: d / "missing.toml", "no such file"),
    "latin1": (lambda d: _write(d / "latin.toml", b'name = "caf\xe9"\n'), "not UTF-8 text"),
    "huge": (lambda d: _write(d / "huge.toml", b"#" * (paths.MAX_INPUT_BYTES + 1)), "at most"),
    "not_toml": (lambda d: _write(d / "bad.toml", b"[curve\nshape = 1"), "not valid TOML"),
    "binary": (lambda d: _write(d / "bin.toml", bytes(range(256))), "not UTF-8"),
    "nul_name": (lambda d: str(d / "a\x00.toml"), "NUL|null"),
    # TOML bombs within the size cap: quadratic memory in the dotted-key depth, recursion.
    "dotted_keys": (lambda d: _write(d / "dots.toml", b"a." * 100_000 + b"b = 1\n"), "dots in keys"),
    "dotted_table": (lambda d: _write(d / "tab.toml", b"[" + b"a." * 5_000 + b"b]\n"), "dots in keys"),
    "nested_arrays": (lambda d: _write(d / "arr.toml", b"a = " + b"[" * 100_000), "nested too deeply"),
    "nested_tables": (lambda d: _write(d / "inl.toml", b"a = " + b"{x=" * 20_000), "nested too deeply"),
}


@pytest.mark.parametrize("kind", sorted(BAD_SCENE_FILES))
def test_bad_scene_files_name_the_file(kind, tmp_path):
    make, message = BAD_SCENE_FILES[kind]
    path = make(tmp_path)
    with pytest.raises(SceneError, match=message) as info:
        load_scene(path)
    assert os.path.basename(str(path)).replace("\x00", "\\x00") in str(info.value)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("kind", sorted(BAD_SCENE_FILES))
def test_bad_sweep_files_are_one_line_errors(kind, tmp_path, capsys):
    """``symvib sweep --file`` reads through the same guard as a scene file (it once used tomllib directly)."""
    from symvib.cli import sweep_main

    make, message = BAD_SCENE_FILES[kind]
    path = make(tmp_path)
    assert sweep_main(["--file", str(path), "-o", str(tmp_path / "out"), "--quiet"]) == common.EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and re.search(message, err)
    assert not (tmp_path / "out").exists()


# --------------------------------------------------------------------------- command line

from symvib import cli  # noqa: E402
from symvib.cli import common  # noqa: E402


def run_cli(capsys, *args):
    """``symvib ARGS`` in this process: (exit status, stdout, stderr)."""
    code = cli.main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


def _scene_file(folder: Path, name="paper-parabola") -> Path:
    text = PARABOLA.read_text(encoding="utf-8").replace('name = "paper-parabola"', f"name = {name!r}")
    path = folder / "scene.toml"
    path.write_text(text + "\n[run]\nmax_events = 3\n", encoding="utf-8")
    return path


#: Command lines with a path that cannot be used: (arguments from the tmp folder, part of the message).
BAD_PATH_COMMANDS = {
    "scene_is_dir": (lambda d, s: ["run", d], "is a directory"),
    "scene_dev_zero": (lambda d, s: ["run", "/dev/zero"], "/dev/zero: is not a regular file"),
    "scene_fifo": (lambda d, s: ["run", _fifo(d)], "not a regular file"),
    "scene_missing": (lambda d, s: ["run", d / "nope.toml"], "nope.toml: no such file"),
    "scene_latin1": (lambda d, s: ["run", _write(d / "l.toml", b"name = '\xe9'")], "l.toml: scene file is not UTF-8"),
    "scene_huge": (lambda d, s: ["run", _write(d / "h.toml", b" " * (paths.MAX_INPUT_BYTES + 1))], "h.toml"),
    "scene_newline_name": (lambda d, s: ["run", d / "a\nb.toml"], r"a\\nb.toml"),
    "scene_long_name": (lambda d, s: ["run", d / ("n" * 300 + ".toml")], "File name too long|no such file"),
    "json_is_dir": (lambda d, s: ["run", s, "--json", d], "is a directory; the --json file"),
    "json_device": (lambda d, s: ["run", s, "--json", "/dev/full"], "--json file"),
    "json_no_folder": (lambda d, s: ["run", s, "--json", d / "no" / "r.json"], "does not exist"),
    "json_under_file": (lambda d, s: ["run", s, "--json", s / "r.json"], "not a folder"),
    "json_is_scene": (lambda d, s: ["run", s, "--json", s], "would overwrite the scene file"),
    "plot_on_file": (lambda d, s: ["run", s, "--plot", s], r"is a file, not a folder \(the --plot folder\)"),
    "plot_under_file": (lambda d, s: ["run", s, "--plot", s / "figs"], "which is a file"),
    "plot_device": (lambda d, s: ["run", s, "--plot", "/dev/null"], "device"),
    "plot_fifo": (lambda d, s: ["run", s, "--plot", _fifo(d)], "device, fifo"),
    "audit_write_dir": (lambda d, s: ["audit", "--write", d], "--write file"),
    "paper_out_file": (lambda d, s: ["paper", "--out", s], "--out folder"),
    "generate_out_file": (lambda d, s: ["generate", "--z", "x**2", "--out", s], "--out folder"),
    "generate_scene_dir": (lambda d, s: ["generate", "--scene", d, "--out", d / "gen"], "is a directory"),
    "generate_scene_dev": (lambda d, s: ["generate", "--scene", "/dev/zero", "--out", d / "gen"], "/dev/zero"),
}


@pytest.mark.parametrize("case", sorted(BAD_PATH_COMMANDS))
def test_bad_paths_are_one_line_errors_before_any_work(case, tmp_path, capsys):
    scene = _scene_file(tmp_path)
    args, message = BAD_PATH_COMMANDS[case]
    argv = args(tmp_path, scene)
    before = listing(tmp_path)
    code, out, err = run_cli(capsys, *argv)
    assert code == common.EXIT_BAD_INPUT
    assert out == ""  # nothing ran: no event table, no "wrote"
    assert err.startswith(f"symvib {argv[0]}: error: ") and err.count("\n") == 1, err
    assert re.search(message, err), err
    assert "Traceback" not in err
    assert listing(tmp_path) == before


#: Scene names that try to leave the figure folder or break the figure titles.
HOSTILE_SCENE_NAMES = ["../../x", "/abs/path", "..", "$", "a$b$$c", "$\\frac{", "x" * 200, "κ-ü ∂", "a/b\\c",
                       "~/x", "'\"", "C:\\x", "-rf"]


@pytest.mark.parametrize("name", HOSTILE_SCENE_NAMES, ids=range(len(HOSTILE_SCENE_NAMES)))
def test_figures_of_hostile_names_stay_in_their_folder(name, tmp_path):
    from symvib import simulate
    from symvib.numeric.figures import save_run_figures

    work = tmp_path / "work"
    work.mkdir()
    scene = load_scene(PARABOLA).replace(name=name, max_events=3)
    written = save_run_figures(simulate(scene), work / "figs", only=["phase"])
    assert listing(tmp_path) == {"work", "work/figs", f"work/figs/{written[0].name}"}
    assert re.fullmatch(r"[A-Za-z0-9_][A-Za-z0-9._-]*-phase\.png", written[0].name)


def test_run_with_a_traversal_name_writes_only_inside_the_plot_folder(tmp_path, capsys):
    scene = _scene_file(tmp_path, name="../../escaped")
    before = listing(tmp_path)
    code, out, err = run_cli(capsys, "run", scene, "--plot", tmp_path / "figs", "--json", tmp_path / "r.json")
    assert code == 0, err
    new = listing(tmp_path) - before
    assert new == {"figs", "r.json"} | {f"figs/{p.name}" for p in (tmp_path / "figs").iterdir()}
    assert len(list((tmp_path / "figs").iterdir())) == len(FIGURE_NAMES)  # issue 16: the sketch and force plan too
    assert not (tmp_path.parent.parent / "escaped-phase.png").exists()


@pytest.mark.slow  # a SymPy derivation per name (about 10 s)
@pytest.mark.parametrize("name", ["../../evil", "/abs/evil", "a" * 300, "κ"])
def test_generate_name_stays_inside_out(name, tmp_path, capsys):
    out_dir = tmp_path / "gen"
    code, out, err = run_cli(capsys, "generate", "--z", "x**2", "--name", name, "--out", out_dir)
    assert code == 0, err
    files = listing(tmp_path)
    assert len(files) == 2 and "gen" in files, files
    (module,) = out_dir.iterdir()
    assert re.fullmatch(r"[A-Za-z][A-Za-z0-9_]*\.py", module.name) and len(module.name) < 120


@pytest.mark.parametrize("message, expected", [
    ("a\nb", "a\\nb"), ("a\x00b", "a\\x00b"), ("plain", "plain"), ("x" * 1000, "x" * 497 + "..."),
    (KeyError("k"), "'k'"), ("tab\there", "tab\\there"),
])
def test_one_line(message, expected):
    assert common.one_line(message) == expected


def test_module_names_of_hostile_curve_names_are_short_identifiers():
    from symvib.numeric.kernels import module_name

    assert module_name("parabola_x") == "parabola_x"
    for name in HOSTILE_STEMS:
        module = module_name(name)
        assert module.isidentifier() and module.isascii() and len(module) < 110, module
    assert module_name("a/b") != module_name("a_b")


#: Scene texts from the issue (and a few more), run through `symvib run`: (TOML, field named).
USER_CURVE_TOML = """name = "t"
[curve]
{curve}
[parameters]
p = 1.0
[physics]
alpha0 = 0.05
restitution = 0.8
[initial]
q = {q}
qdot = {qdot}
"""
BAD_TOML_SCENES = {
    "shape_list": ('shape = ["parabola"]', "0", "1", "curve.shape"),
    "digits_400": ('z = "x**2/(2*p)"', "0", "9" * 400, "initial.qdot"),
    "digits_400_q": ('z = "x**2/(2*p)"', "-" + "9" * 400, "1", "initial.q"),
    "expression_100kb": ('z = "x' + "+x" * 50_000 + '"', "0", "1", "curve.z"),
    "unary_100000": ('z = "' + "-" * 100_000 + 'x*p"', "0", "1", "curve.z"),
    "nested_powers": ('z = "x**2*((((9**64)**64)**64)**64)**64*p"', "0", "1", "curve.z"),
    "domain_reversed": ('z = "x**2/(2*p)"\ndomain = ["1", "-1"]', "0", "1", "curve.domain"),
    "domain_oo_outside": ('z = "x**2/(2*p)"\ndomain = ["0.3", "oo"]', "0", "1", "initial.q"),
    "domain_text": ('z = "x**2/(2*p)"\ndomain = ["zz", "oo"]', "0", "1", r"curve.domain\[0\]"),
    "name_newline": ('z = "x**2/(2*p)"\nname = "a\\nb"', "0", "1", "curve.name"),
    "q_dunder": ('z = "__x**2/(2*p)"\nq = "__x"', "0", "1", "curve.q"),
    "attack_in_q": ('z = "x**2/(2*p)"', "\"__import__('os').system('echo hi')\"", "1", "initial.q"),
    "string_qdot": ('z = "x**2/(2*p)"', "0", "'fast'", "initial.qdot"),
}


@pytest.mark.parametrize("case", sorted(BAD_TOML_SCENES))
def test_bad_scene_files_through_the_cli(case, tmp_path, capsys):
    curve, q, qdot, field = BAD_TOML_SCENES[case]
    path = tmp_path / "s.toml"
    path.write_text(USER_CURVE_TOML.format(curve=curve, q=q, qdot=qdot), encoding="utf-8")
    code, out, err = run_cli(capsys, "run", path)
    assert code == common.EXIT_BAD_INPUT and out == ""
    assert re.match(rf"symvib run: error: {field}: ", err), err
    assert err.count("\n") == 1 and len(err) <= common.MAX_MESSAGE_LENGTH + 40


@pytest.mark.parametrize("args, message", [
    (["derive", "--z=" + "-" * 100_000 + "x"], "characters long"),
    (["derive", "--z=x" + "+x" * 50_000], "characters long"),
    (["derive", "--z=x**2*((((9**64)**64)**64)**64)**64"], "larger than"),
    (["derive", "--z=__import__('os').system('true')"], "attribute access"),
    (["derive", "--z=(lambda: x)()"], "not allowed"),
    (["derive", "--z=x**2", "--q=1"], "identifier"),
    (["derive", "../../etc/passwd"], "unknown shape"),
    (["generate", "--z=x**2/0", "--out=OUT"], "division"),
    (["run", "SCENE", "--t-max=nan"], "run.t_max: must be finite"),
    (["run", "SCENE", "--restitution=inf"], "physics.restitution: must be finite"),
])
def test_hostile_command_lines_are_one_line_errors(args, message, tmp_path, capsys):
    scene = _scene_file(tmp_path)
    args = [a.replace("OUT", str(tmp_path / "out")).replace("SCENE", str(scene)) for a in args]
    before = listing(tmp_path)
    code, out, err = run_cli(capsys, *args)
    assert code == common.EXIT_BAD_INPUT and out == ""
    assert err.startswith(f"symvib {args[0]}: error: ") and err.count("\n") == 1 and message in err, err
    assert listing(tmp_path) == before


def test_a_file_name_that_is_not_a_scene_name_is_made_safe(tmp_path):
    text = PARABOLA.read_text(encoding="utf-8").replace('name = "paper-parabola"\n', "")
    path = tmp_path / "a\tb.toml"
    path.write_text(text, encoding="utf-8")
    assert load_scene(path).name == safe_stem("a\tb")
    path = tmp_path / "plain name.toml"
    path.write_text(text, encoding="utf-8")
    assert load_scene(path).name == "plain name"


def test_dots_in_strings_and_numbers_are_not_keys(tmp_path):
    text = 'description = "' + "." * 5000 + '"\n# ' + "." * 5000 + "\nv = 1.5\n"
    assert read_user_file(_write(tmp_path / "ok.toml", text.encode())) == text
    assert paths.read_user_toml(tmp_path / "ok.toml")["v"] == 1.5


@pytest.mark.parametrize("name", ["__class__", "_Q", "lambda", "None", "class"])
def test_coordinate_and_parameter_names_are_plain(name):
    """``symvib derive --q __class__`` was accepted (harmless in SymPy; the code generator
    refused it later): the curve refuses it at construction, for the coordinate and parameters."""
    from symvib.symbolic.branches import CurveError
    from symvib.symbolic.curve import graph, parametric

    with pytest.raises(CurveError, match=r"keyword or starts with '_'"):
        parametric("cos(t)", "sin(t)", q=name)
    with pytest.raises(CurveError, match=r"keyword or starts with '_'"):
        graph("a*x**2", params={"a": "positive", name: "positive"})
