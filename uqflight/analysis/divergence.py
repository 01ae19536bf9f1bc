"""Kullback–Leibler divergence between the densities of two sample sets (Eq. 50)."""
import numpy as np

from .density import KERNEL_REACH, kde_bandwidth, kde_on_grid
from .moments import as_runs_by_time, sorted_by_time

DENSITY_FLOOR = 1e-10  # relative to the larger peak density; see kl_divergence


def kl_divergence(samples_p, samples_q, grid_points: int = 512, rule: str = "scott"):
    """D_KL(p || q) = ∫ ρ_p ln(ρ_p / ρ_q) dx, each density a Gaussian KDE of its samples.

    p is the method's samples (e.g. its PCE sampled), q the reference (Monte Carlo). Both are
    estimated on one common support (all samples plus four bandwidths). Where ρ_p is below the
    floor (DENSITY_FLOOR times the larger peak) the integrand is taken as 0 (ρ ln ρ → 0); ρ_q is
    raised to that floor, so a region q never visits costs a large but finite penalty instead of
    ∞ from a density that is only empty for lack of samples. Samples (N,) give a float; (N, T)
    arrays (one column per time, the same T) give (T,).
    """
    p, q = as_runs_by_time(samples_p), as_runs_by_time(samples_q)
    ordered_p, ordered_q = sorted_by_time(p), sorted_by_time(q)  # their extremes, and the KDEs' binning
    bandwidth_p = kde_bandwidth(p, rule, extremes=(ordered_p[:, 0], ordered_p[:, -1]))
    bandwidth_q = kde_bandwidth(q, rule, extremes=(ordered_q[:, 0], ordered_q[:, -1]))
    reach = KERNEL_REACH * np.maximum(bandwidth_p, bandwidth_q)
    lower = np.minimum(ordered_p[:, 0], ordered_q[:, 0]) - reach
    upper = np.maximum(ordered_p[:, -1], ordered_q[:, -1]) + reach
    support, density_p = kde_on_grid(p, lower, upper, bandwidth_p, grid_points, ordered_p)
    _, density_q = kde_on_grid(q, lower, upper, bandwidth_q, grid_points, ordered_q)

    floor = DENSITY_FLOOR * np.maximum(density_p.max(axis=1), density_q.max(axis=1))[:, None]
    present = density_p > floor
    log_ratio = np.log(np.where(present, density_p, 1.0) / np.maximum(density_q, floor))
    divergence = (np.where(present, density_p * log_ratio, 0.0)).sum(axis=1) * (support[:, 1] - support[:, 0])
    return divergence if np.ndim(samples_p) > 1 else float(divergence[0])
