"""Non-intrusive UQ methods (paper section 4): one entry point, ``fit``, for every kind."""
from dataclasses import dataclass

import numpy as np

from ..analysis.moments import as_runs_by_time
from .basis import orthonormal_basis, total_degree_indices
from .collocation import interpolation, least_squares, regression
from .galerkin import pseudo_galerkin
from .integration import direct_integration, monte_carlo
from .pce import PCE

METHOD_KINDS = ("integration", "pseudo_galerkin", "interpolation", "regression", "least_squares", "monte_carlo")
SPLIT_FORM_KINDS = ("pseudo_galerkin", "interpolation")


@dataclass
class Result:
    """Mean and variance per time (each (T,)), and the PCE when the method builds one."""

    mean: np.ndarray
    variance: np.ndarray
    pce: PCE | None


def fit(kind: str, xi, weights, Y, germs, order: int = 2, x0=None) -> Result:
    """Apply method ``kind`` to the runs Y (N, T) at points xi (N, d) with weights (N,).

    * ``integration``: weighted sums (Eq. 17), no PCE;
    * ``monte_carlo``: sample mean and unbiased variance, the weights ignored, no PCE;
    * ``pseudo_galerkin``: projection (Eq. 21), split form (Eq. 24) when x0 is given;
    * ``interpolation``: moments from the weights, PCE by projection (Eq. 34, 42);
    * ``regression``: V c = Y by least squares (Eq. 36), the weights ignored;
    * ``least_squares``: weighted least squares (Eq. 44) with |w|.
    ``order`` is the total degree of the PCE; x0 ((T,) or (N, 1)) applies to the projections only.
    """
    if kind not in METHOD_KINDS:
        raise ValueError(f"unknown method kind {kind!r}: expected one of {', '.join(METHOD_KINDS)}")
    if x0 is not None and kind not in SPLIT_FORM_KINDS:
        raise ValueError(
            f"x0 (the split form x = x0 + S) applies to {' and '.join(SPLIT_FORM_KINDS)}; {kind!r} "
            "either builds no PCE or fits the constant term itself, so the split would change nothing"
        )
    Y = as_runs_by_time(Y)
    if kind == "monte_carlo":
        return Result(*monte_carlo(Y), None)
    if kind == "integration":
        return Result(*direct_integration(Y, weights), None)
    if kind == "interpolation":
        return Result(*interpolation(xi, weights, Y, germs, order, x0))
    if kind == "pseudo_galerkin":
        pce = pseudo_galerkin(xi, weights, Y, germs, order, x0)
    elif kind == "regression":
        pce = regression(xi, Y, germs, order)
    else:
        pce = least_squares(xi, weights, Y, germs, order)
    return Result(pce.mean(), pce.variance(), pce)


__all__ = [
    "METHOD_KINDS",
    "PCE",
    "Result",
    "fit",
    "orthonormal_basis",
    "total_degree_indices",
]
