"""The engineer's number first (issue 45): exceedance probabilities with their intervals in the headline
("—" where there is none), thresholds drawn on the quantity PDFs and changeable at report time
(`report --exceedance`), recorded times shown as asked for, and a quantity's statistics as attributes."""
import csv
import json

import numpy as np
import pytest
from conftest import cli_in_process
from test_quantities import python_campaign

import uqflight
from uqflight.campaign import parse_campaign
from uqflight.running.runner import run_campaign
from uqflight.text.labels import shown_time
from uqflight.quantities.spec import parse_exceedance_option
from uqflight.report import write_report
from uqflight.analysis.statistics import summary_json

# final y = a + 4b with a ~ U(-1, 1), b ~ U(0.5, 1.5) (test_exceedance): P(final_y > 5) = 1/4
QUANTITIES = "{final_y: {of: y, take: final}}"


@pytest.fixture(scope="module")
def campaigns(tmp_path_factory):
    """A Monte Carlo file (Wilson intervals) and a grid with a PCE (no interval), both asking P(final_y > 5)."""
    folder = tmp_path_factory.mktemp("trust")
    files = {}
    for name, design, method in (("mc", "{kind: monte_carlo, samples: 400}", "{kind: monte_carlo}"),
                                 ("pce", "{kind: sparse_grid, rule: gauss_legendre, level: 2}",
                                  "{kind: pseudo_galerkin, order: 2}")):
        text = python_campaign(folder, QUANTITIES, design, method, name=name,
                               analysis="{band_samples: 20000, exceedance: {final_y: [{above: 5}]}}")
        files[name] = folder / f"{name}.h5"
        run_campaign(parse_campaign(text, str(folder / f"{name}.yaml")), out=files[name])
    return folder, files


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def test_a_pce_exceedance_has_a_dash_for_its_interval_never_none(campaigns):
    from uqflight.report.headline import headline_section
    from uqflight.report.loading import load_entries
    from uqflight.report.render import _cell, render_markdown

    _, files = campaigns
    (entry,), _ = load_entries([files["pce"]], None)
    markdown = render_markdown("t", [headline_section(entry, [float("inf")])])
    line = next(line for line in markdown.splitlines() if "P(final\\_y \\> 5)" in line)
    assert "| — |" in line and "pce" in line
    assert "None" not in markdown and _cell(None) == "—"  # no table cell of the page says None


@pytest.mark.slow
def test_report_exceedance_leads_the_headline_with_its_interval_without_flying(campaigns):
    # one report (the slow part of these tests): the thresholds given at report time replace the campaign's,
    # and the headline shows them with their Wilson intervals before the key numbers, the contents and any figure
    folder, files = campaigns
    report = folder / "changed"
    before = files["mc"].stat().st_mtime_ns
    done = cli_in_process("report", files["mc"], "--out", report, "--times", "end",
                          "--exceedance", "final_y>6", "--exceedance", "final_y<1.1")
    assert done.returncode == 0, done.stderr
    assert files["mc"].stat().st_mtime_ns == before  # read, not written: nothing flown again
    items = json.loads((report / "summary.json").read_text())["quantities"]["final_y"]["exceedance"]
    assert [{k: item[k] for k in ("above", "below") if k in item} for item in items] == [{"above": 6.0},
                                                                                         {"below": 1.1}]
    rows = _rows(report / "tables" / "headline_exceedance.csv")
    assert [row["event"] for row in rows] == ["P(final_y > 6)", "P(final_y < 1.1)"]
    for row, item in zip(rows, items):
        assert [float(row[k]) for k in ("probability", "lower", "upper")] == [
            item["probability"], item["lower"], item["upper"]] and item["method"] == "wilson"
    page = (report / "report.html").read_text()
    interval = f"{items[0]['lower']:.3g} to {items[0]['upper']:.3g}"
    assert page.index("P(final_y &gt; 6)") < page.index("Key numbers of") < page.index("<h2>Contents</h2>")
    assert page.index(interval) < page.index("<img")
    assert "None" not in (report / "report.md").read_text()


@pytest.mark.parametrize("value, words", [
    ("nothing>3", ["--exceedance", "'nothing'", "final_y"]),
    ("final_y>abc", ["--exceedance", "NAME>X"]),
    ("final_y>inf", ["--exceedance", "finite"]),
    ("final_y=3", ["--exceedance", "NAME>X"]),
])
def test_a_bad_exceedance_is_refused_naming_the_flag(campaigns, value, words):
    folder, files = campaigns
    done = cli_in_process("report", files["mc"], "--out", folder / "refused", "--exceedance", value)
    assert done.returncode == 2
    assert all(word in done.stderr for word in words), done.stderr
    assert "Traceback" not in done.stderr and not (folder / "refused").exists()


def test_parse_exceedance_option_keeps_the_order_per_quantity():
    assert parse_exceedance_option(["a>1", " b < -2.5 ", "a<0"]) == {"a": [{"above": 1.0}, {"below": 0.0}],
                                                                   "b": [{"below": -2.5}]}


def test_a_quantitys_statistics_are_attributes_as_summary_json(campaigns):
    _, files = campaigns
    stats = uqflight.analyse(files["mc"])
    q = stats.quantities["final_y"]
    entry = json.loads(json.dumps(summary_json(stats)))["quantities"]["final_y"]
    assert q.mean == entry["mean"] and q.std == entry["std"] and q.variance == entry["variance"]
    assert q.band99 == (entry["band99"]["lower"], entry["band99"]["upper"])
    assert {f"{p:g}": v for p, v in q.quantiles.items()} == entry["quantiles"]
    assert q.skewness == entry["skewness"] and q.kurtosis == entry["kurtosis"]
    assert q.exceedance[0]["probability"] == entry["exceedance"][0]["probability"]
    assert q.flags == [] and isinstance(q.mean, float)
    # final y = a + 4b: mean 0 + 4 = 4 exactly; 400 runs: its standard error is sqrt(1/3 + 16/12)/20 = 0.065
    assert abs(q.mean - 4.0) < 4 * 0.065


def test_recorded_times_show_as_asked():
    # JSBSim's clock adds 1/120-s steps: 9.99996 s and 24.9999 s stand for 10 and 25 s at 20 Hz and at 120 Hz
    grid = np.arange(1001) * 0.05
    grid[200], grid[500], grid[-1] = 9.99996, 24.9999, 49.9998
    assert [shown_time(grid, i) for i in (200, 500, 1000, 3)] == [10.0, 25.0, 50.0, 0.15]
    fine = np.arange(3001) / 120 * (1 - 4e-6)
    assert [shown_time(fine, i) for i in (1200, 3000)] == [10.0, 25.0]
    assert shown_time(np.array([0.0, 0.3, 1.7, 2.0]), 2) == 1.7  # off any regular grid: as recorded
    assert shown_time(np.array([3.0]), 0) == 3.0


@pytest.mark.slow
def test_a_changed_campaign_is_refused_naming_the_first_key_and_force(tmp_path):
    text = python_campaign(tmp_path, QUANTITIES, "{kind: monte_carlo, samples: 8}", name="c",
                           analysis="{exceedance: {final_y: [{above: 5}]}}")
    out = tmp_path / "c.h5"
    run_campaign(parse_campaign(text, str(tmp_path / "c.yaml")), out=out)
    changed = text.replace("b: {distribution: uniform, lower: 0.5, upper: 1.5}",
                           "b: {distribution: uniform, lower: 0.5, upper: 1.6}")
    (tmp_path / "c.yaml").write_text(changed)
    refused = cli_in_process("run", tmp_path / "c.yaml", "--out", out)
    assert refused.returncode == 2
    assert "its campaign differs first at parameters.b.upper" in refused.stderr and "--force" in refused.stderr
    assert cli_in_process("run", tmp_path / "c.yaml", "--out", out, "--force").returncode == 0
    (tmp_path / "c.yaml").write_text(changed.replace("take: final", "take: max"))
    refused = cli_in_process("run", tmp_path / "c.yaml", "--out", out)
    assert refused.returncode == 2 and "differs first at quantities.final_y.take" in refused.stderr
    assert "finer than the stored histories" in refused.stderr


@pytest.mark.slow
def test_a_change_of_analysis_alone_resumes_without_flying_again(tmp_path):
    text = python_campaign(tmp_path, QUANTITIES, "{kind: monte_carlo, samples: 8}", name="c",
                           analysis="{exceedance: {final_y: [{above: 5}]}}")
    out = tmp_path / "c.h5"
    run_campaign(parse_campaign(text, str(tmp_path / "c.yaml")), out=out)
    from uqflight.store import ResultStore

    with ResultStore.open(out) as store:
        flown = store.quantity("final_y")
    changed = text.replace("{exceedance: {final_y: [{above: 5}]}}", "{exceedance: {final_y: [{below: 3}]}}")
    summary = run_campaign(parse_campaign(changed, str(tmp_path / "c.yaml")), out=out)
    assert summary.ran == 0 and summary.skipped == 8  # nothing flown again
    stats = uqflight.analyse(out)
    assert list(stats.quantities["final_y"].exceedance[0])[0] == "below"  # the new threshold is read
    with ResultStore.open(out) as store:
        assert store.campaign_text == changed
        np.testing.assert_array_equal(store.quantity("final_y"), flown)  # the runs of the first run


def test_a_flagged_quantity_is_marked_in_the_headline_and_an_unflagged_page_has_no_flags_column(campaigns):
    from uqflight.report.headline import headline_section
    from uqflight.report.loading import load_entries
    from uqflight.report.render import page_view

    _, files = campaigns
    (entry,), _ = load_entries([files["mc"]], None)
    exceedance, key_numbers = headline_section(entry, [float("inf")]).blocks
    assert "flags" not in page_view(key_numbers)[0] and "flags" not in page_view(exceedance)[0]
    quantity = entry.stats.quantities["final_y"]
    quantity.flags.append("band beyond the runs: use least_squares")  # as the analysis flags an expansion's
    quantity.exceedance[0]["flags"].append("band beyond the runs: use least_squares")  # and its draws' fraction
    quantity.exceedance[0]["note"] += "; band beyond the runs: use least_squares"  # with the flag in its note
    exceedance, key_numbers = headline_section(entry, [float("inf")]).blocks
    header, [(_, rows)] = page_view(key_numbers)
    row = next(row for row in rows if row[0].endswith("final_y"))
    assert row[0] == "⚠ final_y" and row[header.index("flags")] == "band beyond the runs: use least_squares"
    header, [(_, rows)] = page_view(exceedance)
    assert rows[0][0] == "⚠ P(final_y > 5)" and rows[0][header.index("flags")].startswith("band beyond")
    assert "band beyond" not in rows[0][header.index("note")]  # said once on the page, in its column


def test_the_python_api_takes_thresholds_too(campaigns):
    _, files = campaigns
    stats = uqflight.analyse(files["mc"], exceedance=["final_y<2", "final_y>6"])
    items = stats.quantities["final_y"].exceedance
    assert [item.get("below", item.get("above")) for item in items] == [2.0, 6.0]
    with pytest.raises(uqflight.analysis.statistics.BadInput, match="--exceedance nothing: no such quantity"):
        uqflight.analyse(files["mc"], exceedance="nothing>1")
    with pytest.raises(ValueError, match="NAME>X"):
        uqflight.analyse(files["mc"], exceedance="final_y~1")
