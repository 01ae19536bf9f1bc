"""The rare-event algorithms (issue 46) against closed-form limit states (tests/reliability_problems.py).

Fast tests: one or a few seeds on small problems, with tolerances of several standard deviations of the
estimator (so that they fail on a wrong algorithm, not on an unlucky seed; each seed is fixed, so they are
deterministic). Slow tests (-m slow): the issue's acceptance numbers over 20 seeds.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import special

from uqflight.designs.rare.active import active_learning
from uqflight.designs.rare.estimate import (Evaluations, RareEventEstimate, importance_shares, lognormal_interval,
                                            zero_count_upper)
from uqflight.designs.rare.importance import KernelMixture, importance_sampling
from uqflight.designs.rare.subset import chain_correlation, subset_simulation

sys.path.insert(0, str(Path(__file__).parent))
from reliability_problems import PROBLEMS, repeat  # noqa: E402


class Recorder:
    """An evaluate that records every batch it is given (bit for bit) and its answers."""

    def __init__(self, margin):
        self.margin = margin
        self.batches: list[np.ndarray] = []
        self.answers: list[np.ndarray] = []

    def __call__(self, u):
        self.batches.append(u.copy())
        self.answers.append(np.asarray(self.margin(u), dtype=float))
        return self.answers[-1]


def linear_margin(beta, dimension):
    """g = Σu/√d − β: exact P = Φ(−β)."""
    return lambda u: u.sum(axis=1) / np.sqrt(dimension) - beta


# ---------------------------------------------------------------- estimate.py

def test_beta_is_the_reliability_index():
    estimate = RareEventEstimate("subset_simulation", float(special.ndtr(-3.0)), 0.0, 1.0, 0.1, 10, 0, None, (),
                                 "converged", ())
    assert estimate.beta == pytest.approx(3.0, rel=1e-12)
    assert RareEventEstimate("subset_simulation", 0.0, 0.0, 1e-3, np.nan, 10, 0, None, (), "budget",
                             ()).beta == np.inf


def test_importance_shares_sum_to_one():
    shares = importance_shares(np.array([3.0, -4.0, 0.0]))
    np.testing.assert_allclose(shares, [0.36, 0.64, 0.0], rtol=1e-15)
    with pytest.raises(ValueError):
        importance_shares(np.zeros(2))


def test_lognormal_interval_has_the_lognormal_quantiles():
    # the log-normal law of mean p and c.o.v. 1 has σ² = ln 2; the interval is p exp(±1.96 σ)
    lower, upper = lognormal_interval(1e-5, 1.0)
    sigma = np.sqrt(np.log(2.0))
    assert lower == pytest.approx(1e-5 * np.exp(-1.959964 * sigma), rel=1e-6)
    assert upper == pytest.approx(1e-5 * np.exp(1.959964 * sigma), rel=1e-6)
    assert lognormal_interval(1e-5, np.nan) == (0.0, 1.0)


def test_zero_count_upper_is_clopper_pearson():
    # 0 of n: 1 − 0.025^(1/n), about 3.69/n
    assert zero_count_upper(1000) == pytest.approx(1 - 0.025 ** (1 / 1000), rel=1e-12)
    assert zero_count_upper(1000) == pytest.approx(3.689 / 1000, rel=2e-3)
    assert zero_count_upper(1000, largest_weight=20.0) == pytest.approx(20 * (1 - 0.025 ** (1 / 1000)))
    assert zero_count_upper(0) == 1.0


def test_evaluations_count_failed_runs_and_keep_the_design_point():
    runs = Evaluations(lambda u: np.array([np.nan, 1.0, 2.0, -1.0]), 2, budget=6)
    g = runs(np.array([[0.0, 0.1], [3.0, 4.0], [1.0, 1.0], [0.0, 0.0]]))
    assert runs.failed == 1 and runs.runs == 4 and g[0] == -np.inf
    np.testing.assert_array_equal(runs.design_point, [1.0, 1.0])   # the failing point nearest the origin
    with pytest.raises(ValueError, match="budget"):
        runs(np.zeros((4, 2)))


def test_chain_correlation_of_independent_draws_is_zero_and_of_frozen_chains_is_large():
    indicator = np.array([True, False] * 50)
    singles = [np.array([i]) for i in range(100)]
    assert chain_correlation(indicator, singles, 0.5) == 0.0
    # 10 chains of 10 identical states: ρ_k = 1 at every lag, γ = 2 Σ_k (1 − k/10) = 9
    frozen = np.repeat([True, False], 50)
    chains = [np.arange(10 * c, 10 * c + 10) for c in range(10)]
    assert chain_correlation(frozen, chains, 0.5) == pytest.approx(9.0, rel=1e-12)


# ---------------------------------------------------------------- subset simulation

def test_subset_simulation_linear_1e_minus_4():
    # P = Φ(−3.719) = 1e-4 in 5 inputs: 4 levels of 1000 (3,700 runs). The estimator's c.o.v. is about
    # 0.3 here; a factor 2.5 either way is 3 standard deviations on the log scale.
    beta = float(-special.ndtri(1e-4))
    estimate = subset_simulation(linear_margin(beta, 5), 5, seed=3, budget=5000)
    assert estimate.stopped == "converged" and estimate.method == "subset_simulation"
    assert 1e-4 / 2.5 < estimate.probability < 1e-4 * 2.5
    assert estimate.lower < 1e-4 < estimate.upper
    # 1000 + 3 × 900 runs, a few more when a stuck chain's repeated sample ties at a threshold
    assert 3700 <= estimate.runs <= 3720 and estimate.rounds[-1].runs == estimate.runs
    assert 0.1 < estimate.cov < 0.6
    # the design point lies near the exact one, β/√5 (1, …, 1): its shares are about 1/5 each
    np.testing.assert_allclose(importance_shares(estimate.design_point), 0.2, atol=0.15)


def test_subset_simulation_budget_stop_is_an_honest_upper_bound():
    # 1e-9 cannot be reached with 3 levels: the estimate is 0 and the upper bound is that of P[level 2]
    beta = float(-special.ndtri(1e-9))
    estimate = subset_simulation(linear_margin(beta, 3), 3, seed=1, budget=3000)
    assert estimate.stopped == "budget" and estimate.probability == 0.0
    assert 1e-9 < estimate.upper < 0.1 and estimate.runs <= 3000
    assert any("upper bound" in note for note in estimate.notes)


def test_subset_simulation_four_branch():
    problem = PROBLEMS["four_branch"]
    estimate = subset_simulation(problem.margin, 2, seed=0, budget=12000)
    # c.o.v. about 0.2 (measured over 20 seeds): a factor 1.8 is 3 standard deviations
    assert problem.exact / 1.8 < estimate.probability < problem.exact * 1.8


# ---------------------------------------------------------------- importance sampling

def test_kernel_mixture_density_integrates_to_one_and_is_its_sampler():
    rng = np.random.default_rng(0)
    mixture = KernelMixture(rng.normal(2.0, 0.5, (30, 2)), rng.random(30), defensive=0.1)
    # E_h[φ/h] = 1 by Monte Carlo on 20,000 draws of h: its c.o.v. is below 0.01 here
    draws = mixture.sample(20000, rng)
    ratios = np.exp(-0.5 * (draws ** 2).sum(axis=1) - np.log(2 * np.pi) - mixture.logpdf(draws))
    assert ratios.mean() == pytest.approx(1.0, abs=0.03)
    assert ratios.max() <= 1.0 / 0.1 + 1e-9      # the defensive part bounds φ/h by 1/η


def test_importance_sampling_linear_1e_minus_5():
    # P = 1e-5 in 4 inputs with 2,500 runs: c.o.v. about 0.1; a factor 1.4 is over 3 standard deviations
    beta = float(-special.ndtri(1e-5))
    estimate = importance_sampling(linear_margin(beta, 4), 4, seed=2, budget=2500)
    assert estimate.method == "importance_sampling" and estimate.runs <= 2500
    assert 1e-5 / 1.4 < estimate.probability < 1e-5 * 1.4
    assert estimate.lower < 1e-5 < estimate.upper and estimate.cov < 0.2


def test_importance_sampling_keeps_the_seed_dimension_at_its_law():
    problem = PROBLEMS["seeded"]
    recorder = Recorder(problem.margin)
    estimate = importance_sampling(recorder, 2, seed=0, budget=5000, redrawn=(1,))
    # its own c.o.v. is 0.2 on this seed (a heavy weight in round 6): a factor 1.5 is 2 standard deviations
    assert problem.exact / 1.5 < estimate.probability < problem.exact * 1.5
    adapted = np.concatenate(recorder.batches[1:])
    # the adapted dimension moved to the event (u_1 near 3.5); the seed dimension stayed N(0, 1):
    # with 4,500 draws the mean's standard error is 0.015 and the standard deviation's 0.011
    assert adapted[:, 0].mean() > 2.5
    assert abs(adapted[:, 1].mean()) < 0.08 and abs(adapted[:, 1].std() - 1.0) < 0.06


def test_importance_sampling_budget_stop_is_an_honest_upper_bound():
    beta = float(-special.ndtri(1e-12))
    estimate = importance_sampling(linear_margin(beta, 3), 3, seed=0, budget=1000)
    assert estimate.stopped == "budget" and estimate.probability == 0.0
    assert 1e-12 < estimate.upper < 0.1
    assert any("upper bound" in note for note in estimate.notes)


# ---------------------------------------------------------------- active learning

@pytest.mark.slow
def test_active_learning_reaches_a_1e_minus_6_event_from_an_all_safe_first_design():
    # the false stop of AK-MCS: every point of the first design is safe (|u| <= 5.5 but the event is a
    # half-space at distance 4.75 in 7 dimensions); the trend and the enrichment still find it.
    # Over 20 seeds the c.o.v. is below 0.05 at about 300 runs: a factor 1.25 is 4 standard deviations.
    problem = PROBLEMS["linear"]
    recorder = Recorder(problem.margin)
    estimate = active_learning(recorder, 7, seed=0, budget=1000)
    assert (recorder.answers[0] <= 0).all()
    assert estimate.method == "active_learning" and estimate.runs <= 1000
    assert 1e-6 / 1.25 < estimate.probability < 1e-6 * 1.25
    assert estimate.lower < 1e-6 < estimate.upper


@pytest.mark.slow
def test_active_learning_never_answers_a_silent_zero():
    # an event that never happens: the estimate is 0, but with an upper bound above 0 and a note
    estimate = active_learning(lambda u: -1.0 - np.square(u).sum(axis=1), 2, seed=0, budget=200, batch=10,
                               learning=0.25, batch_is=50)
    assert estimate.probability == 0.0 and estimate.lower == 0.0
    # the learning rounds carry no estimate (nan); the fresh runs are those after the last of them
    draws = estimate.runs - max(r.runs for r in estimate.rounds if np.isnan(r.probability))
    assert estimate.upper == pytest.approx(10 * (1 - 0.025 ** (1 / draws)), rel=1e-12)
    assert any("no fresh run reached the event" in note for note in estimate.notes)


def test_active_learning_whose_runs_all_fail_stops_with_no_bound():
    estimate = active_learning(lambda u: np.full(u.shape[0], np.nan), 2, seed=0, budget=400)
    assert estimate.stopped == "stalled" and estimate.failed == estimate.runs == 20
    assert (estimate.probability, estimate.lower, estimate.upper) == (0.0, 0.0, 1.0)


# ---------------------------------------------------------------- determinism, resume, failed runs

SMALL = {
    # (algorithm, settings, event probability): small problems in 2 or 3 inputs, a few hundred runs
    "subset_simulation": (subset_simulation, dict(budget=1000, samples_per_level=200), 1e-3),
    "importance_sampling": (importance_sampling, dict(budget=600, samples=100), 1e-4),
    "active_learning": (active_learning, dict(budget=400), 1e-3),
}


def small_run(kind, margin_of=None, seed=0):
    algorithm, settings, probability = SMALL[kind]
    dimension = 2 if kind == "active_learning" else 3
    margin = linear_margin(float(-special.ndtri(probability)), dimension)
    recorder = Recorder(margin if margin_of is None else margin_of(margin))
    return algorithm(recorder, dimension, seed=seed, **settings), recorder


def assert_same_estimate(a, b):
    assert (a.probability, a.lower, a.upper, a.runs, a.failed, a.stopped, a.notes) == \
        (b.probability, b.lower, b.upper, b.runs, b.failed, b.stopped, b.notes)
    np.testing.assert_array_equal(a.cov, b.cov)
    np.testing.assert_array_equal(a.design_point, b.design_point)
    np.testing.assert_array_equal([(r.runs, r.probability, r.cov) for r in a.rounds],
                                  [(r.runs, r.probability, r.cov) for r in b.rounds])


@pytest.mark.slow
@pytest.mark.parametrize("kind", SMALL)
def test_same_seed_same_runs_and_estimate_bit_for_bit(kind):
    first, calls = small_run(kind)
    second, again = small_run(kind)
    assert len(calls.batches) == len(again.batches) > 1
    for a, b in zip(calls.batches, again.batches):
        np.testing.assert_array_equal(a, b)
    assert_same_estimate(first, second)
    assert first.probability > 0.0 and first.method == kind


@pytest.mark.slow
@pytest.mark.parametrize("kind", SMALL)
def test_replayed_values_resume_to_the_same_bits(kind):
    # the runner's resume: the algorithm runs again from the start, and the batches already flown are
    # answered from the store (here: the first half of the batches of an uninterrupted run)
    whole, calls = small_run(kind)
    stored = len(calls.batches) // 2

    def resumed(margin):
        answered = []

        def evaluate(u):
            if len(answered) < stored:
                np.testing.assert_array_equal(u, calls.batches[len(answered)])
                answered.append(calls.answers[len(answered)])
                return answered[-1].copy()
            return margin(u)
        return evaluate
    again, _ = small_run(kind, margin_of=resumed)
    assert_same_estimate(whole, again)


@pytest.mark.slow
@pytest.mark.parametrize("kind", SMALL)
def test_another_seed_gives_another_estimate(kind):
    assert small_run(kind, seed=0)[0].probability != small_run(kind, seed=1)[0].probability


@pytest.mark.slow
@pytest.mark.parametrize("kind", SMALL)
def test_failed_runs_are_counted_outside_the_event(kind):
    # about 1 run in 10 fails (NaN), chosen by a hash of the point: no crash, every one counted, a note
    def failing(margin):
        def evaluate(u):
            g = margin(u)
            return np.where(np.modf(1e3 * special.ndtr(u[:, 0]))[0] < 0.1, np.nan, g)
        return evaluate
    estimate, calls = small_run(kind, margin_of=failing)
    returned_nan = sum(int(np.isnan(a).sum()) for a in calls.answers)
    assert estimate.failed == returned_nan > 0
    assert np.isfinite(estimate.probability) and np.isfinite(estimate.upper)
    assert any("failed" in note for note in estimate.notes)


# ---------------------------------------------------------------- the acceptance numbers (slow)
# Each over seeds 0..19. The thresholds are the issue's; an empirical c.o.v. from 20 seeds has a relative
# standard error of about 16 %, so each setting was chosen with its measured c.o.v. well below the
# threshold (benchmarks/rare_events.py prints them). "Within a factor 2 with its defaults" is read as:
# the mean of the 20 estimates within a factor 2 of the exact value, and no estimate 0.

DEFAULT_BUDGETS = {subset_simulation: 12000, importance_sampling: 5000, active_learning: 1500}


@pytest.mark.slow
@pytest.mark.parametrize("name", ["linear", "four_branch"])
def test_active_learning_cov_and_bias_within_1000_runs(name):
    result = repeat(active_learning, PROBLEMS[name], budget=1000)
    assert result.runs.max() <= 1000 and (result.probabilities > 0).all()
    assert result.cov <= 0.10 and abs(result.bias) <= 0.10
    assert result.covered >= 16


@pytest.mark.slow
def test_importance_sampling_cov_within_4000_runs_on_linear():
    result = repeat(importance_sampling, PROBLEMS["linear"], budget=4000)
    assert result.runs.max() <= 4000 and result.cov <= 0.12 and result.covered >= 16


@pytest.mark.slow
def test_subset_simulation_cov_within_10000_runs_on_curved():
    # 1,800 samples a level: 1,800 + 5 × 1,620 = 9,900 runs for the 6 levels of 9.2e-6
    result = repeat(subset_simulation, PROBLEMS["curved"], budget=10000, samples_per_level=1800)
    assert result.runs.max() <= 10000 and result.cov <= 0.4 and result.covered >= 16


# Active learning on the seed problem spends its whole 1,500 runs refitting its process (about 10 minutes
# for the 20 seeds): its row is measured by benchmarks/rare_events.py (c.o.v. 0.36, 16 of 20 intervals
# cover), not flown at every CI run.
DEFAULT_CASES = [(algorithm, name) for name in PROBLEMS for algorithm in DEFAULT_BUDGETS
                 if (algorithm, name) != (active_learning, "seeded")]


@pytest.mark.slow
@pytest.mark.parametrize("algorithm, name", DEFAULT_CASES, ids=lambda a: getattr(a, "__name__", a))
def test_defaults_within_a_factor_2_and_intervals_cover(algorithm, name):
    result = repeat(algorithm, PROBLEMS[name], budget=DEFAULT_BUDGETS[algorithm])
    assert result.runs.max() <= DEFAULT_BUDGETS[algorithm] and (result.probabilities > 0).all()
    assert 0.5 <= result.probabilities.mean() / result.exact <= 2.0
    assert result.covered >= 16
