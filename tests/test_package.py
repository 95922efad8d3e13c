"""The package's lazy top-level names (``symvib/__init__.py``)."""
import subprocess
import sys
import textwrap


def _run(code: str) -> str:
    out = subprocess.run([sys.executable, "-c", textwrap.dedent(code)],
                         capture_output=True, text=True, check=True)
    return out.stdout.strip()


def test_import_symvib_loads_neither_sympy_nor_numpy():
    assert _run("""
        import sys, symvib
        print('sympy' in sys.modules, 'numpy' in sys.modules)
    """) == "False False"


def test_derive_and_audit_stay_functions_after_their_modules_are_imported():
    # Importing symvib.derive / symvib.audit binds the submodule on the package;
    # the top-level names must still be the functions, in either order.
    assert _run("""
        import types
        import symvib.audit, symvib.derive
        from symvib import derive, audit
        import symvib
        from symvib.derive import Derivation
        print(isinstance(derive, types.FunctionType), isinstance(audit, types.FunctionType),
              symvib.derive is derive, Derivation.__module__)
    """) == "True True True symvib.derive"
    assert _run("""
        from symvib import derive
        import symvib.derive, symvib
        print(symvib.derive is derive, callable(symvib.derive))
    """) == "True True"


def test_unknown_attribute_names_itself():
    assert "nonsense" in _run("""
        import symvib
        try:
            symvib.nonsense
        except AttributeError as exc:
            print(exc)
    """)


def test_figures_leave_the_callers_matplotlib_backend_alone(tmp_path):
    # A notebook's inline backend must survive importing and using the figure modules.
    assert _run(f"""
        import matplotlib
        matplotlib.use("svg")
        import symvib.plots, symvib.sweepmaps
        from symvib.driver import simulate
        from symvib.scene import load_scene
        import symvib
        from pathlib import Path
        scene = load_scene(Path(symvib.__file__).parent / "scenes" / "paper-parabola.toml")
        result = simulate(scene, backend="python")
        paths = symvib.plots.save_run_figures(result, {str(tmp_path)!r}, only=["phase"])
        print(matplotlib.get_backend(), [p.suffix for p in paths])
    """) == "svg ['.png']"
