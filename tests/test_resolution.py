"""uqflight.analysis.resolution: variances judged against the output's own magnitude, not the largest variance;
in summary.json, Sobol' indices of rounding noise and the CoV of a zero mean are null."""

import numpy as np
import pytest
from conftest import (NORMAL_2D, NORMAL_X, cli_in_process, closed_form_campaign, read_summary, run_python_campaign,
                      strict_json)

from uqflight.analysis import weighted_mean, weighted_std, weighted_variance
from uqflight.analysis.resolution import (
    EPS,
    RESOLUTION_RTOL,
    cov_or_none,
    resolved_variance,
    variance_floor,
)
from uqflight.designs import build_design
from uqflight.methods import fit
from uqflight.analysis.statistics import analyse, summary_json


def test_the_altitude_example_of_the_issue():
    # h ≈ 15000 ft: a variance of 2.5e-20 ft² (std 1.6e-10, ~1e-14 of h) is noise, 1 ft² is real.
    mean = np.full(3, 15000.0)
    np.testing.assert_array_equal(resolved_variance([2.5e-20, 1.0, 0.0], mean), [False, True, False])
    # A scalar output (T = 1) whose only variance is noise: a guard relative to the largest
    # variance over time (pce.RESOLVED_VARIANCE) cannot fire here, this one does.
    assert not resolved_variance([2.5e-20], [15000.0])[0]
    # The threshold is (1e-12 · 15000)² = 2.25e-16: just above it is resolved, just below is not.
    np.testing.assert_array_equal(resolved_variance([2.2e-16, 2.3e-16], [15000.0, 15000.0]), [False, True])


def test_sobol_indices_of_x1_squared_plus_x2_squared_resolved_only_where_the_spread_is_real():
    # t = 0: h = 15000 + 1e-10 (ξ1² + ξ2²), a trimmed state whose spread is ~1e-14 of its value;
    # t = 1: h = 15000 + ξ1² + ξ2², variance 4 and first-order indices (1/2, 1/2) in closed form.
    germs = ["normal", "normal"]
    design = build_design({"kind": "tensor_grid", "points": 4}, germs, 0)
    r2 = (design.xi**2).sum(axis=1)
    Y = np.column_stack([15000 + 1e-10 * r2, 15000 + r2])
    pce = fit("pseudo_galerkin", design.xi, design.weights, Y, germs, 2).pce
    mean, variance = pce.mean(), pce.variance()
    np.testing.assert_allclose(variance[1], 4.0, rtol=1e-9)
    resolved = resolved_variance(variance, mean, n=len(Y), weights=design.weights)
    np.testing.assert_array_equal(resolved, [False, True])
    first = np.where(resolved, pce.sobol_first(), np.nan)  # as the statistics keep them: NaN, null in JSON
    assert np.isnan(first[:, 0]).all()
    np.testing.assert_allclose(first[:, 1], [0.5, 0.5], rtol=1e-9)
    # The same output alone at t = 0 (a scalar output): still unresolved.
    assert not resolved_variance(pce.variance()[:1], pce.mean()[:1])[0]


def test_y_equals_x_on_a_symmetric_grid():
    # Mean 0 (up to rounding), variance 1: the variance is resolved, the CoV is undefined: None, no crash.
    design = build_design({"kind": "tensor_grid", "points": 5}, ["normal"], 0)
    y = design.xi[:, :1]
    mean, variance = weighted_mean(y, design.weights), weighted_variance(y, design.weights)
    assert abs(mean[0]) < 1e-15 and variance[0] == pytest.approx(1.0, rel=1e-13)
    assert resolved_variance(variance, mean)[0]
    assert cov_or_none(weighted_std(y, design.weights), mean) == [None]
    assert cov_or_none([1.0], [1e-17]) == [None]  # a mean of rounding size, not exactly 0
    assert cov_or_none([0.0], [0.0]) == [None]


def test_cov_where_defined():
    assert cov_or_none([1.0, 2.0], [10.0, -20.0]) == pytest.approx([0.05, 0.1])
    assert cov_or_none([0.0, 0.0], [3.0, 3.0]) == [0.0, 0.0]  # a constant output has CoV 0, not None


def test_zero_mean_exact_zero_negative_and_nan_variances():
    mean = np.zeros(4)
    np.testing.assert_array_equal(resolved_variance([1e-300, 0.0, -1.0, np.nan], mean), [True, False, False, False])


def test_scale_atol_n_and_signed_weights_raise_the_floor():
    mean = np.array([100.0])
    base = variance_floor(mean)[0]
    assert base == pytest.approx((RESOLUTION_RTOL * 100) ** 2)
    # A larger magnitude the output is computed from (e.g. a geocentric radius of 2.09e7 ft).
    assert variance_floor(mean, scale=2.09e7)[0] == pytest.approx((RESOLUTION_RTOL * 2.09e7) ** 2)
    assert variance_floor(mean, atol=1e-6)[0] == pytest.approx(1e-12)
    # Summing n values: 4 eps √n takes over from rtol beyond n = (1e-12 / 4 eps)² ≈ 1.3e6.
    assert variance_floor(mean, n=10_000)[0] == base
    assert variance_floor(mean, n=10**8)[0] == pytest.approx((4 * EPS * 1e4 * 100) ** 2)
    # Signed weights: Σ|w| / Σw amplifies per-run noise.
    assert variance_floor(mean, weights=[2.0, -1.0])[0] == pytest.approx(3 * base)
    var = 2 * base
    assert resolved_variance([var], mean)[0] and not resolved_variance([var], mean, weights=[2.0, -1.0])[0]


def test_sobol_indices_are_null_where_the_variance_is_rounding_noise(tmp_path):
    results = run_python_campaign(tmp_path, closed_form_campaign("sq", "sum_of_squares", NORMAL_2D,
                                                     "{kind: tensor_grid, points: 4}",
                                                     "method: {kind: pseudo_galerkin, order: 2}\n"))
    y = strict_json(summary_json(analyse(results)))["outputs"]["y"]
    assert y["resolved"] == [False, True, True, True, True]
    for parameter in ("x1", "x2"):
        assert y["sobol_first"][parameter][0] is None and y["sobol_total"][parameter][0] is None
        np.testing.assert_allclose(y["sobol_first"][parameter][1:], 0.5, atol=1e-12)


@pytest.mark.slow
def test_a_zero_mean_is_reported_without_a_crash_and_its_cov_is_null(tmp_path):
    results = run_python_campaign(tmp_path, closed_form_campaign("id", "identity", NORMAL_X, "{kind: tensor_grid, points: 5}",
                                                     "method: {kind: pseudo_galerkin, order: 1}\n"))
    done = cli_in_process("report", results, "--out", tmp_path / "r")
    assert done.returncode == 0, done.stderr
    y = read_summary(tmp_path / "r" / "summary.json")["outputs"]["y"]
    assert abs(y["mean"][0]) < 1e-15 and y["variance"][0] == pytest.approx(1.0)
    assert y["cov"] == [None] and y["sobol_first"]["x"] == [pytest.approx(1.0)]
