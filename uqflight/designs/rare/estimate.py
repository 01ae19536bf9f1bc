"""What a rare-event algorithm returns, and the pieces the three algorithms share.

Every algorithm works in standard-normal space u ∈ R^d and estimates P[g(U) > 0], U ~ N(0, I), from
the margins g its `evaluate` returns (NaN: the run failed, counted outside the event).

`Evaluations` wraps `evaluate`: it enforces the budget, turns the answer into float64, counts the
failed runs and keeps the most probable failure point seen (the failing point of largest
standard-normal density, i.e. smallest |u|).

The 95 % interval of an estimate p̂ with coefficient of variation δ is log-normal,
p̂ · exp(±z σ) with σ² = ln(1 + δ²): a rare-event estimator is positive and right-skewed (subset
simulation's product of level probabilities, an importance-sampling mean of heavy-tailed weights), and
the log-normal law with that mean and c.o.v. keeps the interval inside (0, 1] where p̂ ± z δ p̂ would
cross zero for δ > 0.51.

When no run fell in the event the estimate is 0, and the upper bound is never 0: it is what the runs
can honestly say (`zero_count_upper`: the exact Clopper–Pearson bound of 0 events in n independent
draws, about 3.7/n, scaled by the largest weight the sampling density can give).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from scipy import special
from threadpoolctl import threadpool_limits

CONFIDENCE = 0.95


@dataclass(frozen=True)
class RoundRecord:
    """The state of an estimate after one round (a level, an adaptation step, an enrichment).

    Attributes
    ----------
    runs : int
        Runs so far (cumulative) at the end of the round.
    probability : float
        The estimate after this round (nan where there is none yet).
    cov : float
        Its coefficient of variation (nan where undefined).
    """

    runs: int
    probability: float
    cov: float


@dataclass(frozen=True)
class RareEventEstimate:
    """The estimate of P[g(U) > 0] an algorithm returns.

    Attributes
    ----------
    method : str
        "subset_simulation", "importance_sampling" or "active_learning".
    probability : float
        The estimate of P[g > 0].
    lower, upper : float
        The 95 % interval, 0 <= lower <= probability <= upper <= 1.
    cov : float
        The estimated coefficient of variation of `probability` (nan if undefined).
    runs : int
        Points evaluated in total, failed ones included.
    failed : int
        Points whose value was NaN (counted outside the event).
    design_point : numpy.ndarray or None
        (d,) the failing point of largest standard-normal density seen, in u; None if none failed.
    rounds : tuple of RoundRecord
        The estimate round by round.
    stopped : str
        Why it stopped: "converged", "budget" or "stalled".
    notes : tuple of str
        Plain sentences for the report.
    """

    method: str
    probability: float
    lower: float
    upper: float
    cov: float
    runs: int
    failed: int
    design_point: np.ndarray | None
    rounds: tuple[RoundRecord, ...]
    stopped: str
    notes: tuple[str, ...]

    @property
    def beta(self) -> float:
        """The reliability index −Φ⁻¹(p): inf when p is 0, −inf when p is 1."""
        return float(-special.ndtri(self.probability))


def single_threaded(algorithm):
    """Run `algorithm` with one BLAS thread: a multi-threaded product may round differently with another
    thread count, and the runs an algorithm asks for must not depend on the machine (nor, on 2 busy
    cores, does a second thread pay)."""
    @functools.wraps(algorithm)
    def wrapper(*args, **kwargs):
        with threadpool_limits(limits=1):
            return algorithm(*args, **kwargs)
    return wrapper


def importance_shares(design_point) -> np.ndarray:
    """Each input's share of the design point: α_k² = u_k² / |u|², summing to 1.

    Parameters
    ----------
    design_point : array_like
        (d,) a point in standard-normal space, not the origin.

    Returns
    -------
    numpy.ndarray
        (d,) the shares.
    """
    u = np.asarray(design_point, dtype=float)
    squares = u * u
    total = squares.sum()
    if not total > 0.0:
        raise ValueError("the design point is the origin: it has no direction to share")
    return squares / total


def lognormal_interval(probability: float, cov: float, confidence: float = CONFIDENCE) -> tuple[float, float]:
    """The interval p̂ · exp(±z σ), σ² = ln(1 + δ²), clipped to [0, 1].

    Parameters
    ----------
    probability : float
        The estimate p̂ > 0.
    cov : float
        Its coefficient of variation δ >= 0; an undefined one (nan, inf) gives [0, 1].
    confidence : float
        The two-sided confidence level.

    Returns
    -------
    tuple of float
        (lower, upper).
    """
    if not np.isfinite(cov):
        return 0.0, 1.0
    z = float(special.ndtri(0.5 * (1.0 + confidence)))
    sigma = np.sqrt(np.log1p(cov * cov))
    return float(probability * np.exp(-z * sigma)), float(min(1.0, probability * np.exp(z * sigma)))


def zero_count_upper(draws: int, largest_weight: float = 1.0, confidence: float = CONFIDENCE) -> float:
    """The upper bound on P[g > 0] when none of `draws` independent draws fell in the event.

    With draws from a density h and weights φ/h ≤ W, P = E_h[1{g>0} φ/h] ≤ W · P_h[g > 0], and the
    exact (Clopper–Pearson) upper bound of 0 events in n draws is 1 − (α/2)^(1/n) ≈ 3.7/n at 95 %.

    Parameters
    ----------
    draws : int
        Independent draws, none in the event.
    largest_weight : float
        The largest likelihood ratio φ/h of the sampling density (1 for draws from the input law).
    confidence : float
        The two-sided confidence level.

    Returns
    -------
    float
        The bound, at most 1.
    """
    if draws <= 0:
        return 1.0
    alpha = 1.0 - confidence
    return float(min(1.0, largest_weight * -np.expm1(np.log(0.5 * alpha) / draws)))


def standard_normal_logpdf(u: np.ndarray) -> np.ndarray:
    """log φ_d(u) of each row of u (n, d)."""
    return -0.5 * np.einsum("ij,ij->i", u, u) - 0.5 * u.shape[1] * np.log(2.0 * np.pi)


class Evaluations:
    """`evaluate` behind a budget: float64 answers, failed runs counted, design point kept.

    Parameters
    ----------
    evaluate : callable
        (n, d) float64 -> (n,) float64 margins; NaN for a failed run.
    dimension : int
        d.
    budget : int
        The most points ever evaluated.
    """

    def __init__(self, evaluate, dimension: int, budget: int):
        if dimension < 1:
            raise ValueError(f"dimension must be at least 1, got {dimension}")
        self._evaluate = evaluate
        self.dimension = dimension
        self.budget = int(budget)
        self.runs = 0
        self.failed = 0
        self.design_point: np.ndarray | None = None
        self._design_radius = np.inf

    @property
    def left(self) -> int:
        """Runs the budget still allows."""
        return self.budget - self.runs

    def __call__(self, u: np.ndarray) -> np.ndarray:
        """Evaluate a batch; NaN margins become −inf (outside the event, below every threshold)."""
        u = np.ascontiguousarray(u, dtype=np.float64)
        if u.ndim != 2 or u.shape[1] != self.dimension:
            raise ValueError(f"a batch is (n, {self.dimension}), got {u.shape}")
        if u.shape[0] > self.left:
            raise ValueError(f"a batch of {u.shape[0]} runs exceeds the budget's {self.left} left")
        g = np.asarray(self._evaluate(u), dtype=np.float64).reshape(-1)
        if g.shape[0] != u.shape[0]:
            raise ValueError(f"evaluate returned {g.shape[0]} values for {u.shape[0]} points")
        self.runs += u.shape[0]
        missing = np.isnan(g)
        self.failed += int(missing.sum())
        g = np.where(missing, -np.inf, g)
        inside = g > 0.0
        if inside.any():
            radii = np.einsum("ij,ij->i", u[inside], u[inside])
            k = int(np.argmin(radii))
            if radii[k] < self._design_radius:
                self._design_radius = float(radii[k])
                self.design_point = u[inside][k].copy()
        return g

    def notes(self) -> list[str]:
        """The sentences every estimate carries about its runs (failed ones)."""
        if not self.failed:
            return []
        return [f"{self.failed} of {self.runs} runs failed (no value): they are counted outside the event, "
                "so the estimate is that of the event among runs that give a value or fail"]

    def estimate(self, method: str, probability: float, cov: float, rounds: list[RoundRecord], stopped: str,
                 notes: list[str], upper_if_zero: float = 1.0, interval_cov: float | None = None
                 ) -> RareEventEstimate:
        """The estimate with its log-normal 95 % interval; for p̂ = 0 the interval is [0, upper_if_zero].

        Parameters
        ----------
        method : str
            The algorithm's name.
        probability, cov : float
            The estimate and its c.o.v.
        rounds : list of RoundRecord
            Its history.
        stopped : str
            Why it stopped.
        notes : list of str
            The algorithm's sentences; the failed-run sentence is added here.
        upper_if_zero : float
            The honest upper bound when no run fell in the event (never 0).
        interval_cov : float, optional
            The c.o.v. the interval is built on, when it is not `cov` (a bound on it).

        Returns
        -------
        RareEventEstimate
        """
        if probability > 0.0:
            lower, upper = lognormal_interval(probability, cov if interval_cov is None else interval_cov)
        else:
            if not upper_if_zero > 0.0:
                raise ValueError("an estimate of 0 needs an upper bound above 0")
            probability, lower, upper, cov = 0.0, 0.0, float(upper_if_zero), float("nan")
        return RareEventEstimate(method=method, probability=float(probability), lower=lower, upper=upper,
                                 cov=float(cov), runs=self.runs, failed=self.failed,
                                 design_point=self.design_point, rounds=tuple(rounds), stopped=stopped,
                                 notes=tuple(notes + self.notes()))
