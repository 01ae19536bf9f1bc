"""uqflight.analysis against closed forms: moments, bands, KDE, KL divergence, Eq. 49, Sobol' indices."""
import numpy as np
import pytest
from conftest import ishigami, ishigami_indices
from scipy.stats import gaussian_kde

from uqflight.analysis import (
    error_summary,
    kl_divergence,
    modified_cov,
    pdf_over_time,
    pick_freeze_indices,
    relative_errors,
    weighted_mean,
    weighted_std,
    weighted_variance,
)
from uqflight.analysis.moments import hazen_quantiles, sorted_by_time, weighted_quantiles
from uqflight.methods import fit
from uqflight.parameters.germs import draw_germs

Z_995 = 2.5758293035489


def quantile_band(Y, weights=None, level: float = 0.99):
    """The central `level` band per time, as the statistics take it: the (1 − level)/2 and (1 + level)/2
    weighted quantiles (weighted_quantiles), each (T,)."""
    lower, upper = weighted_quantiles(Y, (0.5 * (1.0 - level), 0.5 * (1.0 + level)), weights)
    return lower, upper


def saltelli_design(germs, n, seed):
    """Rows [A; B; AB_1; …; AB_d] with AB_i = A whose column i comes from B."""
    a, b = draw_germs(germs, n, seed), draw_germs(germs, n, seed + 1)
    mixed = np.repeat(a[None], len(germs), axis=0)
    mixed[np.arange(len(germs)), :, np.arange(len(germs))] = b.T
    return np.vstack([a, b, *mixed])


def test_weighted_moments_by_hand():
    Y = np.array([[1.0, 5.0], [3.0, 5.0]])
    w = np.array([0.25, 0.75])
    np.testing.assert_allclose(weighted_mean(Y, w), [2.5, 5.0])
    np.testing.assert_allclose(weighted_variance(Y, w), [0.75, 0.0])
    np.testing.assert_allclose(weighted_std(Y, 4 * w), [np.sqrt(0.75), 0.0])  # weights are normalised
    np.testing.assert_allclose(weighted_variance(Y, unbiased=True), np.var(Y, axis=0, ddof=1))
    with pytest.raises(ValueError, match="expected \\(2,\\)"):
        weighted_mean(Y, np.ones(3))


def test_weighted_quantile_band_agrees_with_the_hazen_quantile_of_equal_weights():
    # Weights unequal by 1e-12 take the sorting path but move the positions by ~1e-12 only.
    Y = np.random.default_rng(0).normal(size=(1001, 4))
    nearly_equal = 1 + 1e-12 * np.random.default_rng(1).uniform(size=1001)
    for weights in (None, nearly_equal):
        lower, upper = quantile_band(Y, weights)
        np.testing.assert_allclose(lower, np.quantile(Y, 0.005, axis=0, method="hazen"), atol=1e-9)
        np.testing.assert_allclose(upper, np.quantile(Y, 0.995, axis=0, method="hazen"), atol=1e-9)


@pytest.mark.parametrize("n", [2, 3, 17, 113, 20000])
@pytest.mark.parametrize("kind", ["normal", "ties", "constant", "nan"])
def test_hazen_quantiles_are_numpys_to_the_bit(n, kind):
    # the fast selection must give numpy's numbers exactly, at both ends, at ties and with a NaN (numpy's path)
    rng = np.random.default_rng(n)
    Y = {"normal": rng.standard_normal((n, 5)), "ties": rng.integers(0, 3, (n, 5)).astype(float),
         "constant": np.full((n, 5), 2.5), "nan": rng.standard_normal((n, 5))}[kind]
    if kind == "nan":
        Y[n // 2, 1] = np.nan
    probabilities = np.array([0.0, 1e-9, 0.005, 0.3, 0.5, 0.5 / n, 1 - 0.5 / n, 0.995, 0.995, 1 - 1e-12, 1.0])
    found = hazen_quantiles(Y, probabilities)
    np.testing.assert_array_equal(found, np.quantile(Y, probabilities, axis=0, method="hazen"))
    for shaped in (0.3, probabilities.reshape(-1, 1)):  # a single probability, and a column of them: numpy's shapes
        np.testing.assert_array_equal(hazen_quantiles(Y, shaped), np.quantile(Y, shaped, axis=0, method="hazen"))
    empty = Y[:, :0]  # no times at all: numpy's empty answer
    np.testing.assert_array_equal(hazen_quantiles(empty, probabilities), np.quantile(empty, probabilities, axis=0,
                                                                                    method="hazen"))


def test_hazen_quantiles_of_presorted_columns_read_only_those():
    # the analysis sorts each block once (sorted_by_time) and passes it on: the quantiles must be numpy's
    # from the sorted rows alone (Y is not read then: a Y of zeros beside them must change nothing)
    rng = np.random.default_rng(3)
    Y = rng.standard_normal((20000, 3))
    probabilities = np.array([0.005, 0.995, 0.5, 1.0])
    ordered = sorted_by_time(Y)
    assert ordered.shape == (3, 20000) and (np.diff(ordered, axis=1) >= 0).all()
    np.testing.assert_array_equal(hazen_quantiles(np.zeros_like(Y), probabilities, ordered),
                                  np.quantile(Y, probabilities, axis=0, method="hazen"))


def test_quantile_band_of_a_normal_sample_is_2_5758_sigma():
    # The sampling std of the 99.5 % quantile for n = 2e5 is √(p(1−p)/n)/φ(z) ≈ 0.011σ: 0.05σ is > 4 of them.
    sigma = np.array([1.0, 3.0])
    Y = 10 + sigma * np.random.default_rng(1).standard_normal((200_000, 2))
    lower, upper = quantile_band(Y, level=0.99)
    np.testing.assert_allclose((lower - 10) / sigma, -Z_995, atol=0.05)
    np.testing.assert_allclose((upper - 10) / sigma, Z_995, atol=0.05)


def test_weighted_quantile_band_of_a_density_weighted_grid():
    # A fine grid weighted by the normal density is a discrete normal law: spacing 6e-4 bounds the error.
    y = np.linspace(-6, 6, 20_001)
    lower, upper = quantile_band(y, np.exp(-0.5 * y**2))
    np.testing.assert_allclose([lower[0], upper[0]], [-Z_995, Z_995], atol=1e-3)
    with pytest.raises(ValueError, match="non-negative"):
        quantile_band(y, np.where(y > 5, -1e-3, 1.0))


def test_modified_cov_divides_by_the_largest_absolute_mean():
    np.testing.assert_allclose(modified_cov([1.0, -4.0, 2.0], [0.1, 0.2, 0.4]), [0.025, 0.05, 0.1])


def test_pdf_over_time_matches_scipy_kde_and_integrates_to_one():
    # Linear binning on 400 points (≈ 40 per bandwidth) errs by O(Δx²): 1e-3 of the peak is generous.
    rng = np.random.default_rng(2)
    Y = np.column_stack([rng.normal(1.0, 2.0, 3000), rng.gamma(2.0, 1.0, 3000)])
    support, density = pdf_over_time(Y, grid_points=400)
    assert support.shape == density.shape == (2, 400)
    for t in range(2):
        exact = gaussian_kde(Y[:, t])(support[t])
        np.testing.assert_allclose(density[t], exact, atol=1e-3 * exact.max())
        assert abs(density[t].sum() * (support[t, 1] - support[t, 0]) - 1) < 1e-3


@pytest.mark.parametrize("runs, outside", [(1, False), (2, False), (17, False), (5000, False),
                                           (2, True), (17, True), (5000, True)])
def test_binning_of_sorted_rows_is_linear_binning(runs, outside):
    # each left point's samples are one run of the sorted row, their shares Σp − k·count: that sum of
    # positions rounds to ε·count²·k at worst, 1.4e-7 here (5000² × 50 × 1.1e-16); a sample in the wrong
    # bin would move a whole share. `outside`: samples beyond the grid, binned at the nearer end (clipped).
    from uqflight.analysis.density import _linear_bins

    rng = np.random.default_rng(runs)
    Y = rng.normal(size=(runs, 5)) * [1.0, 2.0, 1e-3, 5.0, 1.0] + [0.0, 3.0, 1.0, -2.0, 1e4]
    margin = -0.2 * np.ptp(Y, axis=0) if outside else 0.1
    lower, grid_points = Y.min(axis=0) - margin, 50
    spacing = (Y.max(axis=0) + margin - lower) / (grid_points - 1)
    position = np.clip((Y - lower) / spacing, 0, grid_points - 1)
    left = np.minimum(position.astype(int), grid_points - 2)
    share = position - left
    expected_samples, expected_right = np.zeros((5, grid_points - 1)), np.zeros((5, grid_points - 1))
    for t in range(5):
        np.add.at(expected_samples[t], left[:, t], 1)
        np.add.at(expected_right[t], left[:, t], share[:, t])
    samples, to_right = _linear_bins(sorted_by_time(Y), lower, spacing, grid_points)
    np.testing.assert_array_equal(samples, expected_samples)
    np.testing.assert_allclose(to_right, expected_right, rtol=0, atol=1.1e-16 * runs**2 * grid_points)


def test_pdf_of_a_constant_column_is_a_narrow_unit_peak():
    Y = np.column_stack([np.full(500, 3.0), np.random.default_rng(3).normal(size=500)])
    support, density = pdf_over_time(Y)
    assert np.isfinite(density).all()
    assert abs(support[0, np.argmax(density[0])] - 3.0) < 1e-6
    assert abs(density[0].sum() * (support[0, 1] - support[0, 0]) - 1) < 1e-3


def test_kl_divergence_of_two_gaussians():
    # KDE widens both laws by ~1 % in variance (Scott's bandwidth for 1e5 samples, bias ≈ −0.8 % of the KL)
    # and the samples' own moments scatter by ~1 % of it: a 3 % tolerance.
    rng = np.random.default_rng(4)
    (mu1, s1), (mu2, s2) = (0.0, 1.0), (1.0, 1.5)
    exact = np.log(s2 / s1) + (s1**2 + (mu1 - mu2) ** 2) / (2 * s2**2) - 0.5
    divergence = kl_divergence(rng.normal(mu1, s1, 100_000), rng.normal(mu2, s2, 100_000))
    assert divergence == pytest.approx(exact, rel=0.03)
    same_law = kl_divergence(rng.normal(0, 1, (20_000, 3)), rng.normal(0, 1, (20_000, 3)))
    assert same_law.shape == (3,) and (np.abs(same_law) < 0.01).all()


def test_relative_errors_by_hand():
    eps_m, eps_v = relative_errors([1.0, 2.5, -4.0], [0.0, 1.0, 2.0], [1.0, 2.0, -5.0], [0.0, 2.0, 2.0])
    np.testing.assert_allclose(eps_m, [0.0, 0.1, 0.2])
    np.testing.assert_allclose(eps_v, [0.0, 0.5, 0.0])
    _, eps_zero = relative_errors([0.0], [0.3], [1.0], [0.0])
    np.testing.assert_allclose(eps_zero, [0.3])  # an identically zero reference gives the absolute error
    assert error_summary(eps_m) == pytest.approx({"max": 0.2, "mean": 0.1})


def test_sobol_indices_of_a_linear_model_from_the_pce_and_from_pick_freeze():
    # y = Σ a_i ξ_i is its own order-1 PCE, so S_i = ST_i = a_i² σ_i² / Σ a_j² σ_j² to rounding;
    # pick-freeze with n = 4096 has sampling error ~0.02, so 0.05 covers it.
    germs = ["normal", "uniform", "normal"]
    a = np.array([1.0, 2.0, 0.5])
    share = a**2 * np.array([1.0, 1 / 3, 1.0])
    share /= share.sum()
    xi = draw_germs(germs, 50, seed=5)
    pce = fit("regression", xi, None, xi @ a, germs, order=1).pce
    np.testing.assert_allclose(pce.sobol_first()[:, 0], share, atol=1e-12)
    np.testing.assert_allclose(pce.sobol_total()[:, 0], share, atol=1e-12)
    design = saltelli_design(germs, 4096, seed=6)
    indices = pick_freeze_indices(design @ a, d=3)
    np.testing.assert_allclose(indices["first"][:, 0], share, atol=0.05)
    np.testing.assert_allclose(indices["total"][:, 0], share, atol=0.05)


def test_ishigami_indices_from_a_regression_pce():
    # An order-10 Legendre fit leaves ~1e-4 of the variance unresolved: 1e-2 is a wide margin.
    first, total = ishigami_indices()
    xi = draw_germs(["uniform"] * 3, 3000, seed=7)
    pce = fit("regression", xi, None, ishigami(xi), ["uniform"] * 3, order=10).pce
    np.testing.assert_allclose(pce.sobol_first()[:, 0], first, atol=1e-2)
    np.testing.assert_allclose(pce.sobol_total()[:, 0], total, atol=1e-2)


def test_ishigami_indices_from_pick_freeze_lie_in_their_bootstrap_intervals():
    # n = 2^14 base rows give bootstrap 95 % intervals of half-width ≲ 0.03 (≈ 2 standard errors):
    # the estimates lie within 0.03 of the truth and the truth within two half-widths of them (≈ 4 SE;
    # asserting plain 95 % coverage of six indices would fail for one seed in four).
    first, total = ishigami_indices()
    design = saltelli_design(["uniform"] * 3, 2**14, seed=8)
    indices = pick_freeze_indices(ishigami(design)[:, None], d=3, n_boot=200, seed=9)
    for name, exact in (("first", first), ("total", total)):
        estimate, (lower, upper) = indices[name][:, 0], indices[f"{name}_ci"][:, :, 0]
        np.testing.assert_allclose(estimate, exact, atol=0.03)
        assert (lower <= estimate).all() and (estimate <= upper).all()
        assert (upper - lower < 0.06).all()
        assert (np.abs(estimate - exact) <= upper - lower).all()


def test_pick_freeze_gives_zero_for_a_constant_output_and_checks_the_design():
    design = saltelli_design(["normal", "normal"], 64, seed=10)
    Y = np.column_stack([np.full(len(design), 7.0), design[:, 0]])
    indices = pick_freeze_indices(Y, d=2, n_boot=20)
    assert indices["first"].shape == (2, 2) and indices["first_ci"].shape == (2, 2, 2)
    np.testing.assert_array_equal(indices["first"][:, 0], 0.0)
    with pytest.raises(ValueError, match="Saltelli design"):
        pick_freeze_indices(Y[:-1], d=2)


def test_pce_sobol_indices_are_undefined_where_the_variance_is_zero():
    xi = draw_germs(["normal", "uniform"], 40, seed=11)
    Y = np.column_stack([np.full(40, 2.0), xi[:, 0] * xi[:, 1]])
    pce = fit("regression", xi, None, Y, ["normal", "uniform"], order=2).pce
    pce.coefficients[1:, 0] = 0.0  # exactly constant, not rounding noise
    assert np.isnan(pce.sobol_first()[:, 0]).all() and np.isnan(pce.sobol_total()[:, 0]).all()  # 0/0
    np.testing.assert_allclose(pce.sobol_first()[:, 1], 0.0, atol=1e-12)  # only the interaction term
    np.testing.assert_allclose(pce.sobol_total()[:, 1], 1.0)


def test_statistics_take_whole_histories_at_once():
    # 10 000 runs × 1 001 times: every statistic is one vectorised pass (no loop over runs or times).
    rng = np.random.default_rng(12)
    Y = rng.normal(size=(10_000, 1001)) * np.linspace(0.0, 1.0, 1001)
    w = np.full(10_000, 1e-4)
    assert weighted_mean(Y, w).shape == weighted_variance(Y, w).shape == (1001,)
    lower, upper = quantile_band(Y, w)
    assert (lower <= upper).all() and lower.shape == (1001,)
    support, density = pdf_over_time(Y)
    assert density.shape == (1001, 200) and np.isfinite(density).all()
