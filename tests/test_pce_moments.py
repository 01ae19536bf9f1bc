"""The closed-form skewness and kurtosis of a PCE (methods.pce_moments) against exact values, and the
tolerance against the sampled estimate it replaced in the statistics (20,000 seeded draws)."""
import itertools

import numpy as np
import pytest
from numpy.polynomial.hermite_e import hermegauss
from numpy.polynomial.legendre import leggauss

from uqflight.analysis.moments import standardised_moments
from uqflight.methods.basis import orthonormal_basis, total_degree_indices
from uqflight.methods import pce_moments
from uqflight.methods.pce_moments import pce_standardised_moments
from uqflight.parameters.germs import draw_germs


def test_known_laws():
    # (ξ² − 1)/√2 = He₂/√2 of ξ ~ N(0, 1) is (χ²₁ − 1)/√2: skewness √8, kurtosis 3 + 12
    skewness, kurtosis = pce_standardised_moments(["normal"], [[0], [1], [2]], [[5.0], [0.0], [1.0]])
    assert skewness[0] == pytest.approx(np.sqrt(8.0), rel=1e-13) and kurtosis[0] == pytest.approx(15.0, rel=1e-13)
    # ξ ~ U(−1, 1): skewness 0, kurtosis 9/5; 1 + ξ₁ + ξ₂ (triangular law): kurtosis 3 − 6/10 = 2.4
    skewness, kurtosis = pce_standardised_moments(["uniform"], [[0], [1]], [[1.0], [2.0]])
    assert abs(skewness[0]) < 1e-14 and kurtosis[0] == pytest.approx(1.8, rel=1e-13)
    indices = total_degree_indices(2, 1)
    _, kurtosis = pce_standardised_moments(["uniform", "uniform"], indices, [[1.0], [1.0], [1.0]])
    assert kurtosis[0] == pytest.approx(2.4, rel=1e-13)
    # a constant has no spread: NaN, as the sampled moments
    skewness, kurtosis = pce_standardised_moments(["normal"], [[0], [1]], [[3.0, 3.0], [0.0, 2.0]])
    assert np.isnan(skewness[0]) and np.isnan(kurtosis[0]) and abs(skewness[1]) < 1e-14


@pytest.mark.parametrize("germs,order", [(["normal", "uniform", "normal"], 2), (["uniform", "normal"], 3)])
def test_random_expansions_against_tensor_gauss_quadrature(germs, order):
    # a tensor Gauss rule of 2·order + 1 points per input integrates Z⁴ (degree 4·order) exactly;
    # rtol 1e-10: rounding of sums of a few hundred terms
    rng = np.random.default_rng(7)
    indices = total_degree_indices(len(germs), order)
    coefficients = rng.standard_normal((len(indices), 3)) / (1.0 + indices.sum(axis=1))[:, None]
    rules = {"normal": lambda n: (hermegauss(n)[0], hermegauss(n)[1] / np.sqrt(2 * np.pi)),
             "uniform": lambda n: (leggauss(n)[0], leggauss(n)[1] / 2)}
    one_d = [rules[g](2 * order + 1) for g in germs]
    nodes = np.array(list(itertools.product(*(x for x, _ in one_d))))
    weights = np.prod(np.array(list(itertools.product(*(w for _, w in one_d)))), axis=1)
    values = orthonormal_basis(germs, indices, nodes) @ coefficients
    centred = values - weights @ values
    variance = weights @ centred**2
    skewness, kurtosis = pce_standardised_moments(germs, indices, coefficients)
    np.testing.assert_allclose(skewness, (weights @ centred**3) / variance**1.5, rtol=1e-10)
    np.testing.assert_allclose(kurtosis, (weights @ centred**4) / variance**2, rtol=1e-10)


def test_the_sampled_estimate_it_replaces_is_within_its_sampling_error():
    # The statistics used the adjusted sample moments of 20,000 seeded draws (analysis seed 0); the exact
    # values differ from them by that estimate's sampling error. Stated tolerance: 4 standard errors,
    # each from 20 batch means of 1000 draws (a skewed, heavy-tailed PCE; the seeded draws make this
    # deterministic)
    germs, indices = ["normal", "uniform"], total_degree_indices(2, 2)
    coefficients = np.array([[1.0, 0.0], [1.0, 0.3], [0.5, 1.0], [0.6, 0.2], [0.0, 0.4], [0.2, 0.5]])
    draws = orthonormal_basis(germs, indices, draw_germs(germs, 20000, 0)) @ coefficients
    sampled = np.array(standardised_moments(draws))
    batches = np.array([standardised_moments(draws[k::20]) for k in range(20)])
    error = batches.std(axis=0, ddof=1) / np.sqrt(20)
    exact = np.array(pce_standardised_moments(germs, indices, coefficients))
    assert np.all(np.abs(sampled - exact) <= 4 * error)


def test_blocks_of_times_change_nothing_and_a_large_basis_is_left_to_the_draws(monkeypatch):
    germs, indices = ["normal", "uniform", "normal"], total_degree_indices(3, 2)  # 9 varying terms, 35 in Φ
    coefficients = np.random.default_rng(0).standard_normal((len(indices), 50))
    whole = pce_standardised_moments(germs, indices, coefficients)
    monkeypatch.setattr(pce_moments, "MAX_TENSOR_ENTRIES", 9**2 * 35)  # blocks of 35 of the 50 times
    assert all(np.array_equal(a, b) for a, b in zip(whole, pce_standardised_moments(germs, indices, coefficients)))
    monkeypatch.setattr(pce_moments, "MAX_TENSOR_ENTRIES", 9**2 * 35 - 1)
    assert pce_standardised_moments(germs, indices, coefficients) is None


def test_outputs_on_one_basis_share_its_draws_and_triple_products_and_get_the_same_numbers():
    from uqflight.analysis.statistics import BasisCache, Options

    germs, options, basis_cache = ["normal", "uniform", "normal"], Options(band_samples=500, seed=3), BasisCache()
    indices = total_degree_indices(3, 2)
    rows = basis_cache.band_rows(germs, indices, options)
    assert rows is basis_cache.band_rows(germs, indices.copy(), options)  # the same basis: computed once
    assert np.array_equal(rows, orthonormal_basis(germs, indices, draw_germs(germs, 500, 3)))
    with pytest.raises(ValueError):
        rows[0, 0] = 1.0  # shared, so read-only
    other = basis_cache.band_rows(germs, indices[:-1], options)  # another basis (a sparse selection): its own
    assert other.shape == (500, len(indices) - 1) and basis_cache.band_rows(germs, indices, options) is not rows
    coefficients = np.random.default_rng(0).normal(size=(len(indices), 4))
    for _ in range(2):  # the second expansion on the same basis reads the kept triple products
        shared = pce_standardised_moments(germs, indices, coefficients, basis_cache.triple_products)
        assert all(np.array_equal(a, b) for a, b in zip(shared, pce_standardised_moments(germs, indices, coefficients)))
