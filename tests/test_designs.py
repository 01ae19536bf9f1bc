"""Designs: point counts, polynomial exactness against closed-form moments, sampling statistics,
pick-freeze structure and spec errors."""
import warnings
from itertools import combinations_with_replacement
from math import prod

import numpy as np
import pytest
from scipy import special

from uqflight.designs import DESIGN_KINDS, build_design, describe
from uqflight.designs import rules

# Errors are relative to Σ|w ξ^α|, the scale of the round-off: exact sums stay near 1e-15, a
# monomial beyond the degree errs by 1e-7 or (much) more.
EXACT = 1e-12
INEXACT = 1e-9


def moment(germ, power):
    """E[ξ^power]: (power − 1)!! for N(0, 1), 1/(power + 1) for U(−1, 1), 0 for odd powers."""
    if power % 2:
        return 0.0
    return float(prod(range(power - 1, 0, -2))) if germ == "normal" else 1.0 / (power + 1)


def exponents(d, total):
    """All α in N^d with |α| = total."""
    return np.array(
        [np.bincount(c, minlength=d) for c in combinations_with_replacement(range(d), total)]
    ).reshape(-1, d)


def relative_error(nodes_weights_values, exact):
    weights, values = nodes_weights_values
    scale = np.maximum(np.abs(weights) @ np.abs(values), np.finfo(float).tiny)  # 0 when ξ^α ≡ 0
    return np.abs(weights @ values - exact) / scale


def monomial_errors(design, germs, total):
    """Relative errors of Σ w ξ^α against E[ξ^α] for every α with |α| = total."""
    alphas = exponents(len(germs), total)
    powers = [design.xi[:, k, None] ** np.arange(total + 1) for k in range(len(germs))]
    exact = np.array([prod(moment(g, a) for g, a in zip(germs, alpha)) for alpha in alphas])
    errors = []
    for start in range(0, len(alphas), 2000):
        block = alphas[start : start + 2000]
        values = powers[0][:, block[:, 0]]
        for k in range(1, len(germs)):
            values *= powers[k][:, block[:, k]]
        errors.append(relative_error((design.weights, values), exact[start : start + 2000]))
    return np.concatenate(errors)


def assert_exact_to_its_degree(design, germs):
    """Exact for every monomial of total degree ≤ info["degree"], not for all of degree + 1."""
    degree = design.info["degree"]
    assert design.weights.sum() == pytest.approx(1.0, abs=EXACT)
    for total in range(1, degree + 1):
        assert monomial_errors(design, germs, total).max() < EXACT, f"degree {total}"
    assert monomial_errors(design, germs, degree + 1).max() > INEXACT


def sparse(germs, level, **keys):
    return build_design({"kind": "sparse_grid", "level": level, **keys}, germs, seed=0)


# --- sparse grid point counts -------------------------------------------------------------------


def test_non_nested_gauss_hermite_gives_the_papers_grids_in_7_dimensions():
    counts = [
        len(sparse(["normal"] * 7, level, rule="gauss_hermite", nested=False, growth="linear").xi)
        for level in range(5)
    ]
    assert counts == [1, 15, 113, 589, 2437]


@pytest.mark.parametrize("level", [2, 3, 4])
def test_nested_grid_is_smaller_than_non_nested_at_the_same_level(level):
    nested = sparse(["normal"] * 2, level, rule="gauss_hermite", nested=True)
    non_nested = sparse(["normal"] * 2, level, rule="gauss_hermite", nested=False)
    assert nested.info["rule"] == "genz_keister"
    assert len(nested.xi) < len(non_nested.xi)
    assert nested.info["degree"] >= non_nested.info["degree"]


def test_grid_points_are_distinct():
    design = sparse(["normal"] * 5, 3, rule="gauss_hermite")
    assert len(np.unique(design.xi.round(10), axis=0)) == len(design.xi)


# --- polynomial exactness -----------------------------------------------------------------------


@pytest.mark.parametrize("level, d", [
    pytest.param(level, d, marks=[pytest.mark.slow] if (level, d) == (4, 7) else [])  # 2437 points: the slow suite
    for d in (3, 4, 5, 6, 7) for level in (1, 2, 3, 4)])
def test_non_nested_gauss_hermite_is_exact_to_degree_2_level_plus_1(d, level):
    design = sparse(["normal"] * d, level, rule="gauss_hermite", nested=False)
    assert design.info["degree"] == 2 * level + 1
    assert_exact_to_its_degree(design, ["normal"] * d)


@pytest.mark.parametrize("growth", ["linear", "exponential"])
@pytest.mark.parametrize(
    "rule, germ",
    [
        ("genz_keister", "normal"),
        ("gauss_legendre", "uniform"),
        ("clenshaw_curtis", "uniform"),
        ("gauss_patterson", "uniform"),
    ],
)
@pytest.mark.parametrize("d", [2, 3])
@pytest.mark.parametrize("level", [0, 1, 2, 3])  # level 4 needs Genz–Keister 43 / Patterson 31
def test_sparse_grids_are_exact_to_their_degree(rule, germ, growth, d, level):
    design = sparse([germ] * d, level, rule=rule, growth=growth)
    if growth == "linear":
        assert design.info["degree"] >= 2 * level + 1
    assert_exact_to_its_degree(design, [germ] * d)


def test_mixed_germs_take_a_rule_per_germ():
    germs = ["normal", "uniform", "normal"]
    design = sparse(germs, 3, rule={"normal": "gauss_hermite", "uniform": "gauss_legendre"}, nested=True)
    assert design.info["rule"] == "genz_keister, gauss_patterson"
    assert_exact_to_its_degree(design, germs)


@pytest.mark.parametrize(
    "rule, germ, points",
    [
        ("gauss_hermite", "normal", 4),
        ("genz_keister", "normal", 9),
        ("gauss_legendre", "uniform", 5),
        ("clenshaw_curtis", "uniform", 6),
        ("clenshaw_curtis", "uniform", 7),
        ("gauss_patterson", "uniform", 7),
    ],
)
def test_tensor_grids_are_exact_to_their_degree(rule, germ, points):
    design = build_design({"kind": "tensor_grid", "rule": rule, "points": points}, [germ] * 2, 0)
    assert len(design.xi) == points**2
    assert design.info["degree"] == rules.degree(rule, points)
    assert_exact_to_its_degree(design, [germ] * 2)


@pytest.mark.parametrize(
    "rule, sizes",
    [
        ("gauss_hermite", range(1, 8)),
        ("genz_keister", rules.GENZ_KEISTER_SIZES[:4]),  # chaospy's 43-point weights: ~1e-9
        ("gauss_legendre", range(1, 8)),
        ("clenshaw_curtis", range(1, 12)),
        ("gauss_patterson", rules.PATTERSON_SIZES[:4]),  # beyond, x^(degree+1) errs below 1e-15
    ],
)
def test_one_dimensional_degrees(rule, sizes):
    germ = rules.RULE_TABLE[rule].germ
    for size in sizes:
        nodes, weights = rules.nodes_weights(rule, size)
        degree = rules.degree(rule, size)
        errors = [relative_error((weights, nodes**p), moment(germ, p)) for p in range(degree + 2)]
        assert max(errors[: degree + 1]) < EXACT and errors[degree + 1] > INEXACT, (rule, size)


@pytest.mark.parametrize("rule", ["genz_keister", "clenshaw_curtis", "gauss_patterson"])
def test_nested_rules_nest(rule):
    sizes = rules.nested_family(rule, 4)
    for small, large in zip(sizes, sizes[1:]):
        small_nodes, large_nodes = rules.nodes_weights(rule, small)[0], rules.nodes_weights(rule, large)[0]
        assert np.min(np.abs(small_nodes[:, None] - large_nodes), axis=1).max() < 1e-12


# --- sampling designs ---------------------------------------------------------------------------

GERMS = ["normal", "uniform", "normal"]
SAMPLING = [
    {"kind": "monte_carlo", "samples": 20000},
    {"kind": "sobol", "samples": 4096},
    {"kind": "halton", "samples": 4096},
    {"kind": "latin_hypercube", "samples": 4096},
]


@pytest.mark.parametrize("spec", SAMPLING, ids=lambda spec: spec["kind"])
def test_sample_moments_within_statistical_tolerance(spec):
    design = build_design(spec, GERMS, seed=7)
    n = spec["samples"]
    assert design.xi.shape == (n, 3)
    assert design.weights == pytest.approx(np.full(n, 1 / n))
    assert np.all(np.abs(design.xi[:, 1]) <= 1)
    variance = np.array([1.0, 1 / 3, 1.0])
    fourth = np.array([3.0, 1 / 5, 3.0])
    # 5 standard errors of the Monte Carlo estimators: a false alarm has probability ~1e-6;
    # QMC designs are at least as accurate.
    assert np.all(np.abs(design.xi.mean(axis=0)) < 5 * np.sqrt(variance / n))
    sample_variance = design.xi.var(axis=0)
    assert np.all(np.abs(sample_variance - variance) < 5 * np.sqrt((fourth - variance**2) / n))


@pytest.mark.parametrize("kind", ["monte_carlo", "sobol", "halton", "latin_hypercube", "pick_freeze"])
def test_same_seed_same_design_other_seed_other_design(kind):
    spec = {"kind": kind, "samples": 100}
    first, again, other = (build_design(spec, GERMS, seed) for seed in (3, 3, 4))
    assert np.array_equal(first.xi, again.xi)
    assert not np.allclose(first.xi, other.xi)


def test_latin_hypercube_has_one_point_per_stratum():
    n = 64
    design = build_design({"kind": "latin_hypercube", "samples": n}, GERMS, seed=1)
    u = np.column_stack([special.ndtr(design.xi[:, 0]), (design.xi[:, 1] + 1) / 2, special.ndtr(design.xi[:, 2])])
    for column in u.T:
        assert sorted(np.floor(n * column).astype(int)) == list(range(n))


@pytest.mark.parametrize("kind", ["sobol", "halton"])
@pytest.mark.parametrize("scramble", [True, False])
def test_qmc_takes_any_count_without_warnings_or_infinities(kind, scramble):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        design = build_design({"kind": kind, "samples": 1000, "scramble": scramble}, GERMS, 0)
    assert design.xi.shape == (1000, 3)
    assert np.all(np.isfinite(design.xi))


# --- pick-freeze --------------------------------------------------------------------------------


def test_pick_freeze_stacks_a_b_and_ab_i():
    n, d = 32, 3
    design = build_design({"kind": "pick_freeze", "samples": n}, GERMS, seed=2)
    assert design.xi.shape == (n * (d + 2), d)
    assert design.info["n_base"] == n
    assert design.weights == pytest.approx(np.full(n * (d + 2), 1 / (n * (d + 2))))
    a, b, ab = design.xi[:n], design.xi[n : 2 * n], design.xi[2 * n :].reshape(d, n, d)
    assert not np.allclose(a, b)
    for i in range(d):
        others = [j for j in range(d) if j != i]
        assert np.array_equal(ab[i][:, i], b[:, i])
        assert np.array_equal(ab[i][:, others], a[:, others])


# --- specs and description ----------------------------------------------------------------------


@pytest.mark.parametrize(
    "spec, germs, message",
    [
        ({"kind": "sparse_grid", "level": -1}, ["normal"], "design.level: expected an integer >= 0, got -1"),
        ({"kind": "sparse_grid"}, ["normal"], "design.level: missing; kind sparse_grid expects an integer >= 0"),
        ({"kind": "sparse_grid", "level": 2.0}, ["normal"], "design.level: expected an integer >= 0, got 2.0"),
        ({"kind": "monte_carlo"}, ["normal"], "design.samples: missing; kind monte_carlo expects an integer >= 1"),
        ({"kind": "sobol", "samples": 0}, ["normal"], "design.samples: expected an integer >= 1, got 0"),
        ({"kind": "halton", "samples": True}, ["normal"], "design.samples: expected an integer >= 1, got True"),
        ({"kind": "mc", "samples": 10}, ["normal"], "design.kind: expected one of monte_carlo, sobol"),
        ({"samples": 10}, ["normal"], "design.kind: expected one of .* got None"),
        ({"kind": "monte_carlo", "sample": 10}, ["normal"], "design.sample: unknown key for kind monte_carlo; accepted keys: kind, samples"),
        ({"kind": "sparse_grid", "level": 1, "rule": "simpson"}, ["normal"], "design.rule: expected one of gauss_hermite, genz_keister"),
        ({"kind": "sparse_grid", "level": 1, "rule": "gauss_legendre"}, ["normal"], "rule gauss_legendre is for uniform germs, but dimension 1 has a normal germ"),
        ({"kind": "sparse_grid", "level": 1, "rule": "gauss_hermite"}, ["normal", "uniform"], "rule gauss_hermite is for normal germs, but dimension 2 has a uniform germ"),
        ({"kind": "sparse_grid", "level": 1, "rule": {"normal": "gauss_hermite"}}, ["uniform"], "design.rule: no rule given for the uniform germ"),
        ({"kind": "sparse_grid", "level": 1, "rule": {"gaussian": "gauss_hermite"}}, ["normal"], "design.rule: a mapping's keys are germs"),
        ({"kind": "sparse_grid", "level": 1, "rule": "clenshaw_curtis", "nested": False}, ["uniform"], "design.nested: rule clenshaw_curtis is nested"),
        ({"kind": "sparse_grid", "level": 1, "nested": "yes"}, ["normal"], "design.nested: expected true or false, got 'yes'"),
        ({"kind": "sparse_grid", "level": 1, "growth": "fast"}, ["normal"], "design.growth: expected one of linear, exponential, got 'fast'"),
        ({"kind": "sparse_grid", "level": 5, "rule": "genz_keister", "growth": "exponential"}, ["normal"], "design.level: rule genz_keister with exponential growth reaches level 4 at most, got 5"),
        ({"kind": "tensor_grid", "rule": "genz_keister", "points": 5}, ["normal"], "design.points: rule genz_keister comes in 1, 3, 9, 19, 43 points, got 5"),
        ({"kind": "tensor_grid", "rule": "gauss_hermite"}, ["normal"], "design.points: missing"),
        ("sparse_grid", ["normal"], "design: expected a mapping"),
        ({"kind": "monte_carlo", "samples": 10}, [], "germs: expected a non-empty list"),
        ({"kind": "monte_carlo", "samples": 10}, ["gaussian"], "germs: expected a non-empty list of normal / uniform"),
    ],
)
def test_bad_specs_name_the_key_and_what_was_expected(spec, germs, message):
    with pytest.raises(ValueError, match=message):
        build_design(spec, germs, seed=0)


def test_seed_must_be_a_non_negative_integer():
    with pytest.raises(ValueError, match="seed: expected an integer >= 0, got -1"):
        build_design({"kind": "monte_carlo", "samples": 10}, ["normal"], seed=-1)


def test_every_kind_builds_and_describes_itself():
    specs = {
        "monte_carlo": {"samples": 10},
        "sobol": {"samples": 10},
        "halton": {"samples": 10},
        "latin_hypercube": {"samples": 10},
        "sparse_grid": {"level": 2},
        "tensor_grid": {"points": 3},
        "pick_freeze": {"samples": 10},
        "morris": {"trajectories": 3},
        "adaptive_sparse_grid": {"budget": 10, "tolerance": 1e-3},
        "subset_simulation": {"event": {"of": "y", "above": 1.0}, "samples_per_level": 20, "budget": 100},
        "importance_sampling": {"event": {"of": "y", "above": 1.0}, "samples": 20, "budget": 100},
        "active_learning": {"event": {"of": "y", "below": -1.0}, "budget": 500},
    }
    assert set(specs) == set(DESIGN_KINDS)
    for kind, keys in specs.items():
        design = build_design({"kind": kind, **keys}, GERMS, seed=0)
        assert design.kind == kind
        assert design.weights.sum() == pytest.approx(1.0)
        text = describe(design)
        assert text.startswith(f"{kind}: {len(design.xi)} points in 3 dimensions")
    assert "degree: 5" in describe(build_design({"kind": "sparse_grid", "level": 2}, GERMS, 0))


def test_the_design_kind_docstring_example_runs():
    import doctest

    from uqflight.designs import base

    result = doctest.testmod(base)
    assert result.attempted >= 3 and result.failed == 0


def test_a_design_refuses_a_value_with_its_fields_path_not_a_parsed_string():
    # the field travels in the error (text.FieldError), never recovered by splitting its message
    from uqflight.designs import build_design
    from uqflight.text import FieldError

    for spec, field in (({"kind": "sparse_grid", "level": -1}, "design.level"),
                        ({"kind": "monte_carlo", "samples": 4, "colour": 1}, "design.colour"),
                        ({"kind": "spiral"}, "design.kind")):
        with pytest.raises(FieldError) as refused:
            build_design(spec, ["normal", "normal"], 0)
        assert refused.value.field == field and str(refused.value) == f"{field}: {refused.value.message}"


def test_every_design_kind_class_has_examples_that_run():
    # each registered kind's class docstring shows the kind at work (numpydoc Examples), and the doctests
    # of every module holding a kind class run without a failure
    import doctest
    import importlib

    from uqflight.designs import REGISTRY, DesignKind

    assert all(isinstance(kind, DesignKind) for kind in REGISTRY.values())  # instances: their classes hold the docs
    without = [name for name, kind in REGISTRY.items()
               if ">>>" not in (type(kind).__doc__ or "") or "\n    Examples\n    --------\n" not in type(kind).__doc__]
    assert not without, f"design kinds without an Examples section: {without}"
    for module in sorted({type(kind).__module__ for kind in REGISTRY.values()}):
        result = doctest.testmod(importlib.import_module(module))
        assert result.attempted >= 1 and result.failed == 0, module
