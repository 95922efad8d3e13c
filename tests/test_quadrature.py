"""Gauss-Legendre rules of the driver: the table (generated/gauss_rules.json), its format and its reader."""
from pathlib import Path

import mpmath
import pytest

from symvib import simulate
from symvib.checks.reference import phase_reference
from symvib.codegen import gauss
from symvib.numeric.quadrature import MAX_NODES, rule
from symvib.numeric.scene import load_scene

ROOT = Path(__file__).resolve().parents[1]


def test_generated_table_is_a_fresh_computation():
    assert gauss.table_problems(ROOT / "generated") == []


@pytest.mark.parametrize("n", [1, 2, 5, 16, 32, 9])  # 9 is not tabulated: computed with mpmath
def test_rule_integrates_polynomials_exactly(n):
    r = rule(n)
    x = [mpmath.mpf(v) for v in r.x]
    for m in range(2 * n):       # Gauss weights: degree 2n - 1
        exact = mpmath.mpf(1 - (-1) ** (m + 1)) / (m + 1)
        got = mpmath.fsum(mpmath.mpf(w) * xi ** m for w, xi in zip(r.weights, x))
        assert abs(got - exact) < 1e-15 * max(1, abs(exact)), m
    for m in range(n):           # cumulative matrices: degree n - 1 (and n with the weight x + 1)
        f = [xi ** m for xi in x]
        for j in range(n):
            s = mpmath.fsum(mpmath.mpf(a) * b for a, b in zip(r.cumulative[j], f))
            exact = (x[j] ** (m + 1) - (-1) ** (m + 1)) / (m + 1)
            assert abs(s - exact) < 1e-14 * max(1, sum(abs(a) for a in r.cumulative[j])), (m, j)
            sw = mpmath.fsum(mpmath.mpf(a) * b for a, b in zip(r.cumulative_weighted[j], f))
            exact_w = (x[j] ** (m + 2) - (-1) ** (m + 2)) / (m + 2) + exact
            assert abs(sw - exact_w) < 1e-14 * max(1, sum(abs(a) for a in r.cumulative_weighted[j])), (m, j)


@pytest.mark.parametrize("n", [16, 24, 32])
def test_weighted_rows_near_the_end_keep_relative_accuracy(n):
    # G next to a turning point is rebuilt from these rows; their sums are tiny
    # ((x_j + 1)^2 / 2), so only correctly rounded entries keep G's relative
    # accuracy (a double-precision matrix was off by 6e-13 at n = 16).
    r = rule(n)
    for j in range(3):
        exact = (mpmath.mpf(r.x[j]) + 1) ** 2 / 2
        got = mpmath.fsum(mpmath.mpf(v) for v in r.cumulative_weighted[j])
        assert abs(got / exact - 1) < 5e-14  # sum of n rounded entries


def test_bad_node_counts_name_the_field():
    for bad in (0, MAX_NODES + 1, 2.5, True):
        with pytest.raises(ValueError, match="nodes"):
            rule(bad)


def test_long_run_of_turning_points_meets_the_reference_to_a_few_ulp():
    # 29 events over 25 s: each interval used to lose 3e-15 s to the rounding of
    # the integration matrices (1e-13 at the end); now the error stays at the
    # rounding floor of the times themselves.
    scene = load_scene(ROOT / "symvib" / "scenes" / "paper-parabola.toml").replace(k=0.8, mu=0.0152, qdot0=7.946)
    ref = phase_reference(scene)
    for nodes in (16, 32):
        run = simulate(scene, samples=False, nodes=nodes, backend="python")
        assert [e.kind.value for e in run.events] == [r.kind for r in ref]
        err = max(abs(e.t - float(r.t)) for e, r in zip(run.events, ref))
        assert err < 2e-14, (nodes, err)


def test_the_table_reads_back_every_double_exactly():
    from symvib.quadrature_rules import read_table, table_text

    rules = {n: rule_mp_tuple(n) for n in (1, 5, 16)}
    assert read_table(table_text(rules), "t") == rules


def rule_mp_tuple(n):
    x, w, S, SW = gauss.rule_mp(n)
    return tuple(x), tuple(w), tuple(map(tuple, S)), tuple(map(tuple, SW))


@pytest.mark.parametrize("damage", ["digit", "truncated", "head", "empty"])
def test_a_table_edited_by_hand_or_truncated_is_refused_naming_the_file(damage):
    from symvib.quadrature_rules import TableError, read_table, table_text

    text = table_text({n: rule_mp_tuple(n) for n in (1, 2, 3)})
    bad = {"digit": text.replace("0.5773502691896257", "0.5773502691896258", 1),
           "truncated": text[: len(text) // 2],
           "head": text.replace('{"body_sha256": "', '{"body_sha": "', 1),
           "empty": ""}[damage]
    assert bad != text
    with pytest.raises(TableError, match=r"gauss_rules\.json.*run `symvib generate`"):
        read_table(bad, "generated/gauss_rules.json")


def test_a_table_with_a_valid_digest_but_wrong_shapes_is_refused():
    import hashlib

    from symvib.quadrature_rules import TABLE_HEAD, TableError, read_table, table_text

    text = table_text({2: rule_mp_tuple(2)})
    body = text.partition("\n")[2].replace('"2": {', '"3": {', 1)        # a 2-point rule under the key 3
    forged = TABLE_HEAD + hashlib.sha256(body.encode()).hexdigest() + '",\n' + body
    with pytest.raises(TableError, match="rule 3 is not n finite nodes"):
        read_table(forged, "t")
    body = text.partition("\n")[2].replace("1.0, 1.0", "NaN, 1.0", 1)     # a weight that is not finite
    forged = TABLE_HEAD + hashlib.sha256(body.encode()).hexdigest() + '",\n' + body
    with pytest.raises(TableError, match="not n finite"):
        read_table(forged, "t")


def test_the_table_is_data_read_without_executing_code():
    # The table used to be a Python module, checked by the kernel whitelist and executed;
    # now it is JSON, and no module of that name exists in the generated folder.
    from symvib.numeric.kernels import generated_dir

    assert (generated_dir() / gauss.TABLE_FILE).suffix == ".json"
    assert not (generated_dir() / gauss.LEGACY_MODULE).exists()
    assert not list(generated_dir().glob("gauss*.py"))
