"""One convention for the sample moments (analysis.moments.standardised_moments): random draws give the
adjusted skewness G1 and kurtosis 3 + G2 (scipy's bias=False), weighted sums the plug-in moments of the
weighted law, a PCE the exact moments of its law; summary.json reports Pearson's kurtosis (3 for a normal law), and Hazen quantiles."""
import h5py
import numpy as np
import pytest
from conftest import run_python_campaign
from data.failure_models import corner_campaign
from scipy import stats as scipy_stats

from uqflight.analysis.moments import standardised_moments, weighted_quantiles
from uqflight.analysis.statistics import analyse, summary_json


def test_closed_forms_of_the_adjusted_and_plug_in_moments():
    # [0, 0, 0, 1]: m2 = 3/16, g1 = 2/√3, g2 = −2/3, so G1 = g1·√12/2 = 2 and
    # G2 = ((5)(−2/3) + 6)(3)/((2)(1)) = 4: kurtosis 7. As weights 3:1 on [0, 1] the same values are the
    # Bernoulli(1/4) law: skewness (1 − 2p)/√(p(1 − p)) = 2/√3, kurtosis 3 + (1 − 6p(1 − p))/(p(1 − p)) = 7/3.
    skewness, kurtosis = standardised_moments(np.array([0.0, 0.0, 0.0, 1.0]))
    assert skewness[0] == pytest.approx(2.0, rel=1e-14) and kurtosis[0] == pytest.approx(7.0, rel=1e-14)
    skewness, kurtosis = standardised_moments(np.array([0.0, 1.0]), np.array([3.0, 1.0]))
    assert skewness[0] == pytest.approx(2 / np.sqrt(3), rel=1e-14)
    assert kurtosis[0] == pytest.approx(7 / 3, rel=1e-14)


@pytest.mark.parametrize("n", [4, 5, 30, 1000])
def test_random_draws_match_scipy_without_bias(n):
    # rtol 1e-11: the same formulas, summed in another order
    Y = np.random.default_rng(n).gamma(2.0, size=(n, 3))
    skewness, kurtosis = standardised_moments(Y)
    np.testing.assert_allclose(skewness, scipy_stats.skew(Y, bias=False), rtol=1e-11)
    np.testing.assert_allclose(kurtosis, scipy_stats.kurtosis(Y, bias=False, fisher=False), rtol=1e-11)


def test_too_few_draws_or_no_spread_are_undefined():
    skewness, kurtosis = standardised_moments(np.array([[0.0], [1.0], [5.0]]))
    assert np.isfinite(skewness[0]) and np.isnan(kurtosis[0])  # G2 needs N ≥ 4 (scipy returns g2 there)
    skewness, kurtosis = standardised_moments(np.array([[1.0], [2.0]]))
    assert np.isnan(skewness[0]) and np.isnan(kurtosis[0])
    skewness, kurtosis = standardised_moments(np.full((10, 1), 3.0))
    assert np.isnan(skewness[0]) and np.isnan(kurtosis[0])


def test_hazen_quantiles_closed_form():
    # the j-th of N sorted values at (j − ½)/N: for 1..4, p = 0.5 lies midway between 2 and 3, p = 0.25
    # midway between 1 (at 1/8) and 2 (at 3/8); below 1/8 the smallest value
    Y = np.array([[3.0], [1.0], [4.0], [2.0]])
    np.testing.assert_allclose(weighted_quantiles(Y, (0.5, 0.25, 0.05)).ravel(), [2.5, 1.5, 1.0], rtol=1e-15)
    # unequal weights: cumulative weight less half its own, the same rule
    np.testing.assert_allclose(weighted_quantiles(np.array([[1.0], [2.0]]), (0.25, 0.5), np.array([1.0, 1.0])).ravel(),
                               [1.0, 1.5], rtol=1e-15)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("moments")
    return {name: run_python_campaign(folder, corner_campaign(name, design, method, 1), name)
            for name, design, method in (("mc", "{kind: monte_carlo, samples: 300}", "monte_carlo"),
                                         ("grid", "{kind: tensor_grid, points: 3}", "least_squares"))}


def test_monte_carlo_statistics_report_the_adjusted_moments_of_the_runs(files):
    stats = analyse(files["mc"])
    with h5py.File(files["mc"]) as f:
        y = f["outputs/y"][:, 0][f["samples/status"][:] == 0]
    summary = summary_json(stats)["outputs"]["y"]
    # rtol 1e-11: the same formulas summed in another order; kurtosis is Pearson's, not the excess
    assert summary["skewness"][0] == pytest.approx(scipy_stats.skew(y, bias=False), rel=1e-11)
    assert summary["kurtosis"][0] == pytest.approx(scipy_stats.kurtosis(y, bias=False, fisher=False), rel=1e-11)
    assert summary["variance"][0] == pytest.approx(y.var(ddof=1), rel=1e-12)


def test_a_pce_reports_the_exact_moments_of_its_law(files):
    # least squares of order 1 on the 8 grid nodes that succeed: the PCE 1 + x1 + x2 of two U(−1, 1),
    # a triangular law: skewness 0, kurtosis 2.4, in closed form (methods.pce_moments), not from draws
    out = analyse(files["grid"]).outputs["y"]
    assert abs(out.skewness[0]) < 1e-12 and out.kurtosis[0] == pytest.approx(2.4, rel=1e-12)
