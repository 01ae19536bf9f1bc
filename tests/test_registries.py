"""Every registered germ, distribution, rule, design and method, picked up from its registry and checked
against closed forms: a new entry is tested without a new test."""
import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from uqflight.designs import REGISTRY as DESIGNS
from uqflight.designs import build_design, design_size
from uqflight.designs.rules import RULE_TABLE, nodes_weights
from uqflight.methods import METHODS, fit
from uqflight.methods.basis import orthonormal_basis, orthonormal_polynomials, total_degree_indices
from uqflight.parameters import DISTRIBUTIONS, GERMS, make_parameter
from uqflight.simulators.kinds import REGISTRY as SIMULATORS
from uqflight.simulators.scenarios import REGISTRY as SCENARIOS

GERM_NAMES = list(GERMS)


@pytest.mark.parametrize("germ", GERM_NAMES)
def test_a_germs_polynomials_are_orthonormal_under_its_default_rule(germ):
    # a 12-point Gauss rule is exact to degree 23 ≥ 2·8: the Gram matrix of p_0..p_8 is the identity
    nodes, weights = nodes_weights(GERMS[germ].default_rule, 12)
    values = orthonormal_polynomials(germ, nodes, 8)
    np.testing.assert_allclose(values.T @ (weights[:, None] * values), np.eye(9), atol=1e-11)
    assert RULE_TABLE[GERMS[germ].default_rule].germ == RULE_TABLE[GERMS[germ].nested_rule].germ == germ


@pytest.mark.parametrize("germ", GERM_NAMES)
def test_a_germs_density_is_its_quantiles_derivative_and_its_draws_follow_its_law(germ):
    """p(Q(u)) Q'(u) = 1 (the density is the CDF's derivative; central differences, h = 1e-6: error
    ~1e-8), −inf just outside a finite support; 100,000 draws have the law's mean 0 and variance
    (quadrature) within 5 standard errors."""
    law = GERMS[germ]
    u, h = np.linspace(0.05, 0.95, 19), 1e-6
    slope = (law.quantile(u + h) - law.quantile(u - h)) / (2 * h)
    np.testing.assert_allclose(np.exp(law.log_density(law.quantile(u))) * slope, 1.0, rtol=1e-6)
    lower, upper = law.support
    for edge, outside in ((lower, lower - 1e-9), (upper, upper + 1e-9)):
        if np.isfinite(edge):
            assert law.log_density(np.array([outside]))[0] == -np.inf
            assert np.isfinite(law.log_density(np.array([edge]))[0])
    draws = law.sample(np.random.default_rng(1), 100_000)
    nodes, weights = nodes_weights(law.default_rule, 12)
    variance = weights @ nodes**2
    assert abs(draws.mean()) < 5 * math.sqrt(variance / draws.size)
    assert draws.var() == pytest.approx(variance, rel=5 * math.sqrt(2 / draws.size) * 1.5)


@pytest.mark.parametrize("germ", GERM_NAMES)
def test_a_germs_quantile_maps_uniforms_to_its_law(germ):
    u = (np.arange(20000) + 0.5) / 20000
    xi = GERMS[germ].quantile(u)
    nodes, weights = nodes_weights(GERMS[germ].default_rule, 10)
    for power in (1, 2, 4):  # midpoint rule in u against the Gauss rule; the normal's tails beyond the
        # outermost midpoints (|ξ| > 4.4) hold 4e-4 of E[ξ⁴]'s 3, hence 5e-3
        assert np.mean(xi**power) == pytest.approx(weights @ nodes**power, abs=5e-3)


@pytest.mark.parametrize("germ", GERM_NAMES)
def test_a_germs_normal_map_is_its_quantile_of_the_normal_cdf_and_inverts(germ):
    # the Nataf transform's step (parameters.dependence): ξ = Q(Φ(z)), increasing, and back; |z| <= 6
    # keeps Φ's tail to 1e-9 relative in the uniform germ, hence 1e-6 on z
    from scipy import special

    z = np.linspace(-6, 6, 49)
    xi = GERMS[germ].from_normal(z)
    np.testing.assert_allclose(xi, GERMS[germ].quantile(special.ndtr(z)), atol=1e-12)
    assert np.all(np.diff(xi) > 0)
    np.testing.assert_allclose(GERMS[germ].to_normal(xi), z, atol=1e-6)


@pytest.mark.parametrize("name", [name for name, law in DISTRIBUTIONS.items() if law.polynomial])
def test_a_distributions_maps_invert_and_its_moments_match_quadrature(name):
    parameter = make_parameter("p", "p", name, 2.0, interval_pct=30.0)
    nodes, weights = nodes_weights(GERMS[parameter.germ].default_rule, 60)
    kappa = parameter.to_physical(nodes)
    inner = np.abs(nodes) <= 6  # beyond, a truncated law's κ sits on its bound to double precision
    np.testing.assert_allclose(parameter.to_standard(kappa[inner]), nodes[inner], atol=1e-9)
    assert np.all(np.diff(kappa[inner]) > 0)  # κ grows with ξ
    mean = weights @ kappa  # a 60-point rule: the moments of these smooth maps to ~1e-10
    assert mean == pytest.approx(parameter.mean, rel=1e-9)
    assert math.sqrt(weights @ (kappa - mean) ** 2) == pytest.approx(parameter.std, rel=1e-7)


@pytest.mark.parametrize("name", [name for name, law in DISTRIBUTIONS.items() if not law.polynomial])
def test_a_seed_law_gives_every_integer_seed_equally_often(name):
    """κ = ⌊(ξ + 1)/2 · n⌋ on ξ ~ U(−1, 1): integers 0 .. n − 1, each slice of ξ of width 2/n mapping to one
    seed, the inverse landing in its own slice; the mean and std are the discrete uniform law's."""
    from uqflight.parameters.distributions import SEED_COUNT

    law = DISTRIBUTIONS[name]()
    edges = -1.0 + 2.0 * np.array([0, 1, 2**20, SEED_COUNT - 1]) / SEED_COUNT
    kappa = law.to_physical(np.concatenate([edges, edges + 1e-12, [1.0 - 1e-16, 1.0]]))
    np.testing.assert_array_equal(kappa, [0, 1, 2**20, SEED_COUNT - 1] * 2 + [SEED_COUNT - 1] * 2)
    seeds = np.array([0.0, 7.0, 123456789.0, SEED_COUNT - 1.0])
    np.testing.assert_array_equal(law.to_physical(law.to_standard(seeds)), seeds)
    u = np.random.default_rng(0).random(200000)
    drawn = law.to_physical(2 * u - 1)
    assert np.all(drawn == np.floor(drawn)) and drawn.min() >= 0 and drawn.max() <= SEED_COUNT - 1
    # 200,000 draws: the sample mean is within 4 standard errors of the law's
    assert abs(drawn.mean() - law.mean) < 4 * law.std / math.sqrt(u.size)
    assert law.std == pytest.approx(drawn.std(), rel=0.01)


@pytest.mark.parametrize("name", list(RULE_TABLE))
def test_a_rule_sums_to_one_and_is_exact_to_its_degree_and_not_beyond(name):
    rule = RULE_TABLE[name]
    for size in (rule.sizes or (1, 3, 5, 9))[:4]:
        nodes, weights = rule.nodes_weights(size)
        degree = rule.degree(size)
        assert weights.sum() == pytest.approx(1.0, abs=1e-12)
        values = orthonormal_polynomials(rule.germ, nodes, degree + 2)
        errors = np.abs(weights @ values - np.eye(degree + 3)[0])
        assert errors[: degree + 1].max() < 1e-8, (size, degree)
        assert errors[degree + 1:].max() > 1e-6, (size, degree)  # degree + 1 is odd: degree + 2 must miss


@pytest.mark.parametrize("kind", list(DESIGNS))
def test_a_design_has_weights_summing_to_one_and_is_random_only_if_sampled(kind):
    """Random points come from sampled designs, and from rare-event designs (their algorithm's seeded first
    round; their runs are not draws of the input law, so they are not `sampled`)."""
    germs = ["normal", "uniform"]
    one, other = (build_design(DESIGNS[kind].example, germs, seed) for seed in (1, 2))
    assert one.xi.shape == (len(one.weights), 2) and one.weights.sum() == pytest.approx(1.0)
    assert np.all(np.abs(one.xi[:, 1]) <= 1.0)  # the uniform germ's support
    assert (not np.array_equal(one.xi, other.xi)) == (DESIGNS[kind].sampled or DESIGNS[kind].rare)


SIZE_CASES = [  # more than each kind's example: replicates, nested and non-nested, linear and exponential growth
    {"kind": "sobol", "samples": 12, "replicates": 3},
    {"kind": "sparse_grid", "level": 3, "rule": "gauss_hermite", "nested": False},
    {"kind": "sparse_grid", "level": 3, "rule": "clenshaw_curtis", "growth": "exponential"},
    {"kind": "tensor_grid", "points": 3, "rule": "gauss_legendre"},
]


def _tensor_points_before_merging(spec: dict, germs: list[str]) -> int:
    """What the combination technique builds before merging: Σ over its multi-indices of the product of
    the 1-D rules' sizes, counted one tensor rule at a time (not by the registry's polynomial product)."""
    from uqflight.designs import rules
    from uqflight.designs.smolyak import multi_indices

    level, growth = spec["level"], spec.get("growth", "linear")
    by_dimension = rules.rules_by_dimension(spec.get("rule"), germs, spec.get("nested"))
    sizes = [rules.level_sizes(rule, growth, level + 1) for rule in by_dimension]
    return sum(int(np.prod([sizes[k][j[k]] for k in range(len(germs))])) for j in multi_indices(len(germs), level))


@pytest.mark.parametrize("spec", [entry.example for entry in DESIGNS.values()] + SIZE_CASES,
                         ids=lambda spec: "-".join(f"{v}" for v in spec.values()))
def test_a_design_states_its_own_size_before_building(spec):
    """The size the campaign's limits use (designs.design_size) is the built design's: its runs, or for a
    sparse grid the points built before merging (its runs are at most that), or an adaptive grid's budget
    (`refine` never passes it: tests/test_adaptive.py)."""
    germs = {"clenshaw_curtis": ["uniform"] * 3, "gauss_legendre": ["uniform"] * 3,
             "gauss_hermite": ["normal"] * 3}.get(spec.get("rule"), ["normal", "uniform", "normal"])
    stated = design_size(spec, germs)
    built = len(build_design(spec, germs, 5).weights)
    if spec["kind"] == "sparse_grid":
        assert stated == _tensor_points_before_merging(spec, germs) >= built
    elif DESIGNS[spec["kind"]].adaptive:  # its first round; the rounds after it stop before the budget
        assert stated == spec["budget"] >= built
    else:
        assert stated == built


def _polynomial_case():
    """A 5 × 5 Gauss tensor grid (exact to degree 9) and a random order-2 PCE sampled on it."""
    germs = ["normal", "uniform"]
    design = build_design({"kind": "tensor_grid", "points": 5}, germs, 0)
    indices = total_degree_indices(2, 2)
    coefficients = np.random.default_rng(3).normal(size=(len(indices), 3))
    return germs, design, coefficients, orthonormal_basis(germs, indices, design.xi) @ coefficients


@pytest.mark.parametrize("kind", [k for k, m in METHODS.items() if not m.sampled_only])
def test_every_grid_method_recovers_a_polynomial_in_its_basis(kind):
    germs, design, coefficients, Y = _polynomial_case()
    result = fit(kind, design.xi, design.weights, Y, germs, order=2)
    np.testing.assert_allclose(result.mean, coefficients[0], atol=1e-12)
    np.testing.assert_allclose(result.variance, (coefficients[1:] ** 2).sum(axis=0), rtol=1e-11)
    np.testing.assert_allclose(result.pce.coefficients, coefficients, atol=1e-11)


@pytest.mark.parametrize("kind", [k for k, m in METHODS.items() if m.sampled_only])
def test_every_sampling_method_gives_the_sample_moments(kind):
    germs = ["normal"]
    design = build_design({"kind": "monte_carlo", "samples": 500}, germs, 4)
    Y = np.exp(design.xi)
    result = fit(kind, design.xi, design.weights, Y, germs)
    np.testing.assert_allclose(result.mean, Y.mean(axis=0), rtol=1e-14)
    np.testing.assert_allclose(result.variance, Y.var(axis=0, ddof=1), rtol=1e-12)


@pytest.mark.parametrize("kind", [k for k, m in METHODS.items() if not m.sampled_only])
def test_every_method_gives_the_same_pce_from_tsvd_factors_as_from_the_runs(kind):
    # Y = rows @ scale as tSVD storage keeps it: a linear method is applied to the rows, the others are given
    # the factors; either way the PCE is the one of Y itself, up to rounding (1e-10 of the coefficients).
    germs, design, _, _ = _polynomial_case()
    rows = np.column_stack([np.exp(0.3 * design.xi[:, 0]), np.sin(design.xi[:, 1]) + design.xi[:, 0]])
    scale = np.random.default_rng(5).normal(size=(2, 4))
    direct = fit(kind, design.xi, design.weights, rows @ scale, germs, order=2).pce
    factored = fit(kind, design.xi, design.weights, rows, germs, order=2, scale=scale).pce
    np.testing.assert_array_equal(direct.indices, factored.indices)
    np.testing.assert_allclose(factored.coefficients, direct.coefficients, atol=1e-10 * np.abs(direct.coefficients).max())


@pytest.mark.parametrize("kind", [k for k, m in METHODS.items() if m.expands and not m.projects])
def test_every_fit_weighs_the_runs_as_its_entry_says(kind):
    # the same points and runs with other (positive) weights: a weighted fit changes, an unweighted one does not
    germs = ["normal", "uniform"]
    design = build_design({"kind": "monte_carlo", "samples": 40}, germs, 6)
    Y = np.exp(0.5 * design.xi[:, 0]) * (1 + design.xi[:, 1] ** 3)
    weights = np.random.default_rng(7).uniform(0.2, 1.0, 40)
    equal = fit(kind, design.xi, design.weights, Y, germs, order=2).pce
    other = fit(kind, design.xi, weights, Y, germs, order=2).pce
    same = equal.indices.shape == other.indices.shape and np.allclose(equal.coefficients, other.coefficients,
                                                                       rtol=1e-12, atol=1e-12)
    assert same != METHODS[kind].weighted


@pytest.mark.parametrize("kind", list(METHODS))
def test_every_method_is_exported_as_a_kind_that_builds_its_own_pce(kind):
    """...on every design it runs on; one that needs a sampled design stays itself on a grid (refused there)."""
    for sampled in (True, False):
        if METHODS[kind].sampled_only and not sampled:
            assert METHODS[kind].exported_kind(sampled) == kind
            continue
        target = METHODS[METHODS[kind].exported_kind(sampled)]
        assert target.expands and target.exported_as is None
        assert not (sampled and target.runs_on_sampled)


def _scenario_campaign(simulator: dict) -> str:
    return yaml.safe_dump({"name": "x", "simulator": simulator, "design": {"kind": "monte_carlo", "samples": 2},
                           "parameters": {"wind": {"property": "atmosphere/wind-north-fps", "distribution": "uniform",
                                                   "lower": -1, "upper": 1}}})


class _Altitude:
    properties = ("position/h-sl-ft",)

    def __init__(self):
        self.t, self.h = [], []

    def step(self, t, values):
        self.t.append(t)
        self.h.append(values[0])


@pytest.mark.parametrize("kind", list(SCENARIOS))
def test_a_scenario_counts_its_times_from_the_campaign_and_its_observers_see_what_it_records(kind, tmp_path):
    from uqflight.campaign import parse_campaign
    from uqflight.simulators import make_simulator
    from uqflight.simulators.aircraft_properties import AircraftProperties

    entry = SCENARIOS[kind]
    campaign = parse_campaign(_scenario_campaign({**entry.example, "outputs": ["h_ft"]}), str(tmp_path / "x.yaml"),
                              AircraftProperties)
    simulator = make_simulator(campaign.simulator, ["wind"], ["atmosphere/wind-north-fps"], tmp_path)
    time = simulator.setup.time
    assert entry.times(campaign.simulator) == len(time)  # the size estimate is the flight's own grid
    assert entry.span(campaign.simulator) == pytest.approx(time[-1], abs=0.1)  # within one output step (10 Hz)
    observer = _Altitude()
    result = simulator.flight.fly({"atmosphere/wind-north-fps": 0.5}, observers=(observer,))
    assert observer.t[0] == time[0] and len(observer.t) > len(time)  # t = 0, then every integration step
    at = np.searchsorted(observer.t, time)
    np.testing.assert_array_equal(np.asarray(observer.t)[at], time)  # the recorded times are steps' times
    np.testing.assert_array_equal(np.asarray(observer.h)[at], result.outputs["h_ft"])  # and their values
    assert all(isinstance(k, str) and not k.startswith(("/", "..")) for k in entry.files(campaign.simulator))


@pytest.mark.parametrize("kind", list(SCENARIOS))
def test_a_scenario_refuses_the_keys_of_the_others(kind, tmp_path):
    from uqflight.campaign import CampaignError, parse_campaign

    foreign = {key for other in SCENARIOS.values() for key in other.keys} - set(SCENARIOS[kind].keys)
    for key in sorted(foreign):
        text = _scenario_campaign({**SCENARIOS[kind].example, key: 1})
        with pytest.raises(CampaignError, match=f"simulator.{key}: unknown key"):
            parse_campaign(text, str(tmp_path / "x.yaml"))


def _simulator_campaign(simulator: dict, parameters: dict) -> str:
    return yaml.safe_dump({"name": "kinds", "simulator": simulator, "parameters": parameters,
                           "design": {"kind": "monte_carlo", "samples": 2}})


@pytest.mark.parametrize("kind", list(SIMULATORS))
def test_a_simulator_kind_builds_what_it_checks_and_counts_what_it_records(kind, tmp_path):
    from uqflight.campaign import parse_campaign
    from uqflight.simulators import make_simulator
    from uqflight.simulators.kinds import make_bundle
    from uqflight.simulators.aircraft_properties import AircraftProperties

    entry = SIMULATORS[kind]
    campaign = parse_campaign(_simulator_campaign(*entry.example), str(tmp_path / "x.yaml"), AircraftProperties)
    names, properties = [p.name for p in campaign.parameters], [p.property for p in campaign.parameters]
    simulator = make_simulator(campaign.simulator, names, properties, tmp_path)
    kappa = np.array([p.nominal for p in campaign.parameters])
    time, outputs = simulator.layout(kappa)
    assert set(simulator.evaluate(kappa)) == set(outputs)
    times, n_outputs = entry.recorded(campaign.simulator)
    span = entry.span(campaign.simulator)
    if entry.aircraft:  # known from the campaign alone: the flight's own grid
        assert (times, n_outputs) == (len(time), len(outputs)) and span == pytest.approx(time[-1])
    else:  # known once a sample has run
        assert (times, span) == (1, None)
    bundle = make_bundle(campaign.simulator, properties, tmp_path)
    assert bundle is None or bundle["kind"] in ("aircraft", "python")
    assert set(entry.provenance(campaign.simulator, tmp_path, properties)) <= {"aircraft_hash", "scenario"}


@pytest.mark.parametrize("kind", list(SIMULATORS))
def test_a_simulator_kind_refuses_the_keys_of_the_others(kind, tmp_path):
    from uqflight.campaign import CampaignError, parse_campaign

    simulator, parameters = SIMULATORS[kind].example
    for key in {k for other in SIMULATORS.values() for k in other.keys} - set(SIMULATORS[kind].keys):
        with pytest.raises(CampaignError, match=f"simulator.{key}: unknown key"):
            parse_campaign(_simulator_campaign({**simulator, key: "x"}, parameters), str(tmp_path / "x.yaml"))


ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("simulator, parameters, folder", [
    ({"kind": "jsbsim", "aircraft": "../aircraft/bacm", "duration_s": 1.0}, None, "campaigns"),
    ({"kind": "jsbsim", "scenario": {"kind": "script", "script": "scripts/c172p-landing.xml", "end_s": 1.0}},
     {"w": {"property": "atmosphere/wind-east-fps", "distribution": "uniform", "lower": -1, "upper": 1}}, "campaigns"),
    ({"kind": "python", "function": "data/quantity_model.py:ramp"}, None, "tests"),
], ids=["aircraft-folder", "script-file", "model-file"])
def test_a_relocated_simulator_reads_the_same_files_from_another_folder(simulator, parameters, folder, tmp_path):
    from uqflight.campaign import CampaignError, parse_campaign
    from uqflight.simulators.aircraft_properties import AircraftProperties

    entry = SIMULATORS[simulator["kind"]]
    parameters = parameters or entry.example[1]
    elsewhere = str(tmp_path / "x.yaml")
    with pytest.raises(CampaignError):  # the relative names do not resolve from elsewhere
        parse_campaign(_simulator_campaign(simulator, parameters), elsewhere, AircraftProperties)
    moved = entry.relocated(simulator, ROOT / folder)
    here = parse_campaign(_simulator_campaign(simulator, parameters), str(ROOT / folder / "x.yaml"), AircraftProperties)
    there = parse_campaign(_simulator_campaign(moved, parameters), elsewhere, AircraftProperties)
    assert ("function" in here.simulator) == ("function" in there.simulator)
    for key in ("aircraft_path", "script_path"):
        assert (getattr(here.simulator, key) is None) == (getattr(there.simulator, key) is None)
        if getattr(here.simulator, key) is not None:
            assert Path(getattr(here.simulator, key)).resolve() == Path(getattr(there.simulator, key)).resolve()
