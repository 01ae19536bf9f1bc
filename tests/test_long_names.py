"""Any output name `run` accepts gives a report: file names built from names stay within 255 bytes of UTF-8
(a long one cut, with a hash of the whole), short ones as they always were; `info` lists names one entry each."""
import csv
import shutil

import pytest
from conftest import cli_in_process

from uqflight.text.console import quoted_name
from uqflight.report.loading import file_name_within

LONG = "L" * 300
SHARED = "L" * 250 + "M" * 50  # the first 250 characters of LONG
FORGED = "y\noutputs: forged"
MODEL = f'''
import numpy as np

def f(p):
    t = np.linspace(0.0, 1.0, 5)
    a = p["x"] + 2.0
    return {{"time": t, {LONG!r}: a * t, {SHARED!r}: 2 * a * t, "α" * 150: a + t, "β" * 150: a + 2 * t,
            "alpha_deg": a * a * t, {FORGED!r}: t}}

def g(p):
    return {{"time": [0.0, 1.0], "y": [p["x"], p["x"] + 1]}}
'''
CAMPAIGN = """name: names
seed: 3
simulator: {kind: python, function: "model.py:f"}
parameters:
  x: {distribution: uniform, lower: -1, upper: 1}
design: {kind: monte_carlo, samples: 8}
execution: {workers: 1, chunk: 4}
analysis: {band_samples: 200, bootstrap: 0}
"""


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    folder = tmp_path_factory.mktemp("names")
    (folder / "model.py").write_text(MODEL, encoding="utf-8")
    (folder / "c.yaml").write_text(CAMPAIGN)
    ran = cli_in_process("run", folder / "c.yaml", "--out", folder / "r.h5", cwd=folder)
    assert ran.returncode == 0, ran.stderr
    (folder / "one.yaml").write_text(CAMPAIGN.replace("model.py:f", "model.py:g"))
    ran = cli_in_process("run", folder / "one.yaml", "--out", folder / "one.h5", cwd=folder)
    assert ran.returncode == 0, ran.stderr
    return folder


def _means(path) -> list[float]:
    with open(path, newline="", encoding="utf-8") as fh:
        return [float(row["mean"]) for row in csv.DictReader(fh)]


def _names(out) -> list[str]:
    return [p.name for p in out.rglob("*")]


@pytest.mark.slow
def test_report_of_long_names_has_bounded_distinct_files(folder):
    out = folder / "rep"
    done = cli_in_process("report", folder / "r.h5", "--out", out)
    assert done.returncode == 0, done.stderr
    assert max(len(n.encode()) for n in _names(out)) <= 255
    tables = out / "tables"
    assert len(list(tables.glob("statistics_r_*.csv"))) == 6  # one per output: none written over another
    long, shared = tables / file_name_within(f"statistics_r_{LONG}.csv"), tables / file_name_within(f"statistics_r_{SHARED}.csv")
    assert long != shared and long.name.startswith("statistics_r_" + "L" * 200) and len(long.name) == 255
    assert _means(shared) == pytest.approx([2 * m for m in _means(long)]) and _means(long)[-1] > 0
    assert (out / "plots" / file_name_within(f"pdf_r_{LONG}.png")).is_file()
    alpha, beta = tables / f"statistics_r_{'_' * 150}.csv", tables / f"statistics_r_{'_' * 150}-2.csv"
    assert _means(beta)[-1] == pytest.approx(_means(alpha)[-1] + 1)  # "α"*150 and "β"*150 each its own
    for short in ("tables/statistics_r_alpha_deg.csv", "plots/pdf_r_alpha_deg.png", "plots/mean_band_r.png"):
        assert (out / short).is_file(), short


@pytest.mark.slow
def test_long_results_file_stems(folder):
    """A stem of 252 bytes, ASCII and UTF-8: tables, summaries/ and the default report folder stay within 255."""
    ascii_stem, utf8_stem = folder / ("S" * 252 + ".h5"), folder / ("α" * 126 + ".h5")
    for path in (ascii_stem, utf8_stem):
        shutil.copy(folder / "one.h5", path)  # one output: a quick report
    out = folder / "both"
    done = cli_in_process("report", ascii_stem, utf8_stem, "--out", out)
    assert done.returncode == 0, done.stderr
    assert max(len(n.encode()) for n in _names(out)) <= 255
    assert len(list((out / "summaries").glob("*.json"))) == 2
    done = cli_in_process("report", utf8_stem)  # the default folder: RESULTS-report, cut
    assert done.returncode == 0, done.stderr
    [report] = folder.glob("α*-report")
    assert len(report.name.encode()) <= 192 and (report / "report.html").is_file()


def test_too_long_report_folder_refused_before_any_work(folder):
    out = folder / ("o" * 230)
    done = cli_in_process("report", folder / "r.h5", "--out", out)
    assert done.returncode == 2 and "choose a shorter --out" in done.stderr, done.stderr
    assert "analysing" not in done.stderr and not out.exists()


def test_bounded_cuts_utf8_between_characters():
    name = file_name_within("α" * 200 + ".png")
    assert len(name.encode()) <= 255 and name.endswith(".png") and name.startswith("α" * 100)
    assert file_name_within("x" * 251 + ".png") == "x" * 251 + ".png"


def test_info_lists_names_one_entry_each(folder):
    done = cli_in_process("info", folder / "r.h5")
    assert done.returncode == 0, done.stderr
    [outputs] = [line for line in done.stdout.splitlines() if line.startswith("outputs:")]
    assert "alpha_deg, 'y\\noutputs: forged' (5 times" in outputs
    assert [quoted_name(n) for n in ("a_b", "a, b", " a", "it's", "\x1b[2J", "")] == \
           ["a_b", "'a, b'", "' a'", '"it\'s"', "'\\x1b[2J'", "''"]
