"""Off a terminal, `report`, `surrogate export` and `calibrate` log their stages and percentages on
stderr (uqflight.running.progress, the mechanism `run` uses): real processes, stderr a pipe."""
import io
import json
import re

import numpy as np
import pytest
from conftest import cli, run_python_campaign

from uqflight.calibration.size import MAX_STEPS
from uqflight.running.runner import Progress

MODEL = """
import numpy as np
T = np.linspace(0.0, 1.0, 11)
def f(p):
    return {"time": T, "y": p["a"] + p["b"] * T}
"""
CAMPAIGN = """
name: progress
seed: 1
simulator: {kind: python, function: "model.py:f"}
parameters:
  a: {distribution: normal, nominal: 1.0, interval_pct: 30}
  b: {distribution: normal, nominal: -0.5, interval_pct: 30}
design: {kind: tensor_grid, points: 3}
method: {kind: pseudo_galerkin, order: 1}
"""
PERCENT = re.compile(r"\d+/\d+ \w+ \(\d+ %\)")


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    folder = tmp_path_factory.mktemp("progress")
    (folder / "model.py").write_text(MODEL)
    return run_python_campaign(folder, CAMPAIGN, "progress")


def logged(stderr: str, label: str) -> list[str]:
    return [line for line in stderr.splitlines() if line.startswith(f"{label}: ")]


@pytest.mark.slow  # a long real-process check; the slow suite runs it in CI
def test_report_and_export_log_their_stages_with_percentages(results, tmp_path):
    report = cli("report", results, "--out", tmp_path / "report")
    assert report.returncode == 0, report.stderr
    lines = logged(report.stderr, "report")
    assert any(line.startswith("report: analysing") and PERCENT.search(line) and "(100 %)" in line for line in lines)
    assert any(line.startswith("report: drawing") and PERCENT.search(line) for line in lines)
    assert "report: writing the page" in lines and "\x1b" not in report.stderr  # no terminal codes in a log
    export = cli("surrogate", "export", results, "--out", tmp_path / "pce.json")
    assert export.returncode == 0, export.stderr
    assert any("(100 %)" in line for line in logged(export.stderr, "surrogate export"))


@pytest.mark.slow
def test_calibrate_logs_the_sampler_steps(results, tmp_path):
    rng = np.random.default_rng(0)
    time = np.linspace(0.0, 1.0, 11)
    values = 1.1 - 0.45 * time + 0.05 * rng.standard_normal(time.size)
    data = tmp_path / "flight.csv"
    data.write_text("time_s,y\n" + "".join(f"{t:g},{float(v)!r}\n" for t, v in zip(time, values)))
    run = cli("calibrate", results, "--data", data, "--out", tmp_path / "cal", "--noise", "y=0.05",
              "--steps", "400", "--predictive-draws", "2")
    assert run.returncode in (0, 3), run.stderr  # 3: not converged in 400 steps; the stages are logged either way
    lines = logged(run.stderr, "calibrate")
    assert any(line.startswith("calibrate: sampling the posterior") and "(100 %)" in line for line in lines)
    assert lines[0].startswith("calibrate: fitting the surrogate")


@pytest.mark.slow
def test_calibrate_says_where_an_adaptive_chain_converged(results, tmp_path):
    rng = np.random.default_rng(1)
    time = np.linspace(0.0, 1.0, 11)
    data = tmp_path / "flight.csv"
    data.write_text("time_s,y\n" + "".join(f"{t:g},{float(1.1 - 0.45 * t + 0.05 * rng.standard_normal())!r}\n" for t in time))
    run = cli("calibrate", results, "--data", data, "--out", tmp_path / "cal", "--noise", "y=0.05",
              "--predictive-draws", "2")
    assert run.returncode == 0, run.stderr
    steps = json.loads((tmp_path / "cal" / "summary.json").read_text())["diagnostics"]["steps"]
    assert steps < MAX_STEPS
    lines = logged(run.stderr, "calibrate")
    assert any("until converged, at most 6000 steps" in line for line in lines)
    assert any(f"converged at {steps} steps" in line and "(100 %)" in line for line in lines), lines


def test_the_progress_counts_resumed_runs_and_fits_the_terminal(monkeypatch):
    monkeypatch.setenv("COLUMNS", "60")  # a terminal of 60 columns
    buffer = io.StringIO()
    buffer.isatty = lambda: True
    progress = Progress(100, done=40, stream=buffer)
    progress.advance(10)
    progress.close()
    screen = buffer.getvalue()
    assert "50/100" in screen and "runs/s" in screen
    assert max(len(line) for line in re.sub(r"\x1b\[[0-9;?]*[A-Za-z]", "", screen).splitlines()) <= 60
