"""emcee's ensemble sampler with its differential-evolution move, seeded, with the convergence rule of `calibrate`.

Start: the posterior mode (BFGS from the prior mean and a few prior draws), the walkers in a small
ball around it. The first half of the steps is burn-in and dropped. Without a number of steps the
chain stops at the first check (every CHECK_EVERY steps from FIRST_CHECK on) where the rules below
hold at that check and the one before, and at MAX_STEPS at the latest. The kept half converged when

* it is at least MIN_TAU_MULTIPLE (50) integrated autocorrelation times τ long (emcee's τ with
  tol=0, the largest over the parameters);
* split-R̂ (every walker's kept chain cut in two, Gelman et al. BDA3 Eq. 11.4) is ≤ MAX_RHAT for
  every parameter;
* the mean acceptance fraction is in [MIN_ACCEPTANCE, MAX_ACCEPTANCE] and no walker is stuck
  (acceptance below MIN_WALKER_ACCEPTANCE).
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import Callable

import emcee
import numpy as np
from scipy import optimize
from threadpoolctl import threadpool_limits

from ..text import Refusal
from .size import MAX_STEPS

MIN_TAU_MULTIPLE = 50.0
MAX_RHAT = 1.05
MIN_ACCEPTANCE, MAX_ACCEPTANCE = 0.1, 0.9
MIN_WALKER_ACCEPTANCE = 0.02
STARTS = 6  # optimiser starts: the prior mean and STARTS - 1 prior draws
FIRST_CHECK, CHECK_EVERY = 1000, 250  # an adaptive chain's convergence checks, in steps


# emcee's differential-evolution move alone: its stationary distribution is the target, and on the
# closed forms of benchmarks/sampler_moves.py its τ is the smallest measured (a corrected snooker mixed
# in gives the same τ; the stretch move's is 3-4x larger). emcee 3.1's DESnookerMove, mixed in at 20 %
# before, is biased: with it the posterior stds were 0.93-0.99 of the exact ones there.
MOVES = [(emcee.moves.DEMove(), 1.0)]


@dataclass
class Chain:
    samples: np.ndarray        # (steps, walkers, D): the whole chain, burn-in included
    log_prob: np.ndarray       # (steps, walkers)
    acceptance: np.ndarray     # (walkers,)
    burn: int
    labels: list[str]
    mode: np.ndarray
    diagnostics: dict = field(default_factory=dict)

    @property
    def kept(self) -> np.ndarray:
        return self.samples[self.burn:]

    @property
    def flat(self) -> np.ndarray:
        """The kept draws, (kept steps × walkers, D)."""
        return self.kept.reshape(-1, self.samples.shape[2])


def split_rhat(chains: np.ndarray) -> np.ndarray:
    """Split-R̂ per parameter of chains (n, m, D): each of the m chains cut in two halves."""
    n = chains.shape[0] // 2
    if n < 2:
        return np.full(chains.shape[2], np.nan)
    halves = np.concatenate([chains[:n], chains[chains.shape[0] - n:]], axis=1)  # (n, 2m, D)
    means = halves.mean(axis=0)
    within = halves.var(axis=0, ddof=1).mean(axis=0)
    between = n * means.var(axis=0, ddof=1)
    pooled = (n - 1) / n * within + between / n
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.sqrt(pooled / within)


def find_mode(log_prob: Callable, start: np.ndarray, prior_draws: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The best of BFGS runs on −log p from `start` and each prior draw: (mode, step scale per axis).
    The gradient is scipy's forward difference (its steps), evaluated with the point in one vectorised call."""
    eps = math.sqrt(np.finfo(float).eps)

    def objective(theta):
        steps = eps * np.where(theta >= 0, 1.0, -1.0) * np.maximum(1.0, np.abs(theta))
        steps = (theta + steps) - theta
        values = log_prob(np.vstack([theta, theta + np.diag(steps)]))
        values = np.where(np.isfinite(values), -values, 1e300)
        return values[0], (values[1:] - values[0]) / steps

    best = None
    for x0 in [start, *prior_draws]:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = optimize.minimize(objective, x0, jac=True, method="BFGS", options={"gtol": 1e-6, "maxiter": 2000})
        if best is None or result.fun < best.fun:
            best = result
    scale = np.sqrt(np.clip(np.diag(np.atleast_2d(best.hess_inv)), 1e-12, 1.0))
    return best.x, np.where(np.isfinite(scale), scale, 1e-3)


def sample(log_prob: Callable, ndim: int, labels: list[str], start: np.ndarray, prior_draw: Callable,
           walkers: int, steps: int | None, seed: int, progress=None, moves=None) -> Chain:
    """Run the ensemble (vectorised log_prob: (M, D) → (M,)), seeded; diagnostics in chain.diagnostics.
    `steps`: exactly that many, or None: adaptive (see the module). The first S steps are the same
    either way, so an adaptive chain that stopped at S is the fixed chain of S steps. `moves`: emcee's
    [(move, weight)] (default MOVES); `progress` (a uqflight.running.progress.Progress) counts the steps."""
    if walkers < 2 * ndim:
        raise Refusal(f"--walkers: expected at least 2 × {ndim} parameters = {2 * ndim}, got {walkers}")
    if walkers % 2:
        raise Refusal(f"--walkers: expected an even number, got {walkers}")
    with threadpool_limits(limits=1):  # small matrices: one BLAS thread is 5-10x faster than several
        return _sample(log_prob, ndim, labels, start, prior_draw, walkers, steps, seed, progress, moves or MOVES)


def _sample(log_prob, ndim, labels, start, prior_draw, walkers, steps, seed, progress, moves) -> Chain:
    rng = np.random.default_rng(seed)
    mode, scale = find_mode(log_prob, start, prior_draw(rng, STARTS - 1))
    initial = mode + 0.1 * scale * rng.standard_normal((walkers, ndim))
    for _ in range(100):  # a start outside the prior's support (uniform germs) is drawn again
        bad = ~np.isfinite(log_prob(initial))
        if not bad.any():
            break
        initial[bad] = mode + 0.01 * scale * rng.standard_normal((int(bad.sum()), ndim))
    else:
        raise Refusal("cannot place the walkers where the posterior is positive around its mode (it lies at "
                      "the edge of the priors' support, or the likelihood vanishes there): check the data against "
                      "the results file's outputs (units, times), or widen the parameters' intervals")
    sampler = emcee.EnsembleSampler(walkers, ndim, log_prob, vectorize=True, moves=moves)
    sampler.random_state = np.random.RandomState(seed).get_state()
    passed = False  # the previous check's verdict
    for step, _ in enumerate(sampler.sample(initial, iterations=steps or MAX_STEPS), 1):  # run_mcmc, step by step
        if progress:
            progress.advance()
        if steps is None and step >= FIRST_CHECK and step % CHECK_EVERY == 0 and step < MAX_STEPS:
            chain = _chain_so_far(sampler, labels, mode)
            if chain.diagnostics["converged"] and passed:
                break  # the chain just diagnosed is the one returned
            passed = chain.diagnostics["converged"]
    else:
        chain = _chain_so_far(sampler, labels, mode)
    chain.diagnostics["stopping"] = ("fixed" if steps else
                                     f"adaptive: checked every {CHECK_EVERY} steps from {FIRST_CHECK} on, stopped "
                                     f"where two checks in a row passed, at most {MAX_STEPS}")
    return chain


def _chain_so_far(sampler, labels, mode) -> Chain:
    """The steps the sampler has taken, the first half burn-in, diagnosed."""
    samples = sampler.get_chain()
    chain = Chain(samples, sampler.get_log_prob(), sampler.acceptance_fraction.copy(), len(samples) // 2,
                  list(labels), mode)
    chain.diagnostics = diagnose(chain)
    return chain


def diagnose(chain: Chain) -> dict:
    """Acceptance, τ, split-R̂ and the verdict, with what to change when not converged."""
    kept = chain.kept
    n_kept, walkers, _ = kept.shape
    with np.errstate(invalid="ignore", divide="ignore"):  # a constant chain: τ NaN, a problem below, no warning
        tau = np.array([emcee.autocorr.integrated_time(kept[:, :, [k]], tol=0)[0] for k in range(kept.shape[2])])
    rhat = split_rhat(kept)
    tau_max = float(np.max(tau))
    acceptance = chain.acceptance
    problems = []
    if not np.isfinite(tau_max) or n_kept < MIN_TAU_MULTIPLE * tau_max:
        needed = 2 * math.ceil(1.2 * MIN_TAU_MULTIPLE * tau_max) if np.isfinite(tau_max) else None
        problems.append(f"the kept half of the chain ({n_kept} steps) is shorter than {MIN_TAU_MULTIPLE:g} "
                        f"autocorrelation times (τ_max = {tau_max:.1f}, {chain.labels[int(np.argmax(tau))]}): "
                        f"run --steps {needed} or more" if needed else "τ is undefined: run more --steps")
    if not np.all(rhat <= MAX_RHAT):
        worst = int(np.nanargmax(np.where(np.isfinite(rhat), rhat, np.inf)))
        problems.append(f"split-R̂ of {chain.labels[worst]} is {rhat[worst]:.3f} > {MAX_RHAT}: the walkers disagree; "
                        "run more --steps (or more --walkers if a mode is missed)")
    mean_acceptance = float(np.mean(acceptance))
    if not MIN_ACCEPTANCE <= mean_acceptance <= MAX_ACCEPTANCE:
        problems.append(f"mean acceptance fraction {mean_acceptance:.3f} is outside [{MIN_ACCEPTANCE}, "
                        f"{MAX_ACCEPTANCE}]: the posterior is badly scaled or multimodal; use more --walkers")
    stuck = int(np.sum(acceptance < MIN_WALKER_ACCEPTANCE))
    if stuck:
        problems.append(f"{stuck} of {walkers} walkers accepted fewer than {MIN_WALKER_ACCEPTANCE:.0%} of their "
                        "moves (stuck): use more --walkers and --steps")
    return {
        "converged": not problems, "problems": problems,
        "walkers": int(walkers), "steps": int(chain.samples.shape[0]), "burn_in": int(chain.burn),
        "kept_draws": int(n_kept * walkers),
        "acceptance_fraction": {"mean": mean_acceptance, "min": float(np.min(acceptance)),
                                "max": float(np.max(acceptance))},
        "autocorrelation_time": dict(zip(chain.labels, tau.tolist())),
        "steps_per_tau": n_kept / tau_max if tau_max > 0 else None,
        "effective_draws": dict(zip(chain.labels, (n_kept * walkers / tau).tolist())),
        "split_rhat": dict(zip(chain.labels, rhat.tolist())),
        "rules": {"min_steps_per_tau": MIN_TAU_MULTIPLE, "max_split_rhat": MAX_RHAT,
                  "acceptance": [MIN_ACCEPTANCE, MAX_ACCEPTANCE], "min_walker_acceptance": MIN_WALKER_ACCEPTANCE},
    }
