"""uqflight.analysis.floors: the Monte Carlo reference's own noise in Eq. 49's normalisation, and the KLD's;
the errors of an exact grid against a Monte Carlo or randomised-QMC reference carry that floor."""
import h5py
import numpy as np
import pytest
from conftest import NORMAL_2D, closed_form_campaign, run_python_campaign

from uqflight.analysis import kl_divergence
from uqflight.analysis.floors import central_moments, floors_from_moments, kld_floor
from uqflight.analysis.statistics import analyse


def reference_floors(Y) -> dict:
    """floors_from_moments of the runs Y (N, T): the floors of a reference of all times at once."""
    return floors_from_moments(*central_moments(Y), len(Y))


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


def exact_grid_errors_against(tmp_path, flown, reference_design: str, tag: str):
    """(errors of an exact PG grid on sum_of_squares against a reference of that design, the reference's
    runs): what is left of the errors is the reference's own noise."""
    reference = run_python_campaign(tmp_path, closed_form_campaign(tag, "sum_of_squares", NORMAL_2D, reference_design), tag)
    grid = flown(closed_form_campaign("pg", "sum_of_squares", NORMAL_2D, "{kind: tensor_grid, points: 4}",
                                      "method: {kind: pseudo_galerkin, order: 2}\n"), "pg")
    errors = analyse(grid, reference=str(reference)).outputs["y"].errors
    with h5py.File(reference) as f:
        return errors, f["outputs/y"][()]


@pytest.mark.slow
def test_errors_carry_the_reference_noise_floor(tmp_path, flown):
    errors, Y = exact_grid_errors_against(tmp_path, flown, "{kind: monte_carlo, samples: 400}", "ref")
    # σ/√N of the reference's mean and the distribution-free standard error of its variance,
    # √((μ4 − (N−3)/(N−1) σ⁴)/N), in Eq. 49's normalisation, recomputed here from the runs
    n, variance = len(Y), Y.var(axis=0, ddof=1)
    fourth = ((Y - Y.mean(axis=0)) ** 4).mean(axis=0)
    np.testing.assert_allclose(errors["eps_m_floor"], np.sqrt(variance / n) / Y.mean(axis=0).max(), rtol=1e-12)
    se_variance = np.sqrt((fourth - (n - 3) / (n - 1) * variance**2) / n)
    np.testing.assert_allclose(errors["eps_v_floor"][1:], se_variance[1:] / variance.max(), rtol=1e-9)
    assert errors["kld_floor"] > 0 and "400 monte_carlo runs" in errors["floor_note"]
    assert np.max(errors["eps_m"]) < 3 * np.max(errors["eps_m_floor"])  # the grid is exact: only noise is left


def test_a_randomised_qmc_reference_takes_its_floor_from_the_replicates(tmp_path, flown):
    errors, runs = exact_grid_errors_against(tmp_path, flown, "{kind: sobol, samples: 64, replicates: 8}", "rqmc")
    Y = runs.reshape(8, 64, -1)
    means = Y.mean(axis=1)
    np.testing.assert_allclose(errors["eps_m_floor"], means.std(axis=0, ddof=1) / np.sqrt(8) / means.mean(axis=0).max(),
                               rtol=1e-9)
    assert "8 replicates" in errors["floor_note"]
    # scrambled Sobol' points resolve this smooth mean better than as many random draws would (σ/√512,
    # σ = 2 at t = 1); measured 0.32 of it, and 8 replicates estimate the spread to ~25 %: below 0.6
    assert np.max(errors["eps_m_floor"]) < 0.6 * np.sqrt(4 / 512) / 15001


def test_the_kld_floor_with_the_estimators_bias_covers_a_wider_law():
    # p ~ N(0, s²) (20,000 draws, a PCE's band draws) against a reference q ~ N(0, 1) of 2000 runs: the KDE
    # estimator overstates the KLD of a wider law (measured +27 % at s = 1.2, +33 % at 1.5) by more than the
    # split floor; with the estimator's bias for normal laws of the same means and spreads the floor covers
    # |estimate − closed form| in 99 of 100 draws over s = 0.8 ... 1.5 (20 each); here 10 draws at s = 1.2 and 1.5
    from uqflight.analysis.divergence import kl_divergence
    from uqflight.analysis.floors import kld_estimator_bias

    for s in (1.2, 1.5):
        true = np.log(1 / s) + s**2 / 2 - 0.5
        missed_by_split, missed = 0, 0
        for seed in range(10):
            rng = np.random.default_rng(seed)
            p, q = rng.normal(0, s, 20000), rng.normal(0, 1, 2000)
            error, split = abs(kl_divergence(p, q) - true), kld_floor(q, n_method=20000, seed=seed)
            missed_by_split += error > split
            missed += error > split + kld_estimator_bias(p, q, seed=seed)
        assert missed <= 1 and missed_by_split >= 3, (s, missed, missed_by_split)
    # the closed form of the bias's reference: two normal laws with equal spreads differ by their means alone
    rng = np.random.default_rng(1)
    assert kld_estimator_bias(rng.normal(0, 1, 5000), rng.normal(0, 1, 5000)) < 0.01
    assert np.isnan(kld_estimator_bias(np.zeros(100), rng.normal(0, 1, 100)))
