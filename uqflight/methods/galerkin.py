"""Pseudo-Galerkin projection (Eq. 19–21) and its split form x = x0 + S (Eq. 22–24).

c_α = Σ_j Y_j Ψ_α(ξ_j) w_j. The split form projects only the change S = Y − x0 and adds the
PCE of x0 back. In exact arithmetic with a rule that integrates every Ψ_α exactly it changes
nothing, since projection is linear. It matters in two cases:

* a deterministic x0 (T,), e.g. the nominal trajectory or the trim state: its PCE is x0 in the
  constant term alone, so a rule that does not integrate some Ψ_α exactly (Σ_j Ψ_α(ξ_j) w_j ≠ 0:
  Monte Carlo points, a low sparse-grid level against a high order) no longer aliases the large
  value x0 into c_α; and Σ_j S_j Ψ_α w_j no longer cancels big terms (altitude ~ 10⁴ ft that
  varies by a few ft), which signed sparse-grid weights with Σ|w_j| ≫ 1 amplify;
* per-sample initial values x0 (N, 1), e.g. Y[:, :1]: x0 is projected with the same rule, so
  the result equals the direct projection up to rounding; only the cancellation error shrinks.
"""
import numpy as np

from ..analysis.moments import as_runs_by_time, probability_weights
from ..parameters.germs import check_germs
from .kind import Method, scaled
from .basis import orthonormal_basis, total_degree_indices
from .exactness import exact_total_degree, max_projection_order
from .pce import PCE


def project(xi, weights, Y, germs, indices) -> np.ndarray:
    """Eq. 21: c_α = Σ_j Y_j Ψ_α(ξ_j) w_j for every α in indices (Z, d): (Z, T)."""
    Y = as_runs_by_time(Y)
    basis = orthonormal_basis(germs, indices, xi)
    return basis.T @ (probability_weights(weights, len(Y))[:, None] * Y)


def _split_offset(x0, Y: np.ndarray) -> np.ndarray:
    """x0 as an array that broadcasts against Y (N, T): (T,) deterministic or (N, 1) per sample."""
    x0 = np.asarray(x0, dtype=float)
    if x0.shape not in ((Y.shape[1],), (Y.shape[0], 1)):
        raise ValueError(
            f"x0 has shape {x0.shape}: expected ({Y.shape[1]},) for a deterministic initial state "
            f"or ({Y.shape[0]}, 1) for per-sample initial values"
        )
    return x0


def pseudo_galerkin(xi, weights, Y, germs, order: int = 2, x0=None) -> PCE:
    """PCE of total degree ``order`` by projection (Eq. 21), or by the split form (Eq. 24) when x0 is given."""
    germs = check_germs(germs)
    Y = as_runs_by_time(Y)
    indices = total_degree_indices(len(germs), order)
    if x0 is None:
        return PCE(germs, indices, project(xi, weights, Y, germs, indices))
    x0 = _split_offset(x0, Y)
    coefficients = project(xi, weights, Y - x0, germs, indices)
    if x0.ndim == 1:
        coefficients[0] += x0
    else:
        coefficients += project(xi, weights, x0, germs, indices)
    return PCE(germs, indices, coefficients)



class Projection(Method):
    """A PCE by projection (Eq. 21), split form with x0 (Eq. 24): the kinds below (no kind of its own)."""

    rule, failed_runs, split = "projection", "projected", True

    def points_problem(self, order: int, xi, weights, germs: list[str], sampled: bool,
                       allow_aliasing: bool = False) -> str | None:
        """A grid exact to degree 2p (the discrete Gram matrix the identity), unless aliasing is allowed."""
        degree = 2 * order if sampled or allow_aliasing else exact_total_degree(xi, weights, germs, 2 * order)
        if degree < 2 * order:
            return (f"{self.kind} of order {order} needs a grid exact to degree {2 * order}, but this grid is exact "
                    f"to degree {degree}: the largest order it can project is {max_projection_order(degree)} "
                    "(or allow aliasing explicitly)")
        return None

    def expansion(self, xi, weights, Y, germs, order: int, x0=None, scale=None, **settings) -> PCE:
        return scaled(pseudo_galerkin(xi, weights, Y, germs, order, x0), scale)


class Integration(Projection):
    """Weighted sums of the runs (Eq. 17); on a grid the PCE for bands, PDFs and Sobol' indices is the
    projection.

    Examples
    --------
    >>> import numpy as np
    >>> from uqflight.methods import Method
    >>> xi, w = np.array([[-3**0.5], [0.0], [3**0.5]]), np.array([1, 4, 1]) / 6  # 3-point Gauss-Hermite
    >>> result = Method.of("integration").fit(xi, w, xi**2, ["normal"], order=1)
    >>> round(float(result.mean[0]), 12), round(float(result.variance[0]), 12)  # E[ξ²] = 1, Var[ξ²] = 2
    (1.0, 2.0)
    >>> round(float(result.pce.variance()[0]), 12)  # the moments are the weights', not the order-1 PCE's
    0.0
    """

    kind, label, failed_runs, runs_on_sampled, quadrature = "integration", "Int", "conditional", True, True
    exported_as = ("least_squares", "pseudo_galerkin")


class PseudoGalerkin(Projection):
    """Projection of the runs on the PCE (Eq. 19–21); moments from the PCE.

    Examples
    --------
    >>> import numpy as np
    >>> from uqflight.methods import Method
    >>> xi, w = np.array([[-3**0.5], [0.0], [3**0.5]]), np.array([1, 4, 1]) / 6  # 3-point Gauss-Hermite
    >>> pce = Method.of("pseudo_galerkin").fit(xi, w, xi**2, ["normal"], order=2).pce
    >>> [round(float(c), 12) for c in pce.coefficients[:, 0]]  # ξ² = 1 + √2 · He₂(ξ)/√2
    [1.0, 0.0, 1.414213562373]
    >>> round(float(pce.mean()[0]), 12), round(float(pce.variance()[0]), 12)  # E[ξ²] = 1, Var[ξ²] = (√2)² = 2
    (1.0, 2.0)
    >>> order1 = Method.of("pseudo_galerkin").fit(xi, w, xi**2, ["normal"], order=1)
    >>> round(float(order1.variance[0]), 12)  # moments from the PCE: order 1 carries none of Var[ξ²]
    0.0
    """

    kind, label = "pseudo_galerkin", "PG"


class Interpolation(Projection):
    """Moments from the weights (Eq. 32–34), PCE by projection.

    Examples
    --------
    >>> import numpy as np
    >>> from uqflight.methods import Method
    >>> x, w = np.array([[-0.6**0.5], [0.0], [0.6**0.5]]), np.array([5, 8, 5]) / 18  # 3-point Gauss-Legendre
    >>> result = Method.of("interpolation").fit(x, w, x**2, ["uniform"], order=2)
    >>> round(float(result.mean[0]), 12), round(float(result.variance[0]), 12)  # 1/3 and 1/5 − 1/9 = 4/45
    (0.333333333333, 0.088888888889)
    >>> round(float(result.pce.evaluate(np.array([[0.5]]))[0, 0]), 12)  # the projection is x² itself
    0.25
    """

    kind, label, quadrature = "interpolation", "interpolation", True
    exported_as = ("pseudo_galerkin", "pseudo_galerkin")
