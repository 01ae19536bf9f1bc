"""What the report page shows first and its runs and sensitivity figures: the headline table against
summary.json, the compact Sobol' text, the partial variances of a closed-form model, the seeded run subset."""
import csv
import math

import numpy as np
import pytest

from conftest import read_summary, run_python_campaign
from test_closed_forms_end_to_end import LINEAR  # y = x1 + 2 x2 + 3 x3, exact on a level-1 grid
from uqflight.report import write_report
from uqflight.report.headline import band_text, mean_std_text
from uqflight.report.sensitivity import index_text, negligible, partial_variances, top_contributors
from uqflight.analysis.drawn import run_subset
from uqflight.report.trajectories import plot_spaghetti
from uqflight.simulators.base import Status
from uqflight.analysis.statistics import analyse, read_statistics

PHUGOID = """
name: phugoid-grid
seed: 17
simulator: {kind: python, function: "uqflight.simulators.models:phugoid"}
parameters:
  a: {distribution: normal, nominal: 0, lower: -3, upper: 3}
  b: {distribution: normal, nominal: 0, lower: -3, upper: 3}
  c: {distribution: normal, nominal: 0, lower: -3, upper: 3}
quantities:
  peak_h: {of: h_ft, take: max}
design: {kind: sparse_grid, rule: gauss_hermite, level: 2}
method: {kind: pseudo_galerkin, order: 2}
storage: {raw: false, tsvd: {tol: 1.0e-10, batch: 10}}
analysis: {band_samples: 500}
"""


@pytest.mark.parametrize("value, text", [(0.62, "0.620"), (1.0, "1.00"), (0.00123, "0.00123"), (3.3e-10, "<0.001"),
                                         (-3.3e-10, "<0.001"), (-0.0512, "-0.0512"), (0.9996, "1.00"),
                                         (float("nan"), "unresolved"), (None, "unresolved"), (123.4, "123"),
                                         ("", "")])
def test_sobol_indices_print_with_three_significant_digits(value, text):
    assert index_text(value) == text


def test_top_contributors_name_the_largest_shares_and_the_interactions():
    first = {"CL0": np.array([0.62]), "k2": np.array([0.21]), "CD0": np.array([0.004]), "k1": np.array([0.1])}
    assert top_contributors(first, 0) == "CL0 62 %, k2 21 %, k1 10 %, interactions 7 %"
    assert top_contributors({"a": np.array([0.995]), "b": np.array([0.005])}, 0) == "a 100 %"
    assert top_contributors({"a": np.array([np.nan]), "b": np.array([0.5])}, 0) == "unresolved"


def test_mean_and_band_are_rounded_to_two_digits_of_the_std():
    assert mean_std_text(14966.13, 12.3, "ft") == "14966 ± 12 ft"
    assert mean_std_text(6.3124, 0.0345, "deg") == "6.312 ± 0.035 deg"
    assert mean_std_text(2.0, 0.0, "") == "2 ± 0"
    assert band_text(14930.4, 15001.6, 12.3) == "14930 to 15002"


def test_partial_variances_of_a_linear_model_are_exact(tmp_path):
    # y = x1 + 2 x2 + 3 x3 with sigma 1, 2 and U(0, 2): partial variances 1, 16 and 9/3, no interactions;
    # a level-1 grid and an order-1 PCE represent y exactly, so only rounding remains (1e-12).
    out = analyse(run_python_campaign(tmp_path, LINEAR)).outputs["y"]
    parts, rest = partial_variances(out)
    np.testing.assert_allclose([parts[p][0] for p in ("x1", "x2", "x3")], [1.0, 16.0, 3.0], rtol=1e-12)
    assert abs(rest[0]) < 1e-12 * out.variance[0]
    assert sum(parts.values())[0] + rest[0] == pytest.approx(out.variance[0], rel=1e-15)
    assert not negligible(out).any()


@pytest.mark.slow
def test_the_headline_of_a_scalar_output_is_summary_json(tmp_path):
    write_report([run_python_campaign(tmp_path, LINEAR)], tmp_path / "report")
    summary = read_summary(tmp_path / "report" / "summary.json")["outputs"]["y"]
    with open(tmp_path / "report" / "tables" / "headline.csv", newline="") as fh:
        (row,) = csv.DictReader(fh)
    assert [float(row[k]) for k in ("mean", "std", "band99 lower", "band99 upper")] == [
        summary["mean"][0], summary["std"][0], summary["band99"]["lower"][0], summary["band99"]["upper"][0]]
    assert row["top contributors (first-order Sobol')"] == "x2 80 %, x3 15 %, x1 5 %"  # 16, 3, 1 of 20


@pytest.fixture(scope="module")
def phugoid_report(tmp_path_factory):
    folder = tmp_path_factory.mktemp("phugoid")
    results = run_python_campaign(folder, PHUGOID, "phugoid")
    write_report([results], folder / "report", times=[10.0, float("inf")])
    return results, folder / "report"


@pytest.mark.slow  # a report of 25 histories of 1001 times: about 10 s of CPU
def test_the_headline_is_summary_json_at_the_selected_times(phugoid_report):
    _, report = phugoid_report
    summary = read_summary(report / "summary.json")
    with open(report / "tables" / "headline.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [row["output or quantity"] for row in rows] == [name for name in summary["outputs"] for _ in (0, 1)] + [
        "peak_h"]
    for row in rows[:-1]:
        entry = summary["outputs"][row["output or quantity"]]
        i = entry["time"].index(float(row["time [s]"]))
        assert entry["time"][i] in (10.0, entry["time"][-1])
        assert [float(row[k]) for k in ("mean", "std", "band99 lower", "band99 upper")] == [
            entry["mean"][i], entry["std"][i], entry["band99"]["lower"][i], entry["band99"]["upper"][i]]
    quantity = summary["quantities"]["peak_h"]
    assert [float(rows[-1][k]) for k in ("mean", "std", "band99 lower", "band99 upper")] == [
        quantity["mean"], quantity["std"], quantity["band99"]["lower"], quantity["band99"]["upper"]]
    share = max(quantity["sobol_first"].values())
    assert f"{100 * share:.0f} %" in rows[-1]["top contributors (first-order Sobol')"]
    page, markdown = (report / "report.html").read_text(), (report / "report.md").read_text()
    assert page.index("Key numbers of") < page.index("<h2>Contents</h2>")  # the first block after the title
    assert markdown.index("Key numbers of") < markdown.index("## Contents")


@pytest.mark.slow  # a report of 25 histories of 1001 times: about 10 s of CPU
def test_the_page_shows_compact_sobol_tables_with_the_file_label_once(phugoid_report):
    _, report = phugoid_report
    page = (report / "report.html").read_text()
    table = page[page.index("First-order Sobol&#x27; indices at the selected times (paper Table 3)</h3>"):]
    table = table[:table.index("</table>")]
    assert table.count("phugoid-grid: PG order 2") == 1
    assert "e-" not in table and "&lt;0.001" in table  # no 3.3e-10: tiny indices print as <0.001
    with open(report / "tables" / "sobol_first.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert {row["file"] for row in rows} == {"phugoid-grid: PG order 2, 25 runs"}  # the CSV keeps every row's
    for row in rows:
        assert "<td>" + "</td><td>".join([row["output"], f"{float(row['time [s]']):g}"] + [
            index_text(float(row[p])).replace("<", "&lt;") for p in "abc"]) + "</td>" in table


@pytest.mark.slow  # a report of 25 histories of 1001 times: about 10 s of CPU
def test_the_runs_drawn_are_the_same_on_every_report(phugoid_report, tmp_path):
    results, report = phugoid_report
    status = np.full(113, Status.OK, dtype=np.int8)
    status[[3, 50]] = Status.DIVERGED
    subset = run_subset(status, 50, 20261124)
    assert subset.size == 50 and 3 not in subset and 50 not in subset and np.all(np.diff(subset) > 0)
    np.testing.assert_array_equal(subset, run_subset(status, 50, 20261124))
    assert not np.array_equal(subset, run_subset(status, 50, 1))
    assert run_subset(status[:20], 50, 0).size == 19  # all successful runs when fewer
    stats, _ = read_statistics(results, scatter_time=float("inf"))
    outputs = stats.outputs
    assert stats.seed == 17 and stats.drawn.spaghetti_rows.tolist() == list(range(25))  # every run when fewer
    first, drawn = plot_spaghetti(stats.drawn, outputs, tmp_path / "a.png", "t")
    again, _ = plot_spaghetti(read_statistics(results, scatter_time=0.0)[0].drawn, outputs, tmp_path / "b.png", "t")
    assert drawn == 25 and first.read_bytes() == again.read_bytes()
    assert {"spaghetti_phugoid.png", "scatter_phugoid.png", "sensitivity_phugoid.png"} <= {
        p.name for p in (report / "plots").iterdir()}
    assert "nodes, not random draws" in (report / "report.md").read_text()
    assert math.isfinite(outputs["h_ft"].variance[-1])


DECAY_ONE_INPUT = """
name: decay-one
seed: 5
simulator: {kind: python, function: "uqflight.simulators.models:exp_decay"}
parameters:
  a: {distribution: normal, lower: 0.5, upper: 1.5}
design: {kind: monte_carlo, samples: 40}
method: {kind: monte_carlo}
analysis: {band_samples: 500, bootstrap: 0}
"""


@pytest.mark.slow
def test_one_input_is_scattered_in_one_uncoloured_panel_per_output(tmp_path):
    """With one input, the output against it is the whole response: one panel, no colouring input to name."""
    from PIL import Image

    from uqflight.report.plots import DPI

    write_report([run_python_campaign(tmp_path, DECAY_ONE_INPUT, "decay")], tmp_path / "report")
    with Image.open(tmp_path / "report" / "plots" / "scatter_decay.png") as image:
        assert image.size[0] == round(8.0 * DPI)  # one panel: the figure's least width, not two panels' 9.2 in
    markdown = (tmp_path / "report" / "report.md").read_text()
    assert "(a row each) against its one input in physical values, 40 runs (at most 1000, seed 5)." in markdown
    assert "colour" not in markdown[markdown.index("against its one input"):][:200]
