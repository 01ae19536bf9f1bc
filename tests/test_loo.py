"""Leave-one-out residuals and relative errors against direct refits and closed forms."""
import numpy as np
import pytest

from uqflight.methods.basis import orthonormal_basis, total_degree_indices
from uqflight.methods.loo import loo_residuals, relative_loo_error


def direct_loo(X, Y, w):
    """Refit without each point (weights |w|) and predict it: the definition of LOO."""
    w = np.ones(len(X)) if w is None else np.abs(w)
    out = np.empty_like(Y)
    for i in range(len(X)):
        keep = np.arange(len(X)) != i
        root = np.sqrt(w[keep])[:, None]
        c, *_ = np.linalg.lstsq(root * X[keep], root * Y[keep], rcond=None)
        out[i] = Y[i] - X[i] @ c
    return out


@pytest.fixture
def case():
    rng = np.random.default_rng(3)
    xi = rng.standard_normal((25, 2))
    X = orthonormal_basis(["normal", "normal"], total_degree_indices(2, 2), xi)  # 25 x 6
    Y = np.column_stack([np.sin(xi[:, 0]) + xi[:, 1] ** 3, np.exp(0.3 * xi[:, 1]), rng.standard_normal(25)])
    signed = rng.uniform(0.1, 2.0, 25) * rng.choice([-1.0, 1.0], 25)  # signed, like sparse-grid weights
    return X, Y, signed


@pytest.mark.parametrize("weighted", [False, True])
def test_loo_residuals_equal_a_direct_refit(case, weighted):
    X, Y, signed = case
    w = signed if weighted else None
    np.testing.assert_allclose(loo_residuals(X, Y, w), direct_loo(X, Y, w), rtol=1e-8, atol=1e-10)


@pytest.mark.parametrize("weighted", [False, True])
def test_relative_loo_error_matches_its_definition(case, weighted):
    X, Y, signed = case
    w = np.abs(signed) if weighted else np.ones(len(X))
    loo = direct_loo(X, Y, w)
    mean = w @ Y / w.sum()
    expected = (w @ loo**2) / (w @ (Y - mean) ** 2)
    np.testing.assert_allclose(relative_loo_error(X, Y, signed if weighted else None), expected, rtol=1e-8)


def test_a_polynomial_in_the_basis_has_zero_loo_error(case):
    X, _, signed = case
    y = X @ np.array([1.0, -2.0, 0.5, 3.0, 0.0, 1.5])  # exactly in the span: every refit recovers it
    assert np.max(np.abs(loo_residuals(X, y, signed))) < 1e-10
    assert relative_loo_error(X, y, signed) < 1e-20


def test_one_dimensional_y_and_a_constant_column():
    X = np.column_stack([np.ones(6), np.arange(6.0)])
    y = np.array([0.0, 1.1, 1.9, 3.2, 3.9, 5.1])
    assert loo_residuals(X, y).shape == (6,)
    assert np.isfinite(relative_loo_error(X, y))
    # a column that does not vary: the relative error is 0/0, reported as NaN (null in JSON)
    errors = relative_loo_error(X, np.column_stack([y, np.full(6, 7.0)]))
    assert np.isfinite(errors[0]) and np.isnan(errors[1])


def test_interpolation_and_rank_deficiency_are_refused():
    X = np.column_stack([np.ones(3), np.arange(3.0), np.arange(3.0) ** 2])  # N = Z: interpolation
    with pytest.raises(ValueError, match="interpolates"):
        loo_residuals(X, np.arange(3.0))
    X = np.column_stack([np.ones(5), np.arange(5.0), 2 * np.arange(5.0)])  # two equal columns
    with pytest.raises(ValueError, match="rank 2 < Z = 3"):
        relative_loo_error(X, np.arange(5.0))
    with pytest.raises(ValueError, match="N > Z"):
        loo_residuals(np.ones((2, 3)), np.ones(2))
    # a point alone in its direction (a column only it touches) is interpolated too
    X = np.column_stack([np.ones(5), [0, 0, 0, 0, 1.0]])
    with pytest.raises(ValueError, match="rows 4"):
        loo_residuals(X, np.arange(5.0))
