"""Which variances are real and which are floating-point noise, and the statistics undefined without them.

A variance is judged against the output's OWN magnitude at the same time, never against the largest
variance over time (a test that cannot fire for a scalar output, or for an output whose every
variance is noise). The rule: at time t the standard deviation is unresolved when

    var(t) ≤ A · (r · M(t))² ,   M(t) = max(|mean(t)|, scale(t)),   r = max(rtol, 4 eps √n),

or var(t) ≤ A · atol(t)², with A = Σ|w_j| / |Σ w_j| (1 for positive weights).

Why: a float64 output y carries an absolute error of at least ~eps·|y| per value, and a simulated
output far more: every integration step rounds the state again (10⁴–10⁵ steps add up to 10⁻¹⁴–10⁻¹³
relative as a random walk), and a quantity derived from a larger one inherits that one's ulp
(JSBSim's altitude comes from a geocentric radius ~1400 times larger: ~3·10⁻¹³ of the altitude).
Summing n runs for the mean adds ~eps·M·√n (random-walk accumulation; 4 for a margin), and a
centred variance inherits the square of the mean's error. Spreads of this size are differences
between runs that carry no information, so RESOLUTION_RTOL = 1e-12 (~4500 ulps) sits above all of
these and 8 orders of magnitude below any spread that matters in a UQ study (relative std ≥ 10⁻⁴).
Signed weights amplify per-run noise in Σ w_j (y_j − m)² by up to Σ|w|/Σw, hence A. `scale` is
the magnitude an output is computed from when it is larger than the output (e.g. the Earth's
radius for an altitude); `atol` an absolute resolution (e.g. the truncation error of a tSVD).
"""
import numpy as np

EPS = np.finfo(float).eps
RESOLUTION_RTOL = 1e-12  # relative std below which a spread is rounding noise; see the module doc
SUM_ULPS = 4.0  # margin on the eps·√n rounding of a sum of n values


def variance_floor(mean, scale=None, rtol: float = RESOLUTION_RTOL, n: int | None = None,
                   weights=None, atol=0.0) -> np.ndarray:
    """The largest variance per time, (T,), that rounding noise can produce (the rule of the module doc).

    mean (T,); scale, atol: None/0, a float or (T,); n: the number of runs summed (None: ignored);
    weights: the design's weights (N,) for the signed-weight amplification Σ|w|/|Σw| (None: 1).
    """
    mean = np.abs(np.asarray(mean, dtype=float))
    magnitude = mean if scale is None else np.maximum(mean, np.abs(np.asarray(scale, dtype=float)))
    relative = max(rtol, SUM_ULPS * EPS * np.sqrt(n)) if n else rtol
    amplification = 1.0
    if weights is not None:
        weights = np.asarray(weights, dtype=float)
        amplification = float(np.abs(weights).sum() / abs(weights.sum()))
    absolute = np.abs(np.asarray(atol, dtype=float))
    return amplification * np.maximum(relative * magnitude, absolute) ** 2


def resolved_variance(variance, mean, scale=None, rtol: float = RESOLUTION_RTOL, n: int | None = None,
                      weights=None, atol=0.0) -> np.ndarray:
    """bool (T,): True where var(t) exceeds variance_floor(mean, ...) (see the module doc).

    False where the variance is at or below the floor, negative (signed weights) or not finite;
    an exact 0 is unresolved even when the mean is 0 too.
    """
    variance = np.asarray(variance, dtype=float)
    floor = variance_floor(mean, scale, rtol, n, weights, atol)
    with np.errstate(invalid="ignore"):
        return np.isfinite(variance) & (variance > floor)


def cov_or_none(std, mean, rtol: float = RESOLUTION_RTOL) -> list:
    """Modified coefficient of variation std(t) / max_t|mean(t)| as a list (T,), or all None.

    Undefined (every entry None) when the mean is zero up to rounding: max_t|mean| ≤ rtol ·
    max_t √(mean² + std²), i.e. the mean is below the resolution of the outputs' own magnitude
    (a symmetric grid gives a mean of ~1e-17 for y = ξ, not 0, and a CoV of 1e17 would be noise).
    """
    std = np.asarray(std, dtype=float).reshape(-1)
    mean = np.asarray(mean, dtype=float).reshape(-1)
    peak = np.max(np.abs(mean), initial=0.0)
    magnitude = np.max(np.sqrt(mean**2 + std**2), initial=0.0)
    if not peak > rtol * magnitude or not np.isfinite(peak):
        return [None] * std.size
    return [float(v) if np.isfinite(v) else None for v in std / peak]
