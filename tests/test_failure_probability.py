"""The failure probability of a grid: no interval (its nodes are not random draws), and no estimate at
all from signed weights; Kish's effective number of runs. The model fails on exactly 13 % of its box
(tests/data/failure_models.py), run by real worker processes into real HDF5 files."""
import math

import h5py
import numpy as np
import pytest
from conftest import UNIFORM_X, cli_in_process, closed_form_campaign, read_summary, run_python_campaign
from data.failure_models import C, P_FAIL, corner_campaign

from uqflight.analysis.failures import grid_failure_probability, kish_effective_runs
from uqflight.designs import build_design
from uqflight.analysis.statistics import analyse, summary_json
from uqflight.methods import MethodSpec


@pytest.fixture(scope="module")
def runs(flown):
    return {name: flown(corner_campaign(name, design), name)  # the Monte Carlo file: test_failed_runs.py's too
            for name, design in (("sparse", "{kind: sparse_grid, level: 5}"),
                                 ("tensor", "{kind: tensor_grid, points: 10}"),
                                 ("mc", "{kind: monte_carlo, samples: 1000}"))}


def test_the_model_fails_on_13_percent_of_its_box():
    # The triangle x1 + x2 > C of U(-1, 1)² has legs 2 − C: probability (2 − C)² / 8, to rounding.
    assert (2 - C) ** 2 / 8 == pytest.approx(P_FAIL, rel=1e-14)


def test_a_sparse_grid_with_negative_weights_reports_no_probability(runs):
    # The case: level 5 in 2-D, 89 runs, 33 negative weights. The weighted failed fraction is
    # far from 0.13 (0.38 here) and no probability: it must not be reported as one.
    with h5py.File(runs["sparse"]) as f:
        weights, status = f["samples/weight"][:], f["samples/status"][:]
    failed = status > 0
    assert (len(weights), int((weights < 0).sum())) == (89, 33) and failed.any()
    raw = weights[failed].sum() / weights.sum()
    assert abs(raw - P_FAIL) > 0.2  # what the weighted fraction with an interval used to report
    stats = analyse(runs["sparse"])
    p = stats.failure_probability
    assert all(math.isnan(p[key]) for key in ("estimate", "lower", "upper"))
    assert "33 of the grid's 89 weights are negative" in p["method"] and "sampled design" in p["method"]
    # Kish's (Σw)²/Σw² (Σw = 1 here): the grid is worth less than one random draw
    assert p["n_effective"] == pytest.approx(weights.sum() ** 2 / np.square(weights).sum(), rel=1e-12)
    assert p["n_effective"] < 1
    assert "failure probability: not estimated from a grid with negative weights; a sampled design is needed" \
        in stats.notes
    summary = summary_json(stats)["failure_probability"]
    assert (summary["estimate"], summary["lower"], summary["upper"]) == (None, None, None)


def test_a_tensor_grid_reports_its_quadrature_of_the_indicator_without_an_interval(runs):
    # Closed form of the estimate: the Gauss–Legendre product rule's weight on the failing nodes,
    # from numpy's nodes and weights (w/2 per dimension for U(-1, 1)); 1e-12: sums of 100 weights.
    nodes, weights = np.polynomial.legendre.leggauss(10)
    x1, x2 = np.meshgrid(nodes, nodes, indexing="ij")
    expected = (np.outer(weights, weights) / 4)[x1 + x2 > C].sum()
    stats = analyse(runs["tensor"])
    p = stats.failure_probability
    assert p["estimate"] == pytest.approx(expected, abs=1e-12)
    assert math.isnan(p["lower"]) and math.isnan(p["upper"])
    assert "without an interval" in p["method"] and "not random draws" in p["method"]
    assert f"failure probability: {expected:.3g}, the grid's quadrature" in " ".join(stats.notes)
    summary = summary_json(stats)["failure_probability"]
    assert summary["estimate"] == pytest.approx(expected, abs=1e-12)
    assert (summary["lower"], summary["upper"]) == (None, None)


def test_a_monte_carlo_design_keeps_its_wilson_interval(runs):
    stats = analyse(runs["mc"], method=MethodSpec("monte_carlo"))
    p = stats.failure_probability
    assert p["estimate"] == stats.failed / 1000 and p["n_effective"] == 1000.0
    assert p["lower"] <= P_FAIL <= p["upper"] and "Wilson" in p["method"]


@pytest.mark.slow
def test_the_report_says_a_sparse_grid_estimates_no_failure_probability(runs, tmp_path):
    done = cli_in_process("report", runs["sparse"], "--out", tmp_path / "r")
    assert done.returncode == 0, done.stderr
    summary = read_summary(tmp_path / "r" / "summary.json")  # strict JSON: null, not NaN
    assert summary["failure_probability"]["estimate"] is None
    page = (tmp_path / "r" / "report.md").read_text()
    assert "failure probability not estimated (11 of 89 grid runs failed" in page
    notes = page[page.index('<a id="notes"></a>'):page.index('<a id="run"></a>')]
    assert "statistics of a fit extrapolated over the failed region: 11 of 89 runs failed" in notes, notes


def test_grid_estimate_with_positive_weights_is_the_weighted_failed_fraction():
    failed = np.array([True, False, False, True])
    p = grid_failure_probability(failed, np.array([0.1, 0.2, 0.3, 0.4]))
    assert p["estimate"] == pytest.approx(0.5, rel=1e-15)
    assert p["n_effective"] == pytest.approx(1 / 0.3, rel=1e-14)  # (Σw)²/Σw² = 1/0.30
    assert math.isnan(p["lower"]) and math.isnan(p["upper"])
    scaled = grid_failure_probability(failed, 7 * np.array([0.1, 0.2, 0.3, 0.4]))
    assert scaled["estimate"] == pytest.approx(0.5, rel=1e-15)  # the weights' scale does not matter


def test_signed_weights_give_no_estimate_even_without_failures():
    design = build_design({"kind": "sparse_grid", "level": 2}, ["uniform"] * 3, 0)
    assert (design.weights < 0).any()
    p = grid_failure_probability(np.zeros(len(design.weights), dtype=bool), design.weights)
    assert math.isnan(p["estimate"]) and p["method"].startswith("0 of ")


def test_kish_effective_runs_closed_forms():
    assert kish_effective_runs(np.full(17, 0.3)) == pytest.approx(17, rel=1e-14)
    assert kish_effective_runs([1.0, 1.0, 2.0, 2.0]) == pytest.approx(36 / 10, rel=1e-14)
    # signed weights: (Σw)² not (Σ|w|)²
    assert kish_effective_runs([2.0, -1.0]) == pytest.approx(1 / 5, rel=1e-14)


def test_grid_inputs_are_checked():
    with pytest.raises(ValueError, match="sum"):
        grid_failure_probability(np.array([True, False]), np.array([1.0, -1.0]))
    with pytest.raises(ValueError, match="expected \\(3,\\)"):
        grid_failure_probability(np.array([True, False, False]), np.ones(4))


def test_the_failure_probability_interval_contains_the_true_fraction(tmp_path):
    results = run_python_campaign(tmp_path, closed_form_campaign("fail", "fails_above", UNIFORM_X,
                                                     "{kind: monte_carlo, samples: 400}"))
    stats = analyse(results)
    p = stats.failure_probability
    assert p["lower"] <= 0.2 <= p["upper"] and "Wilson" in p["method"]
    assert stats.failed == len(stats.failures) and stats.completed + stats.failed == 400
    assert all(f["parameters"]["x"] > 0.6 and f["reason"] for f in stats.failures)
    assert any("conditional on success" in note for note in stats.notes)
    summary = summary_json(stats)
    assert summary["failed"] == stats.failed and summary["failure_probability"]["estimate"] == pytest.approx(
        stats.failed / 400)
