"""What the statistics are when runs failed, said once per method (methods.FAILED_RUNS) in the notes and
the report's Notes box: conditional on success, or a fit extrapolated over the failed region. The
model y = 1 + x1 + x2 fails where x1 + x2 > C, on 13 % of U(-1, 1)² (tests/data/failure_models.py)."""
import math

import h5py
import numpy as np
import pytest
from conftest import NORMAL_2D, cli_in_process, closed_form_campaign, run_python_campaign
from data.failure_models import C, P_FAIL, corner_campaign

from uqflight.methods import FAILED_RUNS, METHODS, MethodSpec
from uqflight.analysis.statistics import BadInput, analyse

# E[x1 + x2 | success] = −E[(x1 + x2) 1_fail] / 0.87, with x1 + x2 = u of density (2 − |u|)/4 on [−2, 2]:
# E[u 1_fail] = ∫_C^2 u (2 − u)/4 du = (4/3 − C² + C³/3)/4.
CONDITIONAL_MEAN = 1.0 - (4 / 3 - C**2 + C**3 / 3) / 4 / (1 - P_FAIL)


@pytest.fixture(scope="module")
def runs(flown):
    return {name: flown(corner_campaign(name, design), name)  # the Monte Carlo file: test_failure_probability.py's too
            for name, design in (("mc", "{kind: monte_carlo, samples: 1000}"),
                                 ("tensor", "{kind: tensor_grid, points: 6}"))}


def successful_y(path):
    with h5py.File(path) as f:
        return f["outputs/y"][:, 0][f["samples/status"][:] == 0]


def test_every_method_says_what_its_statistics_are_with_failed_runs():
    assert {entry.failed_runs for entry in METHODS.values()} <= set(FAILED_RUNS)
    assert METHODS["monte_carlo"].failed_runs == "conditional"
    assert METHODS["least_squares"].failed_runs == METHODS["regression"].failed_runs == "extrapolated"


def test_monte_carlo_statistics_are_conditional_on_success(runs):
    stats = analyse(runs["mc"], method=MethodSpec("monte_carlo"))
    y = successful_y(runs["mc"])
    out = stats.outputs["y"]
    assert out.mean[0] == pytest.approx(y.mean(), abs=1e-13)  # the successful runs' sample mean
    # ... which estimates the closed-form conditional mean: within 4 standard errors of the 878 runs
    assert abs(out.mean[0] - CONDITIONAL_MEAN) < 4 * y.std(ddof=1) / math.sqrt(y.size)
    assert stats.notes[0] == (f"statistics conditional on success: {stats.failed} of 1000 runs failed; they are "
                              f"those of the {y.size} successful runs alone, not of the whole input law")


@pytest.mark.parametrize("name", ["mc", "tensor"])
def test_a_fit_is_extrapolated_over_the_failed_region(runs, name):
    # y = 1 + x1 + x2 lies in the order-1 basis, so the fit on the successful runs is exact and its
    # moments are the whole box's: mean 1, variance 1/3 + 1/3 (to rounding, 1e-12).
    stats = analyse(runs[name], method=MethodSpec("least_squares", 1))
    out = stats.outputs["y"]
    assert out.mean[0] == pytest.approx(1.0, abs=1e-12) and out.variance[0] == pytest.approx(2 / 3, abs=1e-12)
    assert stats.notes[0].startswith(f"statistics of a fit extrapolated over the failed region: {stats.failed} of ")
    assert "least_squares fits its PCE on the" in stats.notes[0]


def test_a_projection_of_the_successful_runs_is_flagged_as_of_neither_law(runs):
    stats = analyse(runs["mc"], method=MethodSpec("pseudo_galerkin", 1))
    out, y = stats.outputs["y"], successful_y(runs["mc"])
    assert out.mean[0] == pytest.approx(y.mean(), abs=1e-13)  # c₀: the conditional mean
    # its variance Σ c_α² is neither the conditional (sample) variance nor the whole law's 2/3
    assert abs(out.variance[0] - y.var()) > 0.1 and abs(out.variance[0] - 2 / 3) > 0.1
    assert stats.notes[0].startswith("statistics of a projection of the successful runs, of neither law")


@pytest.mark.slow
def test_the_reports_notes_box_says_the_statistics_are_conditional(runs, tmp_path):
    # (the extrapolated fit's box: test_failure_probability.py, on the sparse grid)
    done = cli_in_process("report", runs["mc"], "--method", "monte_carlo", "--out", tmp_path / "r")
    assert done.returncode == 0, done.stderr
    page = (tmp_path / "r" / "report.md").read_text()
    notes = page[page.index('<a id="notes"></a>'):page.index('<a id="run"></a>')]
    assert "statistics conditional on success: " in notes, notes


@pytest.fixture(scope="module")
def grid(tmp_path_factory):
    """A complete 4 × 4 Gauss–Hermite grid of the quadratic, one corner failed."""
    folder = tmp_path_factory.mktemp("grid")
    return run_python_campaign(folder, closed_form_campaign("grid", "quadratic_failing_corner", NORMAL_2D,
                                                "{kind: tensor_grid, points: 4}",
                                                "method: {kind: pseudo_galerkin, order: 1}\n"))


def test_a_grid_with_a_failed_run_refuses_projections_and_fits_the_rest_exactly(grid, tmp_path):
    with pytest.raises(BadInput, match="1 of 16 runs are missing; use least_squares or regression"):
        analyse(grid)
    refused = cli_in_process("report", grid, "--out", tmp_path / "r")
    assert refused.returncode == 2 and "pseudo_galerkin" in refused.stderr and not (tmp_path / "r").exists()
    stats = analyse(grid, method=MethodSpec("least_squares", 2))
    out = stats.outputs["y"]
    # y = 1 + x1 + x1 x2 + x2² is in the order-2 basis, which the 15 remaining points still resolve
    assert out.mean[0] == pytest.approx(2.0, abs=1e-10) and out.variance[0] == pytest.approx(4.0, abs=1e-9)
    assert out.loo_error[0] == pytest.approx(0.0, abs=1e-20)
    # a tensor grid: the quadrature of the failure indicator, no interval (test_failure_probability.py)
    assert stats.failure_probability["estimate"] > 0 and np.isnan(stats.failure_probability["lower"])
    with pytest.raises(BadInput, match="rank"):
        analyse(grid, method=MethodSpec("regression", 4))
