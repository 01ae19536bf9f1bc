"""Closed-form limit states for the rare-event algorithms (issue 46), in standard-normal space.

Each margin g takes u (n, d) and returns (n,); the event is g > 0. The exact probabilities are
computed here by one-dimensional quadrature to a relative accuracy of about 1e-10 (scipy.integrate.quad,
epsrel 1e-12), far below any tolerance the tests use.

- linear: g = Σ u_k / √7 − β in 7 inputs, β = −Φ⁻¹(1e-6): exact p = Φ(−β) = 1e-6.
- curved: g = u_1 + κ Σ_{k=2..7} u_k² − β (κ = 0.1, β = 5.35), a paraboloid opening towards the origin in
  6 of its 7 inputs. p = Φ(−β) + ∫_{−∞}^{β} φ(x) P[χ²_6 > (β − x)/κ] dx = 9.243e-6. FORM started at the
  origin meets the surface at (β, 0, …) where the gradient is e_1, a saddle of |u| on the surface,
  and answers Φ(−β) = 4.4e-8: −99.5 %, as in the issue's table.
- four_branch: the series system of Waarts (2000) with k = 7: failure when any of
  3 + 0.1 (u_1 − u_2)² ∓ (u_1 + u_2)/√2 or ±(u_1 − u_2) + k/√2 is negative, so g = −min of the four.
  With a = (u_1 + u_2)/√2 and b = (u_1 − u_2)/√2, independent N(0, 1), the safe set is
  |b| < k/2 and |a| < 3 + 0.2 b²: p = 1 − ∫_{−k/2}^{k/2} φ(b) (2 Φ(3 + 0.2 b²) − 1) db = 2.2228e-3
  (Echard et al. 2011 report 2.233e-3 from 10^6 Monte Carlo runs).
- seeded: g = u_1 + c s(u_2) − β (c = 0.5, β = 4) in 2 inputs, u_2 a random-stream seed: s = +1 when the
  fractional part of 10^6 Φ(u_2) is below 1/2, else −1, a noise that flips between neighbouring seeds
  and takes each sign with probability 1/2 exactly (Φ(U_2) is uniform). p = (Φ(c − β) + Φ(−c − β))/2.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import integrate, special, stats


@dataclass(frozen=True)
class Problem:
    """A limit state with its exact probability."""

    name: str
    dimension: int
    margin: object
    exact: float
    redrawn: tuple[int, ...] = field(default=())


LINEAR_BETA = float(-special.ndtri(1e-6))
CURVED_BETA, CURVED_KAPPA = 5.35, 0.1
BRANCH_K = 7.0
SEEDED_BETA, SEEDED_C = 4.0, 0.5


def linear(u):
    return u.sum(axis=1) / np.sqrt(u.shape[1]) - LINEAR_BETA


def curved(u):
    return u[:, 0] + CURVED_KAPPA * np.square(u[:, 1:]).sum(axis=1) - CURVED_BETA


def four_branch(u):
    a = (u[:, 0] + u[:, 1]) / np.sqrt(2.0)
    d = u[:, 0] - u[:, 1]
    branches = np.stack([3.0 + 0.1 * d * d - a, 3.0 + 0.1 * d * d + a,
                         d + BRANCH_K / np.sqrt(2.0), -d + BRANCH_K / np.sqrt(2.0)])
    return -branches.min(axis=0)


def seed_noise(u_seed):
    """±1 from the sixth decimal of Φ(u_seed): each sign with probability 1/2, no smoothness in u_seed."""
    return np.where(np.modf(1e6 * special.ndtr(u_seed))[0] < 0.5, 1.0, -1.0)


def seeded(u):
    return u[:, 0] + SEEDED_C * seed_noise(u[:, 1]) - SEEDED_BETA


def _curved_exact():
    def density(x):
        return stats.norm.pdf(x) * stats.chi2.sf((CURVED_BETA - x) / CURVED_KAPPA, 6)
    return integrate.quad(density, -np.inf, CURVED_BETA, epsabs=0, epsrel=1e-12, limit=500)[0] \
        + stats.norm.sf(CURVED_BETA)


def _four_branch_exact():
    def safe(b):
        return stats.norm.pdf(b) * (2.0 * special.ndtr(3.0 + 0.2 * b * b) - 1.0)
    return 1.0 - integrate.quad(safe, -BRANCH_K / 2, BRANCH_K / 2, epsabs=0, epsrel=1e-13)[0]


PROBLEMS = {
    "linear": Problem("linear", 7, linear, 1e-6),
    "curved": Problem("curved", 7, curved, _curved_exact()),
    "four_branch": Problem("four_branch", 2, four_branch, _four_branch_exact()),
    "seeded": Problem("seeded", 2, seeded,
                      0.5 * (special.ndtr(SEEDED_C - SEEDED_BETA) + special.ndtr(-SEEDED_C - SEEDED_BETA)),
                      redrawn=(1,)),
}


@dataclass(frozen=True)
class Repetitions:
    """An algorithm's estimates of one problem over seeds 0 … n − 1, against the exact value."""

    exact: float
    probabilities: np.ndarray
    lowers: np.ndarray
    uppers: np.ndarray
    runs: np.ndarray

    @property
    def cov(self) -> float:
        """The c.o.v. of the estimates over the seeds (sample standard deviation / mean)."""
        return float(self.probabilities.std(ddof=1) / self.probabilities.mean())

    @property
    def bias(self) -> float:
        """The relative bias of their mean."""
        return float(self.probabilities.mean() / self.exact - 1.0)

    @property
    def covered(self) -> int:
        """How many of the 95 % intervals hold the exact value."""
        return int(((self.lowers <= self.exact) & (self.exact <= self.uppers)).sum())

    @property
    def within_2(self) -> int:
        """How many estimates lie within a factor 2 of the exact value."""
        ratio = self.probabilities / self.exact
        return int(((ratio >= 0.5) & (ratio <= 2.0)).sum())


def repeat(algorithm, problem: Problem, seeds: int = 20, **settings) -> Repetitions:
    """Run `algorithm` (one of uqflight.designs.rare's) on `problem` with seeds 0 … seeds − 1."""
    estimates = [algorithm(problem.margin, problem.dimension, seed=seed, redrawn=problem.redrawn, **settings)
                 for seed in range(seeds)]
    return Repetitions(problem.exact, *(np.array([getattr(e, name) for e in estimates])
                                        for name in ("probability", "lower", "upper", "runs")))
