"""Probabilities from a sampled design's runs (analysis.proportions): each interval covers the true
probability as often as it says, for how the design drew its points, or there is none.

The event: ξ1² + ξ2² < 1/2 for uniform germs on [-1, 1]^d, probability π/8 exactly (a disk of area π/2
in a square of area 4; curved, so that no QMC net stratifies it exactly). Coverage over 300 independent designs is a binomial mean with s.d. 0.0126 at
0.95: the bounds below are 3 s.d. either side."""
import numpy as np
import pytest

from uqflight.analysis.failures import wilson_interval
from uqflight.analysis.proportions import Independent, Net
from uqflight.designs import REGISTRY, build_design

TRUE = np.pi / 8
SEEDS = range(300)


def _found(spec: dict, d: int, seed: int) -> tuple[dict, np.ndarray]:
    design = build_design(spec, ["uniform"] * d, seed)
    hits = design.xi[:, 0] ** 2 + design.xi[:, 1] ** 2 < 0.5
    return REGISTRY[spec["kind"]].sampling.proportion(hits, np.ones(hits.size, bool), design.info), hits


def _coverage(spec: dict, d: int) -> float:
    covered = []
    for seed in SEEDS:
        found, _ = _found(spec, d, seed)
        covered.append(found["lower"] <= TRUE <= found["upper"])
    return float(np.mean(covered))


def test_pick_freeze_counts_its_independent_rows_only_and_then_covers():
    spec = {"kind": "pick_freeze", "samples": 64}
    found, hits = _found(spec, 4, 0)
    assert found["n_effective"] == 128 and "rows A and B" in found["sentence"]  # not the 384 rows
    assert found["estimate"] == hits[:128].mean()
    assert _coverage(spec, 4) >= 0.912  # A and B are scrambled Sobol' points: conservative


def test_independent_draws_get_the_wilson_interval_that_covers():
    assert 0.912 <= _coverage({"kind": "monte_carlo", "samples": 128}, 3) <= 0.988


@pytest.mark.slow
def test_randomised_qmc_replicates_give_an_interval_that_covers():
    # the hull of the pooled Wilson interval and the replicates' Student-t: at p = π/8 over 512 points the
    # Wilson interval of independent draws is wider than the scrambled nets' own error, so it covers more
    # than 0.95 (conservative); benchmarks/rqmc_interval_coverage.py measures it at a few exceedances
    spec = {"kind": "sobol", "samples": 64, "replicates": 8}
    found, hits = _found(spec, 3, 1)
    assert found["method"] == "replicates"
    assert found["estimate"] == pytest.approx(np.mean([hits[r * 64:(r + 1) * 64].mean() for r in range(8)]))
    wilson = wilson_interval(hits.mean(), hits.size)
    assert found["lower"] <= wilson[0] and found["upper"] >= wilson[1]
    assert _coverage(spec, 3) >= 0.912


@pytest.mark.slow
def test_randomised_qmc_covers_at_a_few_exceedances():
    # the disk of probability 6/512 (six exceedances expected over 8 replicates of 64 points): the
    # replicates' Student-t interval alone covers 0.93-0.96 there (benchmarks/rqmc_interval_coverage.py);
    # the reported hull must cover >= 0.95 over these 300 seeds (it gave 0.97-0.99 in the benchmark)
    radius = np.sqrt(4 * 6 / 512 / np.pi)
    covered = []
    for seed in SEEDS:
        design = build_design({"kind": "sobol", "samples": 64, "replicates": 8}, ["uniform"] * 3, seed)
        hits = design.xi[:, 0] ** 2 + design.xi[:, 1] ** 2 < radius**2
        found = Net().proportion(hits, np.ones(hits.size, bool), design.info)
        covered.append(found["lower"] <= 6 / 512 <= found["upper"])
    assert np.mean(covered) >= 0.95


def test_a_latin_hypercube_gets_the_conservative_wilson_interval_of_n_minus_one_draws():
    spec = {"kind": "latin_hypercube", "samples": 128}
    found, _ = _found(spec, 3, 2)
    assert found["n_effective"] == 127 and found["method"] == "wilson"
    assert _coverage(spec, 3) >= 0.912


def test_one_scrambled_net_is_flagged_and_fixed_points_get_no_interval():
    found, _ = _found({"kind": "sobol", "samples": 128}, 3, 3)
    assert found["method"] == "wilson" and "design.replicates" in found["sentence"]
    found, hits = _found({"kind": "sobol", "samples": 128, "scramble": False}, 3, 3)
    assert (found["lower"], found["upper"], found["method"]) == (None, None, "points")
    assert found["estimate"] == hits.mean()


def test_replicates_that_all_agree_get_the_pooled_wilson_interval():
    # no exceedance in any of 4 replicates: their spread is 0, the pooled runs' Wilson interval remains
    hits, counted = np.zeros(32, bool), np.ones(32, bool)
    found = Net().proportion(hits, counted, {"replicates": 4, "scramble": True})
    assert found["estimate"] == 0.0 and (found["lower"], found["upper"]) == wilson_interval(0.0, 32)
    assert "Wilson" in found["sentence"]


def test_only_counted_runs_count():
    hits = np.array([True, True, False, False])
    found = Independent().proportion(hits, np.array([True, False, True, True]), {})
    assert found["estimate"] == pytest.approx(1 / 3) and found["n_effective"] == 3
