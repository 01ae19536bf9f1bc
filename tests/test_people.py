"""The CLI and report for people (issue 14): --version, -h, units in --help, the report's default
folder and its temp-dir-then-move, repeatable --method, `design --csv`, `surrogate export`, --restart,
`check` against another campaign, "did you mean", the progress bar."""
import csv
import io
import json
import re
from pathlib import Path

import h5py
import numpy as np
import pytest

import uqflight
from conftest import cli, cli_in_process
from uqflight.campaign import parse_campaign
from uqflight.check import write_baseline
from uqflight.execution import Progress, run_campaign
from uqflight.methods.basis import orthonormal_basis
from uqflight.report import write_report
from uqflight.statistics import analyse
from uqflight.surrogate import fit_surrogate, load


DECAY = """
name: decay-people
seed: 3
simulator: {kind: python, function: "uqflight.simulators.models:exp_decay"}
parameters:
  a: {distribution: normal, lower: 0.5, upper: 1.5}
  b: {distribution: uniform, lower: 1.0, upper: 2.0, nominal: 1.4}
design: {kind: sparse_grid, level: 3}
method: {kind: pseudo_galerkin, order: 2}
analysis: {band_samples: 500, bootstrap: 0}
"""



@pytest.fixture(scope="module")
def results(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("people")
    (root / "decay.yaml").write_text(DECAY)
    path = root / "decay.h5"
    run_campaign(parse_campaign(DECAY, str(root / "decay.yaml")), out=path, workers=1)
    return path


def test_version_and_short_help():
    result = cli("--version")
    assert result.returncode == 0 and result.stdout.strip() == f"uqflight {uqflight.__version__}"
    short, long = cli_in_process("-h"), cli_in_process("--help")
    assert short.returncode == 0 and short.stdout == long.stdout and "-h, --help" in short.stdout
    for command in ("report", "design", "simulate", "calibrate", "aircraft"):
        assert cli_in_process(command, "-h").returncode == 0
    assert "surrogate" in short.stdout and "design" in short.stdout


def test_units_are_visible_in_simulate_help():
    text = " ".join(cli_in_process("simulate", "--help").stdout.split())
    for unit in ("altitude [ft]", "airspeed [kt]", "amplitude [deg]", "start [s]", "[Hz]"):
        assert unit in text, (unit, text)


def test_report_writes_next_to_the_results_file_by_default(results):
    result = cli_in_process("report", results)
    assert result.returncode == 0, result.stderr
    out = results.with_name("decay-report")
    files = [p for p in out.rglob("*") if p.is_file()]
    assert result.stdout.strip() == f"wrote {len(files)} files to {out}: open {out / 'report.html'}"
    assert (out / "summary.json").is_file() and (out / "tables" / "parameters.csv").is_file()
    parameters = list(csv.DictReader(open(out / "tables" / "parameters.csv")))
    assert [(r["parameter"], r["distribution"], float(r["nominal"])) for r in parameters] == \
        [("a", "normal", 1.0), ("b", "uniform", 1.4)]
    page = (out / "report.html").read_text()
    assert "What was run" in page and "design_decay.png" in page and "name: decay-people" in page
    assert not [p for p in results.parent.iterdir() if p.name.startswith(".decay-report")]


@pytest.mark.slow
def test_a_report_that_fails_midway_leaves_nothing(results, tmp_path, monkeypatch):
    import uqflight.report.render as render

    def broken(*args, **kwargs):
        raise RuntimeError("disk on fire")

    out = tmp_path / "nested" / "report"
    monkeypatch.setattr(render, "render_markdown", broken)  # after the plots and tables are written
    with pytest.raises(RuntimeError, match="disk on fire"):
        write_report([results], out)
    assert list(out.parent.iterdir()) == []
    old = tmp_path / "old"  # an earlier report: the one thing a report replaces (test_report.py)
    (old / "tables").mkdir(parents=True)
    (old / "report.html").write_text("previous report")
    (old / "tables" / "stale.csv").write_text("x")
    with pytest.raises(RuntimeError):
        write_report([results], old)
    assert sorted(p.name for p in old.rglob("*")) == ["report.html", "stale.csv", "tables"]
    assert (old / "report.html").read_text() == "previous report" and len(list(tmp_path.iterdir())) == 2
    monkeypatch.undo()
    written = write_report([results], old)
    assert not (old / "tables" / "stale.csv").exists() and (old / "report.html") in written


@pytest.mark.slow
def test_several_methods_over_the_same_runs(results, tmp_path):
    out = tmp_path / "methods"
    result = cli_in_process("report", results, "--method", "pseudo_galerkin:2", "--method", "least_squares:1",
                 "--method", "regression", "--order", "2", "--out", out)
    assert result.returncode == 0, result.stderr
    labels = [row["label"] for row in csv.DictReader(open(out / "tables" / "files.csv"))]
    assert [label.split(": ")[1].split(",")[0] for label in labels] == \
        ["PG order 2", "least squares order 1", "regression order 2"]
    plots = {p.name for p in (out / "plots").iterdir()}
    assert {"sobol_compared.png", "bands_compared.png", "mean_band_decay_least_squares1.png"} <= plots
    summaries = {p.name: json.loads(p.read_text()) for p in (out / "summaries").iterdir()}
    least = summaries["decay_least_squares1.json"]
    assert least["method"]["kind"] == "least_squares" and least["method"]["order"] == 1
    exact = analyse(results, method={"kind": "least_squares", "order": 1}).outputs["x"].mean
    np.testing.assert_allclose(least["outputs"]["x"]["mean"], exact, rtol=1e-12)
    for bad, message in ((["--method", "galerkin:2"], "expected KIND[:ORDER]"),
                         (["--method", "least_squares:two"], "integer ORDER"),
                         (["--order", "2"], "--order needs --method")):
        refused = cli_in_process("report", results, *bad, "--out", tmp_path / "bad")
        assert refused.returncode == 2 and message in refused.stderr and "Traceback" not in refused.stderr, bad
        assert not (tmp_path / "bad").exists()


def test_design_csv(tmp_path):
    campaign = tmp_path / "decay.yaml"
    campaign.write_text(DECAY)
    out = tmp_path / "design.csv"
    result = cli_in_process("design", campaign, "--csv", out)
    assert result.returncode == 0, result.stderr
    rows = list(csv.DictReader(open(out)))
    design = parse_campaign(DECAY, str(campaign)).design()
    assert result.stdout.strip() == (f"wrote {out}: {len(design.xi)} points of a sparse_grid design in 2 "
                                     "parameters (a, b)")
    assert list(rows[0]) == ["run", "xi_a", "xi_b", "a", "b", "weight"] and len(rows) == len(design.xi)
    xi = np.array([[float(r["xi_a"]), float(r["xi_b"])] for r in rows])
    np.testing.assert_array_equal(xi, design.xi)
    np.testing.assert_array_equal([float(r["weight"]) for r in rows], design.weights)
    kappa = np.array([[float(r["a"]), float(r["b"])] for r in rows])
    np.testing.assert_allclose(kappa[:, 0], 1.0 + xi[:, 0] / 6, rtol=1e-14)  # normal: ±3σ on [0.5, 1.5]
    np.testing.assert_allclose(kappa[:, 1], 1.5 + 0.5 * xi[:, 1], rtol=1e-14)  # uniform on [1, 2]
    missing = cli_in_process("design", tmp_path / "missing.yaml", "--csv", out)
    assert missing.returncode == 2 and "Traceback" not in missing.stderr


@pytest.mark.slow
def test_surrogate_export_round_trip(results, tmp_path):
    out = tmp_path / "pce.json"
    result = cli_in_process("surrogate", "export", results, "--out", out)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == f"wrote {out}"
    data = json.loads(out.read_text(), parse_constant=lambda c: pytest.fail(f"not strict JSON: {c}"))
    assert data["method"] == "pseudo_galerkin" and data["order"] == 2 and len(data["germs"]) == 2
    assert [p["name"] for p in data["parameters"]] == ["a", "b"] and data["parameters"][1]["nominal"] == 1.4
    surrogate = load(out)
    stats = analyse(results)
    np.testing.assert_allclose(surrogate.mean()["x"], stats.outputs["x"].mean, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(surrogate.variance()["x"], stats.outputs["x"].variance, rtol=1e-10, atol=1e-15)
    rng = np.random.default_rng(1)
    xi = np.column_stack([rng.standard_normal(50), rng.uniform(-1, 1, 50)])
    fitted = fit_surrogate(results)
    expected = orthonormal_basis(fitted.germs, fitted.indices["x"], xi) @ fitted.coefficients["x"]
    np.testing.assert_allclose(surrogate.evaluate(xi=xi)["x"], expected, rtol=1e-12, atol=1e-14)
    kappa = np.column_stack([1.0 + xi[:, 0] / 6, 1.5 + 0.5 * xi[:, 1]])
    np.testing.assert_allclose(surrogate.evaluate(kappa)["x"], expected, rtol=1e-12, atol=1e-14)
    # a quadratic PCE of exp(-a t) · b is close to the model itself at the nominal point
    time = np.asarray(data["time"])
    near = surrogate.evaluate([[1.0, 1.5]])["x"][0]
    assert near.shape == time.shape
    mc = cli_in_process("surrogate", "export", results, "--out", tmp_path / "mc.json", "--method", "monte_carlo")
    assert mc.returncode == 2 and "needs a sampled design" in mc.stderr and not (tmp_path / "mc.json").exists()


@pytest.mark.slow
def test_restart_starts_a_same_campaign_file_over_and_force_keeps_its_meaning(tmp_path):
    campaign = tmp_path / "decay.yaml"
    campaign.write_text(DECAY)
    out = tmp_path / "d.h5"
    assert cli_in_process("run", campaign, "--out", out).returncode == 0
    with h5py.File(out, "a") as f:
        f.attrs["marker"] = "the first run's file"
    again = cli_in_process("run", campaign, "--out", out, "--force")  # a file of this campaign: resumed, nothing to do
    assert again.returncode == 0 and " 0 run now" in again.stdout
    with h5py.File(out, "r") as f:
        assert "marker" in f.attrs
    restarted = cli_in_process("run", campaign, "--out", out, "--restart")
    assert restarted.returncode == 0 and " 0 already done" in restarted.stdout
    with h5py.File(out, "r") as f:
        assert "marker" not in f.attrs  # a new file


def test_check_against_another_campaigns_baseline_exits_2(results, tmp_path):
    baseline = write_baseline(analyse(results), "", tmp_path / "baseline.json")
    data = json.loads(baseline.read_text())
    data["campaign_hash"] = "0" * 64
    baseline.write_text(json.dumps(data))
    checked = cli_in_process("check", results, "--baseline", baseline)
    assert checked.returncode == 2 and "comes from another campaign" in checked.stderr


def test_a_mistyped_property_gets_a_did_you_mean():
    result = cli_in_process("simulate", "--set", "aero/uq/CLO=0.2", "--duration-s", "1")
    assert result.returncode == 2 and "did you mean aero/uq/CL0" in result.stderr


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
