"""Subset simulation (Au & Beck 2001) in standard-normal space.

P[g > 0] is written as a product of larger conditional probabilities, P = Π_j P[g > c_j | g > c_{j−1}]
over thresholds c_1 < c_2 < … < c_m < 0 chosen as we go. Level 0 is N draws of N(0, I); the
threshold c_{j+1} is the midpoint between the ⌊p0 N⌋-th and the next largest margin, so that p0 N
samples (the seeds) lie above it; Markov chains started at the seeds and kept inside {g > c_{j+1}}
give the N samples of the next level. It stops when at least p0 N samples of a level are in the event
(g > 0): P̂ = Π p_j · (their fraction).

The chains move by adaptive conditional sampling (Papaioannou, Betz, Zwirglmaier & Straub 2015), a
Metropolis-Hastings move whose proposal v_k = ρ_k u_k + √(1 − ρ_k²) ξ_k leaves N(0, 1) invariant in
every dimension, so a candidate is accepted exactly when its run stays in the level. The spread
σ_k = √(1 − ρ_k²) = min(1, λ σ̂_k), σ̂_k the seeds' standard deviation, and λ (0.6 at first) is
adapted after every step of all chains towards the acceptance rate 0.44: log λ += (â − 0.44)/√i.
Dimensions that are random-stream seeds (`redrawn`) have σ_k = 1: they are redrawn independently at
every step, and the redraw is kept only if the run stays in the level. The redraw alone rejects many
moves near the level's boundary, so with such dimensions λ targets an acceptance of 0.2: at 0.44 it
shrank the other dimensions' steps until the chains barely moved (c.o.v. over 20 seeds 0.76 at 0.44,
0.37 at 0.2, 0.40 at 0.15, on the seeded problem of tests/reliability_problems.py).

All chains move together: one step of all chains is one batch of runs.

The c.o.v. is Au & Beck's: δ_j² = (1 − p_j)/(N p_j) · (1 + γ_j), γ_j from the correlation of the
level indicator along the chains, and δ² = Σ δ_j² (levels taken as uncorrelated). The levels are
positively correlated (each level's seeds come from the last), and that δ understates the spread over
seeds (0.36 estimated against 0.44 measured on the linear problem at 1e-6): the 95 % interval is built
on Au & Beck's bound for fully correlated levels, Σ δ_j, which held the exact value in 17 to 20 of 20
seeds on each closed-form problem, against 12 to 18 of 20 with δ itself (tests/test_rare_algorithms.py).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .estimate import Evaluations, RareEventEstimate, RoundRecord, lognormal_interval, single_threaded

TARGET_ACCEPTANCE = 0.44
TARGET_ACCEPTANCE_REDRAWN = 0.2
FIRST_SPREAD = 0.6


@dataclass
class Levels:
    """The levels of one subset simulation.

    Attributes
    ----------
    probabilities : list of float
        The conditional probabilities p_j of the intermediate levels.
    covs : list of float
        Their c.o.v.s δ_j.
    thresholds : list of float
        The thresholds c_j.
    u, g : numpy.ndarray
        The last level's samples (N, d) and margins (N,).
    chains : list of numpy.ndarray
        The last level's samples' indices, chain by chain in chain order (for its correlation).
    stopped : str
        "converged" (the event reached), "budget", "stalled" (no threshold above the last) or "floor".
    rounds : list of RoundRecord
        The estimate of P[g > 0] after each level.
    """

    probabilities: list[float] = field(default_factory=list)
    covs: list[float] = field(default_factory=list)
    thresholds: list[float] = field(default_factory=list)
    u: np.ndarray | None = None
    g: np.ndarray | None = None
    chains: list[np.ndarray] = field(default_factory=list)
    stopped: str = ""
    rounds: list[RoundRecord] = field(default_factory=list)

    @property
    def reached(self) -> float:
        """Π p_j: the probability of the last intermediate level (1 before any)."""
        return float(np.prod(self.probabilities))

    def final(self) -> tuple[float, float, float, float]:
        """(P̂, δ, δ_max, fraction of the last level in the event).

        P̂ = Π p_j · fraction; δ² = Σ δ_j² (uncorrelated levels); δ_max = Σ δ_j, Au & Beck's bound for
        fully correlated levels.
        """
        inside = self.g > 0.0
        fraction = float(inside.mean())
        if fraction == 0.0:
            return 0.0, float("nan"), float("nan"), 0.0
        covs = self.covs + [level_cov(inside, self.chains, fraction)]
        return self.reached * fraction, float(np.sqrt(np.sum(np.square(covs)))), float(np.sum(covs)), fraction


def chain_correlation(indicator: np.ndarray, chains: list[np.ndarray], p: float) -> float:
    """Au & Beck's γ: 2 Σ_k (1 − k N_c/N) ρ_k, ρ_k the lag-k correlation of the indicator along chains.

    Parameters
    ----------
    indicator : numpy.ndarray
        (N,) bool, the samples in the level.
    chains : list of numpy.ndarray
        Each chain's sample indices in chain order (a chain of one sample for independent draws).
    p : float
        The fraction of samples in the level, 0 < p < 1.

    Returns
    -------
    float
        γ >= 0 in practice (negative lag correlations are kept as estimated).
    """
    n = indicator.shape[0]
    variance = p * (1.0 - p)
    longest = max(len(c) for c in chains)
    gamma = 0.0
    for lag in range(1, longest):
        products, pairs = 0.0, 0
        for chain in chains:
            if len(chain) > lag:
                values = indicator[chain].astype(float)
                products += float(values[:-lag] @ values[lag:])
                pairs += len(chain) - lag
        gamma += 2.0 * (pairs / n) * (products / pairs - p * p) / variance
    return gamma


def level_cov(indicator: np.ndarray, chains: list[np.ndarray], p: float) -> float:
    """δ = √((1 − p)/(N p) (1 + γ)), Au & Beck's c.o.v. of a level's conditional probability."""
    if p >= 1.0:
        return 0.0
    gamma = chain_correlation(indicator, chains, p)
    return float(np.sqrt((1.0 - p) / (indicator.shape[0] * p) * (1.0 + max(gamma, 0.0))))


def _threshold(g_sorted: np.ndarray, seeds: int) -> float:
    """The midpoint between the `seeds`-th largest margin and the next (just below the former if the next
    is a failed run's −inf); nan when the `seeds`-th largest is itself −inf."""
    top, below = g_sorted[seeds - 1], g_sorted[seeds]
    if not np.isfinite(top):
        return float("nan")
    return float(0.5 * (top + below)) if np.isfinite(below) else float(np.nextafter(top, -np.inf))


def run_levels(runs: Evaluations, rng: np.random.Generator, samples_per_level: int, p0: float,
               redrawn: tuple[int, ...] = (), floor: float = 0.0) -> Levels:
    """Run subset simulation's levels until the event is reached or it cannot go on.

    Parameters
    ----------
    runs : Evaluations
        The margins, within their budget.
    rng : numpy.random.Generator
        The only source of randomness.
    samples_per_level : int
        N.
    p0 : float
        The conditional probability of each intermediate level.
    redrawn : tuple of int
        Dimensions redrawn independently at every step.
    floor : float
        Stop ("floor") once Π p_j falls below it (0: never).

    Returns
    -------
    Levels
    """
    n = samples_per_level
    seeds_wanted = int(np.floor(p0 * n))
    dimension = runs.dimension
    levels = Levels()
    u = rng.standard_normal((n, dimension))
    g = runs(u)
    chains = [np.array([i]) for i in range(n)]
    mobile = np.ones(dimension, dtype=bool)
    mobile[list(redrawn)] = False
    while True:
        levels.u, levels.g, levels.chains = u, g, chains
        probability, cov, _, fraction = levels.final()
        levels.rounds.append(RoundRecord(runs=runs.runs, probability=probability, cov=cov))
        if fraction * n >= seeds_wanted:
            levels.stopped = "converged"
            return levels
        if levels.reached < floor:
            levels.stopped = "floor"
            return levels
        order = np.argsort(-g, kind="stable")
        threshold = _threshold(g[order], seeds_wanted)
        inside = g > threshold
        if not inside.any():
            levels.stopped = "stalled"
            return levels
        seeds = np.flatnonzero(inside)
        if n - seeds.size > runs.left:
            levels.stopped = "budget"
            return levels
        p = float(inside.mean())
        levels.probabilities.append(p)
        levels.covs.append(level_cov(inside, chains, p))
        levels.thresholds.append(threshold)
        u, g, chains = _move_chains(runs, rng, u[seeds], g[seeds], threshold, n, mobile,
                                    TARGET_ACCEPTANCE if mobile.all() else TARGET_ACCEPTANCE_REDRAWN)


def _move_chains(evaluate, rng, u_seeds, g_seeds, threshold, n, mobile, target):
    """N samples of the level {g > threshold}: chains of adaptive conditional sampling from the seeds."""
    count, dimension = u_seeds.shape
    lengths = np.full(count, n // count)
    lengths[: n % count] += 1
    spread_seeds = u_seeds.std(axis=0) if count > 1 else np.ones(dimension)
    scale = FIRST_SPREAD
    states_u, states_g = u_seeds.copy(), g_seeds.copy()
    path_u, path_g = [states_u.copy()], [states_g.copy()]
    for step in range(1, int(lengths.max())):
        moving = np.flatnonzero(lengths > step)
        sigma = np.where(mobile, np.minimum(1.0, scale * spread_seeds), 1.0)
        rho = np.sqrt(1.0 - sigma * sigma)
        candidates = rho * states_u[moving] + sigma * rng.standard_normal((moving.size, dimension))
        values = evaluate(candidates)
        accepted = values > threshold
        states_u[moving[accepted]] = candidates[accepted]
        states_g[moving[accepted]] = values[accepted]
        path_u.append(states_u[moving].copy())
        path_g.append(states_g[moving].copy())
        scale *= np.exp((accepted.mean() - target) / np.sqrt(step))
    # order the samples chain by chain: step s holds the chains still moving at s, in chain order
    index = np.full((len(path_u), count), -1)
    position = 0
    for step, block in enumerate(path_u):
        index[step, : block.shape[0]] = np.arange(position, position + block.shape[0])
        position += block.shape[0]
    chains = [index[: lengths[c], c] for c in range(count)]
    return np.concatenate(path_u), np.concatenate(path_g), chains


@single_threaded
def subset_simulation(evaluate, dimension, *, seed: int, budget: int, samples_per_level: int = 1000,
                      p0: float = 0.1, redrawn: tuple[int, ...] = ()) -> RareEventEstimate:
    """Estimate P[g(U) > 0], U ~ N(0, I_d), by subset simulation.

    Parameters
    ----------
    evaluate : callable
        (n, d) float64 -> (n,) float64 margins g; NaN for a failed run (outside the event).
    dimension : int
        d.
    seed : int
        Seed of `numpy.random.default_rng`, the only randomness.
    budget : int
        The most runs; a level that would exceed it is not started ("budget").
    samples_per_level : int
        N, the samples of each level (p0 N of them are the next level's seeds).
    p0 : float
        The conditional probability of each intermediate level, in (0, 0.5].
    redrawn : tuple of int
        Dimensions redrawn independently at every chain step (random-stream seeds).

    Returns
    -------
    RareEventEstimate
        "converged" when p0 N samples of a level reached the event; on "budget" or "stalled" the
        fraction of the last level in the event (its product with the levels), and when that is 0 the
        upper bound of the last level's probability, which holds the event.
    """
    if not 0.0 < p0 <= 0.5:
        raise ValueError(f"p0 must lie in (0, 0.5], got {p0}")
    if int(np.floor(p0 * samples_per_level)) < 1:
        raise ValueError(f"samples_per_level {samples_per_level} times p0 {p0} gives no seed")
    if samples_per_level > budget:
        raise ValueError(f"the budget {budget} does not hold one level of {samples_per_level} samples")
    runs = Evaluations(evaluate, dimension, budget)
    levels = run_levels(runs, np.random.default_rng(seed), samples_per_level, p0, tuple(redrawn))
    probability, cov, cov_bound, _ = levels.final()
    notes = []
    upper_if_zero = 1.0
    if levels.stopped != "converged":
        reached = levels.reached
        level_upper = lognormal_interval(reached, float(np.sqrt(np.sum(np.square(levels.covs)))))[1]
        why = ("the budget ended" if levels.stopped == "budget"
               else "no threshold above the last could be found (the margins of its seeds are equal)")
        notes.append(f"{why} after {len(levels.probabilities)} levels, before p0 N samples of a level reached "
                     f"the event; the last level's probability is {reached:.3g}")
        if probability == 0.0:
            upper_if_zero = level_upper
            notes.append("no run reached the event: the estimate is 0 and the upper bound is that of the last "
                         "level, which holds the event")
    return runs.estimate("subset_simulation", probability, cov, levels.rounds, levels.stopped, notes, upper_if_zero,
                         interval_cov=cov_bound)

