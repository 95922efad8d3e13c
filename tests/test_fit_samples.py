"""Fitting parameters to a sampled trajectory (symvib/numeric/fit.py with symvib/numeric/fit_data.py)."""
import subprocess
import sys
import warnings

import numpy as np
import pytest

import symvib
from symvib.numeric.fit import fit, observed_samples, read_observations, read_samples
from symvib.numeric.fit_data import Observed, ObservedSamples
from symvib.numeric.sample_sensitivity import sample_positions
from symvib.numeric.scene import resolve_scene
from symvib.paths import UserPathError

TRUTH = resolve_scene("paper-parabola").replace(mu=0.03, k=0.8)
TIMES = np.linspace(0.05, 6.0, 30)


def positions(scene, coordinates, times=TIMES):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return sample_positions(symvib.simulate(scene), times, coordinates)


def test_noise_free_samples_of_q_give_back_mu_and_k():
    q = positions(TRUTH, "q")[:, 0]
    result = fit(TRUTH.replace(mu=0.05, k=0.7), observed_samples(TIMES, q=q), free=("mu", "k"))
    assert result.status == "converged", result.message
    assert result.estimates["mu"] == pytest.approx(0.03, rel=1e-8)
    assert result.estimates["k"] == pytest.approx(0.8, rel=1e-8)
    assert result.matched == len(TIMES) and np.max(np.abs(result.residuals)) < 1e-10
    assert "30 samples of q" in result.summary()


@pytest.mark.parametrize("seed", [3, 11])
def test_noisy_samples_of_x_and_z_give_mu_and_k_within_three_standard_errors(seed):
    xz = positions(TRUTH, "xz")
    rng = np.random.default_rng(seed)
    sigma = 2e-3                                              # 2 mm of tracking noise, known
    noisy = xz + rng.normal(0.0, sigma, xz.shape)
    observed = observed_samples(TIMES, x=noisy[:, 0], z=noisy[:, 1])
    result = fit(TRUTH.replace(mu=0.04, k=0.75), observed, free=("mu", "k"), weights=np.full(observed.count, 1 / sigma))
    assert result.status == "converged", result.message
    for name, true in (("mu", 0.03), ("k", 0.8)):
        assert abs(result.estimates[name] - true) <= 3 * result.stderr[name], (name, result.summary())
    assert len(result.residuals) == 2 * len(TIMES)
    # the weighted residuals scatter as the noise: chi^2 / dof within its sampling spread
    assert 0.6 < 2 * result.cost / (observed.count - 2) < 1.5


def test_arc_length_samples_through_the_top_level_verb_and_a_dict():
    s = positions(TRUTH, "s")[:, 0]
    result = symvib.fit(TRUTH.replace(mu=0.035, k=0.78), {"t": TIMES[:12], "s": s[:12]}, free=("mu", "k"))
    assert result.status == "converged", result.message
    assert result.estimates["k"] == pytest.approx(0.8, rel=1e-7) and result.data == "s"


@pytest.mark.parametrize("kwargs, match", [
    ({"t": [0.3, 0.2], "q": [0.0, 0.1]}, "observed.t: the times must be ascending"),
    ({"t": [0.1, float("nan")], "q": [0.0, 0.1]}, "observed.t: time 2 is not a finite number"),
    ({"t": [0.1, 0.2], "q": [0.0, float("nan")]}, "observed.q: sample 2 is not a finite number"),
    ({"t": [-0.1, 0.2], "q": [0.0, 0.1]}, "observed.t: sample 1 is at -0.1 s, before the run starts"),
    ({"t": [0.1, 0.2], "x": [0.0, 0.1]}, "give q, or x and z, or s .*got x"),
    ({"t": [0.1, 0.2], "q": [0.0, 0.1], "s": [0.0, 0.1]}, "give q, or x and z, or s"),
    ({"t": [0.1, 0.2], "s": [0.0]}, "observed.s: 1 values for 2 times"),
    ({"t": []}, "observed.t: no sample times"),
])
def test_bad_samples_are_refused_naming_the_field(kwargs, match):
    with pytest.raises(ValueError, match=match):
        observed_samples(kwargs.pop("t"), **kwargs)


def test_a_fit_refuses_too_few_samples_and_a_sample_after_the_run_s_end():
    with pytest.raises(ValueError, match="free: 3 parameters from 2 observations"):
        fit(TRUTH, observed_samples([0.1, 0.2], q=[0.0, 0.1]), free=("mu", "k", "qdot0"))
    stopped = TRUTH.replace(t_max=2.0)                           # its run ends at t = 2 s, moving
    with pytest.raises(ValueError, match=r"observed.t: the last sample \(3.0 s\) comes after the run's end"):
        fit(stopped, observed_samples([1.0, 3.0], q=[0.0, 0.1]), free=("mu",))


def test_a_csv_file_is_told_events_or_samples_by_its_columns(tmp_path):
    def write(text):
        path = tmp_path / "data.csv"
        path.write_text(text, encoding="utf-8")
        return path

    assert isinstance(read_observations(write("t,q\n0.1,0.5\n0.2,0.4\n")), ObservedSamples)
    xz = read_observations(write("t,x,z\n0.1,0.5,0.1\n\n0.2,0.4,0.05\n"))
    assert xz.coordinates == "xz" and xz.values.tolist() == [[0.5, 0.1], [0.4, 0.05]]
    assert read_observations(write("t,s\n0.1,0.5\n")).coordinates == "s"
    assert isinstance(read_observations(write("t,kind,q\n0.1,impact,0.78\n")), Observed)
    assert isinstance(read_observations(write("t\n0.1\n0.3\n")), Observed)
    for text, match in (("t,x\n0.1,0.5\n", "needs a column t"),
                        ("t,q\n0.2,0.5\n0.1,0.4\n", "observed.t: the times must be ascending"),
                        ("t,q\n0.1,nan\n", "row 2, column q: 'nan' is not a finite number"),
                        ("t,s\n0.1,__import__('os')\n", "row 2, column s: .* is not a number"),
                        ("t,x,z\n0.1,0.5\n", "row 2 has 2 cells for 3 columns"),
                        ("t,q,Q\n0.1,0.5,0.5\n", "names column 'q' twice")):
        with pytest.raises(ValueError, match=match):
            read_observations(write(text))
    with pytest.raises(ValueError, match="a sampled trajectory needs t and q"):
        read_samples(write("t,kind\n0.1,impact\n"))


def test_symvib_fit_on_the_command_line_detects_a_sampled_trajectory(tmp_path):
    xz = positions(resolve_scene("paper-parabola").replace(mu=0.03), "xz", TIMES[:10])   # the file's k
    data = tmp_path / "track.csv"
    rows = "".join(f"{t!r},{x!r},{z!r}\n" for t, (x, z) in zip(TIMES[:10].tolist(), xz.tolist()))
    data.write_text("t,x,z\n" + rows, encoding="utf-8")
    out = subprocess.run([sys.executable, "-m", "symvib.cli", "fit", "paper-parabola", str(data), "--free", "mu",
                          "--plot", str(tmp_path / "res.png")], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    assert "10 samples of xz, 20 observations" in out.stdout and "mu     = 0.03" in out.stdout
    assert (tmp_path / "res.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    help_text = " ".join(subprocess.run([sys.executable, "-m", "symvib.cli", "fit", "--help"], capture_output=True,
                                        text=True, timeout=600).stdout.split())
    assert "sampled trajectory" in help_text and "x,z" in help_text


#: Hostile data files -> what the error says (each names the file, and the row and column or the header).
HOSTILE_CSV = {
    "nan time": ("t,q\nnan,0.1\n0.2,0.1\n", "row 2, column t: 'nan' is not a finite number"),
    "inf position": ("t,q\n0.1,inf\n", "row 2, column q: 'inf' is not a finite number"),
    "overflowing number": ("t,q\n0.1,1e999\n", "row 2, column q: '1e999' is not a finite number"),
    "digit separator": ("t,q\n1_0,0.1\n", "row 2, column t: '1_0' is not a number"),
    "arabic-indic digit": ("t,q\n\u0661,0\n", "row 2, column t: .* is not a number"),
    "nul byte": ("t,q\n\x00,0\n", "row 2, column t: .* is not a number"),
    "semicolons": ("t;q\n0.1;0\n", "separate the columns by commas"),
    "tabs": ("t\tq\n0.1\t0\n", "separate the columns by commas"),
    "unnamed column": ("t,,q\n0.1,,0\n", "column 2 has no name"),
    "x without z": ("t,x\n0.1,0\n", "or t with q, x and z, or s"),
    "s and q": ("t,s,q\n0.1,0,0\n", "or t with q, x and z, or s"),
    "unknown column": ("t,y\n0.1,0\n", "needs a column t"),
    "header only": ("t,q\n", r"data.csv: observed.t: no sample times"),
    "descending": ("t,q\n0.2,0\n0.1,0\n", r"data.csv: observed.t: the times must be ascending"),
    "negative time": ("t,q\n-0.1,0\n", r"data.csv: observed.t: sample 1 is at -0.1 s"),
    "code as kind": ("t,kind\n0.1,impact\n0.2,__import__('os')\n", r"data.csv: observed.kind: event 2 is"),
    "unclosed quote": ('"t\n,q\n0.1,0\n', "row 3: not comma-separated values .*unexpected end of data"),
    "unclosed quote at the end": ('t,q\n0.1,"0', "row 2: not comma-separated values"),
    "text after a quote": ('t,q\n"0.1"x,0\n', "row 2: not comma-separated values"),
    "cell beyond the csv field limit": ('t,q\n"' + "1" * 200_000 + '",0\n', "row 2: not comma-separated .*limit"),
    "wide header": ("t," + ",".join(f"c{i}" for i in range(60_000)) + "\n", r"has 60001 columns; .* at most 3"),
    "long column name": ("t," + "q" * 100_000 + "\n0.1,0\n", r"header \['t', 'qqqq.*\.\.\.: needs a column t"),
    "long kind": ("t,kind\n0.1," + "x" * 100_000 + "\n", r"observed.kind: event 1 is 'xxxx.*\.\.\., not one of"),
    "long cell": ("t,q\n0.1," + "9" * 400 + "x\n", r"row 2, column q: '9999.*\.\.\. is not a number"),
    "short row": ("t,q\n0.1\n", "row 2 has 1 cells for 2 columns"),
    "duplicate upper case": ("t,q,Q\n0.1,0,0\n", "names column 'q' twice"),
    "empty": ("", "empty; give a header row"),
}


@pytest.mark.parametrize("case", sorted(HOSTILE_CSV))
def test_hostile_data_files_are_refused_naming_the_file_and_the_cell(case, tmp_path):
    text, match = HOSTILE_CSV[case]
    path = tmp_path / "data.csv"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ValueError, match=match) as info:
        read_observations(path)
    assert str(path) in str(info.value) and "\n" not in str(info.value) and len(str(info.value)) < 1000


@pytest.mark.parametrize("raw, kind, t", [
    (b"\xef\xbb\xbft,q\r\n0.1,0.0\r\n0.2,0.01\r\n", ObservedSamples, [0.1, 0.2]),   # spreadsheet: BOM, CRLF
    (b" T , Q \n0.1,0\n", ObservedSamples, [0.1]),                                     # spaces, upper case
    (b'kind,t\nimpact,"0.1"\n', Observed, [0.1]),                                      # columns swapped, quoted
])
def test_spreadsheet_exports_are_read(raw, kind, t, tmp_path):
    path = tmp_path / "data.csv"
    path.write_bytes(raw)
    observed = read_observations(path)
    assert isinstance(observed, kind) and observed.t.tolist() == t


def test_a_utf16_data_file_is_refused_naming_the_file(tmp_path):
    path = tmp_path / "data.csv"
    path.write_text("t,q\n0.1,0\n", encoding="utf-16")
    with pytest.raises(UserPathError, match="data.csv: data file is not UTF-8"):
        read_observations(path)


@pytest.mark.parametrize("kwargs, match", [
    ({"t": "abc", "q": [1, 2, 3]}, "observed.t: give numbers"),
    ({"t": [1j, 2j], "q": [1, 2]}, "observed.t: give numbers"),
    ({"t": [0.1, 0.2, 0.3], "q": ["a", "b", "c"]}, "observed.q: give numbers"),
    ({"t": [0.1], "x": {"a": 1}, "z": [0]}, "observed.x: give numbers"),
    ({"t": None, "q": [1]}, "observed.t: time 1 is not a finite number"),
])
def test_samples_that_are_not_numbers_are_refused_naming_the_field(kwargs, match):
    with pytest.raises(ValueError, match=match):
        observed_samples(kwargs.pop("t"), **kwargs)


@pytest.mark.parametrize("observed, match", [
    ({"t": [0.1, 0.2], "y": [0.0, 0.1]}, "observed: a dict of samples has the keys t with q.*'y'"),
    ({"q": [0.0, 0.1]}, "observed: a dict of samples has the keys t"),
    (0.5, "observed: a CSV file, a list of impact times.*got float"),
    (None, "observed: a CSV file, a list of impact times.*got NoneType"),
    (["a", "b"], "observed.t: give numbers"),
])
def test_the_top_level_fit_refuses_observations_of_the_wrong_shape(observed, match):
    with pytest.raises(ValueError, match=match):
        symvib.fit("paper-parabola", observed, free=("mu",))
