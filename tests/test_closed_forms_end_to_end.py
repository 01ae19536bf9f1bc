"""Closed-form models run through the whole tool: campaign → python simulator → runner → HDF5 →
statistics. Each tolerance is stated with its reason."""
import numpy as np
import pytest

from uqflight.campaign import parse_campaign
from uqflight.running.runner import run_campaign
from uqflight.simulators.models import DECAY_TIME
from uqflight.analysis.statistics import analyse

PI = 3.141592653589793
ISHIGAMI = f"""
name: ishigami-{{name}}
seed: 11
simulator: {{{{kind: python, function: "uqflight.simulators.models:ishigami"}}}}
parameters:
  x1: {{{{distribution: uniform, lower: {-PI}, upper: {PI}}}}}
  x2: {{{{distribution: uniform, lower: {-PI}, upper: {PI}}}}}
  x3: {{{{distribution: uniform, lower: {-PI}, upper: {PI}}}}}
design: {{design}}
method: {{method}}
execution: {{{{workers: 2, chunk: 256}}}}
analysis: {{{{band_samples: 2000, bootstrap: 100}}}}
"""
S1 = [0.3139, 0.4424, 0.0]
ST = [0.5576, 0.4424, 0.2437]


def results(tmp_path, text: str, name: str):
    path = tmp_path / f"{name}.h5"
    summary = run_campaign(parse_campaign(text, str(tmp_path / f"{name}.yaml")), out=path)
    assert not summary.failures
    return analyse(path)


def indices(stats, output="y"):
    out = stats.outputs[output]
    return ([float(out.sobol_first[p][0]) for p in ("x1", "x2", "x3")],
            [float(out.sobol_total[p][0]) for p in ("x1", "x2", "x3")])


@pytest.mark.slow  # 3000 runs and an order-10 fit: test_analysis.py fits the same PCE in process
def test_ishigami_sobol_indices_from_a_pce(tmp_path):
    # Regression of order 10 on 3000 Latin-hypercube points: the truncation error of the degree-10
    # expansion of sin and x^4 sin is below 1e-2 on the indices (checked against the closed form).
    stats = results(tmp_path, ISHIGAMI.format(name="pce", design="{kind: latin_hypercube, samples: 3000}",
                                              method="{kind: regression, order: 10}"), "pce")
    first, total = indices(stats)
    np.testing.assert_allclose(first, S1, atol=1e-2)
    np.testing.assert_allclose(total, ST, atol=1e-2)
    assert stats.outputs["y"].mean[0] == pytest.approx(3.5, abs=2e-2)  # E[y] = a/2


@pytest.mark.slow  # 20 480 runs: test_analysis.py checks pick-freeze on Ishigami in process, test_seeds.py flies one
def test_ishigami_sobol_indices_from_pick_freeze_monte_carlo(tmp_path):
    # n = 4096 base samples: the estimators' standard error is ~0.01-0.02; 0.05 is about 3 of them.
    stats = results(tmp_path, ISHIGAMI.format(name="pf", design="{kind: pick_freeze, samples: 4096}",
                                              method="{kind: monte_carlo}"), "pf")
    first, total = indices(stats)
    np.testing.assert_allclose(first, S1, atol=0.05)
    np.testing.assert_allclose(total, ST, atol=0.05)
    ci = stats.outputs["y"].sobol_first_ci["x2"][:, 0]
    assert ci[0] < first[1] < ci[1]


LINEAR = """
name: linear
seed: 1
simulator: {kind: python, function: "uqflight.simulators.models:linear"}
parameters:
  x1: {distribution: normal, lower: -3, upper: 3}
  x2: {distribution: normal, lower: -6, upper: 6}
  x3: {distribution: uniform, lower: 0, upper: 2}
design: {kind: sparse_grid, level: 1}
method: {kind: pseudo_galerkin, order: 1}
"""


def test_linear_model_moments_and_indices_are_exact_on_a_grid(tmp_path):
    # y = x1 + 2 x2 + 3 x3, sigma = 1, 2 and uniform on [0, 2] (variance 1/3): a level-1 grid and an
    # order-1 PCE represent y exactly, so only rounding remains (1e-12).
    stats = results(tmp_path, LINEAR, "linear")
    partial = np.array([1.0, 16.0, 9.0 / 3.0])
    out = stats.outputs["y"]
    assert out.mean[0] == pytest.approx(3.0, abs=1e-12)
    assert out.variance[0] == pytest.approx(partial.sum(), rel=1e-12)
    first, total = indices(stats)
    np.testing.assert_allclose(first, partial / partial.sum(), atol=1e-12)
    np.testing.assert_allclose(total, partial / partial.sum(), atol=1e-12)


DECAY = """
name: decay-{name}
seed: 4
simulator: {{kind: python, function: "uqflight.simulators.models:exp_decay"}}
parameters:
  a: {{distribution: normal, lower: 0.7, upper: 1.3}}
design: {design}
method: {method}
"""


def decay_moments(mu=1.0, sigma=0.1):
    t = DECAY_TIME
    mean = np.exp(-mu * t + sigma**2 * t**2 / 2)
    return mean, np.exp(-2 * mu * t + 2 * sigma**2 * t**2) - mean**2


@pytest.mark.parametrize("method", ["pseudo_galerkin", "integration", "least_squares"])
def test_exp_decay_moments_over_time_from_a_sparse_grid(tmp_path, method):
    # a ~ N(1, 0.1^2); 10 Gauss-Hermite points integrate exactly to degree 19 and exp(-a t) over
    # t <= 5 is resolved by order 8 to ~1e-8 of its variance: 1e-6 relative leaves margin.
    text = DECAY.format(name=method, design="{kind: sparse_grid, rule: gauss_hermite, level: 9}",
                        method=f"{{kind: {method}, order: 8}}")
    out = results(tmp_path, text, method).outputs["x"]
    mean, variance = decay_moments()
    np.testing.assert_allclose(out.mean, mean, rtol=1e-6)
    np.testing.assert_allclose(out.variance, variance, rtol=1e-6, atol=1e-15)
    np.testing.assert_array_equal(out.time, DECAY_TIME)


@pytest.mark.slow
def test_exp_decay_moments_from_monte_carlo(tmp_path):
    # 20,000 runs: the standard error of the mean is sigma_x / sqrt(N) and of the variance about
    # var * sqrt(2 / N) (~1 %); 5 standard errors bound the check.
    text = DECAY.format(name="mc", design="{kind: monte_carlo, samples: 20000}", method="{kind: monte_carlo}")
    out = results(tmp_path, text, "mc").outputs["x"]
    mean, variance = decay_moments()
    n = 20000
    assert np.all(np.abs(out.mean - mean) <= 5 * np.sqrt(variance / n) + 1e-12)  # t = 0: rounding only
    assert np.all(np.abs(out.variance - variance) <= 5 * variance * np.sqrt(2 / n) + 1e-12)
