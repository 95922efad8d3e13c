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


def test_top_level_derive_and_audit_are_the_functions_and_the_modules_live_in_their_wing():
    # The modules live in symvib.symbolic and in the paper's wing symvib.paper; the package's
    # names are the functions, in whatever order things are imported.
    assert _run("""
        import types
        import symvib.paper.audit, symvib.symbolic.derive
        from symvib import derive, audit
        import symvib
        print(isinstance(derive, types.FunctionType), isinstance(audit, types.FunctionType),
              symvib.derive is symvib.symbolic.derive.derive, derive.__module__, audit.__module__)
    """) == "True True True symvib.symbolic.derive symvib.paper.audit"


def test_the_paper_wing_keeps_the_old_names():
    """``symvib/paper.py`` became the package ``symvib.paper`` (issue 25): its names stay, loaded on
    first use from the module that defines each; the modules gathered into the package keep their
    old names as aliases (the same module objects, so a name set on one is seen on the other)."""
    assert _run("""
        import sys
        import symvib.paper
        print(sorted(m for m in sys.modules if m.startswith("symvib")), "numpy" in sys.modules)
        from symvib.paper import (ALPHA0_READINGS, HIGH_K, LOW_K, PDF_FIGURES_PER_PAGE, REMARK, SCENES, formulas,
                                  main, markdown_to_html, parse_event_tables, pdf_text_pages, run_paper, write_pdf)
        from symvib.paper import errata, report, report_html, report_pdf
        print(run_paper is report.run_paper and main is report.main and SCENES is report.SCENES,
              markdown_to_html is report_html.markdown_to_html and formulas is report_html.formulas,
              write_pdf is report_pdf.write_pdf and pdf_text_pages is report_pdf.pdf_text_pages,
              ALPHA0_READINGS is errata.ALPHA0_READINGS, set(symvib.paper.__all__) <= set(dir(symvib.paper)))
        import importlib
        old = {"symvib.errata": "errata", "symvib.conclusions": "conclusions", "symvib.texmathml": "texmathml"}
        print(all(importlib.import_module(name) is importlib.import_module("symvib.paper." + new)
                  for name, new in old.items()))
        from symvib.paper.audit import EXPLANATIONS, pm
        from symvib.texmathml import to_mathml
        print(to_mathml("x") is not None)
    """).splitlines() == ["['symvib', 'symvib.paper'] False", "True True True True True", "True", "True"]


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
        import symvib.numeric.figures, symvib.numeric.sweepmaps
        from symvib import simulate
        from symvib.numeric.scene import load_scene
        import symvib
        from pathlib import Path
        scene = load_scene(Path(symvib.__file__).parent / "scenes" / "paper-parabola.toml")
        result = simulate(scene, backend="python")
        paths = symvib.numeric.figures.save_run_figures(result, {str(tmp_path)!r}, only=["phase"])
        print(matplotlib.get_backend(), [p.suffix for p in paths])
    """) == "svg ['.png']"


def test_simulate_and_sweep_of_a_catalogue_curve_import_neither_sympy_nor_mpmath(tmp_path):
    # The wing boundary, tested for the jobs and not only for the kernels: the numeric
    # wing runs a curve whose kernels exist without the symbolic wing.
    assert _run(f"""
        import sys
        from symvib import simulate
        from symvib.numeric.scene import resolve_scene
        from symvib.numeric.sweep import sweep
        scene = resolve_scene("paper-circle-7")
        r = simulate(scene, backend="python")
        s = sweep(scene, {{"qdot": [6.0, 7.0]}}, backend="python", out={str(tmp_path / "out")!r}, progress=False)
        print(r.status.value, list(s.status_names()), 'sympy' in sys.modules, 'mpmath' in sys.modules)
    """) == "arrested ['arrested', 'arrested'] False False"


def test_top_level_simulate_load_scene_and_sweep_leave_sympy_unloaded():
    # symvib.simulate / load_scene / sweep are the light top-level names (symvib/api.py);
    # only derive loads SymPy.
    assert _run("""
        import sys
        import symvib
        symvib.simulate, symvib.load_scene, symvib.sweep
        before = 'sympy' in sys.modules
        r = symvib.simulate("paper-parabola", backend="python")
        q, qdot = r.state(1.0)
        s = symvib.sweep("paper-circle-7", {"qdot": [6.0, 7.0]}, backend="python", progress=False)
        print(before, r.status.value, len(s.status_names()), 'sympy' in sys.modules)
        symvib.derive
        print('sympy' in sys.modules)
    """).splitlines() == ["False arrested 2 False", "True"]
