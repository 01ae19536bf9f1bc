"""Pending runs (what an interrupted campaign leaves): `report` and `check` refuse them naming the command
that resumes the campaign, and `report --partial` reports a sampled design on its completed runs, labelled."""
import h5py
import numpy as np
import pytest
from conftest import NORMAL_2D, UNIFORM_X, cli_in_process, closed_form_campaign, read_summary, run_python_campaign

from uqflight.analysis.check import write_baseline
from uqflight.analysis.statistics import analyse


def make_pending(path, runs):
    """What an interrupted run leaves: these runs not written yet."""
    with h5py.File(path, "r+") as f:
        f["samples/status"][runs] = -1
        for name in f["outputs"]:
            data = f["outputs"][name]
            data[runs] = np.full((len(runs), data.shape[1]), np.nan)  # h5py broadcasts no index list across chunks


def test_pending_runs_refuse_report_and_check_with_the_resume_command(tmp_path):
    results = run_python_campaign(tmp_path, closed_form_campaign("pend", "sum_of_squares", NORMAL_2D,
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


@pytest.mark.slow
def test_partial_monte_carlo_is_reported_on_its_completed_runs_and_labelled(tmp_path):
    results = run_python_campaign(tmp_path, closed_form_campaign("mc", "identity", UNIFORM_X, "{kind: monte_carlo, samples: 100}"))
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
