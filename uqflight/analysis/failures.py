"""Probability that a run fails: from random draws with a confidence interval that holds for small
counts; from a quadrature grid only what its weights can say.

Independent draws: k failures of n runs give p̂ = k/n and the Wilson score interval (default) or the
exact Clopper–Pearson interval; how other sampled designs (QMC, Latin hypercube, pick-freeze) count
their runs for it is analysis.proportions'.

Grids (`grid_failure_probability`): the nodes are fixed, not drawn, so the failed count is no
binomial sample and no interval has a coverage. With weights all ≥ 0 (tensor grids) Σ_failed w / Σw
is the failure probability of the discrete law on the nodes, a quadrature of the failure indicator
that converges as the grid is refined: it is the estimate, without an interval. With signed weights
(sparse grids) that sum is no probability at all (a level-5 grid of a model failing on 13 % of its
box gives 0.38): no estimate, and the sentence says a sampled design is needed.

`n_effective` is Kish's effective number of runs (Σw)² / Σw², n for equal weights: how many equally
weighted random draws the weights are worth (below 1 for a level-5 sparse grid); a fact about the
weights, used for no interval.
"""
import numpy as np
from scipy import special

METHODS = ("wilson", "clopper_pearson")
SAMPLED = "monte_carlo, sobol, halton or latin_hypercube"


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
    # at p̂ = 0 (or 1) the bound is 0 (1) exactly; the formula leaves rounding (1e-19) there
    lower = 0.0 if p_hat <= 0.0 else max(centre - half, 0.0)
    upper = 1.0 if p_hat >= 1.0 else min(centre + half, 1.0)
    return float(lower), float(upper)


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


def kish_effective_runs(weights) -> float:
    """Kish's effective number of runs (Σw)² / Σw²: n for n equal weights, 0 when Σw = 0."""
    weights = np.asarray(weights, dtype=float)
    squares = float(np.square(weights).sum())
    return float(weights.sum() ** 2 / squares) if squares > 0 else 0.0


def failure_probability(failed, confidence: float = 0.95, method: str = "wilson") -> dict:
    """Estimate and two-sided interval of the probability that a run fails, from a sampled design.

    failed: bool (N,), one entry per run done. method: "wilson" or "clopper_pearson". Returns
    {"estimate", "lower", "upper", "n_effective", "method"}: k/N, the interval, N, and a sentence
    saying how they were computed. No runs (N = 0): estimate NaN, interval [0, 1].
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    failed = np.asarray(failed, dtype=bool).reshape(-1)
    n = failed.size
    if n == 0:
        return {"estimate": float("nan"), "lower": 0.0, "upper": 1.0, "n_effective": 0.0,
                "method": "no runs: the probability is undefined, the interval is [0, 1]"}
    name = "Wilson score" if method == "wilson" else "Clopper-Pearson exact"
    k = int(failed.sum())
    estimate = k / n
    lower, upper = (wilson_interval(estimate, n, confidence) if method == "wilson"
                    else clopper_pearson_interval(k, n, confidence))
    return {"estimate": estimate, "lower": lower, "upper": upper, "n_effective": float(n),
            "method": f"{k} of {n} runs failed; {100 * confidence:g} % {name} interval"}


def grid_failure_probability(failed, weights) -> dict:
    """What a quadrature grid's runs say about the probability that a run fails (module docstring).

    failed: bool (N,), weights (N,) with Σw > 0, one per run done. Returns the keys of
    `failure_probability`: lower and upper NaN (no interval exists); the estimate Σ_failed w / Σw
    when every weight is ≥ 0, NaN when any is negative; n_effective Kish's; the sentence says which.
    """
    failed = np.asarray(failed, dtype=bool).reshape(-1)
    n = failed.size
    weights = np.asarray(weights, dtype=float)
    if weights.shape != (n,):
        raise ValueError(f"weights have shape {weights.shape}, expected ({n},): one per run")
    total = weights.sum()
    if not total > 0:
        raise ValueError(f"weights sum to {total}; a grid's weights must sum to a positive number")
    counted = f"{int(failed.sum())} of {n} grid runs failed"
    negative = int((weights < 0).sum())
    result = {"estimate": float("nan"), "lower": float("nan"), "upper": float("nan"),
              "n_effective": kish_effective_runs(weights)}
    if negative:
        result["method"] = (f"{counted}; not estimated: {negative} of the grid's {n} weights are negative, so "
                            "the weighted failed fraction Σ_failed w / Σw is no probability (it can lie "
                            f"outside [0, 1]); run a sampled design ({SAMPLED}) for a failure probability "
                            "with an interval")
        return result
    result["estimate"] = float(weights[failed].sum() / total)
    result["method"] = (f"{counted}; estimate Σ_failed w / Σw, the grid's quadrature of the failure indicator "
                        "(the failure probability of the discrete law on its nodes), without an interval: the "
                        "nodes are fixed, not random draws, and the error of a quadrature of a discontinuous "
                        f"indicator is not bounded by the grid's degree; a sampled design ({SAMPLED}) gives "
                        "an interval")
    return result
