"""How a user curve's F_sigma is found when its kernels are first generated (curve.closed_form):
the field and its errors, the routes each choice takes, the cache identity, the command line's
option and its progress line on a terminal."""
from __future__ import annotations

import io
import logging

import pytest

from symvib.codegen.generate import (
    AUTO_ROUTE_SECONDS,
    AUTO_ROUTES,
    AUTO_SEARCH_SECONDS,
    Plan,
    module_source,
    route_plan,
)
from symvib.numeric.scene import SceneError, scene_from_dict
from symvib.provenance import input_hash
from symvib.shapes import CLOSED_FORMS
from symvib.symbolic.integrals import ROUTE_SECONDS, ROUTES


def scene(z="a*x**2/2", **curve):
    return scene_from_dict({"curve": {"name": "cup", "z": z, **curve}, "parameters": {"a": 1.0},
                            "physics": {"mu": 0.1, "restitution": 0.8},
                            "limiters": {"left": -0.5, "right": 0.6}, "initial": {"q": 0.0, "qdot": 2.0}})


def test_each_choice_takes_its_routes_and_budget():
    assert route_plan("never").routes == ()
    assert route_plan("required") == Plan(ROUTES, ROUTE_SECONDS, None, "symbolic")
    assert route_plan("auto") == Plan(AUTO_ROUTES, AUTO_ROUTE_SECONDS, AUTO_SEARCH_SECONDS, "numeric")
    assert sorted(AUTO_ROUTES) == sorted(ROUTES)
    assert AUTO_ROUTE_SECONDS <= AUTO_SEARCH_SECONDS < ROUTE_SECONDS
    with pytest.raises(ValueError, match="curve.closed_form"):
        route_plan("sometimes")


def test_auto_spends_one_total_budget_on_all_routes(monkeypatch):
    """Under "auto" the routes share one budget: a route gets its own budget or what is left of the
    total, whichever is less; a curve with no elementary F_sigma ends its search within the total,
    the routes that found too little left are recorded as not tried, and the numeric F_sigma
    stands in."""
    from symvib.symbolic import integrals

    started = []
    real_start = integrals.budget.start

    def start(job, args, seconds):
        started.append(seconds)
        return real_start(job, args, seconds=seconds)

    monkeypatch.setattr(integrals.budget, "start", start)
    curve = scene(z="a*(1 - cos(x))").shape.curve()   # F_sigma: no elementary form
    plan = route_plan("auto")
    seconds, total = 0.6, 1.0
    found = integrals.antiderivatives(curve, seconds=seconds, routes=plan.routes, total=total, check=plan.check)
    assert all(F.route == "numeric" for F in found.values())
    assert started[:2] == [seconds, seconds] and max(started) <= seconds and sum(started[::2]) <= total + 1e-9
    assert [a.route for a in found[1].attempts] == list(plan.routes)
    outcomes = [a.outcome for a in found[1].attempts]
    assert outcomes[0].startswith("timeout") and outcomes[-1].startswith("not tried: the total budget")
    assert sum(a.seconds for a in found[1].attempts) < total + 0.5   # (starting and stopping the children)


def test_auto_tries_the_tangent_angle_route_first_and_checks_numerically():
    """The tilted parabola's F_sigma under "auto"'s routes and check (a budget long enough not to
    matter here): the tangent-angle route, first, finds both branches' (integrate takes 3-6 s
    on branch -1 alone), each checked numerically."""
    from symvib.symbolic import integrals

    plan = route_plan("auto")
    curve = scene(z="x**2/(2*a) + x/3").shape.curve()
    found = integrals.antiderivatives(curve, seconds=60.0, routes=plan.routes, total=180.0, check=plan.check)
    assert {F.route for F in found.values()} == {"tangent-angle"}
    assert {F.verification for F in found.values()} == {"numeric"}
    assert all(len(F.attempts) == 1 for F in found.values())


@pytest.mark.parametrize("value", ["sometimes", "", "AUTO", "never "])
def test_an_unknown_choice_names_the_field(value):
    with pytest.raises(SceneError) as err:
        scene(closed_form=value)
    assert err.value.field == "curve.closed_form"
    assert all(choice in err.value.reason for choice in CLOSED_FORMS)


@pytest.mark.parametrize("value", [1, True, ["never"]])
def test_a_choice_that_is_not_text_names_the_field(value):
    with pytest.raises(SceneError) as err:
        scene(closed_form=value)
    assert err.value.field == "curve.closed_form"


def test_a_catalogue_shape_takes_no_choice():
    with pytest.raises(SceneError) as err:
        scene_from_dict({"curve": {"shape": "parabola", "closed_form": "never"}, "parameters": {"p": 1},
                         "physics": {"mu": 0.1, "restitution": 0.8}, "initial": {"q": 0, "qdot": 1}})
    assert err.value.field == "curve.closed_form"


def test_the_default_keeps_a_curves_identity_and_another_choice_changes_it():
    """A cached module is found by the hash of the curve's defining data: "auto" (the default) leaves
    that data as it was before the field existed, so kernels cached earlier are used; "never" and
    "required" make other modules."""
    auto, never, required = (scene(closed_form=c).shape for c in ("auto", "never", "required"))
    assert "closed_form" not in auto.source() and auto.source() == scene().shape.source()
    hashes = {input_hash(s.source()) for s in (auto, never, required)}
    assert len(hashes) == 3
    assert scene_from_dict(scene(closed_form="never").to_dict()).shape.closed_form == "never"   # round trip


def test_never_takes_the_numeric_antiderivative_of_a_curve_that_has_a_closed_form():
    shape = scene(closed_form="never").shape
    text = module_source(shape, origin="<test>")
    assert "F_ROUTES = {1: 'numeric', -1: 'numeric'}" in text
    closed = module_source(scene(closed_form="required").shape, origin="<test>")
    assert "'numeric'" not in closed.split("F_ROUTES = ", 1)[1].split("\n", 1)[0]


def test_required_fails_naming_the_field_when_no_route_finds_a_closed_form():
    shape = scene(z="a*(1 - cos(x))", closed_form="required").shape   # F_sigma: no elementary form
    with pytest.raises(ValueError, match=r"curve.closed_form: 'required'.*no closed form"):
        module_source(shape, seconds=0.5, origin="<test>")


@pytest.mark.slow
def test_never_and_required_give_the_same_events():
    from symvib import simulate

    runs = [simulate(scene(closed_form=c), backend="python", samples=False) for c in ("never", "required")]
    assert [e.kind for e in runs[0].events] == [e.kind for e in runs[1].events] and runs[0].events
    for a, b in zip(runs[0].events, runs[1].events):
        assert a.t == pytest.approx(b.t, rel=1e-12, abs=1e-13) and a.q == pytest.approx(b.q, rel=1e-12, abs=1e-13)


class _Terminal(io.StringIO):
    def isatty(self):
        return True


def test_progress_lines_show_on_a_terminal_only():
    from symvib.cli.command import _progress_on_terminal

    logger = logging.getLogger("symvib")
    before, level = list(logger.handlers), logger.level
    try:
        piped = io.StringIO()
        _progress_on_terminal("run", piped)
        assert logger.handlers == before
        tty = _Terminal()
        _progress_on_terminal("run", tty)
        _progress_on_terminal("run", tty)   # once
        logging.getLogger("symvib.numeric.kernels").info("deriving the kernels of curve %r", "cup")
        assert tty.getvalue() == "symvib run: deriving the kernels of curve 'cup'\n"
        assert piped.getvalue() == ""
    finally:
        logger.handlers[:] = before
        logger.setLevel(level)


def test_the_option_refuses_a_catalogue_curve(tmp_path, capsys):
    from symvib.cli import main

    path = tmp_path / "s.toml"
    path.write_text('[curve]\nshape = "parabola"\n[parameters]\np = 1\n[physics]\nmu = 0.1\nrestitution = 0.8\n'
                    '[initial]\nq = 0\nqdot = 1\n', encoding="utf-8")
    assert main(["run", str(path), "--closed-form", "never"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--closed-form" in err and "catalogue" in err


def test_a_user_curve_says_it_is_being_prepared_and_a_catalogue_curve_says_nothing(caplog, tmp_path, monkeypatch):
    """The first progress line comes before SymPy is imported (the singular points of a user curve),
    so a terminal sees it at once; a catalogue curve has nothing to prepare."""
    from symvib.numeric.scene import resolve_scene
    from symvib.prepare import prepare

    monkeypatch.setenv("SYMVIB_CACHE", str(tmp_path))   # its first time, whatever ran before
    with caplog.at_level(logging.INFO, logger="symvib"):
        prepare(resolve_scene("paper-parabola"))
        assert not caplog.records
        prepare(scene())
    assert [r.getMessage() for r in caplog.records][:1] == ["preparing curve 'cup': its singular points and kernels"]
