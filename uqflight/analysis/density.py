"""Probability densities over time by Gaussian kernel density estimation, one column at a time.

The estimate is binned: each sample is split linearly between its two neighbouring grid
points and the binned counts are convolved with the Gaussian kernel by FFT. That costs
O(N·T log N + T·G log G) instead of O(N·T·G) for direct summation, and differs from the exact
KDE by O(Δx²) where Δx is the grid spacing: accurate while Δx is well below the bandwidth
(the support spans 8 bandwidths plus the data, so raise grid_points for far outliers).
The binning reads each time's samples sorted (moments.sorted_by_time, which the quantiles share):
the samples between two grid points are then one run of the row, found by search and summed at once.
"""
import numpy as np

from .moments import as_runs_by_time, sorted_by_time, weighted_std

BANDWIDTH_RULES = {
    "scott": lambda n: n ** (-1.0 / 5.0),
    "silverman": lambda n: (0.75 * n) ** (-1.0 / 5.0),
}
KERNEL_REACH = 4.0  # bandwidths beyond the extreme samples kept in the support (tail mass < 4e-5)


def kde_bandwidth(Y, rule: str = "scott", std=None, extremes=None) -> np.ndarray:
    """Kernel width per column, (T,): the rule's factor times the sample std (as scipy's gaussian_kde).

    A constant column (std 0) gets √eps·max(1, |value|), so its density is a narrow peak
    at the value instead of a division by zero. `std` (T,), the columns' sample std (N − 1), and
    `extremes`, their (min, max), save passes over Y when the caller has them.
    """
    if rule not in BANDWIDTH_RULES:
        raise ValueError(f"unknown bandwidth rule {rule!r}: expected one of {', '.join(BANDWIDTH_RULES)}")
    Y = as_runs_by_time(Y)
    low, high = extremes if extremes is not None else (Y.min(axis=0), Y.max(axis=0))
    magnitude = np.maximum(1.0, np.maximum(high, -low))
    floor = np.sqrt(np.finfo(float).eps) * magnitude
    std = weighted_std(Y, unbiased=True) if std is None else std
    return np.maximum(BANDWIDTH_RULES[rule](len(Y)) * std, floor)


def kde_on_grid(Y, lower, upper, bandwidth, grid_points: int, ordered=None) -> tuple[np.ndarray, np.ndarray]:
    """Gaussian KDE of each column of Y (N, T) on G evenly spaced points from lower to upper (T,).

    Returns support (T, G) and density (T, G). The grid must cover the samples (callers extend
    it by KERNEL_REACH bandwidths beyond them); a sample outside is binned at the nearer end.
    `ordered`: sorted_by_time(Y) when the caller has it (then all that is read of the samples).
    """
    ordered = sorted_by_time(Y) if ordered is None else ordered
    n_times, n_runs = ordered.shape
    lower, upper, bandwidth = (np.broadcast_to(np.asarray(a, dtype=float), (n_times,)) for a in (lower, upper, bandwidth))
    spacing = (upper - lower) / (grid_points - 1)
    support = lower[:, None] + spacing[:, None] * np.arange(grid_points)

    samples, to_right = _linear_bins(ordered, lower, spacing, grid_points)
    counts = np.zeros((n_times, grid_points))
    counts[:, :-1] = samples - to_right
    counts[:, 1:] += to_right

    length = 1 << int(np.ceil(np.log2(2 * grid_points)))
    frequency = np.fft.rfftfreq(length)
    kernel = np.exp(-2.0 * (np.pi * frequency * (bandwidth / spacing)[:, None]) ** 2)
    spectrum = np.fft.rfft(counts, length, axis=1) * kernel
    density = np.fft.irfft(spectrum, length, axis=1)[:, :grid_points] / (n_runs * spacing[:, None])
    return support, np.clip(density, 0.0, None)


def _linear_bins(ordered, lower, spacing, grid_points: int) -> tuple[np.ndarray, np.ndarray]:
    """The samples of each time (row of `ordered`, ascending) whose left grid point is k, and the sum of
    their shares passed to point k + 1: (T, G − 1) each. A sample at position p = (y − lower)/spacing
    (clipped to the grid) has left point min(⌊p⌋, G − 2) and share p − left. Sorted, the samples of
    each left point are one run of the row: its bounds by search, its positions summed at once, and
    Σ share = Σ p − k·count. That sum of positions rounds to ε·count²·k at worst: 1e-9 of a bin of
    20,000 samples on 120 points, against the grid's own O(Δx²) error of the estimate."""
    n_times, n_runs = ordered.shape
    samples = np.empty((n_times, grid_points - 1), dtype=np.intp)
    sums = np.empty(samples.shape)
    inner = np.arange(1.0, grid_points - 1)
    position = np.empty(n_runs + 1)  # one row's positions, then a 0 that ends its last run
    position[-1] = 0.0
    row = position[:-1]
    for t in range(n_times):
        np.subtract(ordered[t], lower[t], out=row)
        row /= spacing[t]
        if n_runs and not (row[0] >= 0 and row[-1] <= grid_points - 1):  # sorted: its ends tell
            np.clip(row, 0, grid_points - 1, out=row)
        starts = np.concatenate(([0], np.searchsorted(row, inner)))  # first sample of each left point
        samples[t] = np.diff(starts, append=n_runs)
        sums[t] = np.add.reduceat(position, starts)
    sums[samples == 0] = 0.0  # a run with no sample read its next one's first value: none
    return samples, sums - samples * np.arange(grid_points - 1)


def pdf_over_time(Y, grid_points: int = 200, rule: str = "scott", std=None,
                  ordered=None) -> tuple[np.ndarray, np.ndarray]:
    """PDF of each time's output (column of Y, (N, T)) on its own support: support (T, G), density (T, G).

    Each support spans the column's samples plus four bandwidths on either side. `std` (T,): the
    columns' sample std (N − 1) when known (e.g. from tSVD or PCE factors), else computed.
    `ordered`: sorted_by_time(Y) when the caller has it.
    """
    Y = as_runs_by_time(Y)
    ordered = sorted_by_time(Y) if ordered is None else ordered
    low, high = ordered[:, 0], ordered[:, -1]
    bandwidth = kde_bandwidth(Y, rule, std, (low, high))
    reach = KERNEL_REACH * bandwidth
    return kde_on_grid(Y, low - reach, high + reach, bandwidth, grid_points, ordered)
