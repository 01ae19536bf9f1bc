"""uqflight.methods against closed forms: orthonormality, exact recovery of polynomials, e^{-at}."""
from itertools import product
from math import comb

import numpy as np
import pytest
from numpy.polynomial.hermite_e import hermegauss
from numpy.polynomial.legendre import leggauss

from uqflight.methods import METHOD_KINDS, fit
from uqflight.methods.basis import orthonormal_basis, total_degree_indices
from uqflight.parameters.germs import draw_germs
from uqflight.methods.galerkin import pseudo_galerkin
from uqflight.methods.pce import PCE

MIXED = ["normal", "uniform", "normal"]


def gauss_tensor_grid(germs, points_per_dim):
    """Tensor Gauss rule for the germs' laws: points (n^d, d) and probability weights summing to 1."""
    rules = {
        "normal": lambda n: (hermegauss(n)[0], hermegauss(n)[1] / np.sqrt(2 * np.pi)),
        "uniform": lambda n: (leggauss(n)[0], leggauss(n)[1] / 2),
    }
    nodes, weights = zip(*(rules[germ](points_per_dim) for germ in germs))
    xi = np.array(list(product(*nodes)))
    w = np.prod(np.array(list(product(*weights))), axis=1)
    return xi, w


def random_polynomial(germs, order, n_times, seed=1):
    """Coefficients (Z, T) of a random polynomial of total degree ``order`` in the orthonormal basis."""
    indices = total_degree_indices(len(germs), order)
    return indices, np.random.default_rng(seed).normal(size=(len(indices), n_times))


def test_total_degree_indices_are_graded_complete_and_constant_first():
    indices = total_degree_indices(3, 4)
    assert indices.shape == (comb(3 + 4, 4), 3)
    assert not indices[0].any()
    assert (np.diff(indices.sum(axis=1)) >= 0).all()
    assert len({tuple(row) for row in indices}) == len(indices)


def test_basis_is_orthonormal_under_each_germ():
    # 5 Gauss points per dimension integrate degree 9 exactly, enough for products of degree 8.
    indices = total_degree_indices(3, 4)
    xi, w = gauss_tensor_grid(MIXED, 5)
    basis = orthonormal_basis(MIXED, indices, xi)
    np.testing.assert_allclose(basis.T @ (w[:, None] * basis), np.eye(len(indices)), atol=1e-12)


def test_one_dimensional_polynomials_match_their_closed_forms():
    x = np.linspace(-1, 1, 7)
    indices = np.array([[0], [1], [2], [3]])
    hermite = orthonormal_basis(["normal"], indices, x[:, None])
    legendre = orthonormal_basis(["uniform"], indices, x[:, None])
    np.testing.assert_allclose(hermite[:, 2], (x**2 - 1) / np.sqrt(2), atol=1e-14)
    np.testing.assert_allclose(hermite[:, 3], (x**3 - 3 * x) / np.sqrt(6), atol=1e-14)
    np.testing.assert_allclose(legendre[:, 2], np.sqrt(5) * (3 * x**2 - 1) / 2, atol=1e-14)
    np.testing.assert_allclose(legendre[:, 3], np.sqrt(7) * (5 * x**3 - 3 * x) / 2, atol=1e-14)


def test_unknown_germ_is_refused():
    with pytest.raises(ValueError, match="gamma"):
        orthonormal_basis(["gamma"], np.zeros((1, 1), dtype=int), np.zeros((2, 1)))


def test_projection_recovers_a_polynomial_on_an_exact_gauss_grid():
    # Degree 3 times degree 3 is degree 6; 4 Gauss points integrate degree 7: only rounding is left.
    indices, coefficients = random_polynomial(MIXED, 3, n_times=5)
    xi, w = gauss_tensor_grid(MIXED, 4)
    Y = orthonormal_basis(MIXED, indices, xi) @ coefficients
    result = fit("pseudo_galerkin", xi, w, Y, MIXED, order=3)
    np.testing.assert_allclose(result.pce.coefficients, coefficients, atol=1e-12)
    np.testing.assert_allclose(result.mean, coefficients[0], atol=1e-12)
    np.testing.assert_allclose(result.variance, (coefficients[1:] ** 2).sum(axis=0), atol=1e-12)


@pytest.mark.parametrize("kind", ["regression", "least_squares"])
def test_regression_recovers_a_polynomial_from_random_points(kind):
    # The data lie in the span of V, so any full-rank least-squares fit is exact up to rounding.
    indices, coefficients = random_polynomial(MIXED, 3, n_times=4)
    xi = draw_germs(MIXED, 200, seed=2)
    w = np.random.default_rng(3).uniform(0.1, 1.0, 200)
    Y = orthonormal_basis(MIXED, indices, xi) @ coefficients
    result = fit(kind, xi, w, Y, MIXED, order=3)
    np.testing.assert_allclose(result.pce.coefficients, coefficients, atol=1e-10)


def test_least_squares_uses_absolute_values_of_signed_weights():
    xi = draw_germs(["normal", "normal"], 60, seed=4)
    Y = np.exp(0.3 * xi[:, :1]) * np.cos(xi[:, 1:])
    signed = np.random.default_rng(5).uniform(-0.5, 1.0, 60)
    signed[0] = -0.3
    with_signed = fit("least_squares", xi, signed, Y, ["normal", "normal"], order=2)
    with_absolute = fit("least_squares", xi, np.abs(signed), Y, ["normal", "normal"], order=2)
    np.testing.assert_allclose(with_signed.pce.coefficients, with_absolute.pce.coefficients, atol=1e-12)


def test_regression_with_too_few_points_names_n_z_and_order():
    xi = draw_germs(MIXED, 9, seed=0)
    with pytest.raises(ValueError, match=r"N = 9 .* Z = 10 .* order-2"):
        fit("regression", xi, None, np.ones((9, 2)), MIXED, order=2)


def test_regression_on_points_that_cannot_separate_the_basis_is_refused():
    with pytest.raises(ValueError, match="rank"):
        fit("regression", np.zeros((10, 2)), None, np.ones(10), ["normal", "normal"], order=1)


def test_interpolation_moments_are_the_weighted_sums_and_its_pce_the_projection():
    xi, w = gauss_tensor_grid(["normal", "uniform"], 3)
    Y = np.column_stack([np.sin(xi[:, 0]) + xi[:, 1] ** 3, np.exp(xi[:, 1])])
    result = fit("interpolation", xi, w, Y, ["normal", "uniform"], order=2)
    np.testing.assert_allclose(result.mean, w @ Y, atol=1e-14)
    np.testing.assert_allclose(result.variance, w @ (Y - w @ Y) ** 2, atol=1e-14)
    projection = fit("pseudo_galerkin", xi, w, Y, ["normal", "uniform"], order=2)
    np.testing.assert_allclose(result.pce.coefficients, projection.pce.coefficients, atol=1e-14)


def test_moment_kinds_and_unknown_kind():
    rng = np.random.default_rng(6)
    Y = rng.normal(size=(50, 3))
    w = rng.uniform(size=50)
    mc = fit("monte_carlo", None, w, Y, ["normal"])
    np.testing.assert_allclose(mc.mean, Y.mean(axis=0), atol=1e-14)
    np.testing.assert_allclose(mc.variance, Y.var(axis=0, ddof=1), atol=1e-14)
    xi = draw_germs(["normal"], 50, seed=6)
    integration = fit("integration", xi, w, Y, ["normal"])
    np.testing.assert_allclose(integration.mean, w @ Y / w.sum(), atol=1e-14)
    assert mc.pce is None
    # the PCE that serves bands and Sobol' indices is the projection
    np.testing.assert_allclose(integration.pce.coefficients, fit("pseudo_galerkin", xi, w, Y, ["normal"]).pce.coefficients)
    with pytest.raises(ValueError, match=", ".join(METHOD_KINDS)):
        fit("kriging", None, w, Y, ["normal"])


def test_split_form_is_refused_where_it_changes_nothing():
    xi = draw_germs(["normal"], 20, seed=0)
    with pytest.raises(ValueError, match="x0"):
        fit("regression", xi, None, np.ones((20, 3)), ["normal"], x0=np.ones(3))


def test_split_form_with_a_deterministic_x0_removes_aliasing_of_the_offset():
    # 50 MC points do not integrate Ψ_α exactly, so projecting 1e6 + ξ leaks ~1e6·Σ Ψ_α w into c_α;
    # with x0 = 1e6 the offset sits in the constant term alone and c_1 is the projection of ξ.
    xi = draw_germs(["normal"], 50, seed=7)
    w = np.full(50, 1 / 50)
    x0 = np.array([1e6, 2e6])
    Y = x0 + xi
    plain = pseudo_galerkin(xi, w, Y, ["normal"], order=2)
    split = pseudo_galerkin(xi, w, Y, ["normal"], order=2, x0=x0)
    change = pseudo_galerkin(xi, w, xi, ["normal"], order=2)
    np.testing.assert_allclose(split.coefficients[1:], np.repeat(change.coefficients[1:], 2, axis=1), atol=1e-9)
    np.testing.assert_allclose(split.coefficients[0], x0 + change.coefficients[0, 0], rtol=1e-15)
    assert np.abs(plain.coefficients[2]).min() > 1e3


def test_split_form_with_per_sample_initial_values_equals_the_projection():
    # Projection is linear, so projecting Y[:, :1] and Y − Y[:, :1] separately sums to the same PCE.
    xi = draw_germs(["normal", "uniform"], 80, seed=8)
    w = np.full(80, 1 / 80)
    Y = np.exp(0.2 * xi[:, :1] * np.linspace(0, 1, 6)) + 1e4 * (1 + 0.1 * xi[:, 1:])
    plain = pseudo_galerkin(xi, w, Y, ["normal", "uniform"], order=3)
    split = pseudo_galerkin(xi, w, Y, ["normal", "uniform"], order=3, x0=Y[:, :1])
    np.testing.assert_allclose(split.coefficients, plain.coefficients, rtol=1e-12, atol=1e-9)
    with pytest.raises(ValueError, match="x0 has shape"):
        pseudo_galerkin(xi, w, Y, ["normal", "uniform"], x0=np.ones(5))


def test_pseudo_galerkin_recovers_moments_of_a_decaying_exponential():
    # x = e^{-at}, a = μ + σξ: the PCE coefficients are e^{s²/2}(−s)^n/√n! with s = σt ≤ 0.5, so the
    # order-6 truncation drops Σ_{n>6} s^{2n}/n! ≈ 1e-8 (relative to var ≈ 0.3), and 10 Gauss–Hermite
    # points integrate degree 19 exactly, so aliasing needs terms of degree ≥ 14: 1e-6 is a safe margin.
    mu, sigma = 0.8, 0.1
    t = np.linspace(0.0, 5.0, 101)
    xi, w = gauss_tensor_grid(["normal"], 10)
    Y = np.exp(-(mu + sigma * xi) * t)
    result = fit("pseudo_galerkin", xi, w, Y, ["normal"], order=6)
    mean = np.exp(-mu * t + sigma**2 * t**2 / 2)
    variance = np.exp(-2 * mu * t + 2 * sigma**2 * t**2) - mean**2
    np.testing.assert_allclose(result.mean, mean, rtol=1e-6)
    np.testing.assert_allclose(result.variance[1:], variance[1:], rtol=1e-6)
    assert abs(result.variance[0]) < 1e-20


def test_pce_sampling_is_seeded_and_matches_its_moments():
    indices, coefficients = random_polynomial(["normal", "uniform"], 2, n_times=2)
    pce = PCE(["normal", "uniform"], indices, coefficients)
    samples = pce.sample(100_000, seed=3)
    np.testing.assert_array_equal(pce.sample(50, seed=3), pce.sample(50, seed=3))
    assert samples.shape == (100_000, 2)
    # Monte Carlo error of the mean is σ/√n ≈ 0.003σ; 0.02σ leaves room.
    np.testing.assert_allclose(samples.mean(axis=0), pce.mean(), atol=0.02 * np.sqrt(pce.variance()).max())
