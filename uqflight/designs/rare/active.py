"""Active learning of the event's boundary, then importance sampling on true runs.

1. First design: `first` points reaching into the tails, on spheres of radii spread evenly over
   [0, 5.5] (a direction drawn uniformly for each), so that a first design of safe points only is no
   reason to stop: the surrogate still has a trend to follow outwards.
2. Surrogate: a least-squares linear trend plus a Gaussian process on its residuals (scikit-learn,
   constant × anisotropic RBF + white noise, `random_state` drawn from the seed): outside the runs it
   reverts to the trend, not to a constant, which is what carries it from the first design to a
   boundary at |u| = 5.
3. Enrichment (AK-MCS's U learning function, Echard et al. 2011): the candidates are the last level of
   a subset simulation on μ + 2σ (1,000 samples a level, on the surrogate alone): N(0, I) draws in the
   set {μ > 0} ∪ {U < 2} where the event is plausible, or, if that set is below 1e-12, where μ + 2σ is
   largest. Each round flies the `batch` candidates of smallest U = |μ|/σ (each one farther than 0.2
   from those already picked). It stops when every candidate has U ≥ 2 after at least `min_rounds`
   rounds, after `max_rounds` rounds (a seed input's noise keeps U small at the boundary), or when the
   first design and the enrichment have spent `learning` of the budget.
4. Correction on true runs (a control variate): an importance-sampling density h is fitted on the
   candidates (a Gaussian kernel mixture, `importance.KernelMixture`, mixed with 10 % of N(0, I); its
   bandwidth twice as wide with a seed input, whose noise blurs the boundary the candidates draw), the
   surrogate's probability P̂_μ = E_h[1{μ > 0} φ/h] is computed from 20,000 draws of h on the surrogate
   alone, and rounds of `batch_is` fresh true runs drawn from h correct it:

       P̂ = mean(Y − c X) + c P̂_μ,   Y = 1{g > 0} φ/h,   X = 1{μ > 0} φ/h,

   c = cov(Y, X)/var(X) from the runs, until its c.o.v. reaches `target_cov` (after two rounds) or the
   budget ends.

Y alone is an unbiased importance-sampling estimate whatever the surrogate, since h > 0 everywhere, and
X − P̂_μ has mean 0: P̂ stays unbiased where the surrogate is wrong (up to the O(1/n) of an estimated c),
and the better the surrogate the smaller its variance (c near 1 and Y − X nearly always 0). That
variance is taken at least (P̂/n)², as if one of the n fresh runs had disagreed with the surrogate:
agreement on 200 runs is no proof. The fresh runs are the final check of the surrogate: how many it
classified wrongly is in the notes. Should P̂ come out at 0 or below (a surrogate far off), the estimate
is plain importance sampling of the fresh runs, mean(Y). When none of them reaches the event it is 0
and the upper bound is the exact bound of 0 events among them, scaled by the largest ratio φ/h (10,
from the defensive part): never 0.

Random-stream seed dimensions (`redrawn`) are not inputs of the surrogate (their effect is the white
noise) and keep their N(0, 1) law in every run.
"""
from __future__ import annotations

import warnings

import numpy as np
from sklearn.exceptions import ConvergenceWarning
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

from .estimate import Evaluations, RareEventEstimate, RoundRecord, single_threaded, zero_count_upper
from .importance import WIDENING, KernelMixture, draw, likelihood_ratios, pooled_mean, weighted_mean
from .subset import run_levels

FIRST_RADIUS = 5.5
SURROGATE_SAMPLES = 1000
SURROGATE_FLOOR = 1e-12
SPACING = 0.2
STOP_U = 2.0
DEFENSIVE = 0.1
WIDENING_NOISY = 3.0
MAX_CENTRES = 400
SURROGATE_DRAWS, SURROGATE_CHUNK = 20_000, 5_000


class Surrogate:
    """A linear trend plus a Gaussian process on its residuals, fitted on the runs that gave a value.

    Parameters
    ----------
    u : numpy.ndarray
        (n, k) the runs' points on the surrogate's dimensions.
    g : numpy.ndarray
        (n,) their margins, finite.
    random_state : int
        scikit-learn's seed for the optimiser's restarts.
    previous : Surrogate, optional
        The last round's surrogate: its fitted hyperparameters start the optimiser, without restarts.
    """

    def __init__(self, u: np.ndarray, g: np.ndarray, random_state: int, previous: Surrogate | None = None):
        k = u.shape[1]
        design = np.column_stack([np.ones(len(u)), u])
        self.trend = np.linalg.lstsq(design, g, rcond=None)[0]
        if previous is None:
            kernel, restarts = (ConstantKernel(1.0, (1e-4, 1e4)) * RBF(np.full(k, 2.0), (0.05, 100.0))
                                + WhiteKernel(1e-6, (1e-10, 1.0))), 1
        else:
            kernel, restarts = previous.process.kernel_, 0
        self.process = GaussianProcessRegressor(kernel, normalize_y=True, n_restarts_optimizer=restarts,
                                                random_state=random_state)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            self.process.fit(u, g - design @ self.trend)

    def mean(self, u: np.ndarray) -> np.ndarray:
        """μ(u)."""
        return self.trend[0] + u @ self.trend[1:] + self.process.predict(u)

    def mean_and_std(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(μ(u), σ(u)), σ the process's predictive standard deviation."""
        residual, std = self.process.predict(u, return_std=True)
        return self.trend[0] + u @ self.trend[1:] + residual, std

    def plausible(self, u: np.ndarray) -> np.ndarray:
        """μ + 2σ: positive where the event is plausible, {μ > 0} ∪ {U < 2}."""
        mean, std = self.mean_and_std(u)
        return mean + STOP_U * std


def first_design(count: int, k: int, rng: np.random.Generator) -> np.ndarray:
    """`count` points on spheres of radii evenly spread over [0, 5.5], one uniform direction each."""
    directions = rng.standard_normal((count, k))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    radii = np.linspace(0.0, FIRST_RADIUS, count)
    return directions * radii[:, None]


def pick(candidates: np.ndarray, score: np.ndarray, count: int) -> np.ndarray:
    """Indices of up to `count` candidates of smallest score, each farther than SPACING from the others."""
    chosen: list[int] = []
    for i in np.argsort(score, kind="stable"):
        if all(np.linalg.norm(candidates[i] - candidates[j]) > SPACING for j in chosen):
            chosen.append(int(i))
            if len(chosen) == count:
                break
    return np.array(chosen, dtype=int)


def surrogate_levels(surrogate: Surrogate, k: int, rng: np.random.Generator):
    """Subset simulation on μ + 2σ: its last level's samples, margins, and whether μ + 2σ > 0 was reached."""
    runs = Evaluations(surrogate.plausible, k, budget=np.iinfo(np.int64).max)
    levels = run_levels(runs, rng, SURROGATE_SAMPLES, 0.1, floor=SURROGATE_FLOOR)
    return levels.u, levels.g, levels.stopped == "converged"


def smallest_budget(k: int, *, first: int | None = None, batch: int = 5, learning: float = 0.4,
                    batch_is: int = 100) -> int:
    """The fewest runs `active_learning` accepts with `k` surrogate inputs: its first design and one
    enrichment within the `learning` share, and two importance-sampling rounds in the rest."""
    first = 4 * k + 12 if first is None else first
    budget = 1
    while first + batch > int(learning * budget) or budget - int(learning * budget) < 2 * batch_is:
        budget += 1
    return budget


@single_threaded
def active_learning(evaluate, dimension, *, seed: int, budget: int, redrawn: tuple[int, ...] = (),
                    first: int | None = None, batch: int = 5, min_rounds: int = 10, max_rounds: int = 40,
                    learning: float = 0.4, batch_is: int = 100, target_cov: float = 0.05) -> RareEventEstimate:
    """Estimate P[g(U) > 0], U ~ N(0, I_d), by a Gaussian-process surrogate and importance sampling.

    Parameters
    ----------
    evaluate : callable
        (n, d) float64 -> (n,) float64 margins g; NaN for a failed run (outside the event).
    dimension : int
        d.
    seed : int
        Seed of `numpy.random.default_rng`, the only randomness (scikit-learn's included).
    budget : int
        The most runs.
    redrawn : tuple of int
        Random-stream seed dimensions: not surrogate inputs, always N(0, 1).
    first : int, optional
        Points of the first design (default 4k + 12, k the surrogate's dimensions).
    batch : int
        Runs per enrichment round.
    min_rounds : int
        Enrichment rounds before the U criterion may stop it.
    max_rounds : int
        The most enrichment rounds (a noisy margin, from a seed input, never makes every U ≥ 2).
    learning : float
        The largest share of the budget the first design and the enrichment may spend.
    batch_is : int
        Runs per importance-sampling round.
    target_cov : float
        Stop once the estimate's c.o.v. is at most this (after two importance-sampling rounds).

    Returns
    -------
    RareEventEstimate
    """
    active = np.ones(dimension, dtype=bool)
    active[list(redrawn)] = False
    k = int(active.sum())
    if k == 0:
        raise ValueError("every dimension is redrawn: there is nothing to learn (Monte Carlo is the design)")
    first = 4 * k + 12 if first is None else first
    learning_runs = int(learning * budget)
    if budget < smallest_budget(k, first=first, batch=batch, learning=learning, batch_is=batch_is):
        raise ValueError(f"a budget of {budget} holds too few runs: the first design ({first}), one enrichment "
                         f"({batch}) within {learning:.0%} of it, and two importance-sampling rounds ({batch_is})")
    rng = np.random.default_rng(seed)
    runs = Evaluations(evaluate, dimension, budget)
    u = rng.standard_normal((first, dimension))
    u[:, active] = first_design(first, k, rng)
    g = runs(u)
    seen_u, seen_g = [u[:, active]], [g]
    rounds, notes = [], []
    enrichments = 0
    surrogate = None
    while True:
        train_u, train_g = np.concatenate(seen_u), np.concatenate(seen_g)
        valid = np.isfinite(train_g)
        if valid.sum() < k + 2:
            notes.append(f"only {int(valid.sum())} of the first {train_g.size} runs gave a value: too few to learn "
                         "a surrogate from")
            return runs.estimate("active_learning", 0.0, float("nan"), rounds, "stalled", notes)
        surrogate = Surrogate(train_u[valid], train_g[valid], int(rng.integers(2 ** 31)), surrogate)
        candidates, _, reached = surrogate_levels(surrogate, k, rng)
        mu, sigma = surrogate.mean_and_std(candidates)
        score = np.abs(mu) / np.maximum(sigma, 1e-300)
        rounds.append(RoundRecord(runs=runs.runs, probability=float("nan"), cov=float("nan")))
        if enrichments >= min_rounds and reached and score.min() >= STOP_U:
            learned = f"the surrogate's boundary was learned (min U ≥ {STOP_U:g}) after {enrichments} rounds"
            break
        if runs.runs + batch > learning_runs or enrichments == max_rounds:
            learned = (f"the enrichment stopped after {enrichments} rounds ({runs.runs} runs) with min U = "
                       f"{score.min():.2g}: the boundary is not sure everywhere (noise, or too few runs)")
            break
        chosen = candidates[pick(candidates, score, batch)]
        u = rng.standard_normal((chosen.shape[0], dimension))
        u[:, active] = chosen
        seen_u.append(chosen)
        seen_g.append(runs(u))
        enrichments += 1
    notes.append(learned)
    if not reached:
        notes.append("the surrogate finds the event implausible (μ + 2σ ≤ 0) everywhere down to a probability "
                     "of 1e-12: the importance sampling looks where μ + 2σ is largest")
    # the density: the surrogate's samples of {μ + 2σ > 0} (or of its top level when it has none)
    centres = candidates[rng.permutation(candidates.shape[0])[:MAX_CENTRES]]
    density = KernelMixture(centres, np.ones(centres.shape[0]), defensive=DEFENSIVE,
                            widening=WIDENING if active.all() else WIDENING_NOISY)
    surrogate_mean, surrogate_variance = surrogate_probability(surrogate, density, k, rng)
    plain: list[np.ndarray] = []
    controls: list[np.ndarray] = []
    wrong = checked = 0
    stopped = "budget"
    while runs.left > 0:
        u = draw(density, min(batch_is, runs.left), dimension, active, rng)
        g = runs(u)
        ratios = likelihood_ratios(u[:, active], density)
        says = surrogate.mean(u[:, active]) > 0.0
        plain.append(ratios * (g > 0.0))
        controls.append(ratios * says)
        valid = np.isfinite(g)
        wrong += int((says[valid] != (g[valid] > 0.0)).sum())
        checked += int(valid.sum())
        probability, cov = corrected(surrogate_mean, surrogate_variance, plain, controls)
        rounds.append(RoundRecord(runs=runs.runs, probability=probability, cov=cov))
        if len(plain) > 1 and cov <= target_cov:
            stopped = "converged"
            break
    draws = sum(t.size for t in plain)
    notes.append(f"the final check: {wrong} of {checked} fresh runs fell on the other side of the surrogate's "
                 f"boundary, and correct its estimate {surrogate_mean:.3g}")
    upper_if_zero = 1.0
    if probability <= 0.0:
        probability, cov = weighted_mean(plain)
        notes.append("the correction took the estimate to 0 or below (the surrogate is far off): the estimate "
                     "is plain importance sampling of the fresh runs")
    if probability == 0.0:
        upper_if_zero = zero_count_upper(draws, largest_weight=1.0 / DEFENSIVE)
        notes.append(f"no fresh run reached the event: the estimate is 0 and the upper bound is the 95 % bound of "
                     f"0 events in {draws} draws, times the largest likelihood ratio {1.0 / DEFENSIVE:g}")
    elif cov > target_cov:
        notes.append(f"the budget ended with a c.o.v. of {cov:.2g}, above the target {target_cov:.2g}")
    return runs.estimate("active_learning", probability, cov, rounds, stopped, notes, upper_if_zero)


def surrogate_probability(surrogate: Surrogate, density: KernelMixture, k: int,
                          rng: np.random.Generator) -> tuple[float, float]:
    """(P̂_μ, its variance): E_h[1{μ > 0} φ/h] by SURROGATE_DRAWS draws of h, on the surrogate alone."""
    terms = []
    for _ in range(SURROGATE_DRAWS // SURROGATE_CHUNK):
        u = density.sample(SURROGATE_CHUNK, rng)
        terms.append(likelihood_ratios(u, density) * (surrogate.mean(u) > 0.0))
    return pooled_mean([np.concatenate(terms)])


def corrected(surrogate_mean: float, surrogate_variance: float, plain: list[np.ndarray],
              says: list[np.ndarray]) -> tuple[float, float]:
    """(P̂, c.o.v.) of the control-variate estimate P̂ = mean(Y − c X) + c P̂_μ.

    Y = 1{g > 0} φ/h and X = 1{μ > 0} φ/h on the fresh runs, P̂_μ = E_h[X] from the surrogate alone, and
    c = cov(Y, X)/var(X) estimated from the runs: about 1 where the surrogate classifies well, less where
    a seed input's noise makes it right only on average (c = 1 would then add the noise's variance).
    The variance, var(Y − c X)/n + c² var(P̂_μ), is taken at least (P̂/n)², as if one of the n runs had
    disagreed with the surrogate: a run of agreements is no proof that it is right everywhere.
    """
    y, x = np.concatenate(plain), np.concatenate(says)
    n = y.size
    spread = x.var(ddof=1) if n > 1 else 0.0
    c = float(np.cov(y, x)[0, 1] / spread) if spread > 0.0 else 0.0
    residual = y - c * x
    probability = float(residual.mean() + c * surrogate_mean)
    if probability <= 0.0:
        return probability, float("nan")
    variance = max(residual.var(ddof=1) / n if n > 1 else np.inf, (probability / n) ** 2) \
        + c * c * surrogate_variance
    return probability, float(np.sqrt(variance) / probability)
