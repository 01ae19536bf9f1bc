"""What a design's points and weights can integrate, measured on the points themselves.

Works for any design (tensor, Smolyak, nested or not, Monte Carlo): the degree is read off the
quadrature errors of the orthonormal basis, E[Ψ_α] = δ_{α,0}, not taken from theory.
"""
import numpy as np

from ..parameters.germs import check_germs
from .basis import orthonormal_basis, total_degree_indices

EXACTNESS_RTOL = np.sqrt(np.finfo(float).eps)  # ~1.5e-8; see exact_total_degree


def _indices_of_degree(dim: int, degree: int) -> np.ndarray:
    indices = total_degree_indices(dim, degree)
    return indices[indices.sum(axis=1) == degree]


def quadrature_errors(xi, weights, germs, degree: int) -> tuple[np.ndarray, np.ndarray]:
    """|Σ_j w_j Ψ_α(ξ_j) − δ_{α,0}| and the sum's scale Σ_j |w_j| (1 + |Ψ_α(ξ_j)|), for every α with |α| = degree."""
    germs = check_germs(germs)
    values = orthonormal_basis(germs, _indices_of_degree(len(germs), degree), xi)
    weights = np.asarray(weights, dtype=float)
    exact = 1.0 if degree == 0 else 0.0
    return np.abs(weights @ values - exact), np.abs(weights) @ (1.0 + np.abs(values))


def exact_total_degree(xi, weights, germs, max_degree: int = 25, rtol: float = EXACTNESS_RTOL) -> int:
    """The largest p ≤ max_degree such that the design integrates every Ψ_α with |α| ≤ p exactly.

    "Exactly" means |Σ w_j Ψ_α(ξ_j) − δ_{α,0}| ≤ rtol · Σ_j |w_j| (1 + |Ψ_α(ξ_j)|): the sum's own
    scale (it grows with signed weights and with large |Ψ_α| at outer nodes; the 1 stands for the
    absolute error ~eps of a Ψ_α evaluated where it vanishes, e.g. at Gauss nodes) times rtol = √eps. The rounding of the sum is ≤ N·eps times that scale, far below √eps for any design
    size in use, and tabulated rules with ~9-digit weights (Genz–Keister's 43 points) still pass;
    a rule that is not exact for Ψ_α misses by O(1) of the scale, and Monte Carlo by ~1/√N.
    Returns −1 when not even the weights' sum is 1 (degree 0), max_degree when every degree up
    to it passes (so read "≥ max_degree"). Cost: C(d + p, d) basis functions at the N points.
    """
    xi = np.asarray(xi, dtype=float)
    for degree in range(max_degree + 1):
        error, scale = quadrature_errors(xi, weights, germs, degree)
        if np.any(error > rtol * scale):
            return degree - 1
    return max_degree


def max_projection_order(degree: int) -> int:
    """The highest total order p a pseudo-Galerkin projection can use on a design exact to `degree`.

    The projection's discrete Gram matrix Σ w Ψ_α Ψ_β is the identity only when every product of
    two basis functions of order ≤ p (total degree ≤ 2p) integrates exactly: p = degree // 2.
    A negative degree gives −1 (no order is safe).
    """
    return degree // 2 if degree >= 0 else -1


def design_matrix_rank(xi, germs, order: int, weights=None, rcond: float | None = None) -> tuple[int, int]:
    """(rank, Z) of the design matrix Ψ (N, Z), Ψ_jα = Ψ_α(ξ_j), |α| ≤ order, Z = C(d + order, d).

    weights None: Ψ itself (interpolation, regression on the points). weights given: the rows
    scaled by √|w_j|, so points whose weights cancel to 0 count for nothing, as in a weighted fit.
    rank = number of singular values > rcond · s_max, rcond defaulting to max(N, Z)·eps (the
    rounding level of an SVD of an N×Z matrix, numpy.linalg.matrix_rank's rule). rank < Z: the
    coefficients of an order-`order` fit on these points are not determined.
    """
    germs = check_germs(germs)
    matrix = orthonormal_basis(germs, total_degree_indices(len(germs), order), xi)
    if weights is not None:
        matrix = matrix * np.sqrt(np.abs(np.asarray(weights, dtype=float)))[:, None]
    n, z = matrix.shape
    if n == 0:
        return 0, z
    singular = np.linalg.svd(matrix, compute_uv=False)
    rcond = max(n, z) * np.finfo(float).eps if rcond is None else rcond
    return int(np.count_nonzero(singular > rcond * singular[0])), z
