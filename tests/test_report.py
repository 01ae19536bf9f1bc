"""`uqflight report` on real results files of closed-form and JSBSim campaigns (`check`: test_check.py)."""
import csv
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

from conftest import UQFLIGHT, cli, cli_in_process, read_summary, run_python_campaign
from uqflight.campaign import parse_campaign
from uqflight.analysis.check import write_baseline
from uqflight.simulators.aircraft_properties import AircraftProperties
from uqflight.running.runner import run_campaign
from uqflight.report import write_report
from uqflight.analysis.statistics import analyse, read_statistics
from uqflight.methods import MethodSpec


DECAY = """
name: decay-{name}
seed: 3
simulator: {{kind: python, function: "uqflight.simulators.models:exp_decay"}}
parameters:
  a: {{distribution: {distribution}, lower: 0.5, upper: 1.5}}
design: {design}
method: {method}
analysis: {{band_samples: 2000, bootstrap: 20}}
"""

ISHIGAMI = """
name: ishigami-{name}
seed: 5
simulator: {{kind: python, function: "uqflight.simulators.models:ishigami"}}
parameters:
  x1: {{distribution: uniform, lower: -3.141592653589793, upper: 3.141592653589793}}
  x2: {{distribution: uniform, lower: -3.141592653589793, upper: 3.141592653589793}}
  x3: {{distribution: uniform, lower: -3.141592653589793, upper: 3.141592653589793}}
design: {design}
method: {method}
analysis: {{band_samples: 2000, bootstrap: 20}}
"""

JSBSIM = """
name: small-jsbsim-mc
seed: 7
simulator: {kind: jsbsim, duration_s: 5, output_rate_hz: 10, outputs: [alpha_deg, h_ft]}
parameters:
  CL0: {property: aero/uq/CL0, distribution: normal, interval_pct: 23.05}
  CLalpha: {property: aero/uq/CLalpha, distribution: normal, interval_pct: 5.27}
design: {kind: monte_carlo, samples: 16}
execution: {workers: 1, chunk: 8}
analysis: {band_samples: 1000}
"""


def run(template: str, path: Path, read_aircraft=None, **fields) -> Path:
    campaign = parse_campaign(template.format(**fields) if fields else template, str(path.with_suffix(".yaml")), read_aircraft)
    run_campaign(campaign, out=path, workers=1)
    return path


@pytest.fixture(scope="module")
def pg(tmp_path_factory) -> Path:
    """The pseudo-Galerkin decay campaign: one output x at 51 times, one parameter a (test_check.py's too)."""
    return run(DECAY, tmp_path_factory.mktemp("pg") / "pg.h5", name="pg", distribution="normal",
               design="{kind: sparse_grid, rule: gauss_hermite, level: 3}", method="{kind: pseudo_galerkin, order: 2}")


@pytest.fixture(scope="module")
def files(pg, tmp_path_factory) -> dict[str, Path]:
    root = tmp_path_factory.mktemp("results")
    grid = "{kind: sparse_grid, rule: gauss_hermite, level: %d}"
    return {
        "pg": pg,
        "int": run(DECAY, root / "int.h5", name="int", distribution="normal", design=grid % 2,
                   method="{kind: integration, order: 1}"),
        "mc": run(DECAY, root / "mc.h5", name="mc", distribution="normal", design="{kind: monte_carlo, samples: 1000}",
                  method="{kind: monte_carlo}"),
        "mc_uniform": run(DECAY, root / "mc_uniform.h5", name="mc-uniform", distribution="uniform",
                          design="{kind: monte_carlo, samples: 1000}", method="{kind: monte_carlo}"),
        "ishigami_pce": run(ISHIGAMI, root / "ishigami_pce.h5", name="pce", method="{kind: regression, order: 6}",
                            design="{kind: latin_hypercube, samples: 300}"),
        "ishigami_pf": run(ISHIGAMI, root / "ishigami_pf.h5", name="pick-freeze", method="{kind: monte_carlo}",
                           design="{kind: pick_freeze, samples: 100}"),
    }


def read_csv(path: Path) -> list[dict]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


@pytest.mark.slow
def test_report_of_several_files_against_a_reference(files, tmp_path):
    out = tmp_path / "report"
    result = cli("report", files["pg"], files["int"], "--reference", files["mc"], "--out", out, "--times", "1,2.5,end")
    assert result.returncode == 0, result.stderr

    summary = read_summary(out / "summary.json")
    entry = summary["outputs"]["x"]
    n = len(entry["time"])
    assert n == 51 and entry["time"][-1] == 5.0
    assert {"time", "mean", "variance", "band99", "sobol_first", "sobol_total"} <= entry.keys()
    series = [entry["mean"], entry["variance"], entry["band99"]["lower"], entry["band99"]["upper"]]
    assert [len(values) for values in series] == [n] * 4
    assert list(entry["sobol_first"]) == list(entry["sobol_total"]) == ["a"] and len(entry["sobol_first"]["a"]) == n
    assert summary["campaign"] == "decay-pg"
    assert {p.name for p in (out / "summaries").iterdir()} == {"pg.json", "int.json"}

    errors = read_csv(out / "tables" / "errors.csv")
    assert [row["file"].split(":")[0] for row in errors] == ["decay-pg", "decay-int"]
    assert all(float(row["eps_m max"]) < 0.05 for row in errors)
    over_time = read_csv(out / "tables" / "statistics_pg_x.csv")
    assert len(over_time) == n and float(over_time[-1]["time [s]"]) == 5.0 and "eps_v [-]" in over_time[0]
    at_times = read_csv(out / "tables" / "statistics_at_times.csv")
    assert [float(row["time [s]"]) for row in at_times] == [1.0, 2.5, 5.0] * 2
    assert len(read_csv(out / "tables" / "sobol_first.csv")) == 6

    page = (out / "report.html").read_text()
    assert re.findall(r'src="(?!data:)', page) == [] and "<link" not in page
    plots = sorted(p.name for p in (out / "plots").iterdir())
    assert {"mean_band_pg.png", "cov_pg.png", "pdf_pg_x.png", "mean_band_int.png", "cov_int.png", "pdf_int_x.png",
            "eps_m.png", "eps_v.png", "kld_vs_runs.png", "convergence.png", "bands_compared.png",
            "sobol_pg.png"} <= set(plots)
    assert page.count('src="data:image/png;base64,') == len(plots)
    markdown = (out / "report.md").read_text()
    for name in plots:
        assert f"plots/{name}" in page and f"](plots/{name})" in markdown
    assert "Errors against the reference" in page and "decay-int: Int order 1, 3 runs" in page


@pytest.mark.slow
def test_pce_against_pick_freeze_and_two_monte_carlo_files(files, tmp_path):
    out = tmp_path / "report"
    write_report([files["ishigami_pce"], files["ishigami_pf"]], out)
    table = read_csv(out / "tables" / "sobol_pce_vs_mc.csv")
    assert [row["parameter"] for row in table] == ["x1", "x2", "x3"]
    pce, pick_freeze = (f"ishigami-{name}: {method}" for name, method in
                        (("pce", "regression order 6, 300 runs"), ("pick-freeze", "MC, 500 runs")))
    exact = {"x1": 0.3139, "x2": 0.4424, "x3": 0.0}
    for row in table:
        assert float(row[pce]) == pytest.approx(exact[row["parameter"]], abs=0.03)
        lower, upper = (float(row[f"{pick_freeze} 95 % CI {side}"]) for side in ("lower", "upper"))
        assert lower <= float(row[pick_freeze]) <= upper
    assert (out / "plots" / "sobol_ishigami_pf.png").is_file()

    mc = tmp_path / "mc"
    write_report([files["mc"], files["mc_uniform"]], mc)
    assert {"mc_bands.png", "mc_pdf_final.png"} <= {p.name for p in (mc / "plots").iterdir()}
    assert [row["inputs"] for row in read_csv(mc / "tables" / "files.csv")] == ["normal", "uniform"]


@pytest.mark.slow
def test_report_of_a_jsbsim_campaign_and_its_check(tmp_path):
    results = run(JSBSIM, tmp_path / "jsbsim.h5", read_aircraft=AircraftProperties)
    baseline = tmp_path / "baseline.json"
    result = cli("report", results, "--out", tmp_path / "report", "--write-baseline", baseline)
    assert result.returncode == 0, result.stderr
    summary = read_summary(tmp_path / "report" / "summary.json")
    assert list(summary["outputs"]) == ["alpha_deg", "h_ft"] and len(summary["outputs"]["h_ft"]["time"]) == 51
    with h5py.File(results, "r") as f:
        assert json.loads(baseline.read_text())["campaign_hash"] == f.attrs["campaign_hash"]
    checked = cli_in_process("check", results, "--baseline", baseline)
    assert checked.returncode == 0, checked.stdout + checked.stderr
    assert checked.stdout.startswith("no drift: ")


def test_report_refuses_an_unreadable_results_file(tmp_path):
    result = cli_in_process("report", tmp_path / "missing.h5", "--out", tmp_path / "report")
    assert result.returncode == 2
    assert result.stderr.strip() == f"error: {tmp_path / 'missing.h5'}: no such results file"
    device = cli_in_process("report", "/dev/zero", "--out", tmp_path / "report")  # there, but no file to read
    assert device.returncode == 2
    assert device.stderr.strip() == "error: /dev/zero is not a regular file (a device, a FIFO or a socket), not a results file"


def test_split_form_is_ignored_by_the_kinds_that_fit_their_constant_term(tmp_path):
    """`split: true` is accepted for every method; least squares fits x0 itself, so nothing changes."""
    path = run(DECAY, tmp_path / "split.h5", name="split", distribution="normal",
               design="{kind: sparse_grid, rule: gauss_hermite, level: 3}",
               method="{kind: least_squares, order: 2, split: true}")
    split, plain = analyse(path), analyse(path, method=MethodSpec.from_checked({"kind": "least_squares", "order": 2, "split": False}))
    np.testing.assert_allclose(split.outputs["x"].mean, plain.outputs["x"].mean, rtol=1e-12)
    np.testing.assert_allclose(split.outputs["x"].variance, plain.outputs["x"].variance, rtol=1e-12)


@pytest.mark.slow
def test_method_override_reports_another_method_on_the_same_runs(files, tmp_path):
    result = subprocess.run([UQFLIGHT, "report", str(files["pg"]), "--method", "least_squares", "--order", "3",
                             "--out", str(tmp_path / "ls")], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    summary = read_summary(tmp_path / "ls" / "summary.json")
    assert summary["method"]["kind"] == "least_squares" and summary["method"]["order"] == 3
    exact = analyse(files["pg"], method=MethodSpec("least_squares", 3)).outputs["x"].mean
    np.testing.assert_allclose(summary["outputs"]["x"]["mean"], exact, rtol=1e-12)
    bad = subprocess.run([UQFLIGHT, "report", str(files["pg"]), "--method", "galerkin", "--out", str(tmp_path / "b")],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "Traceback" not in bad.stderr


@pytest.mark.parametrize("occupant", ["a folder with a user's file", "a file", "a report folder with a user's file",
                                      "a symlink to a report"])
def test_report_never_replaces_what_is_not_an_earlier_report(pg, tmp_path, occupant):
    out = tmp_path / "out"
    if occupant == "a file":
        out.write_text("precious")
    elif occupant == "a symlink to a report":
        (tmp_path / "real").mkdir()
        (tmp_path / "real" / "report.html").write_text("<html>")
        out.symlink_to(tmp_path / "real")
    else:
        (out / "plots").mkdir(parents=True)
        (out / "report.html").write_text("<html>")
        kept = out / ("thesis.txt" if occupant == "a folder with a user's file" else "plots/notes.txt")
        kept.write_text("precious")
    before = sorted(str(p) for p in tmp_path.rglob("*"))
    result = cli_in_process("report", pg, "--out", out)
    assert result.returncode == 2
    assert f"{out} exists and is not a uqflight report" in result.stderr and "choose another --out" in result.stderr
    assert sorted(str(p) for p in tmp_path.rglob("*")) == before


@pytest.mark.slow
def test_a_relative_out_counts_the_files_written_and_the_baseline_is_the_files_statistics(pg, tmp_path):
    result = cli_in_process("report", pg, "--out", "rel", "--write-baseline", "b.json", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    written = sum(1 for p in (tmp_path / "rel").rglob("*") if p.is_file())
    assert written > 10 and f"wrote {written} files to rel: open rel/report.html" in result.stdout
    assert "wrote baseline b.json" in result.stdout
    stats, attrs = read_statistics(pg)  # what test_check.py's baseline is
    expected = write_baseline(stats, attrs["campaign_hash"], tmp_path / "expected.json")
    assert (tmp_path / "b.json").read_bytes() == expected.read_bytes()


def test_an_empty_folder_or_an_earlier_report_may_be_replaced(tmp_path):
    from uqflight.report import check_replaceable

    empty, earlier = tmp_path / "empty", tmp_path / "earlier"
    empty.mkdir()
    for name in ("plots/alpha.png", "tables/statistics.csv", "summaries/a.json", "report.html", "report.md",
                 "summary.json"):
        (earlier / name).parent.mkdir(parents=True, exist_ok=True)
        (earlier / name).write_text("x")
    for folder in (empty, earlier, tmp_path / "absent"):
        check_replaceable(folder)


@pytest.mark.slow
def test_report_writes_next_to_the_results_file_by_default(decay_results, tmp_path):
    shutil.copy(decay_results.with_suffix(".yaml"), tmp_path)  # the campaign and its file, copied: the report
    results = Path(shutil.copy(decay_results, tmp_path / "decay.h5"))  # is written beside them
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


SAME_NAME = """
name: decay-{name}
seed: 3
simulator: {{kind: python, function: "uqflight.simulators.models:exp_decay"}}
parameters:
  a: {{distribution: uniform, lower: 0.5, upper: {upper}}}
  b: {{distribution: uniform, lower: 1.0, upper: 2.0}}
design: {{kind: sparse_grid, level: 2}}
method: {{kind: pseudo_galerkin, order: 1}}
analysis: {{band_samples: 200, bootstrap: 0}}
"""


@pytest.mark.slow
def test_two_files_of_one_name_each_get_their_own_design_and_runs_figures(tmp_path):
    """a/r.h5 and b/r.h5: the per-file figures are r and r-2 as the tables are (b's overwrote a's, and the
    page showed b's twice), the second the same as a report of b alone draws."""
    paths = []
    for folder, upper in (("a", 1.5), ("b", 3.0)):
        (tmp_path / folder).mkdir()
        paths.append(run_python_campaign(tmp_path / folder, SAME_NAME.format(name=folder, upper=upper), "r"))
    write_report(paths, tmp_path / "both")
    write_report(paths[1:], tmp_path / "alone")
    page = (tmp_path / "both" / "report.md").read_text()
    plots = tmp_path / "both" / "plots"
    for kind in ("design", "spaghetti", "scatter"):
        first, second = plots / f"{kind}_r.png", plots / f"{kind}_r-2.png"
        assert first.read_bytes() != second.read_bytes(), kind
        assert page.count(f"plots/{kind}_r.png") == page.count(f"plots/{kind}_r-2.png") == 1, kind
    for kind in ("spaghetti", "scatter"):  # the design's title names its file: r-2 here, r alone
        assert (plots / f"{kind}_r-2.png").read_bytes() == (tmp_path / "alone" / "plots" / f"{kind}_r.png").read_bytes()
    assert "The design points of r-2 projected" in page and "successful runs of r-2 " in page


@pytest.mark.slow
def test_several_methods_over_the_same_runs(decay_results, tmp_path):
    out = tmp_path / "methods"
    result = cli_in_process("report", decay_results, "--method", "pseudo_galerkin:2", "--method", "least_squares:1",
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
    exact = analyse(decay_results, method=MethodSpec("least_squares", 1)).outputs["x"].mean
    np.testing.assert_allclose(least["outputs"]["x"]["mean"], exact, rtol=1e-12)
    for bad, message in ((["--method", "galerkin:2"], "expected KIND[:ORDER]"),
                         (["--method", "least_squares:two"], "integer ORDER"),
                         (["--order", "2"], "--order needs --method")):
        refused = cli_in_process("report", decay_results, *bad, "--out", tmp_path / "bad")
        assert refused.returncode == 2 and message in refused.stderr and "Traceback" not in refused.stderr, bad
        assert not (tmp_path / "bad").exists()


def _recording_drawers(monkeypatch, report) -> list:
    """The PreparedChild drawers write_report forks, recorded (to check they are reaped)."""
    drawers = []

    def recorded(*args):
        drawers.append(report.PreparedChild.__wrapped__(*args))
        return drawers[-1]

    recorded.__wrapped__ = report.PreparedChild
    monkeypatch.setattr(report, "PreparedChild", recorded)
    return drawers


def _assert_reaped(drawers, report) -> None:
    assert len(drawers) == (1 if report.FORKS else 0)
    for drawer in drawers:  # no child is left behind, running or unreaped
        with pytest.raises(ChildProcessError):
            os.waitpid(drawer.child.pid, os.WNOHANG)


def test_data_files_that_cannot_be_written_fail_the_report_and_leave_nothing(pg, tmp_path, monkeypatch):
    import uqflight.report as report

    def refuse(entries, out_dir):
        raise OSError("no space left on device")

    drawers = _recording_drawers(monkeypatch, report)
    monkeypatch.setattr(report, "write_statistics_tables", refuse)
    with pytest.raises(OSError, match="no space left on device"):  # the CLI: "cannot write the report: ...", exit 2
        report.write_report([pg], tmp_path / "out")
    assert list(tmp_path.iterdir()) == []  # no report, no staging folder
    _assert_reaped(drawers, report)


@pytest.mark.slow
def test_a_page_module_that_cannot_be_imported_is_the_error_told_and_the_drawer_is_reaped(
        pg, tmp_path, monkeypatch, capfd):
    import sys

    import uqflight.report as report

    drawers = _recording_drawers(monkeypatch, report)
    monkeypatch.setitem(sys.modules, "uqflight.report.render", None)  # `from .render import ...` fails
    with pytest.raises(ImportError, match="uqflight.report.render"):
        report.write_report([pg], tmp_path / "out")
    capfd.readouterr()
    assert list(tmp_path.iterdir()) == []  # no report, no staging folder
    _assert_reaped(drawers, report)


@pytest.mark.slow
@pytest.mark.skipif(not hasattr(os, "fork"), reason="the system cannot fork")
def test_the_reports_own_process_never_imports_matplotlib(pg, tmp_path):
    """The drawer (a child that got ready during the analysis) draws everything: the report's process
    writes the data files and the page without matplotlib."""
    code = ("import sys; from uqflight.report import write_report; "
            f"write_report([{str(pg)!r}], {str(tmp_path / 'out')!r}); "
            "print(sorted(m for m in sys.modules if m.split('.')[0] == 'matplotlib'))")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "[]"
    assert (tmp_path / "out" / "plots" / "mean_band_pg.png").is_file()


@pytest.mark.slow
@pytest.mark.skipif(not hasattr(os, "fork"), reason="the system cannot fork")
@pytest.mark.parametrize("error", [OSError, ZeroDivisionError])
def test_a_section_that_fails_in_the_child_sharing_the_drawing_fails_the_report_and_leaves_nothing(
        pg, tmp_path, monkeypatch, capfd, error):
    """An OSError (a file it could not write: a full disk) comes back to the parent as that OSError, without
    a traceback (the command says "cannot write the report"); any other error is the child's traceback and
    DrawingFailed naming the section and what it raised."""
    import time

    import uqflight.report as report
    import uqflight.report.sections as sections

    parent, jobs_of = os.getpid(), sections.section_jobs

    def failing_in_the_child(build):  # the drawer's own child, the drawer being this test's child
        def job():
            if os.getppid() != parent:
                raise error("no space left on device")
            time.sleep(0.5)  # in the drawer, each section waits: its child takes the next ones meanwhile
            return build()
        return job

    monkeypatch.setattr(sections, "section_jobs", lambda *args: [(cost, stage, failing_in_the_child(build))
                                                                 for cost, stage, build in jobs_of(*args)])
    raised = (OSError, r"^no space left on device$") if error is OSError else \
        (report.DrawingFailed, r"^cannot draw the report's plots: drawing [^:]+ raised ZeroDivisionError: "
                               r"no space left on device$")  # the section is whichever the child took first
    with pytest.raises(raised[0], match=raised[1]):
        report.write_report([pg], tmp_path / "out")
    printed = capfd.readouterr().err
    assert ("Traceback" in printed and "no space left on device" in printed) == (error is not OSError)
    # printed where it was raised, not again by the process relaying it
    assert printed.count("\nZeroDivisionError: no space left on device") == (error is not OSError)
    assert list(tmp_path.iterdir()) == []  # no report, no staging folder


@pytest.mark.slow
def test_a_figure_that_raises_is_one_line_naming_its_section_with_exit_1(pg, tmp_path, monkeypatch):
    import uqflight.report.sections as sections

    jobs_of = sections.section_jobs

    def failing(stage, build):
        def job():
            if stage == "drawing the PDFs":
                raise ValueError("a bad figure")
            return build()
        return job

    monkeypatch.setattr(sections, "section_jobs", lambda *args: [(cost, stage, failing(stage, build))
                                                                 for cost, stage, build in jobs_of(*args)])
    result = cli_in_process("report", pg, "--out", tmp_path / "out")
    assert result.returncode == 1
    assert result.stderr.strip().splitlines()[-1] == (
        "error: cannot draw the report's plots: drawing the PDFs raised ValueError: a bad figure; no report "
        f"written ({tmp_path / 'out'} unchanged)")
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
def test_without_a_drawer_the_report_draws_the_same_files_itself(pg, tmp_path, monkeypatch):
    """Where the system cannot fork there is no drawer (report.FORKS): this process draws the sections,
    the same bytes as the drawer's."""
    import uqflight.report as report

    report.write_report([pg], tmp_path / "drawer")
    monkeypatch.setattr(report, "FORKS", False)
    report.write_report([pg], tmp_path / "here")
    drawn = sorted(p.relative_to(tmp_path / "drawer") for p in (tmp_path / "drawer").rglob("*") if p.is_file())
    assert drawn == sorted(p.relative_to(tmp_path / "here") for p in (tmp_path / "here").rglob("*") if p.is_file())
    for name in drawn:
        if name.suffix in (".png", ".csv", ".json", ".md"):
            assert (tmp_path / "drawer" / name).read_bytes() == (tmp_path / "here" / name).read_bytes(), name
