"""Dependent inputs (`dependence: {kind: gaussian_copula, ...}`, the Nataf transform) against closed forms.

y = a·x1 + b·x2 (the `linear` model: a = 1, b = 2) with x1 ~ N(0, 1), x2 ~ N(0, 2²) and correlation ρ:
y is normal with mean 0 and variance a²σ1² + b²σ2² + 2abρσ1σ2, its 99 % band ±z_0.995·σ_y. In the
independent standard variables (Cholesky: x1 = ξ1, x2 = σ2(ρ ξ1 + √(1 − ρ²) ξ2)) y = 3.4 ξ1 + 3.2 ξ2 for
ρ = 0.6, so an order-1 PCE on a Gauss–Hermite grid is exact and the Sobol' indices of ξ are 3.4²/21.8
and 3.2²/21.8.
"""
import json
import math

import numpy as np
import pytest
from scipy import special, stats

from conftest import cli_in_process
from uqflight.campaign import CampaignError, parse_campaign
from uqflight.running.runner import run_campaign
from uqflight.parameters import make_parameter, to_physical, to_standard
from uqflight.parameters.dependence import GaussianCopula
from uqflight.analysis.statistics import analyse, summary_json

RHO, SIGMA1, SIGMA2 = 0.6, 1.0, 2.0
VARIANCE = SIGMA1**2 + 4 * SIGMA2**2 + 2 * 2 * RHO * SIGMA1 * SIGMA2  # 21.8
Z995 = float(special.ndtri(0.995))
LINEAR = """
name: linear-dependent
seed: 7
simulator: {{kind: python, function: "uqflight.simulators.models:linear"}}
parameters:
  x1: {{distribution: normal, lower: -3, upper: 3}}
  x2: {{distribution: normal, lower: -6, upper: 6}}
dependence: {{kind: gaussian_copula, correlation: [[1, 0.6], [0.6, 1]]}}
design: {design}
method: {method}
execution: {{workers: 2, chunk: 256}}
analysis: {{band_samples: {band}, bootstrap: 0}}
"""


def run_linear(tmp_path, name, design, method, band=20000):
    path = tmp_path / f"{name}.h5"
    campaign = parse_campaign(LINEAR.format(design=design, method=method, band=band), str(tmp_path / f"{name}.yaml"))
    assert not run_campaign(campaign, out=path).failures
    return path, analyse(path)


def result_parameters(path):
    """The parameters (laws) a results file records."""
    from uqflight.campaign.record import read_record
    from uqflight.store import ResultStore

    with ResultStore.open(path) as store:
        return read_record(store.attrs, str(path)).campaign.parameters


def test_nataf_transform_inverts_and_leaves_the_unlisted_and_the_first_listed_alone():
    params = [make_parameter("u", "u", "uniform", 1, lower=-1, upper=3),
              make_parameter("n", "n", "normal", 0, lower=-3, upper=3),
              make_parameter("l", "l", "lognormal", 1, lower=0.5, upper=2)]
    copula = GaussianCopula(("l", "u"), [[1, -0.7], [-0.7, 1]])
    assert copula.germs(params) == ["normal", "normal", "normal"]
    xi = np.random.default_rng(0).standard_normal((1000, 3))
    kappa = to_physical(params, xi, copula)
    np.testing.assert_allclose(kappa[:, 1], params[1].to_physical(xi[:, 1]), rtol=1e-15)  # outside the group
    np.testing.assert_allclose(kappa[:, 2], params[2].to_physical(xi[:, 2]), rtol=1e-15)  # first listed: L11 = 1
    np.testing.assert_allclose(to_standard(params, kappa, copula), xi, atol=1e-9)  # Φ⁻¹ of 1 − 1e-12 loses ~1e-10


def test_uniform_marginals_with_a_copula_have_the_nataf_correlation():
    # 2^14 scrambled Sobol' points, mapped by the campaign's own design and transform. Gaussian copula
    # theory: Spearman's rho (and Pearson's, for uniform marginals) is 6/π·asin(ρ0/2). The standard error
    # of a sample correlation of N draws is below 1/√N = 0.008; the QMC points do better: 0.01 bounds it.
    text = """
name: copula-uniform
seed: 2
simulator: {kind: python, function: "uqflight.simulators.models:linear"}
parameters:
  u1: {distribution: uniform, lower: 0, upper: 1}
  u2: {distribution: uniform, lower: -5, upper: 5}
  u3: {distribution: uniform, lower: 10, upper: 12}
dependence: {kind: gaussian_copula, parameters: [u3, u1, u2], correlation: [[1, 0.8, -0.4], [0.8, 1, -0.2], [-0.4, -0.2, 1]]}
design: {kind: sobol, samples: 16384}
"""
    campaign = parse_campaign(text)
    assert campaign.germs == ["normal"] * 3
    kappa = campaign.to_physical(campaign.design().xi)[:, [2, 0, 1]]  # in the listed order
    nataf = 6 / math.pi * np.arcsin(np.array([[1, 0.8, -0.4], [0.8, 1, -0.2], [-0.4, -0.2, 1]]) / 2)
    np.testing.assert_allclose(stats.spearmanr(kappa).statistic, nataf, atol=0.01)
    np.testing.assert_allclose(np.corrcoef(kappa, rowvar=False), nataf, atol=0.01)
    for column, (lower, upper) in zip(kappa.T, [(10, 12), (0, 1), (-5, 5)]):  # the marginals stay uniform
        assert lower <= column.min() and column.max() <= upper
        assert stats.kstest((column - lower) / (upper - lower), "uniform").pvalue > 1e-3


def test_correlated_normals_on_a_gauss_hermite_grid_are_exact(tmp_path):
    # Order-1 PCE on a level-1 Gauss–Hermite grid: y is linear in ξ, so the mean, variance, PCE and
    # Sobol' indices are exact up to rounding (1e-10). The band is read from 200,000 draws of the PCE:
    # the 0.5 % quantile of N draws has standard error √(p(1−p)/N)/φ(z) σ_y = 0.011 σ_y; 0.06 σ_y is ~5 of them.
    path, result = run_linear(tmp_path, "grid", "{kind: sparse_grid, rule: gauss_hermite, level: 1}",
                              "{kind: pseudo_galerkin, order: 1}", band=200000)
    out = result.outputs["y"]
    assert abs(out.mean[0]) < 1e-10 and out.variance[0] == pytest.approx(VARIANCE, rel=1e-10)
    xi = np.random.default_rng(1).standard_normal((50, 2))
    np.testing.assert_allclose(out.pce.evaluate(xi)[:, 0], 3.4 * xi[:, 0] + 3.2 * xi[:, 1], atol=1e-10)
    assert out.sobol_first["x1"][0] == pytest.approx(3.4**2 / VARIANCE, abs=1e-10)
    assert out.sobol_total["x2"][0] == pytest.approx(3.2**2 / VARIANCE, abs=1e-10)
    sigma = math.sqrt(VARIANCE)
    np.testing.assert_allclose([out.band99[0][0], out.band99[1][0]], [-Z995 * sigma, Z995 * sigma], atol=0.06 * sigma)
    summary = summary_json(result)
    assert summary["dependence"]["parameters"] == ["x1", "x2"]
    assert summary["dependence"]["correlation"] == [[1.0, 0.6], [0.6, 1.0]]
    assert "Cholesky order x1, x2" in summary["dependence"]["sobol_of"]
    assert any("Gaussian copula" in note for note in summary["notes"])
    # the exported surrogate evaluates at physical values through the inverse Nataf transform
    from uqflight.campaign.record import read_record
    from uqflight.store import ResultStore
    from uqflight.analysis.surrogate import export, load
    from uqflight.text import Refusal

    pce = load(export(path, tmp_path / "pce.json"))
    kappa = to_physical(result_parameters(path), xi, GaussianCopula(("x1", "x2"), [[1, RHO], [RHO, 1]]))
    np.testing.assert_allclose(pce.evaluate(kappa)["y"][:, 0], kappa[:, 0] + 2 * kappa[:, 1], atol=1e-10)
    data = json.loads((tmp_path / "pce.json").read_text())
    data["dependence"]["correlation"] = [[1.0, 0.6], [0.5, 1.0]]  # hand-edited: refused, naming the key
    (tmp_path / "bad.json").write_text(json.dumps(data))
    with pytest.raises(Refusal, match=r"dependence\.correlation\[0\]\[1\]: expected a symmetric matrix"):
        load(tmp_path / "bad.json")
    # reading the results rebuilds the transform from the stored campaign text, running no campaign code
    with ResultStore.open(path) as store:
        again = read_record(store.attrs, str(path)).campaign
        np.testing.assert_array_equal(again.to_physical(store.xi), store.kappa)


def test_correlated_normals_by_quasi_monte_carlo(tmp_path):
    # 2048 scrambled Sobol' points, moments and band of the runs themselves. Tolerances are the Monte
    # Carlo ones (QMC does better): the variance's standard error is σ_y²·√(2/N) (3 %), 4 of them; the
    # 0.5 % quantile's √(p(1−p)/N)/φ(z)·σ_y = 0.11 σ_y, 4 of them.
    n = 2048
    _, result = run_linear(tmp_path, "qmc", f"{{kind: sobol, samples: {n}}}", "{kind: monte_carlo}")
    out = result.outputs["y"]
    sigma = math.sqrt(VARIANCE)
    assert abs(out.mean[0]) < 4 * sigma / math.sqrt(n)
    assert out.variance[0] == pytest.approx(VARIANCE, rel=4 * math.sqrt(2 / n))
    half = 4 * math.sqrt(0.005 * 0.995 / n) / stats.norm.pdf(Z995) * sigma
    np.testing.assert_allclose([out.band99[0][0], out.band99[1][0]], [-Z995 * sigma, Z995 * sigma], atol=half)
    independent = SIGMA1**2 + 4 * SIGMA2**2  # 17: far outside the tolerance, so the check can fail
    assert abs(out.variance[0] - independent) > 4 * math.sqrt(2 / n) * VARIANCE


# -- refusals: exit 2 naming file and field --------------------------------------------------------------
BAD = {
    "not symmetric": ("[[1, 0.5], [0.4, 1]]", None, "dependence.correlation[0][1]", "expected a symmetric matrix"),
    "diagonal": ("[[1, 0.5], [0.5, 0.9]]", None, "dependence.correlation[1][1]", "expected 1 on the diagonal"),
    "above one": ("[[1, 1.5], [1.5, 1]]", None, "dependence.correlation[0][1]", "expected a correlation in [-1, 1]"),
    "not positive definite": ("[[1, 0.9, 0.9], [0.9, 1, -0.9], [0.9, -0.9, 1]]", "[x1, x2, x3]",
                              "dependence.correlation", "expected a positive definite matrix"),
    "perfect correlation": ("[[1, 1], [1, 1]]", None, "dependence.correlation", "smallest eigenvalue is"),
    "wrong size": ("[[1, 0.5], [0.5, 1]]", "[x1, x2, x3]", "dependence.correlation", "expected a 3 x 3 list of rows"),
    "short row": ("[[1, 0.5], [0.5]]", None, "dependence.correlation[1]", "expected a row of 2 numbers"),
    "not a number": ("[[1, a], [a, 1]]", None, "dependence.correlation[0][1]", "expected a finite number"),
    "unknown parameter": ("[[1, 0.5], [0.5, 1]]", "[x1, x9]", "dependence.parameters[1]",
                          "expected one of the campaign's parameters (x1, x2, x3, s), got 'x9'"),
    "duplicate": ("[[1, 0.5], [0.5, 1]]", "[x1, x1]", "dependence.parameters[1]", "x1 is listed twice"),
    "seed": ("[[1, 0.5], [0.5, 1]]", "[x1, s]", "dependence.parameters[1]", "s is a seed"),
    "one parameter": ("[[1]]", "[x1]", "dependence.parameters", "at least two parameter names"),
}


def bad_campaign(correlation, names, kind="gaussian_copula"):
    listed = f", parameters: {names}" if names else ""
    return f"""
name: bad-dependence
simulator: {{kind: python, function: "uqflight.simulators.models:linear"}}
parameters:
  x1: {{distribution: normal, lower: -1, upper: 1}}
  x2: {{distribution: uniform, lower: -1, upper: 1}}
  x3: {{distribution: normal, lower: -1, upper: 1}}
  s: {{distribution: seed}}
dependence: {{kind: {kind}{listed}, correlation: {correlation}}}
design: {{kind: monte_carlo, samples: 8}}
"""


@pytest.mark.parametrize("case", sorted(BAD))
def test_a_bad_dependence_is_refused_naming_the_field(case):
    correlation, names, field, expected = BAD[case]
    names = names or "[x1, x2]"
    with pytest.raises(CampaignError) as caught:
        parse_campaign(bad_campaign(correlation, names), "bad.yaml")
    assert caught.value.field == field, str(caught.value)
    assert expected in str(caught.value)


def test_a_fixed_property_is_not_an_uncertain_parameter():
    text = """
name: fixed
simulator: {kind: jsbsim, aircraft: bacm, properties: {atmosphere/turbulence/milspec/severity: 3}}
parameters:
  CL0: {property: aero/uq/CL0, distribution: normal, nominal: 0.2, interval_pct: 10}
  CD0: {property: aero/uq/CD0, distribution: normal, nominal: 0.02, interval_pct: 10}
dependence: {kind: gaussian_copula, parameters: [CL0, atmosphere/turbulence/milspec/severity],
             correlation: [[1, 0.5], [0.5, 1]]}
design: {kind: monte_carlo, samples: 8}
"""
    with pytest.raises(CampaignError) as caught:
        parse_campaign(text, "fixed.yaml")
    assert caught.value.field == "dependence.parameters[1]" and "is a fixed property" in str(caught.value)


def test_plan_exits_2_naming_file_and_field_and_a_uniform_rule_is_refused_for_the_group(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(bad_campaign("[[1, 0.5], [0.4, 1]]", "[x1, x2]"))
    result = cli_in_process("plan", path, cwd=tmp_path)
    assert result.returncode == 2
    assert result.stderr.startswith(f"error: {path}: dependence.correlation[0][1]: expected a symmetric matrix")
    with pytest.raises(CampaignError, match="unknown key; did you mean parameters"):
        parse_campaign(bad_campaign("[[1, 0.5], [0.5, 1]]", None).replace("correlation:",
                                                                         "parameter: [x1], correlation:"))
    with pytest.raises(CampaignError, match="expected one of gaussian_copula"):
        parse_campaign(bad_campaign("[[1, 0.5], [0.5, 1]]", None, kind="clayton"))
    grid = """
name: uniform-grid
simulator: {kind: python, function: "uqflight.simulators.models:linear"}
parameters:
  u1: {distribution: uniform, lower: -1, upper: 1}
  u2: {distribution: uniform, lower: -1, upper: 1}
dependence: {kind: gaussian_copula, correlation: [[1, 0.5], [0.5, 1]]}
design: {kind: sparse_grid, level: 2, rule: gauss_legendre}
"""
    with pytest.raises(CampaignError) as caught:
        parse_campaign(grid)
    assert caught.value.field == "design.rule" and "standard-normal germs" in str(caught.value)
    campaign = parse_campaign(grid.replace("rule: gauss_legendre", "rule: gauss_hermite"))  # the germs are normal
    assert campaign.runs == 13 and campaign.germs == ["normal", "normal"]


# -- calibrate → calibrated.yaml with its dependence → plan → run -------------------------------------------
@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    """`calibrate` on the conjugate line y = a + b·t (test_calibration_conjugate): a strong posterior a–b
    correlation; its output folder."""
    from test_calibration_conjugate import SIGMA, TIME, flight, make_results

    from uqflight.calibration.run import calibrate

    folder = tmp_path_factory.mktemp("dependence-calibration")
    results = make_results(folder)
    data = folder / "flight.csv"
    data.write_text("time_s,y\n" + "".join(f"{t!r},{v!r}\n" for t, v in zip(TIME.tolist(), flight(0).tolist())))
    calibrate(results, data, folder / "out", noise={"y": SIGMA}, seed=0, steps=800, predictive_draws=5)
    return folder / "out"


@pytest.mark.slow  # a real calibrate (800 steps) and four campaign runs: ~20 s under load
def test_calibrated_dependence_plans_runs_and_narrows_the_band(calibrated, tmp_path):
    import h5py
    import yaml

    from uqflight.campaign import load_campaign
    from uqflight.simulators.aircraft_properties import AircraftProperties

    path = calibrated / "calibrated.yaml"
    text = path.read_text()
    assert "LOST" not in text
    campaign = load_campaign(path, AircraftProperties)  # as `uqflight plan` loads it
    with h5py.File(calibrated / "posterior.h5") as f:
        draws = f["draws/kappa"][()]
    r = np.corrcoef(draws, rowvar=False)[0, 1]
    assert campaign.dependence.names == ("a", "b") and r < -0.5  # intercept and slope of a line: strongly negative
    assert campaign.dependence.correlation[0, 1] == pytest.approx(r, rel=1e-9)  # normal marginals: ρ0 = r
    plan = cli_in_process("plan", path, cwd=tmp_path)
    assert plan.returncode == 0 and "dependence: gaussian_copula over a, b" in plan.stdout, plan.stderr
    independent = yaml.safe_load(text)
    del independent["dependence"]
    (tmp_path / "independent.yaml").write_text(yaml.safe_dump(independent, sort_keys=False))
    bands = {}
    for name, source in (("dependent", path), ("independent", tmp_path / "independent.yaml")):
        out = tmp_path / f"{name}.h5"
        ran = cli_in_process("run", source, "--out", out, cwd=tmp_path)
        assert ran.returncode == 0, ran.stderr
        y = analyse(out).outputs["y"]
        bands[name] = y.band99[1] - y.band99[0]
        if name == "dependent":  # the order-1 PCE is the line: the variance is the draws' own, to rounding
            t = y.time
            line = draws[:, :1] + draws[:, 1:] * t[None, :]
            np.testing.assert_allclose(y.variance, line.var(axis=0, ddof=1), rtol=1e-9)
    # y(0) = a: the same band (a is first in the Cholesky order: the same draws); later the correlation narrows it
    assert bands["dependent"][0] == pytest.approx(bands["independent"][0], rel=1e-12)
    assert np.all(bands["dependent"][5:] < 0.8 * bands["independent"][5:])


def test_calibrated_yaml_writes_the_copula_of_the_normal_scores():
    # Draws of three parameters: a, b informed (normal marginals, so ρ0 is the draws' own correlation),
    # c kept at its uniform prior (its score is Φ⁻¹ of its prior CDF), d independent of all (|r| < 0.1:
    # left out of the group). The text must load as a campaign with exactly that block.
    from uqflight.calibration.outputs import calibrated_campaign
    from uqflight.calibration.run import normal_scores
    from uqflight.calibration.surrogate import prior_summaries

    text = """
name: four
simulator: {kind: python, function: "uqflight.simulators.models:linear"}
parameters:
  a: {distribution: normal, lower: -3, upper: 3}
  b: {distribution: normal, lower: -3, upper: 3}
  c: {distribution: uniform, lower: -1, upper: 1}
  d: {distribution: normal, lower: -3, upper: 3}
design: {kind: monte_carlo, samples: 8}
dependence: {kind: gaussian_copula, parameters: [a, d], correlation: [[1, 0.3], [0.3, 1]]}
"""
    campaign = parse_campaign(text)
    rng = np.random.default_rng(4)
    z = rng.standard_normal((20000, 4)) @ np.linalg.cholesky([[1, -0.9, 0.5, 0], [-0.9, 1, -0.4, 0],
                                                               [0.5, -0.4, 1, 0], [0, 0, 0, 1]]).T
    kappa = np.column_stack([0.1 * z[:, 0] + 0.2, 0.3 * z[:, 1], 2 * special.ndtr(z[:, 2]) - 1, z[:, 3]])
    names = ["a", "b", "c", "d"]
    post = {n: {"mean": float(kappa[:, k].mean()), "std": float(kappa[:, k].std(ddof=1))} for k, n in enumerate(names)}
    prior = prior_summaries(campaign.parameters)
    scores = normal_scores(campaign.parameters, kappa, post, prior)
    np.testing.assert_allclose(scores[:, 2], z[:, 2], atol=1e-9)  # kept at its prior: Φ⁻¹(F(κ))
    import yaml

    from uqflight.campaign.schema import CampaignLoader

    written = calibrated_campaign(yaml.load(text, Loader=CampaignLoader), {}, post, prior, scores, names, "test")
    again = parse_campaign(written)
    assert again.dependence.names == ("a", "b", "c")  # the old block replaced; d is independent of all
    np.testing.assert_allclose(again.dependence.correlation, np.corrcoef(scores[:, :3], rowvar=False), atol=1e-12)
    assert again.dependence.correlation[0, 1] == pytest.approx(np.corrcoef(kappa[:, :2], rowvar=False)[0, 1], rel=1e-12)
    assert [p.distribution for p in again.parameters] == ["normal", "normal", "uniform", "normal"]
