"""The probability that a run does something (fails; a quantity exceeds a threshold), from a sampled
design's runs, with an interval only where one holds for how the design drew its points.

How the points were drawn (`DesignKind.sampling`, one of the strategies below, with the design's recorded info):
- independent (monte_carlo): k/n and the Wilson score interval.
- pick_freeze: Saltelli's rows [A; B; AB_1 … AB_d] repeat each other's coordinates (AB_i is A with B's
  i-th column), so the proportion and its Wilson interval are those of the 2n rows A and B alone; they
  are a scrambled Sobol' sample, for which that interval is unverified (usually wider than its own).
- stratified (latin_hypercube): k/n; Latin hypercube sampling's variance is at most n/(n−1) times that
  of n independent draws (Owen 1997), so the Wilson interval of n − 1 draws is conservative.
- net (sobol, halton): with R ≥ 2 scrambled replicates (randomised QMC), the mean of the R proportions
  and the hull of two intervals: the Wilson interval of the pooled runs and the Student-t interval of
  the replicates' spread. The Student-t interval alone falls below 0.95 at a few exceedances whatever R
  (0.93-0.96 over 1000 scrambles at 6 exceedances, 0.92 on the issue's case: the replicates' proportions
  are then far from normal, and their spread often 0); the hull covers 0.97-0.995 there and >= 0.99 at
  20 and 60 (benchmarks/rqmc_interval_coverage.py), at most 1.2 times wider than the Wilson interval, and
  the t interval keeps a net's own spread in when it is wider than independent draws'.
  A single scrambled net: k/n and the Wilson interval of independent draws, flagged (a scrambled net's variance is usually lower but not bounded by theirs for
  an indicator); unscrambled points are fixed, not random: k/n without an interval.
- points (morris): the points are fixed trajectories on a grid, not draws of the law: k/n without an
  interval, the runs' own share.
"""
from __future__ import annotations

import numpy as np
from scipy import special

from .failures import wilson_interval

class Independent:
    """Independent draws (monte_carlo): how a sampled design's runs count for a proportion; each design kind
    carries one of these strategies (`designs.DesignKind.sampling`), the subclasses below being the others."""

    independent = True  # the runs are independent draws of the law

    def proportion(self, hits, counted, info: dict, confidence: float = 0.95, event: str = "") -> dict:
        """{"estimate", "lower", "upper", "n_effective", "method", "sentence"} of the runs `counted` (bool
        (N,), in design order) where `hits` (bool (N,)) holds. lower/upper are None without an interval;
        `method`: "wilson", "replicates" or "points"; `sentence` says how, for a note, counting the runs
        `event` names ("failed", "above 5"). `info`: the design's recorded info (n_base, replicates, scramble)."""
        hits, counted = np.asarray(hits, dtype=bool), self.counted(np.asarray(counted, dtype=bool), info)
        k, n = int((hits & counted).sum()), int(counted.sum())
        if n == 0:
            return {"estimate": None, "lower": None, "upper": None, "n_effective": 0.0, "method": None,
                    "sentence": "no run counts: the probability is undefined"}
        return self.interval(k, n, info, confidence, _counts(k, n, event))

    def counted(self, counted: np.ndarray, info: dict) -> np.ndarray:
        """The runs that count among those `counted` (all of them here)."""
        return counted

    def interval(self, k: int, n: int, info: dict, confidence: float, counts: str) -> dict:
        """The proportion k/n of the counted runs with its interval (here Wilson's); `counts` begins the sentence."""
        return _wilson(k, n, n, confidence, f"{counts}; {100 * confidence:g} % Wilson score interval")


class Points(Independent):
    """Fixed points, not draws of the law (morris)."""

    independent = False
    why = "the design's points are not draws of the inputs' law (the runs' own share, not the law's probability)"

    def interval(self, k, n, info, confidence, counts):
        return {"estimate": k / n, "lower": None, "upper": None, "n_effective": float(n), "method": "points",
                "sentence": f"{counts}; no interval: {self.why}"}


class PickFreeze(Points):
    """Saltelli's rows [A; B; AB_1 … AB_d]: the rows A and B alone count."""

    def counted(self, counted, info):
        return counted & (np.arange(counted.size) < 2 * int(info["n_base"]))

    def interval(self, k, n, info, confidence, counts):
        return _wilson(k, n, n, confidence, f"{counts} (the rows A and B of the pick-freeze design, which the other "
                                            f"rows repeat); {100 * confidence:g} % Wilson score interval of "
                                            "independent draws, unverified for their scrambled Sobol' points "
                                            "(usually wider than their own)")


class Stratified(Points):
    """A Latin hypercube: the Wilson interval of n − 1 draws, conservative."""

    def interval(self, k, n, info, confidence, counts):
        return _wilson(k, n, n - 1, confidence, f"{counts}; {100 * confidence:g} % Wilson score interval of {n - 1} "
                                                "draws (conservative: a Latin hypercube's variance is at most "
                                                "n/(n-1) times that of independent draws)")


class Net(Points):
    """A QMC net (sobol, halton): replicates, one scrambled net, or unscrambled fixed points."""

    why = "unscrambled QMC points are fixed, not random (scramble them, with replicates, for an interval)"

    def proportion(self, hits, counted, info, confidence=0.95, event=""):
        replicates = int(info.get("replicates", 1))
        if replicates > 1:
            return _replicated(np.asarray(hits, dtype=bool), np.asarray(counted, dtype=bool), replicates,
                               confidence, event)
        return super().proportion(hits, counted, info, confidence, event)

    def interval(self, k, n, info, confidence, counts):
        if not info.get("scramble", True):
            return super().interval(k, n, info, confidence, counts)
        return _wilson(k, n, n, confidence, f"{counts}; {100 * confidence:g} % Wilson score interval of independent "
                                            "draws, unverified for one scrambled QMC net (usually wider than its "
                                            "own); set design.replicates for an interval from the design itself")


def _wilson(k: int, n: int, n_interval: int, confidence: float, sentence: str) -> dict:
    lower, upper = wilson_interval(k / n, n_interval, confidence) if n_interval > 0 else (0.0, 1.0)
    return {"estimate": k / n, "lower": lower, "upper": upper, "n_effective": float(n_interval), "method": "wilson",
            "sentence": sentence}


def _counts(k: int, n: int, event: str) -> str:
    return f"{k} of {n} runs {event}" if event else f"{k} of {n} runs"


def _replicated(hits, counted, replicates: int, confidence: float, event: str) -> dict:
    """Randomised QMC: the mean of the replicates' proportions, within the hull of the pooled runs' Wilson
    interval and the Student-t interval of the replicates' spread (module docstring)."""
    size = hits.size // replicates
    shares = [hits[r * size:(r + 1) * size][counted[r * size:(r + 1) * size]].mean()
              for r in range(replicates) if counted[r * size:(r + 1) * size].any()]
    k, n = int((hits & counted).sum()), int(counted.sum())
    counts = _counts(k, n, event)
    if len(shares) < 2:
        return {"estimate": k / n if n else None, "lower": None, "upper": None, "n_effective": float(n),
                "method": None, "sentence": f"{counts}; no interval: fewer than 2 replicates have runs"}
    shares = np.asarray(shares)
    r = shares.size
    estimate = float(shares.mean())
    half = float(special.stdtrit(r - 1, 0.5 * (1 + confidence)) * shares.std(ddof=1) / np.sqrt(r))  # Student t quantile
    lower, upper = wilson_interval(k / n, n, confidence)
    return {"estimate": estimate, "lower": min(lower, max(estimate - half, 0.0)),
            "upper": max(upper, min(estimate + half, 1.0)), "n_effective": float(n), "method": "replicates",
            "sentence": f"{counts}; mean of {r} replicates' proportions, {100 * confidence:g} % interval: the hull "
                        "of the pooled runs' Wilson score interval and the Student-t interval of the replicates' "
                        "spread"}
