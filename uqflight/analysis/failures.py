"""Probability that a run fails, with a confidence interval that holds for small counts.

Unweighted designs (Monte Carlo, QMC, Latin hypercube): k failures of n runs give p̂ = k/n and
the Wilson score interval (default) or the exact Clopper–Pearson interval. Weighted designs
(quadrature grids, possibly with negative weights): p̂ = Σ w_j 1[failed_j] / Σ w_j and the Wilson
interval with Kish's effective sample size n_eff = (Σ|w|)² / Σw² in place of n, clipped to [0, 1].
"""
import numpy as np
from scipy import special

METHODS = ("wilson", "clopper_pearson")


def _two_sided_z(confidence: float) -> float:
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must lie in (0, 1), got {confidence}")
    return float(special.ndtri(0.5 * (1.0 + confidence)))


def wilson_interval(p_hat: float, n: float, confidence: float = 0.95) -> tuple[float, float]:
    """Wilson score interval for a proportion p̂ observed in n trials (n may be fractional).

    (p̂ + z²/2n ± z √(p̂(1−p̂)/n + z²/4n²)) / (1 + z²/n), z the two-sided normal quantile.
    """
    z = _two_sided_z(confidence)
    z2n = z * z / n
    centre = (p_hat + 0.5 * z2n) / (1.0 + z2n)
    half = z * np.sqrt(max(p_hat * (1.0 - p_hat), 0.0) / n + 0.25 * z2n / n) / (1.0 + z2n)
    return float(max(centre - half, 0.0)), float(min(centre + half, 1.0))


def clopper_pearson_interval(k: float, n: float, confidence: float = 0.95) -> tuple[float, float]:
    """Exact (Clopper–Pearson) interval for k successes in n trials: Beta quantiles.

    lower = B⁻¹(α/2; k, n−k+1) (0 when k = 0), upper = B⁻¹(1−α/2; k+1, n−k) (1 when k = n),
    α = 1 − confidence; k and n may be fractional (the Beta quantile is defined for them).
    """
    _two_sided_z(confidence)
    alpha = 1.0 - confidence
    lower = 0.0 if k <= 0 else float(special.betaincinv(k, n - k + 1.0, 0.5 * alpha))
    upper = 1.0 if k >= n else float(special.betaincinv(k + 1.0, n - k, 1.0 - 0.5 * alpha))
    return lower, upper


def failure_probability(failed, weights=None, confidence: float = 0.95, method: str = "wilson") -> dict:
    """Estimate and two-sided interval of the probability that a run fails.

    failed: bool (N,), one entry per run of the design. weights: None for equally weighted runs,
    else the design's weights (N,), any sign, with Σw > 0. method: "wilson" or "clopper_pearson".

    Returns {"estimate", "lower", "upper", "n_effective", "method"}: floats, n_effective = N
    unweighted or Kish's (Σ|w|)²/Σw², and a sentence saying how the numbers were computed. With
    weights, the estimate Σ_failed w / Σw is clipped to [0, 1] (signed weights can push it out;
    the sentence then gives the raw value) and the interval is computed from the clipped estimate
    with n_effective trials. No runs (N = 0): estimate NaN, interval [0, 1].
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    failed = np.asarray(failed, dtype=bool).reshape(-1)
    n = failed.size
    if n == 0:
        return {"estimate": float("nan"), "lower": 0.0, "upper": 1.0, "n_effective": 0.0,
                "method": "no runs: the probability is undefined, the interval is [0, 1]"}
    name = "Wilson score" if method == "wilson" else "Clopper-Pearson exact"
    level = f"{100 * confidence:g} %"
    if weights is None:
        k = int(failed.sum())
        estimate = k / n
        lower, upper = (wilson_interval(estimate, n, confidence) if method == "wilson"
                        else clopper_pearson_interval(k, n, confidence))
        return {"estimate": estimate, "lower": lower, "upper": upper, "n_effective": float(n),
                "method": f"{k} of {n} runs failed; {level} {name} interval"}

    weights = np.asarray(weights, dtype=float)
    if weights.shape != (n,):
        raise ValueError(f"weights have shape {weights.shape}, expected ({n},): one per run")
    total = weights.sum()
    if not total > 0:
        raise ValueError(f"weights sum to {total}; a failure probability needs Σw > 0")
    raw = float(weights[failed].sum() / total)
    estimate = min(max(raw, 0.0), 1.0)
    n_eff = float(np.abs(weights).sum() ** 2 / np.square(weights).sum())
    lower, upper = (wilson_interval(estimate, n_eff, confidence) if method == "wilson"
                    else clopper_pearson_interval(estimate * n_eff, n_eff, confidence))
    clipped = "" if raw == estimate else f" (raw weighted estimate {raw:.6g} clipped to [0, 1])"
    sentence = (f"{int(failed.sum())} of {n} runs failed; estimate Σ_failed w / Σ w = {estimate:.6g}{clipped}; "
                f"{level} {name} interval with Kish's effective sample size (Σ|w|)²/Σw² = {n_eff:.6g} "
                f"in place of the number of runs, clipped to [0, 1]")
    return {"estimate": estimate, "lower": lower, "upper": upper, "n_effective": n_eff, "method": sentence}
