"""uqflight.analysis.failures on sampled designs: Wilson and Clopper–Pearson intervals, coverage (grids:
test_failure_probability.py)."""
import numpy as np
import pytest
from scipy.stats import binom, binomtest

from uqflight.analysis.failures import clopper_pearson_interval, failure_probability, wilson_interval
from uqflight.designs import build_design

Z95 = 1.959963984540054


def failures(k, n):
    return np.arange(n) < k


def test_wilson_closed_forms_at_the_ends():
    # 0 of n: [0, z²/(n + z²)]; n of n: [n/(n + z²), 1] (the score interval's closed forms).
    for n in (1, 10, 250):
        zero, every = failure_probability(failures(0, n)), failure_probability(failures(n, n))
        assert zero["estimate"] == 0.0 and every["estimate"] == 1.0
        assert zero["lower"] == pytest.approx(0.0, abs=1e-15)
        assert zero["upper"] == pytest.approx(Z95**2 / (n + Z95**2), rel=1e-12)
        assert every["lower"] == pytest.approx(n / (n + Z95**2), rel=1e-12)
        assert every["upper"] == pytest.approx(1.0, abs=1e-15)
        assert "Wilson" in zero["method"] and f"0 of {n}" in zero["method"]


def test_clopper_pearson_closed_forms_at_the_ends():
    # 0 of n: upper = 1 − (α/2)^(1/n); n of n: lower = (α/2)^(1/n).
    for n in (1, 10, 250):
        zero = failure_probability(failures(0, n), method="clopper_pearson")
        every = failure_probability(failures(n, n), method="clopper_pearson")
        assert (zero["lower"], every["upper"]) == (0.0, 1.0)
        assert zero["upper"] == pytest.approx(1 - 0.025 ** (1 / n), rel=1e-12)
        assert every["lower"] == pytest.approx(0.025 ** (1 / n), rel=1e-12)


@pytest.mark.parametrize("k, n", [(0, 7), (1, 20), (3, 50), (17, 40), (99, 100), (500, 1000)])
@pytest.mark.parametrize("confidence", [0.9, 0.95, 0.99])
def test_intervals_agree_with_scipy_binomtest(k, n, confidence):
    for method, scipy_name in (("wilson", "wilson"), ("clopper_pearson", "exact")):
        ours = failure_probability(failures(k, n), confidence=confidence, method=method)
        theirs = binomtest(k, n).proportion_ci(confidence, method=scipy_name)
        assert ours["estimate"] == k / n
        np.testing.assert_allclose([ours["lower"], ours["upper"]], [theirs.low, theirs.high], rtol=1e-10, atol=1e-14)


def test_exact_coverage_from_the_binomial_law():
    # Coverage = Σ_k Binom(k; n, p) 1[p ∈ CI(k)], exact. Clopper–Pearson never falls below the level;
    # Wilson stays within a few points of it for n·p ≥ 5 (Brown, Cai & DasGupta 2001, Fig. 4).
    for n, p in ((40, 0.2), (200, 0.05), (500, 0.3)):
        k = np.arange(n + 1)
        for method in ("wilson", "clopper_pearson"):
            inside = [lo <= p <= hi for lo, hi in (
                (wilson_interval(j / n, n) if method == "wilson" else clopper_pearson_interval(j, n)) for j in k)]
            coverage = binom.pmf(k, n, p) @ np.array(inside)
            if method == "clopper_pearson":
                assert coverage >= 0.95
            else:
                assert 0.92 <= coverage <= 0.98


def test_monte_carlo_coverage_of_a_model_failing_on_a_known_fraction():
    # The model fails where its first input ξ ~ N(0, 1) exceeds Φ⁻¹(1 − p): P(fail) = p exactly.
    # 1000 seeds of n = 200 runs. The exact Wilson coverage c at (200, 0.1) comes from the binomial
    # law; the observed coverage must be within 4 binomial standard errors √(c(1−c)/1000) ≈ 0.007.
    p, n, seeds = 0.1, 200, 1000
    threshold = 1.2815515655446004  # Φ⁻¹(0.9)
    k = np.arange(n + 1)
    exact = binom.pmf(k, n, p) @ np.array([lo <= p <= hi for lo, hi in (wilson_interval(j / n, n) for j in k)])
    hits = 0
    for seed in range(seeds):
        xi = build_design({"kind": "monte_carlo", "samples": n}, ["normal"], seed).xi
        result = failure_probability(xi[:, 0] > threshold)
        hits += result["lower"] <= p <= result["upper"]
    assert abs(hits / seeds - exact) <= 4 * np.sqrt(exact * (1 - exact) / seeds)
    assert abs(exact - 0.95) < 0.02


def test_undefined_and_invalid_inputs():
    empty = failure_probability(np.zeros(0, dtype=bool))
    assert np.isnan(empty["estimate"]) and (empty["lower"], empty["upper"]) == (0.0, 1.0)
    with pytest.raises(ValueError, match="method"):
        failure_probability(failures(1, 5), method="wald")


def test_the_wilson_interval_of_no_or_every_success_ends_exactly_at_0_or_1():
    from uqflight.analysis.failures import wilson_interval

    assert wilson_interval(0.0, 384)[0] == 0.0 and wilson_interval(1.0, 384)[1] == 1.0
    low, high = wilson_interval(0.0, 384)
    assert high == pytest.approx(3.8415 / (384 + 3.8415), rel=1e-4)  # z²/(n + z²), z = 1.95996
