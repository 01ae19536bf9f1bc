"""The Monte Carlo reference's own noise, in the normalisation of Eq. 49 and as a KLD.

A method's ε_m, ε_v and KLD against a Monte Carlo reference of N runs cannot be told apart from 0
once they fall to the reference's sampling error. In Eq. 49's normalisation that error is

    eps_m_floor(t) = (σ(t) / √N) / max_t|mean_ref|,
    eps_v_floor(t) = se(s²)(t) / max_t var_ref,   se(s²) = √((μ4 − (N−3)/(N−1) σ⁴) / N),

the standard error of the sample mean and the distribution-free standard error of the sample
variance (it needs only the fourth central moment μ4; for normal data it is σ²√(2/(N−1))).
A zero peak normalises by 1, as analysis.errors does. Every function is per time, so a caller
with tSVD data rebuilds the runs a block of times at a time, takes `central_moments` of each
block, concatenates, and calls `floors_from_moments` once (the peaks are over all times).
"""
import numpy as np

from .divergence import kl_divergence
from .moments import as_runs_by_time


def central_moments(Y) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sample mean, unbiased variance (ddof 1) and fourth central moment (1/N Σ (y − ȳ)⁴) of Y (N, T), each (T,)."""
    Y = as_runs_by_time(Y)
    mean = Y.mean(axis=0)
    deviation_squared = np.square(Y - mean)
    variance = deviation_squared.sum(axis=0) / (len(Y) - 1) if len(Y) > 1 else np.full(Y.shape[1], np.nan)
    return mean, variance, np.mean(np.square(deviation_squared), axis=0)


def _peak(values) -> float:
    peak = float(np.max(np.abs(values)))
    return peak if peak > 0 else 1.0


def floors_from_moments(mean, variance, fourth_central, n: int) -> dict[str, np.ndarray]:
    """Floors from the reference's moments per time (each (T,)) and its number of runs n.

    Returns {"eps_m_floor", "eps_v_floor", "se_mean", "se_variance"}, each (T,): the standard
    errors of the reference's mean and variance, and the same divided by max_t|mean| and
    max_t|variance| (Eq. 49). se_variance clips a negative radicand (possible for estimated
    moments of near-two-point data) to 0. n < 2: every entry NaN (a variance needs two runs).
    """
    mean, variance, fourth = (np.asarray(a, dtype=float) for a in (mean, variance, fourth_central))
    if n < 2:
        nan = np.full(mean.shape, np.nan)
        return {"eps_m_floor": nan, "eps_v_floor": nan.copy(), "se_mean": nan.copy(), "se_variance": nan.copy()}
    sigma2 = np.maximum(variance, 0.0)
    se_mean = np.sqrt(sigma2 / n)
    se_variance = np.sqrt(np.maximum(fourth - (n - 3) / (n - 1) * sigma2**2, 0.0) / n)
    return {"eps_m_floor": se_mean / _peak(mean), "eps_v_floor": se_variance / _peak(variance),
            "se_mean": se_mean, "se_variance": se_variance}


def kld_floor(samples_ref, n_method: int | None = None, repeats: int = 5, seed=0,
              grid_points: int = 512, rule: str = "scott"):
    """The KLD of Eq. 50 that sampling noise alone produces: a float for (N,) samples, (T,) for (N, T).

    The reference's N runs are split at random (numpy default_rng(seed), without replacement) into
    a pseudo-method sample P of n_p = min(n_method, N // 2) runs (n_method None: N // 2) and a
    pseudo-reference Q of the other N − n_p, and kl_divergence(P, Q, grid_points, rule), the
    estimator the statistics use, is taken; the result is the mean over `repeats` splits. P and Q
    come from the same law, so their true KLD is 0 and the value is estimator noise and KDE bias.
    Q has fewer runs than the reference, so this floor is, if anything, above the noise of the
    real comparison. N < 4: NaN.
    """
    samples = np.asarray(samples_ref, dtype=float)
    Y = as_runs_by_time(samples)
    n = len(Y)
    if n < 4:
        value = np.full(Y.shape[1], np.nan)
        return value if samples.ndim > 1 else float("nan")
    n_p = n // 2 if n_method is None else max(2, min(int(n_method), n // 2))
    rng = np.random.default_rng(seed)
    total = np.zeros(Y.shape[1])
    for _ in range(repeats):
        order = rng.permutation(n)
        total += kl_divergence(Y[order[:n_p]], Y[order[n_p:]], grid_points, rule)
    floor = total / repeats
    return floor if samples.ndim > 1 else float(floor[0])


def kld_estimator_bias(samples_method, samples_ref, seed=0, grid_points: int = 512, rule: str = "scott"):
    """The bias of the KLD estimator (kl_divergence) for normal laws of the method's and the reference's means
    and spreads, drawn in their sample sizes: |estimate − closed form| with D_KL(N(μp, σp²) || N(μq, σq²)) =
    ln(σq/σp) + (σp² + (μp − μq)²)/(2σq²) − 1/2. A method's law wider than the reference's puts samples where
    the reference's KDE has collapsed, which the estimator overstates (+20 to +30 % for σp = 1.2 σq); the split
    floor (kld_floor), of two samples of one law, cannot see that. A float for (N,) samples, (T,) for (N, T);
    NaN where a spread is zero. Draws: numpy default_rng(seed)."""
    p_samples, q_samples = np.asarray(samples_method, dtype=float), np.asarray(samples_ref, dtype=float)
    p, q = as_runs_by_time(p_samples), as_runs_by_time(q_samples)
    mean_p, std_p, mean_q, std_q = p.mean(axis=0), p.std(axis=0), q.mean(axis=0), q.std(axis=0)
    defined = (std_p > 0) & (std_q > 0)
    rng = np.random.default_rng(seed)
    normal_p = mean_p + std_p * rng.standard_normal(p.shape)
    normal_q = mean_q + np.where(defined, std_q, 1.0) * rng.standard_normal(q.shape)
    estimate = kl_divergence(normal_p, normal_q, grid_points, rule)
    ratio = np.where(defined, std_p / np.where(defined, std_q, 1.0), 1.0)
    closed = -np.log(np.where(defined, ratio, 1.0)) + 0.5 * ratio**2 + np.where(
        defined, (mean_p - mean_q) ** 2 / (2 * np.where(defined, std_q, 1.0) ** 2), 0.0) - 0.5
    bias = np.where(defined, np.abs(estimate - closed), np.nan)
    return bias if p_samples.ndim > 1 else float(bias[0])
