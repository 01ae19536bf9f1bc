"""Direct integration (Eq. 17): moments as weighted sums over the design's runs."""
import numpy as np

from ..analysis.moments import weighted_mean, weighted_variance


def direct_integration(Y, weights) -> tuple[np.ndarray, np.ndarray]:
    """Mean and variance (each (T,)) of Y (N, T) with the design's weights (MC 1/N or quadrature)."""
    return weighted_mean(Y, weights), weighted_variance(Y, weights)


def monte_carlo(Y) -> tuple[np.ndarray, np.ndarray]:
    """Plain sample mean and unbiased (N − 1) variance of Y (N, T), ignoring any design weights."""
    return weighted_mean(Y), weighted_variance(Y, unbiased=True)
