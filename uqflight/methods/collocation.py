"""Stochastic collocation by fitting: regression (Eq. 35–37) and weighted least squares (Eq. 43–48).

Interpolation (Eq. 26–34, 41–42) needs no fit: its moments are the weighted sums of the runs and its
PCE the projection, because I_j(ξ_k) = δ_jk (see the registry in `uqflight.methods`).
"""
import numpy as np

from ..analysis.moments import as_runs_by_time, probability_weights
from ..parameters.germs import check_germs
from .kind import Method, scaled
from .basis import orthonormal_basis, total_degree_indices
from .exactness import design_matrix_rank
from .pce import PCE


def _basis_matrix(xi, germs, order: int) -> tuple[np.ndarray, np.ndarray]:
    """Total-degree indices (Z, d) and the Vandermonde-like V = [Ψ_α(ξ_j)] (N, Z) of Eq. 37."""
    indices = total_degree_indices(len(germs), order)
    return indices, orthonormal_basis(germs, indices, xi)


def _solve(matrix: np.ndarray, rhs: np.ndarray, order: int) -> np.ndarray:
    """Least-squares solution (Z, T) by SVD (numpy lstsq); refuses an undetermined system."""
    n_points, n_terms = matrix.shape
    if n_points < n_terms:
        raise ValueError(
            f"N = {n_points} points cannot determine Z = {n_terms} coefficients of a total-degree "
            f"order-{order} expansion: use N >= Z points or a lower order"
        )
    coefficients, _, rank, _ = np.linalg.lstsq(matrix, rhs, rcond=None)
    if rank < n_terms:
        raise ValueError(
            f"the {n_points} points determine only {rank} of the Z = {n_terms} coefficients "
            f"of the order-{order} expansion (rank-deficient design): lower the order"
        )
    return coefficients


def regression(xi, Y, germs, order: int = 2) -> PCE:
    """Solve V c = Y (Eq. 36): interpolation when N = Z, least squares when N > Z; N < Z is a ValueError."""
    germs = check_germs(germs)
    indices, matrix = _basis_matrix(xi, germs, order)
    return PCE(germs, indices, _solve(matrix, as_runs_by_time(Y), order))


def least_squares(xi, weights, Y, germs, order: int = 2) -> PCE:
    """Weighted least squares min Σ_z |w_z| (Y_z − V c)² (Eq. 44), solved through lstsq of √|w|·V.

    Factorising √|w|·V (SVD) never forms the Gram matrix J = VᵀWV of Eq. 47, whose condition
    number is the square of V's. Signed sparse-grid weights are replaced by |w|: with a negative
    w_z the objective stops being a sum of squares (it would reward misfit at ξ_z, and √w_z is
    not real), while |w| keeps a true minimisation that still gives the tails of the law the
    small influence their weights say. For non-negative weights (MC, Gauss tensor grids) this is
    exactly Eq. 44; a polynomial in the basis is recovered exactly either way.
    """
    germs = check_germs(germs)
    Y = as_runs_by_time(Y)
    root_weights = np.sqrt(np.abs(probability_weights(weights, len(Y))))[:, None]
    indices, matrix = _basis_matrix(xi, germs, order)
    return PCE(germs, indices, _solve(root_weights * matrix, root_weights * Y, order))


class Fit(Method):
    """A PCE fitted by least squares on a total-degree basis: the kinds below (no kind of its own)."""

    rule, failed_runs, partial = "fit", "extrapolated", True

    def points_problem(self, order: int, xi, weights, germs: list[str], sampled: bool,
                       allow_aliasing: bool = False) -> str | None:
        """A design matrix of full rank Z on the actual points (N >= Z is not enough)."""
        def rank_and_terms(p: int) -> tuple[int, int]:
            return design_matrix_rank(xi, germs, p, weights if self.weighted else None)

        rank, terms = rank_and_terms(order)
        if rank == terms:
            return None
        fitting = next((p for p in range(order - 1, -1, -1) if len(set(rank_and_terms(p))) == 1), -1)
        return (f"{self.kind} of order {order} fits {terms} terms, but the design matrix on the {len(xi)} points has "
                f"rank {rank}: the coefficients are not determined; the largest order with full rank is {fitting}")


class Regression(Fit):
    """Least-squares fit of the PCE, weights ignored (Eq. 35–37).

    Examples
    --------
    >>> import numpy as np
    >>> from uqflight.methods import Method
    >>> fit, xi = Method.of("regression").fit, np.random.default_rng(0).standard_normal((6, 2))  # 6 random points
    >>> result = fit(xi, np.full(6, 1 / 6), 1 + 2 * xi[:, :1] + 3 * xi[:, 1:], ["normal", "normal"], order=1)
    >>> round(float(result.mean[0]), 12), round(float(result.variance[0]), 12)  # exact: 1 and 2² + 3² = 13
    (1.0, 13.0)
    >>> x = np.array([[-1.0], [0.0], [1.0]])  # x² with Simpson's weights: its constant is the plain mean of the runs
    >>> round(float(fit(x, np.array([1, 4, 1]) / 6, x**2, ["uniform"], order=1).mean[0]), 12)  # 2/3, not E[x²] = 1/3
    0.666666666667
    """

    kind, label, weighted = "regression", "regression", False

    def expansion(self, xi, weights, Y, germs, order: int, x0=None, scale=None, **settings) -> PCE:
        return scaled(regression(xi, Y, germs, order), scale)


class LeastSquares(Fit):
    """Weighted least-squares fit of the PCE (Eq. 43–48).

    Examples
    --------
    >>> import numpy as np
    >>> from uqflight.methods import Method
    >>> x, simpson = np.array([[-1.0], [0.0], [1.0]]), np.array([1, 4, 1]) / 6  # Simpson's rule for U(−1, 1)
    >>> order1 = Method.of("least_squares").fit(x, simpson, x**2, ["uniform"], order=1)
    >>> round(float(order1.mean[0]), 12), round(float(order1.variance[0]), 12)  # weighted: E[x²] = 1/3; x carries none
    (0.333333333333, 0.0)
    >>> order2 = Method.of("least_squares").fit(x, simpson, x**2, ["uniform"], order=2)
    >>> round(float(order2.mean[0]), 12), round(float(order2.variance[0]), 12)  # x² in the basis: 1/5 − 1/9 = 4/45
    (0.333333333333, 0.088888888889)
    """

    kind, label = "least_squares", "least squares"

    def expansion(self, xi, weights, Y, germs, order: int, x0=None, scale=None, **settings) -> PCE:
        return scaled(least_squares(xi, weights, Y, germs, order), scale)
