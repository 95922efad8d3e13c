"""Trust in generated code (issue 13): user text never runs, kernel modules are verified before import.

A curve's name, expressions, parameter names and domain reach the text of a
generated kernel module; none of it may close a string or docstring and run.
"""
import hashlib
import importlib.util
import re
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

from symvib.codegen import generate as codegen
from symvib.codegen import kernel_text, printers
from symvib.expr import ExpressionError
from symvib.numeric import kernels
from symvib.numeric.backends import backend_available
from symvib.prepare import load_kernels
from symvib.symbolic.branches import CurveError

#: Whether the numba backend can run here (the numba tests skip otherwise).
NUMBA = backend_available("numba")
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


@pytest.fixture(scope="module")
def bowl():
    """The derivation of BOWL (done once: SymPy takes about a second) and its source."""
    from symvib.shapes import Shape
    from symvib.symbolic.derive import derive

    shape = Shape(name="bowl", **BOWL)
    return derive(shape.curve()), shape.source()


def _import_text(text, folder, stem="hostile"):
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{stem}.py"
    path.write_text(text, encoding="utf-8")
    spec = importlib.util.spec_from_file_location(f"trust_{stem}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _public(module):
    return {n for n in vars(module) if not (n.startswith("__") and n.endswith("__"))}


@pytest.mark.parametrize("label", sorted(HOSTILE_NAMES))
def test_hostile_name_module_imports_and_defines_nothing_else(label, bowl, tmp_path):
    d, source = bowl
    marker = tmp_path / MARKER_NAME
    name = HOSTILE_NAMES[label].format(marker=str(marker))
    expected = _public(_import_text(kernel_text.module_text(d, source), tmp_path / "plain", "plain"))
    module = _import_text(kernel_text.module_text(d, {**source, "name": name}), tmp_path / "hostile")
    assert module.NAME == name and module.SOURCE["name"] == name
    assert _public(module) == expected
    assert not marker.exists()


def test_hostile_name_through_the_cache_never_runs(cache, tmp_path):
    marker = tmp_path / MARKER_NAME
    name = HOSTILE_NAMES["closes_docstring"].format(marker=str(marker))
    module = load_kernels({**BOWL, "name": name})
    assert module.NAME == name
    assert float(module.z_scalar(2.0, 1.0)) == 2.0
    assert not marker.exists()


#: Parameter names that would shadow a name the kernels use.
SHADOWING_PARAMS = ["float", "F_p", "SOURCE", "z_scalar", "numpy", "domain", "print"]


@pytest.mark.parametrize("param", SHADOWING_PARAMS)
def test_parameter_names_that_would_shadow_kernel_names_are_refused(param, cache):
    with pytest.raises(CurveError, match=rf"^curve\.params: parameter name '{param}' is reserved"):
        load_kernels({**BOWL, "name": "shadow", "params": {"p": "positive", param: "positive"}})
    assert not list(cache.glob("*.py"))


@pytest.mark.parametrize("param, why", [("lambda", "keyword"), ("None", "keyword"), ("ﬁ", "ASCII"),
                                        ("_t0", "'_'"), ("p q", "ASCII"), ("", "ASCII"), (3, "ASCII")])
def test_check_param_names_refuses_non_identifiers(param, why):
    with pytest.raises(CurveError, match=rf"^curve\.params: parameter name .* {why}"):
        kernel_text.check_param_names(["p", param])


@pytest.mark.parametrize("field, value", [
    ("z", 'x"""; open("m", "w")'), ("z", "x**2\nimport os"), ("z", "x\\**2"), ("z", "x**2\x00"),
    ("z", "x**2 # comment"), ("domain", ["0", "'''"]), ("domain", ["0.3", "oo\n#"]),
    ("q_scale", "1; import os"),
])
def test_hostile_expressions_are_refused_or_harmless(field, value, cache):
    try:
        module = load_kernels({**BOWL, "name": "expr", field: value})
    except (ExpressionError, CurveError) as err:
        assert "\n" not in str(err) and field in str(err)
        assert not list(cache.glob("*.py"))
    else:
        assert module.SOURCE[field] == value


@pytest.mark.parametrize("value", [object(), b"bytes", {1: "a"}, complex(1, 2)])
def test_source_literal_takes_plain_data_only(value):
    with pytest.raises(CurveError, match=r"^source\.extra"):
        printers.py_literal({"extra": value})


def test_source_literal_prints_non_finite_floats_as_calls():
    assert eval(printers.py_literal([float("inf"), float("-inf")])) == [float("inf"), float("-inf")]  # noqa: S307


GENERATED = Path(__file__).resolve().parents[1] / "generated"


@pytest.mark.parametrize("path", sorted(GENERATED.glob("*.py")), ids=lambda p: p.name)
def test_every_committed_generated_module_passes_the_whitelist(path):
    kernels.verify_text(path.read_text(encoding="utf-8"), path)


def test_a_fresh_user_module_passes_the_whitelist(bowl):
    d, source = bowl
    kernels.verify_text(kernel_text.module_text(d, source), "bowl.py")


#: Hand-made modules the whitelist refuses, and the word of the error that says why.
HOSTILE_MODULES = {
    "import_os": ("import os", "import of 'os'"),
    "import_as": ("import numpy as np", "import of 'numpy'"),
    "from_import": ("from os import system", "ImportFrom"),
    "open_call": ("X = open('m', 'w')", "name 'open'"),
    "eval": ("X = eval('1')", "name 'eval'"),
    "dunder_import": ("X = __import__('os')", "name '__import__'"),
    "bare_call": ("print(1)", "expression statement"),
    "class_escape": ("def f():\n    return ().__class__.__base__", "attribute '__base__'"),
    "numpy_load": ("X = numpy.load('f.npy')", "attribute 'load'"),
    "numpy_ctypes": ("X = numpy.ctypeslib", "attribute 'ctypeslib'"),
    "attr_of_value": ("def f(a):\n    return a.real", "attribute 'real'"),
    "lambda": ("F = lambda: 0", "Lambda"),
    "class": ("class K:\n    pass", "ClassDef"),
    "decorator": ("def f():\n    return 1\n\n\n@f\ndef g():\n    return 2", "decorators"),
    "rebind_math": ("math = 1", "assigning to 'math'"),
    "rebind_float": ("def f():\n    float = 2\n    return float", "assigning to 'float'"),
    "with": ("def f():\n    with f():\n        pass", "With"),
    "global_for": ("for i in range(3):\n    pass", "module-level For"),
    "try": ("def f():\n    try:\n        return 1\n    except Exception:\n        return 2", "Try"),
    "second_string": ('"""doc"""\n"""another"""', "expression statement"),
    "ifexp": ("def f(q):\n    return (1.0) if (q == 0) else (q)", "IfExp"),
    "compare": ("def f(q):\n    return q == 0", "Compare"),
    "if_statement": ("def f(q):\n    if q:\n        return 1.0\n    return q", "If node"),
    "lambda_in_kernel": ("def f(q):\n    return (lambda: q)()", "Lambda"),
    "numpy_select": ("def f(q):\n    return numpy.select([numpy.equal(q, 0), True], [1, q])", "attribute 'select'"),
    "numpy_where": ("def f(q):\n    return numpy.where(numpy.equal(q, 0), 1, q)", "attribute 'where'"),
    "syntax": ("def f(:\n", "not valid Python"),
    "nul": ("X = 1\x00", "not valid Python"),
}


@pytest.mark.parametrize("label", sorted(HOSTILE_MODULES))
def test_whitelist_refuses_hand_made_hostile_modules(label, tmp_path):
    text, why = HOSTILE_MODULES[label]
    path = tmp_path / f"{label}.py"
    with pytest.raises(kernels.KernelError, match=re.escape(why)) as err:
        kernels.verify_text(text, path)
    assert str(err.value).startswith(f"{path}:") and "\n" not in str(err.value)


def test_whitelist_refuses_a_payload_appended_to_a_real_module():
    text = (GENERATED / "circle.py").read_text(encoding="utf-8") + "\nimport os\nos.system('true')\n"
    with pytest.raises(kernels.KernelError, match=r"circle\.py: line \d+: import of 'os'"):
        kernels.verify_text(text, GENERATED / "circle.py")


def _forget(module):
    """As if in a new process: the module is read from its file again."""
    sys.modules.pop(module.__name__, None)
    kernels._LOADED.clear()


def _redigest(text):
    """``text`` with its first line's digest recomputed (a tamperer who knows the format)."""
    body = text.partition("\n")[2]
    return f"{kernels.DIGEST_PREFIX}{hashlib.sha256(body.encode()).hexdigest()}\n{body}"


def _append_payload(text, marker):
    return text + f"\nimport os\nopen({str(marker)!r}, 'w').write('x')\n"


#: Ways to damage a cached module: each must be detected before it runs.
TAMPERINGS = {
    "payload_appended": _append_payload,
    "payload_appended_digest_recomputed": lambda t, m: _redigest(_append_payload(t, m)),
    "payload_in_docstring_digest_recomputed": lambda t, m: _redigest(
        t.replace('"""\nimport math', f'"""\nopen({str(m)!r}, "w")\nimport math', 1)),
    "digits_altered": lambda t, m: t.replace("PANEL = 0.25", "PANEL = 0.35", 1),
    "truncated": lambda t, m: t[: len(t) // 2],
    "input_hash_altered": lambda t, m: _redigest(re.sub(r"INPUT_HASH = '[0-9a-f]{64}'",
                                                        f"INPUT_HASH = '{'0' * 64}'", t)),
    "emptied": lambda t, m: "",
}


@pytest.mark.parametrize("label", sorted(TAMPERINGS))
def test_tampered_cached_module_is_detected_and_regenerated(label, cache, tmp_path):
    marker = tmp_path / MARKER_NAME
    module = load_kernels({**BOWL, "name": "bowl"})
    path = Path(module.__file__)
    good = path.read_text(encoding="utf-8")
    bad = TAMPERINGS[label](good, marker)
    assert bad != good
    path.write_text(bad, encoding="utf-8")
    _forget(module)
    with pytest.warns(UserWarning, match=r"regenerating it"):
        again = load_kernels({**BOWL, "name": "bowl"})
    assert not marker.exists()
    assert path.read_text(encoding="utf-8") == good
    assert again.PANEL == kernel_text.PANEL and float(again.z_scalar(2.0, 1.0)) == 2.0
    assert sorted(p.name for p in cache.iterdir()) == [path.name]


@pytest.mark.parametrize("label", ["payload_appended", "payload_appended_digest_recomputed", "truncated",
                                   "digits_altered"])
def test_tampered_committed_module_is_refused(label, tmp_path, monkeypatch):
    marker = tmp_path / MARKER_NAME
    copy = tmp_path / "generated"
    shutil.copytree(GENERATED, copy)
    path = copy / "circle.py"
    path.write_text(TAMPERINGS[label](path.read_text(encoding="utf-8"), marker), encoding="utf-8")
    monkeypatch.setattr(kernels, "generated_dir", lambda: copy)
    monkeypatch.setattr(kernels, "_LOADED", {})
    monkeypatch.delitem(sys.modules, "symvib.generated.circle", raising=False)
    with pytest.raises(kernels.KernelError, match=rf"^{re.escape(str(path))}: .*run `symvib generate`$"):
        load_kernels("circle")
    assert not marker.exists()


def test_engine_executes_no_text():
    # The engine binds kernel modules that kernels.load has checked; it never reads,
    # compiles or executes source text of its own (no exec/eval/compile/read_text).
    import ast

    import symvib.numeric.engine as engine_pkg

    folder = Path(engine_pkg.__file__).parent
    for path in sorted(folder.glob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name):  # the builtins
                assert node.func.id not in {"exec", "eval", "compile", "__import__"}, (path.name, node.lineno)
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute):  # no source read
                assert node.func.attr not in {"read_text", "exec_module"}, (path.name, node.lineno)


@pytest.mark.parametrize("broken", ["X = float('not a number')\n", "X = F_p_scalar(1.0)\n", "import os\n"])
def test_failed_generation_leaves_nothing_in_the_cache(broken, cache, monkeypatch):
    real = codegen.module_text
    monkeypatch.setattr(codegen, "module_text", lambda d, source: _redigest(real(d, source) + broken))
    with pytest.raises(kernels.KernelError, match=r"bowl_[0-9a-f]{16}\.py: "):
        load_kernels({**BOWL, "name": "bowl"})
    assert list(cache.iterdir()) == []
    monkeypatch.setattr(codegen, "module_text", real)
    assert float(load_kernels({**BOWL, "name": "bowl"}).z_scalar(2.0, 1.0)) == 2.0


@pytest.mark.parametrize("expr, numpy_text", [
    ("x*10**30", "1e+30*x"), ("x/10**30", "(1e-30)*x"), ("x*3/10**20", "(3e-20)*x"), ("-x*10**30", "-1e+30*x"),
    ("x*2**53", "9007199254740992.0*x"), ("x*(2**53 - 1)", "9007199254740991*x"), ("5*x**2", "5*x**2"),
    ("7*x/3", "(7/3)*x"), ("sqrt(10**60 + 1)*x", "numpy.sqrt(1e+60)*x"),
])
def test_big_integers_are_printed_as_floats(expr, numpy_text):
    import sympy as sp

    e = sp.sympify(expr)
    assert printers.NumPy().doprint(e) == numpy_text
    assert printers.Math().doprint(e) == numpy_text.replace("numpy.", "math.")


def test_numbers_beyond_float_are_refused():
    import sympy as sp

    with pytest.raises(CurveError, match=r"^curve: the number 1000.* is too large for a float kernel"):
        printers.Math().doprint(sp.Integer(10) ** 400 * sp.Symbol("x"))


def _scene(z, backend_curve_name):
    from symvib.numeric.scene import scene_from_dict

    return scene_from_dict({"curve": {"z": z, "name": backend_curve_name},
                            "physics": {"g": 9.81, "m": 0.2, "alpha0": 0.05, "restitution": 0.8},
                            "limiters": {"left": "-1", "right": "1"}, "initial": {"q": 0.5, "qdot": 0}})


#: Curves whose kernels hold integers beyond int64, and the curve without them that they equal.
BIG_INT_CURVES = {"x*10**30": None, "x**2*(10**30 + 1)/10**30": "x**2"}


@pytest.mark.parametrize("z", sorted(BIG_INT_CURVES))
def test_big_integer_curve_simulates_on_python(z, cache):
    from symvib import simulate

    result = simulate(_scene(z, "big"), backend="python")
    assert result.events or result.status.value == "t_max"
    assert all(map(np.isfinite, [result.t_final, result.q_final, result.qdot_final]))
    if BIG_INT_CURVES[z]:
        plain = simulate(_scene(BIG_INT_CURVES[z], "plain"), backend="python")
        assert [e.kind for e in result.events] == [e.kind for e in plain.events]
        assert [e.t for e in result.events] == pytest.approx([e.t for e in plain.events], rel=1e-12)
    else:  # a nearly vertical wall: x moves by g t^2 / 2e30 ~ 5e-24 until t_max (a few ulps of 0.5)
        assert result.q_final == pytest.approx(0.5, abs=1e-14)


@pytest.mark.slow
@pytest.mark.skipif(not NUMBA, reason="no numba")
@pytest.mark.parametrize("z", sorted(BIG_INT_CURVES))
def test_big_integer_curve_simulates_on_numba(z, cache):
    from symvib import simulate

    a = simulate(_scene(z, "big"), backend="python")
    b = simulate(_scene(z, "big"), backend="numba")
    assert a.status is b.status and [e.kind for e in a.events] == [e.kind for e in b.events]
    assert [e.t for e in a.events] == pytest.approx([e.t for e in b.events], rel=1e-12)
    assert a.q_final == pytest.approx(b.q_final, rel=1e-12, abs=1e-300)


@pytest.mark.slow
@pytest.mark.skipif(not NUMBA, reason="no numba")
def test_the_compiled_engine_is_named_by_its_kernel_module(cache):
    # No engine source is written to the cache any more (the engine binds checked kernel
    # modules); numba's disk cache of a curve's engine is keyed by the entry points' names,
    # which carry the kernel module's input hash: a regenerated (or different) module never
    # meets another module's compiled engine.
    from symvib.numeric import driver
    from symvib.numeric.scene import scene_from_dict

    scene = scene_from_dict({"curve": {"shape": "parabola"}, "parameters": {"p": 1.0},
                             "physics": {"alpha0": 0.05, "restitution": 0.8}, "initial": {"q": -0.6, "qdot": 0.0},
                             "limiters": {"right": 0.3}})
    assert driver.simulate(scene, backend="numba").success
    module, _ = driver.bound_engine(scene.shape, "numba")
    entries = module._symvib_specialized_engine
    for name in ("simulate_bound", "sample_bound", "sweep_bound"):
        assert entries[name].py_func.__qualname__ == f"{name}__parabola_{module.INPUT_HASH[:16]}"
    assert not list(cache.glob("engines/*.py"))


def test_generate_writes_only_modules_that_pass_the_whitelist(tmp_path, monkeypatch):
    from symvib.shapes import Shape

    real = codegen.module_text
    monkeypatch.setattr(codegen, "module_text", lambda d, source: _redigest(real(d, source) + "import os\n"))
    out = tmp_path / "out"
    with pytest.raises(kernels.KernelError, match=r"bowl\.py: line \d+: import of 'os'"):
        codegen.generate(Shape(name="bowl", **BOWL), out)
    assert list(out.iterdir()) == []


#: Curves on a half-infinite domain (the middle of the domain is infinite) whose F_s has no closed form.
HALF_INFINITE = [("sqrt(x)", ["0.3", "oo"], 1.0, {"left": 0.5}), ("x**4", ["0.3", "oo"], 1.0, {"left": 0.5}),
                 ("(-x)**4", ["-oo", "-0.3"], -1.0, {"right": -0.5})]


@pytest.mark.slow  # a numeric route is reached after the symbolic ones time out (~40 s each)
@pytest.mark.parametrize("z, domain, q0, limiters", HALF_INFINITE, ids=[c[0] for c in HALF_INFINITE])
def test_half_infinite_domain_gives_a_working_module(z, domain, q0, limiters, cache):
    import mpmath

    from symvib import simulate
    from symvib.numeric.scene import scene_from_dict

    module = load_kernels({"name": "half", "kind": "graph", "q": "x", "z": z, "domain": domain})
    assert "numeric" in module.F_ROUTES.values()  # the route that integrates from Q_REF
    assert np.isfinite(module.Q_REF) and module.domain()[0] < module.Q_REF < module.domain()[1]
    mu, a, b = 0.05, q0, q0 + 0.7 * np.sign(q0)
    for s, (F, dF) in {1: (module.F_p_scalar, module.dF_p_scalar), -1: (module.F_m_scalar, module.dF_m_scalar)}.items():
        want = mpmath.quad(lambda u: dF(float(u), mu), [a, b])
        assert F(b, mu) - F(a, mu) == pytest.approx(float(want), rel=1e-12), s
    result = simulate(scene_from_dict({"curve": {"z": z, "domain": domain}, "limiters": limiters,
                                       "physics": {"alpha0": 0.05, "restitution": 0.8},
                                       "initial": {"q": q0, "qdot": 0}}), backend="python")
    assert result.events and result.energy_budget.relative_residual < 1e-9
    assert not list(cache.glob("*.tmp*"))


@pytest.mark.parametrize("edit, message", [
    (lambda t: t.replace("def node_p_scalar(q, mu, R):", "def node_p_scalar(q, R):"), r"node_p_scalar .* must take"),
    (lambda t: t.replace("def N_w_scalar(", "def N_w_other("), r"N_w_scalar .* missing"),
])
def test_a_module_without_the_engine_interface_is_refused(edit, message, tmp_path):
    # The engine's kernel interface is declared once (engine.state.KERNEL_INTERFACE); the
    # generator and the loader both check every module against it.
    text = (GENERATED / "circle.py").read_text(encoding="utf-8")
    edited = edit(text)
    assert edited != text
    with pytest.raises(kernels.KernelError, match=message):
        kernels.verify_text(edited, tmp_path / "circle.py")


def test_whitelist_refuses_a_conditional_edited_into_a_real_kernel():
    # The scalar kernel as SymPy's own printer would write the paper parabola's h' in expressions.
    text = (GENERATED / "parabola.py").read_text(encoding="utf-8")
    edited = text + "\n\ndef dh_if(q, p):\n    return (4*p) if (math.cos(q) == 0) else (3*p)\n"
    with pytest.raises(kernels.KernelError, match="IfExp"):
        kernels.verify_text(edited, GENERATED / "parabola.py")


#: The paper's three curves and others whose derivation holds Abs, sign or an Eq-Piecewise, as a
#: user writes them (symvib run used to exit 2 on the first: "a Compare node is not allowed").
EXPRESSION_CURVES = {
    "paper-parabola": {"kind": "parametric", "x": "tan(phi)", "z": "tan(phi)**2/2", "q": "phi"},
    "secant-sqrt": {"kind": "parametric", "x": "sin(q)*sqrt(tan(q)**2 + 1)", "z": "tan(q)**2/2", "q": "q",
                    "domain": ["-pi/2", "pi/2"]},
    "hyperbola-cosh": {"kind": "parametric", "x": "sinh(q)", "z": "cosh(q)", "q": "q"},
    "abs-cubed": {"kind": "graph", "z": "abs(x)**3/3", "q": "x"},
    "x-abs-x": {"kind": "graph", "z": "x*abs(x)", "q": "x"},
}


@pytest.mark.slow  # a derivation each (the numeric routes of secant-sqrt: about 40 s)
@pytest.mark.parametrize("label", sorted(EXPRESSION_CURVES))
def test_curves_with_abs_and_sign_generate_no_conditional(label, cache):
    source = {"name": label, **EXPRESSION_CURVES[label]}
    mod = load_kernels(source)
    text = Path(mod.__file__).read_text(encoding="utf-8")
    assert " if " not in text and "==" not in text and "select" not in text
    # The scalar twins agree with the array kernels, finite at 0 too (removable values, sign(0)).
    q = np.array([-0.7, -0.3, 0.0, 0.2, 0.6])
    for name in ("x", "z", "h", "alpha", "kappa", "dx", "dz", "dh", "dalpha"):
        arr = getattr(mod, name)(q)
        one = [getattr(mod, f"{name}_scalar")(float(v)) for v in q]
        assert np.all(np.isfinite(arr)), name
        np.testing.assert_allclose(one, arr, rtol=1e-14, atol=1e-15, err_msg=name)


def _module_namespace(d, source, tmp_path):
    """The kernels of derivation ``d`` as a namespace (the text checked by the whitelist first)."""
    text = kernel_text.module_text(d, source)
    kernels.verify_text(text, tmp_path / "m.py")
    namespace = {}
    exec(compile(text, str(tmp_path / "m.py"), "exec"), namespace)  # noqa: S102 - verified above
    return namespace


@pytest.mark.parametrize("z, at_zero", [("x*abs(x)/2 + x**2/2", 2.0), ("abs(x)**3/3", 0.0)])
def test_a_removable_value_is_finite_in_both_twins(z, at_zero, tmp_path):
    # kappa = (x + |x|) / (x (...)) and 2 x**2 / ((1 + x**4)**(3/2) |x|): 0/0 at x = 0, where a
    # kernel may be evaluated (a grid point, the middle of two limiters); written with
    # |x| = x sign(x) and copysign(1, 0) = 1 they are finite, the limit from the right.
    from symvib.symbolic.curve import graph
    from symvib.symbolic.derive import derive

    k = _module_namespace(derive(graph(z), routes=()), {"z": z}, tmp_path)
    assert k["kappa_scalar"](0.0) == pytest.approx(at_zero, abs=1e-15)
    assert k["kappa"](np.array([0.0]))[0] == pytest.approx(at_zero, abs=1e-15)
    for q in (-0.3, 0.4):
        assert k["kappa_scalar"](q) == pytest.approx(k["kappa"](np.array([q]))[0], rel=1e-14)


@pytest.mark.slow  # derives the curve twice: as given, and on its regular interval (about 15 s)
def test_the_paper_parabola_in_expressions_runs():
    # The reproduction of the report: derive, print, whitelist (no Compare node any more).
    from symvib import simulate
    from symvib.numeric.scene import scene_from_dict

    scene = scene_from_dict({"curve": {"x": "tan(phi)", "z": "tan(phi)**2/2", "q": "phi"},
                             "physics": {"mu": 0.05, "restitution": 0.8},
                             "limiters": {"left": -0.5, "right": 0.7}, "initial": {"q": 0.0, "qdot": 3.0}})
    result = simulate(scene, backend="python", samples=False)
    assert result.success and result.events[0].kind.value == "impact"
    assert result.energy_budget.relative_residual < 1e-9


@pytest.mark.parametrize("expr, numpy_text, math_text", [
    ("sign(q)", "numpy.copysign(1.0, q)", "math.copysign(1.0, q)"),
    ("Abs(q - 1)", "numpy.abs(q - 1)", "abs(q - 1)"),
    ("q*sign(cos(q))", "q*numpy.copysign(1.0, numpy.cos(q))", "q*math.copysign(1.0, math.cos(q))"),
])
def test_sign_and_abs_print_without_a_conditional(expr, numpy_text, math_text):
    import sympy as sp

    e = sp.sympify(expr, locals={"q": sp.Symbol("q", real=True)})
    assert printers.NumPy().doprint(e) == numpy_text
    assert printers.Math().doprint(e) == math_text


@pytest.mark.parametrize("expr", ["Piecewise((1, Eq(q, 0)), (q, True))", "Eq(q, 0)", "q > 0",
                                  "KroneckerDelta(q, 1)", "Heaviside(q)"])
def test_printers_refuse_what_would_print_as_a_conditional(expr):
    import sympy as sp

    e = sp.sympify(expr, locals={"q": sp.Symbol("q", real=True)})
    for printer in (printers.NumPy(), printers.Math()):
        with pytest.raises(CurveError, match="conditional"):
            printer.doprint(e)
