"""uqflight.analysis.floors: the Monte Carlo reference's own noise in Eq. 49's normalisation, and the KLD's."""
import numpy as np
import pytest

from uqflight.analysis import kl_divergence
from uqflight.analysis.floors import central_moments, floors_from_moments, kld_floor, reference_floors


def test_floors_from_exact_normal_moments_are_the_closed_form():
    # μ4 = 3σ⁴ gives se(s²) = σ² √((3 − (N−3)/(N−1)) / N) = σ² √(2/(N−1)) exactly.
    n, sigma, mean = 1000, np.array([1.0, 2.0, 3.0]), np.array([5.0, -10.0, 1.0])
    floors = floors_from_moments(mean, sigma**2, 3 * sigma**4, n)
    np.testing.assert_allclose(floors["se_mean"], sigma / np.sqrt(n), rtol=1e-14)
    np.testing.assert_allclose(floors["se_variance"], sigma**2 * np.sqrt(2 / (n - 1)), rtol=1e-14)
    np.testing.assert_allclose(floors["eps_m_floor"], sigma / np.sqrt(n) / 10.0, rtol=1e-14)
    np.testing.assert_allclose(floors["eps_v_floor"], sigma**2 * np.sqrt(2 / (n - 1)) / 9.0, rtol=1e-14)


@pytest.mark.parametrize("law", ["normal", "uniform"])
def test_reference_floors_of_samples_match_the_closed_form(law):
    # N = 40000: the estimated σ² and μ4 − σ⁴ are within ~1.5 % (1 s.e. for the uniform is smaller);
    # 6 % is 4 standard errors. Normal: se(s²) ≈ σ²√(2/N). Uniform on (−a, a): σ² = a²/3, μ4 = a⁴/5
    # (kurtosis 9/5), so se(s²) = a²√(4/(45N)).
    rng = np.random.default_rng(2)
    n, a = 40_000, np.array([1.0, 2.0, 3.0])
    if law == "normal":
        Y = 7.0 + a * rng.standard_normal((n, 3))
        variance, se_variance = a**2, a**2 * np.sqrt(2 / n)
    else:
        Y = 7.0 + a * rng.uniform(-1, 1, (n, 3))
        variance, se_variance = a**2 / 3, a**2 * np.sqrt(4 / (45 * n))
    floors = reference_floors(Y)
    np.testing.assert_allclose(floors["eps_v_floor"], se_variance / variance.max(), rtol=0.06)
    np.testing.assert_allclose(floors["eps_m_floor"], np.sqrt(variance / n) / 7.0, rtol=0.06)


@pytest.mark.parametrize("law", ["normal", "uniform"])
def test_errors_of_the_sample_moments_stay_within_two_floors_in_95_percent_of_seeds(law):
    # Each of S = 4000 columns is an independent reference of N = 400 draws (a seed). Two standard
    # errors cover 95.4 % in the normal limit; the tolerance 0.02 is 4 binomial standard errors of the
    # coverage (√(0.954·0.046/4000) ≈ 0.0033) plus ~0.007 for the laws of ȳ and s² at N = 400 not
    # being normal (t-like with an estimated σ, skewed χ²-like for s²).
    n, seeds = 400, 4000
    rng = np.random.default_rng(1)
    Y = rng.standard_normal((n, seeds)) if law == "normal" else rng.uniform(-1, 1, (n, seeds))
    true_variance = 1.0 if law == "normal" else 1 / 3
    mean, variance, _ = central_moments(Y)
    floors = reference_floors(Y)
    # In Eq. 49's normalisation (one peak for all columns) the comparison is the same as with the s.e.
    assert abs(np.mean(np.abs(mean) <= 2 * floors["se_mean"]) - 0.954) < 0.02
    assert abs(np.mean(np.abs(variance - true_variance) <= 2 * floors["se_variance"]) - 0.954) < 0.02


def test_floors_from_time_blocks_equal_the_floors_of_all_times():
    Y = np.random.default_rng(4).normal(size=(300, 10)) * np.arange(1, 11)
    moments = [central_moments(Y[:, block]) for block in (slice(0, 4), slice(4, 10))]
    joined = [np.concatenate(parts) for parts in zip(*moments)]
    blocked, whole = floors_from_moments(*joined, len(Y)), reference_floors(Y)
    for key in whole:
        np.testing.assert_allclose(blocked[key], whole[key], rtol=1e-14)


def test_undefined_floors():
    assert np.isnan(reference_floors(np.ones((1, 3)))["eps_v_floor"]).all()
    zero = reference_floors(np.zeros((5, 2)))  # zero peaks normalise by 1, as analysis.errors does
    np.testing.assert_array_equal(zero["eps_m_floor"], [0.0, 0.0])
    assert np.isnan(kld_floor(np.arange(3.0)))


def test_kld_floor_is_the_documented_split_and_falls_with_n():
    x = np.random.default_rng(5).standard_normal(2000)
    floor = kld_floor(x, repeats=3, seed=9)
    rng = np.random.default_rng(9)
    by_hand = np.mean([kl_divergence(x[order[:1000]], x[order[1000:]])
                       for order in (rng.permutation(2000) for _ in range(3))])
    assert floor == pytest.approx(by_hand, rel=1e-12)
    assert kld_floor(x, repeats=3, seed=9) == floor  # seeded
    # n_method caps the pseudo-method sample: 300 of the 2000 against the other 1700.
    rng = np.random.default_rng(0)
    order = rng.permutation(2000)
    assert kld_floor(x, n_method=300, repeats=1) == pytest.approx(kl_divergence(x[order[:300]], x[order[300:]]))
    # Columns are independent outputs: (N, T) gives (T,), each column's floor as alone.
    Y = np.column_stack([x, 3 * x[::-1] + 1])
    np.testing.assert_allclose(kld_floor(Y, repeats=2), [kld_floor(Y[:, 0], repeats=2), kld_floor(Y[:, 1], repeats=2)])
    # Sampling noise shrinks with N: 16 times more runs, a floor several times lower (~N^-0.8 here).
    small = kld_floor(np.random.default_rng(6).standard_normal(500))
    large = kld_floor(np.random.default_rng(6).standard_normal(8000))
    assert 0 < large < small / 3


def test_kld_floor_matches_the_kld_of_two_independent_samples_of_one_law():
    # The floor of a normal reference (N = 2000) against the average KLD of 10 pairs of fresh,
    # independent normal samples of sizes 1000 and 1000 from the same law: the same noise, so
    # equal up to the scatter of a mean of a few positive, skewed values (a factor 2 either way).
    rng = np.random.default_rng(7)
    floor = kld_floor(rng.standard_normal(2000))
    fresh = np.mean([kl_divergence(rng.standard_normal(1000), rng.standard_normal(1000)) for _ in range(10)])
    assert fresh / 2 < floor < 2 * fresh
