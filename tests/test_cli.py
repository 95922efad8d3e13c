"""The command line: run (table, JSON, figures), derive, audit, and one-line errors for bad input."""
import json
import subprocess
import sys
from pathlib import Path

from symvib.numeric.figures import FIGURE_NAMES

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "symvib" / "scenes" / "paper-circle-3.8.toml"


def cli(*args, cwd=ROOT):
    return subprocess.run([sys.executable, "-m", "symvib.cli", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, env={"SYMVIB_BACKEND": "python", "PATH": "/usr/bin:/bin",
                                        "HOME": str(Path.home())})


def test_run_prints_table_and_writes_json_and_figures(tmp_path):
    out = cli("run", SCENE, "--json", tmp_path / "r.json", "--plot", tmp_path / "fig")
    assert out.returncode == 0, out.stderr
    assert "impact" in out.stdout and "status: arrested" in out.stdout
    data = json.loads((tmp_path / "r.json").read_text())
    assert data["status"] == "arrested"
    assert [e["kind"] for e in data["events"]] == ["impact", "reversal", "reversal", "arrest"]
    assert set(data["energy_budget"]) == {"initial", "final", "friction_work", "impact_loss", "residual"}
    assert abs(data["energy_budget"]["residual"]) < 1e-12 * data["energy_budget"]["initial"]
    assert len(list((tmp_path / "fig").glob("*.png"))) == len(FIGURE_NAMES)  # issue 16: the sketch and force plan too


def test_bad_scene_is_one_line_naming_the_field(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(SCENE.read_text().replace("restitution = 1.0", "restitution = 1.7"))
    out = cli("run", bad)
    assert out.returncode == 2
    assert out.stderr.strip() == ("symvib run: error: physics.restitution: must be in [0, 1] "
                                  "(1 = ideally elastic, 0 = plastic), got 1.7")
    injected = tmp_path / "evil.toml"
    injected.write_text(SCENE.read_text().replace('q = "pi/12"', 'q = "__import__(\'os\').system(\'echo hi\')"'))
    out = cli("run", injected)
    assert out.returncode == 2 and "initial.q" in out.stderr and "Traceback" not in out.stderr


def test_run_and_sweep_take_static_friction_from_the_scene_and_vary_it(tmp_path):
    static = tmp_path / "static.toml"
    text = SCENE.read_text()
    assert "\nrestitution = " in text
    static.write_text(text.replace("\nrestitution = ", "\nmu_s = 5.0\nrestitution = ", 1))
    out = cli("run", static, "--json", tmp_path / "r.json")
    assert out.returncode == 0, out.stderr
    assert "mu_s = 5" in out.stdout
    data = json.loads((tmp_path / "r.json").read_text())
    assert [e["kind"] for e in data["events"]] == ["impact", "arrest"]     # held at its first turning point
    assert data["units"]["scene"]["physics.mu_s"] == "1"
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace("\nrestitution = ", "\nmu_s = 0.01\nrestitution = ", 1))
    out = cli("run", bad)
    assert out.returncode == 2 and out.stderr.startswith("symvib run: error: physics.mu_s: static friction")
    out = cli("sweep", SCENE, "--vary", "mu_s=0.2,5", "-o", tmp_path / "sweep", "--backend", "python", "--quiet")
    assert out.returncode == 0, out.stderr
    out = cli("sweep", SCENE, "--vary", "mu_s=0.01,5", "-o", tmp_path / "bad-sweep", "--backend", "python")
    assert out.returncode == 2 and "physics.mu_s" in out.stderr


def test_derive_and_audit():
    out = cli("derive", "circle")
    assert out.returncode == 0 and "route: sympy" in out.stdout and "s = +1: symbolic" in out.stdout
    out = cli("derive", "--z", "x**2/(2*p)", "--budget", "5")
    assert out.returncode == 0 and "xdot" in out.stdout
    out = cli("derive", "--z", "import os")
    assert out.returncode == 2 and "curve.z" in out.stderr
    out = cli("audit")
    assert out.returncode == 0 and "DIFFERS" in out.stdout


def test_generate_for_a_scene_and_an_expression(tmp_path):
    scene = tmp_path / "bowl.toml"
    scene.write_text(SCENE.read_text().replace('shape = "circle"', 'z = "x**2/(2*b)"\nname = "bowl"')
                     .replace("R = 0.5", "b = 0.5").replace('right = "pi/4"', "right = 0.5")
                     .replace('q = "pi/12"', "q = 0.1"))
    out = cli("generate", "--scene", scene, "--out", tmp_path / "k")
    assert out.returncode == 0, out.stderr
    text = (tmp_path / "k" / "bowl.py").read_text()
    assert "def w_p(q, C, g, mu, b):" in text and "import sympy" not in text
    out = cli("generate", "--z", "x**4", "--name", "quartic_user", "--out", tmp_path / "k", "--budget", "0.5")
    assert out.returncode == 0 and (tmp_path / "k" / "quartic_user.py").exists()
    out = cli("generate", "--scene", scene)
    assert out.returncode == 2 and "--out" in out.stderr


def test_forwarded_subcommands_take_a_leading_option():
    # bench and sweep parse their own options; a leading one (--help) reaches them.
    for name in ("bench", "sweep"):
        out = cli(name, "--help")
        assert out.returncode == 0, out.stderr
        assert out.stdout.startswith(f"usage: symvib {name}")
    listing = cli("--help")
    assert listing.returncode == 0 and "bench" in listing.stdout and "sweep" in listing.stdout


def test_the_command_leaves_with_its_status_after_exit_handlers_and_every_byte_of_output():
    # symvib.cli.command.leave skips the interpreter's teardown (os._exit): the exit handlers must
    # still run, both streams reach the reader whole, and the status is the command's.
    code = ("import atexit, sys\n"
            "atexit.register(lambda: print('handler ran', file=sys.stderr))\n"
            "from symvib.cli.command import leave\n"
            "sys.stdout.write('x' * 200_000)\n"
            "leave(3)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 3
    assert out.stdout == "x" * 200_000
    assert "handler ran" in out.stderr
    none = subprocess.run([sys.executable, "-c", "from symvib.cli.command import leave; leave(None)"], timeout=120)
    assert none.returncode == 0


def test_the_command_reports_output_it_could_not_deliver_as_a_failure():
    # A stream whose flush fails at the end (a reader that closed the pipe) turns success into 1.
    code = ("import sys\n"
            "class Closed:\n"
            "    def write(self, text): return len(text)\n"
            "    def flush(self): raise BrokenPipeError(32, 'Broken pipe')\n"
            "sys.stdout = Closed()\n"
            "from symvib.cli.command import leave\n"
            "leave(0)\n")
    assert subprocess.run([sys.executable, "-c", code], timeout=120).returncode == 1


def test_python_dash_m_symvib_cli_exits_with_main_s_status():
    bad = cli("run", "no-such-scene")
    assert bad.returncode == 2 and "error" in bad.stderr
