"""Weighted moments and quantile bands over time: the one place where Eq. 15–17 are summed.

Y is (N, T) (one row per run, one column per time); the statistics reduce along axis 0.
Weights are normalised to sum 1, so Monte Carlo rows dropped after failed runs stay 1/N_ok.
"""
import numpy as np


def as_runs_by_time(Y) -> np.ndarray:
    """Y as a float (N, T) array; a 1-D array of N scalar outputs becomes (N, 1)."""
    Y = np.asarray(Y, dtype=float)
    return Y.reshape(Y.shape[0], -1)


def probability_weights(weights, n: int) -> np.ndarray:
    """Weights (N,) rescaled to sum 1; None means equal weights 1/n."""
    if weights is None:
        return np.full(n, 1.0 / n)
    weights = np.asarray(weights, dtype=float)
    if weights.shape != (n,):
        raise ValueError(f"weights have shape {weights.shape}, expected ({n},): one per run")
    total = weights.sum()
    if total <= 0:
        raise ValueError(f"weights sum to {total}; they must sum to a positive number (normally 1)")
    return weights / total


def weighted_moments(basis, weights=None, scale=None, unbiased: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Mean Σ_j w_j Y_j and variance Σ_j w_j (Y_j − mean)² (Eq. 15–17), each (T,), of Y = basis @ scale
    (scale None: Y = basis, (N, T)); the one place where weighted moments are summed.

    Weights are rescaled to sum 1 (None: 1/N). With tSVD factors (basis = V rows (N, r), scale =
    diag(s) Uᵀ (r, T)) Y is never formed: run j is Uc_j with c_j = diag(s) V_j, and centring the
    coefficients before squaring, M = Σ_j w_j (c_j − c̄)(c_j − c̄)ᵀ, avoids the cancellation of
    E[Y²] − mean² on outputs with a large mean and a small spread; the variance is diag(U M Uᵀ).
    With ``unbiased`` the variance is divided by 1 − Σ w_j² (the reliability-weights correction,
    N/(N − 1) for equal weights). Signed sparse-grid weights can make the variance negative.
    """
    basis = np.asarray(basis, dtype=float)
    w = probability_weights(weights, len(basis))
    centre = w @ basis
    deviation = basis - centre
    if scale is None:
        mean = centre
        variance = w @ np.square(deviation, out=deviation)
    else:
        mean = centre @ scale
        spread = deviation.T @ (w[:, None] * deviation)
        variance = ((scale.T @ spread) * scale.T).sum(axis=1)
    if unbiased:
        n = len(basis)
        correction = 1.0 - w @ w
        if correction <= 0:
            raise ValueError("an unbiased variance needs at least two runs with positive weight")
        variance = variance * (n / (n - 1)) if weights is None else variance / correction
    return mean, variance


def weighted_mean(Y, weights=None) -> np.ndarray:
    """Σ_j w_j Y_j (Eq. 17 applied to Eq. 15): (T,)."""
    Y = np.asarray(Y, dtype=float)
    return probability_weights(weights, len(Y)) @ Y


def weighted_variance(Y, weights=None, unbiased: bool = False) -> np.ndarray:
    """Σ_j w_j (Y_j − mean)² (Eq. 16), (T,); see weighted_moments."""
    return weighted_moments(Y, weights, unbiased=unbiased)[1]


def weighted_std(Y, weights=None, unbiased: bool = False) -> np.ndarray:
    """√variance, (T,); a negative variance (possible with signed weights) gives 0."""
    return np.sqrt(np.clip(weighted_variance(Y, weights, unbiased), 0.0, None))


def weighted_quantiles(Y, probabilities, weights=None, ordered=None) -> np.ndarray:
    """The weighted quantiles of each column of Y (N, T) at `probabilities` (P,): (P, T).

    Runs are sorted per time; the j-th sorted run sits at cumulative weight Σ_{i<j} w_i + w_j/2
    (Hazen positions) and the quantile is interpolated linearly between them. Equal weights
    (Monte Carlo, the large case) take numpy's Hazen quantile (`hazen_quantiles`; `ordered`:
    sorted_by_time(Y) when the caller has it). Needs weights ≥ 0: for a signed sparse grid, sample
    its PCE instead.
    """
    Y = as_runs_by_time(Y)
    w = probability_weights(weights, len(Y))
    if (w < 0).any():
        raise ValueError("quantiles need non-negative weights; sample the PCE for a sparse grid")
    if len(Y) < 2:
        raise ValueError("quantiles need at least two runs")
    probabilities = np.asarray(probabilities, dtype=float)
    if np.ptp(w) == 0:
        return hazen_quantiles(Y, probabilities, ordered)
    order = np.argsort(Y, axis=0)
    sorted_weights = w[order]
    positions = np.cumsum(sorted_weights, axis=0)
    sorted_weights *= 0.5
    positions -= sorted_weights
    columns = np.arange(Y.shape[1])
    bounds = []
    for probability in probabilities:
        upper = np.clip((positions < probability).sum(axis=0), 1, len(Y) - 1)
        lower = upper - 1
        gap = positions[upper, columns] - positions[lower, columns]
        fraction = np.divide(probability - positions[lower, columns], gap, out=np.ones_like(gap), where=gap > 0)
        below, above = Y[order[lower, columns], columns], Y[order[upper, columns], columns]
        bounds.append(below + np.clip(fraction, 0.0, 1.0) * (above - below))
    return np.array(bounds)


def sorted_by_time(Y) -> np.ndarray:
    """Each column of Y (N, T) in ascending order, one row per time: (T, N). Sorted once, it gives every
    quantile and the extremes by indexing, and the density's binning by search (analysis.density)."""
    rows = np.array(as_runs_by_time(Y).T, order="C")
    rows.sort(axis=1)
    return rows


def hazen_quantiles(Y, probabilities, ordered=None) -> np.ndarray:
    """numpy's `quantile(Y, probabilities, axis=0, method="hazen")`, (P, T), the same numbers, faster.

    numpy partitions each column anew for every call; here the columns are sorted once (`ordered`:
    sorted_by_time(Y) when the caller has it, which is then all that is read) and each quantile is
    interpolated between its two neighbouring order statistics with numpy's own `_lerp`. A column
    that is not finite takes numpy's answer."""
    probabilities = np.asarray(probabilities, dtype=float)
    ordered = sorted_by_time(Y) if ordered is None else ordered
    n = ordered.shape[1]
    # NaN sorts last and ±inf to the ends: the ends tell whether every value is finite
    if n == 0 or not (np.isfinite(ordered[:, 0]).all() and np.isfinite(ordered[:, -1]).all()):
        return np.quantile(ordered, probabilities, axis=1, method="hazen")
    shape, probabilities = probabilities.shape, probabilities.ravel()
    virtual = n * probabilities + (0.5 + probabilities * (1 - 0.5 - 0.5)) - 1  # numpy's virtual index
    previous = np.clip(np.floor(virtual), 0, n - 1).astype(np.intp)
    previous[virtual >= n - 1] = n - 1
    gamma = virtual - previous
    bounds = []
    for k, v, t in zip(previous, virtual, gamma):
        a = ordered[:, k]
        b = ordered[:, k + 1] if 0 <= v < n - 1 else a  # beyond either end: that end's value
        difference = b - a
        value = a + difference * t
        bounds.append(b - difference * (1 - t) if t >= 0.5 else value)
    return np.array(bounds).reshape(shape + (ordered.shape[0],))


def standardised_moments(Y, weights=None) -> tuple[np.ndarray, np.ndarray]:
    """Skewness and kurtosis (Pearson's, 3 for a normal law, not the excess) of each column of Y (N, T):
    each (T,), NaN where σ = 0 (a constant column) or N is too small.

    The convention of the sample moments, as for the variance (N − 1): equally weighted random draws
    (weights None: Monte Carlo runs, or draws of a PCE) give the adjusted estimators, skewness
    G1 = g1 √(N(N − 1))/(N − 2) (N ≥ 3) and kurtosis G2 + 3 with the excess
    G2 = ((N + 1) g2 + 6)(N − 1)/((N − 2)(N − 3)) (N ≥ 4), from the plug-in g1 = m3/m2^1.5 and
    g2 = m4/m2² − 3 (scipy.stats.skew and kurtosis with bias=False). Weights (a quadrature, or the
    integration method's weighted sums) give the plug-in moments of the weighted law, g1 and g2 + 3:
    they are sums, not samples, and have no bias to correct.
    """
    Y = as_runs_by_time(Y)
    n = len(Y)
    w = probability_weights(weights, n)
    deviation = Y - w @ Y
    power = deviation * deviation  # powers by multiplication, in place: ** 3 and ** 4 call pow per element
    variance = w @ power
    power *= deviation
    third = w @ power
    power *= deviation
    fourth = w @ power
    # a constant column has no spread, whatever the rounding of its mean left in `variance`
    spread = (variance > 0) & (Y.max(axis=0) > Y.min(axis=0))
    with np.errstate(invalid="ignore", divide="ignore"):
        g1 = np.where(spread, third / variance**1.5, np.nan)
        g2 = np.where(spread, fourth / variance**2, np.nan) - 3.0
    if weights is not None:
        return g1, g2 + 3.0
    skewness = g1 * np.sqrt(n * (n - 1.0)) / (n - 2.0) if n >= 3 else np.full_like(g1, np.nan)
    excess = ((n + 1.0) * g2 + 6.0) * (n - 1.0) / ((n - 2.0) * (n - 3.0)) if n >= 4 else np.full_like(g2, np.nan)
    return skewness, excess + 3.0


def modified_cov(mean, std) -> np.ndarray:
    """Modified coefficient of variation std(t) / max_t |mean(t)| (the paper's Fig. 8); NaN (undefined)
    where the mean is zero at every time, up to rounding (see analysis.resolution.cov_or_none)."""
    from .resolution import cov_or_none

    return np.array([np.nan if v is None else v for v in cov_or_none(std, mean)], dtype=float)
