"""A user's number is right, refused with a message that says what to do, or flagged: pending and
failed runs, method validity, resolution, undefined values, the reference's own noise."""
import json

import h5py
import numpy as np
import pytest
from conftest import DATA, cli_in_process, read_summary, run_python_campaign

from uqflight.check import write_baseline
from uqflight.statistics import BadInput, analyse, summary_json

MODELS = DATA / "trust_models.py"


def strict_json(data: dict) -> dict:
    """`data` through a strict JSON writer and reader, as summary.json is written and read."""
    return json.loads(json.dumps(data, allow_nan=False))


def campaign(name, function, parameters, design, method="", extra=""):
    return (f"name: {name}\nseed: 5\nsimulator: {{kind: python, function: \"{MODELS}:{function}\"}}\n"
            f"parameters:\n{parameters}design: {design}\n{method}{extra}"
            "analysis: {band_samples: 2000, bootstrap: 0}\n")


NORMAL_2D = ("  x1: {distribution: normal, lower: -3, upper: 3}\n"
             "  x2: {distribution: normal, lower: -3, upper: 3}\n")
UNIFORM_X = "  x: {distribution: uniform, lower: -1, upper: 1}\n"
NORMAL_X = "  x: {distribution: normal, lower: -3, upper: 3}\n"


def make_pending(path, runs):
    """What an interrupted run leaves: these runs not written yet."""
    with h5py.File(path, "r+") as f:
        f["samples/status"][runs] = -1
        for name in f["outputs"]:
            data = f["outputs"][name]
            data[runs] = np.full((len(runs), data.shape[1]), np.nan)  # h5py broadcasts no index list across chunks


@pytest.fixture(scope="module")
def grid(tmp_path_factory):
    """A complete 4 × 4 Gauss–Hermite grid of the quadratic, one corner failed."""
    folder = tmp_path_factory.mktemp("grid")
    return run_python_campaign(folder, campaign("grid", "quadratic_failing_corner", NORMAL_2D,
                                                "{kind: tensor_grid, points: 4}",
                                                "method: {kind: pseudo_galerkin, order: 1}\n"))


def test_pending_runs_refuse_report_and_check_with_the_resume_command(tmp_path):
    results = run_python_campaign(tmp_path, campaign("pend", "sum_of_squares", NORMAL_2D,
                                                     "{kind: tensor_grid, points: 4}",
                                                     "method: {kind: pseudo_galerkin, order: 2}\n"), "pend")
    baseline = write_baseline(analyse(results), "", tmp_path / "baseline.json")
    make_pending(results, [11, 12, 13, 14, 15])
    report = cli_in_process("report", results)
    assert report.returncode == 2
    message = report.stderr
    assert "5 of 16 runs are pending" in message, message
    assert f"uqflight run {tmp_path / 'pend.yaml'} --out {results}" in message
    assert not list(tmp_path.glob("*report*")), "a refused report must write nothing"
    checked = cli_in_process("check", results, "--baseline", baseline)
    assert checked.returncode == 2 and "pending" in checked.stderr
    partial = cli_in_process("report", results, "--partial", "--out", tmp_path / "r")
    assert partial.returncode == 2 and "needs every run of the grid" in partial.stderr
    assert not (tmp_path / "r").exists()


def test_partial_monte_carlo_is_reported_on_its_completed_runs_and_labelled(tmp_path):
    results = run_python_campaign(tmp_path, campaign("mc", "identity", UNIFORM_X, "{kind: monte_carlo, samples: 100}"))
    with h5py.File(results) as f:
        y = f["outputs/y"][:, 0]
    make_pending(results, np.arange(60, 100))
    done = cli_in_process("report", results, "--partial", "--out", tmp_path / "r")
    assert done.returncode == 0, done.stderr
    summary = read_summary(tmp_path / "r" / "summary.json")
    assert summary["partial"] is True and (summary["completed"], summary["pending"]) == (60, 40)
    assert "partial: 60 of 100 runs" in summary["notes"]
    assert summary["outputs"]["y"]["mean"][0] == pytest.approx(y[:60].mean(), abs=1e-15)
    assert "partial: 60 of 100 runs" in (tmp_path / "r" / "report.html").read_text()


def test_the_failure_probability_interval_contains_the_true_fraction(tmp_path):
    results = run_python_campaign(tmp_path, campaign("fail", "fails_above", UNIFORM_X,
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


def test_a_grid_with_a_failed_run_refuses_projections_and_fits_the_rest_exactly(grid, tmp_path):
    with pytest.raises(BadInput, match="1 of 16 runs are missing; use least_squares or regression"):
        analyse(grid)
    refused = cli_in_process("report", grid, "--out", tmp_path / "r")
    assert refused.returncode == 2 and "pseudo_galerkin" in refused.stderr and not (tmp_path / "r").exists()
    stats = analyse(grid, method={"kind": "least_squares", "order": 2})
    out = stats.outputs["y"]
    # y = 1 + x1 + x1 x2 + x2² is in the order-2 basis, which the 15 remaining points still resolve
    assert out.mean[0] == pytest.approx(2.0, abs=1e-10) and out.variance[0] == pytest.approx(4.0, abs=1e-9)
    assert out.loo_error[0] == pytest.approx(0.0, abs=1e-20)
    # a tensor grid: the quadrature of the failure indicator, no interval (test_failure_probability.py)
    assert stats.failure_probability["estimate"] > 0 and np.isnan(stats.failure_probability["lower"])
    with pytest.raises(BadInput, match="rank"):
        analyse(grid, method={"kind": "regression", "order": 4})


def test_plan_refuses_a_projection_the_grid_cannot_integrate(tmp_path):
    text = campaign("alias", "sum_of_squares", NORMAL_2D, "{kind: sparse_grid, level: 1}",
                    "method: {kind: pseudo_galerkin, order: 2}\n")
    (tmp_path / "a.yaml").write_text(text)
    plan = cli_in_process("plan", tmp_path / "a.yaml")
    assert plan.returncode == 2
    assert "method.order" in plan.stderr and "exact to degree 3" in plan.stderr
    assert "largest order it can project is 1" in plan.stderr
    (tmp_path / "b.yaml").write_text(text.replace("order: 2}", "order: 2, allow_aliasing: true}"))
    assert cli_in_process("plan", tmp_path / "b.yaml").returncode == 0


def test_report_refuses_an_aliased_order_unless_allowed(grid, tmp_path):
    results = run_python_campaign(tmp_path, campaign("l1", "sum_of_squares", NORMAL_2D,
                                                     "{kind: sparse_grid, level: 1}"))
    refused = cli_in_process("report", results, "--method", "pseudo_galerkin", "--order", "4", "--out", tmp_path / "r")
    assert refused.returncode == 2 and "exact to degree 3" in refused.stderr
    allowed = analyse(results, method={"kind": "pseudo_galerkin", "order": 4}, allow_aliasing=True)
    assert any("aliasing allowed" in note for note in allowed.notes)


def test_plan_refuses_a_rank_deficient_least_squares_fit(tmp_path):
    uniform = "".join(f"  x{i}: {{distribution: uniform, lower: -1, upper: 1}}\n" for i in (1, 2, 3))
    (tmp_path / "r.yaml").write_text(campaign("rank", "sum_of_squares", uniform,
                                              "{kind: sparse_grid, level: 2, rule: gauss_legendre}",
                                              "method: {kind: least_squares, order: 3}\n"))
    plan = cli_in_process("plan", tmp_path / "r.yaml")
    assert plan.returncode == 2 and "rank 19" in plan.stderr and "method.order" in plan.stderr


def test_sobol_indices_are_null_where_the_variance_is_rounding_noise(tmp_path):
    results = run_python_campaign(tmp_path, campaign("sq", "sum_of_squares", NORMAL_2D,
                                                     "{kind: tensor_grid, points: 4}",
                                                     "method: {kind: pseudo_galerkin, order: 2}\n"))
    y = strict_json(summary_json(analyse(results)))["outputs"]["y"]
    assert y["resolved"] == [False, True, True, True, True]
    for parameter in ("x1", "x2"):
        assert y["sobol_first"][parameter][0] is None and y["sobol_total"][parameter][0] is None
        np.testing.assert_allclose(y["sobol_first"][parameter][1:], 0.5, atol=1e-12)


def test_a_zero_mean_is_reported_without_a_crash_and_its_cov_is_null(tmp_path):
    results = run_python_campaign(tmp_path, campaign("id", "identity", NORMAL_X, "{kind: tensor_grid, points: 5}",
                                                     "method: {kind: pseudo_galerkin, order: 1}\n"))
    done = cli_in_process("report", results, "--out", tmp_path / "r")
    assert done.returncode == 0, done.stderr
    y = read_summary(tmp_path / "r" / "summary.json")["outputs"]["y"]
    assert abs(y["mean"][0]) < 1e-15 and y["variance"][0] == pytest.approx(1.0)
    assert y["cov"] == [None] and y["sobol_first"]["x"] == [pytest.approx(1.0)]


def exact_grid_errors_against(tmp_path, reference_design: str, tag: str):
    """(errors of an exact PG grid on sum_of_squares against a reference of that design, the reference's
    runs): what is left of the errors is the reference's own noise."""
    reference = run_python_campaign(tmp_path, campaign(tag, "sum_of_squares", NORMAL_2D, reference_design), tag)
    grid = run_python_campaign(tmp_path, campaign("pg", "sum_of_squares", NORMAL_2D, "{kind: tensor_grid, points: 4}",
                                                  "method: {kind: pseudo_galerkin, order: 2}\n"), "pg")
    errors = analyse(grid, reference=str(reference)).outputs["y"].errors
    with h5py.File(reference) as f:
        return errors, f["outputs/y"][()]


def test_errors_carry_the_reference_noise_floor(tmp_path):
    errors, Y = exact_grid_errors_against(tmp_path, "{kind: monte_carlo, samples: 400}", "ref")
    # σ/√N of the reference's mean and the distribution-free standard error of its variance,
    # √((μ4 − (N−3)/(N−1) σ⁴)/N), in Eq. 49's normalisation, recomputed here from the runs
    n, variance = len(Y), Y.var(axis=0, ddof=1)
    fourth = ((Y - Y.mean(axis=0)) ** 4).mean(axis=0)
    np.testing.assert_allclose(errors["eps_m_floor"], np.sqrt(variance / n) / Y.mean(axis=0).max(), rtol=1e-12)
    se_variance = np.sqrt((fourth - (n - 3) / (n - 1) * variance**2) / n)
    np.testing.assert_allclose(errors["eps_v_floor"][1:], se_variance[1:] / variance.max(), rtol=1e-9)
    assert errors["kld_floor"] > 0 and "400 monte_carlo runs" in errors["floor_note"]
    assert np.max(errors["eps_m"]) < 3 * np.max(errors["eps_m_floor"])  # the grid is exact: only noise is left


def test_a_randomised_qmc_reference_takes_its_floor_from_the_replicates(tmp_path):
    errors, runs = exact_grid_errors_against(tmp_path, "{kind: sobol, samples: 64, replicates: 8}", "rqmc")
    Y = runs.reshape(8, 64, -1)
    means = Y.mean(axis=1)
    np.testing.assert_allclose(errors["eps_m_floor"], means.std(axis=0, ddof=1) / np.sqrt(8) / means.mean(axis=0).max(),
                               rtol=1e-9)
    assert "8 replicates" in errors["floor_note"]
    # scrambled Sobol' points resolve this smooth mean better than as many random draws would (σ/√512,
    # σ = 2 at t = 1); measured 0.32 of it, and 8 replicates estimate the spread to ~25 %: below 0.6
    assert np.max(errors["eps_m_floor"]) < 0.6 * np.sqrt(4 / 512) / 15001
