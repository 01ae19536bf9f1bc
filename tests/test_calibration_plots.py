"""Calibration plots with units, posterior-mean and truth marks, tick labels that do not overlap,
`calibrate --truth` and the calibration's page."""
import json
import re

import numpy as np
import pytest
import typer
from typer.testing import CliRunner

from test_calibration import SIGMA, TIME, TRUTH, results, synthetic, write_csv  # noqa: F401 (results: fixture)
from uqflight.calibration.command import register
from uqflight.calibration.outputs import corner_figure, marginals_figure, predictive_plot
from uqflight.cli.commands import app as uqflight_app
from uqflight.text.labels import parameter_label, parameter_unit

PROPERTIES = ["aero/uq/CL0", "aero/uq/CLalpha", "aero/uq/k1", "aero/uq/Cm0", "aero/uq/Cmq"]
NAMES = ["CL0", "CLalpha", "k1", "Cm0", "Cmq"]
# posterior-like draws on the BACM's scales: long tick labels such as -0.01052 and -22.04
CENTRES, SPREADS = np.array([0.2, 5.3, -0.0105, 0.0605, -22.0]), np.array([0.0012, 0.0098, 0.0023, 0.0021, 0.038])


def draws(n=4000, seed=0):
    return CENTRES + SPREADS * np.random.default_rng(seed).standard_normal((n, len(NAMES)))


def test_parameter_units():
    assert [parameter_unit(p) for p in ("aero/uq/CLalpha", "aero/uq/CL0", "aero/uq/scale/CLwbh", "inertia/weight-lbs",
                                        "velocities/q-aero-rad_sec", "aero/uq/offset_value/X")] == \
        ["1/rad", "-", "-", "lbs", "rad/s", ""]
    assert parameter_label("Cmq", "aero/uq/Cmq") == "Cmq [1/rad]"


def overlapping_ticks(fig) -> list:
    """Pairs of visible tick labels of one axis whose drawn boxes intersect."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    found = []
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            boxes = [t.get_window_extent(renderer) for t in axis.get_ticklabels() if t.get_visible() and t.get_text()]
            found += [(ax.get_xlabel(), a, b) for k, a in enumerate(boxes) for b in boxes[k + 1:] if a.overlaps(b)]
    return found


@pytest.mark.slow
def test_corner_and_marginals_have_units_marks_and_readable_ticks():
    truth = np.array([0.201, np.nan, np.nan, np.nan, -22.01])
    fig = corner_figure(draws(), NAMES, truth, properties=PROPERTIES)
    assert not overlapping_ticks(fig)
    labels = {ax.get_xlabel() for ax in fig.axes} | {ax.get_ylabel() for ax in fig.axes}
    assert {"CL0 [-]", "CLalpha [1/rad]", "Cmq [1/rad]"} <= labels
    assert [t.get_text() for t in fig.legends[0].get_texts()] == ["posterior mean", "truth (--truth)"]
    diagonal = fig.axes[0]  # CL0's histogram: the mean dashed black, the truth red
    assert [tuple(line.get_xdata()) for line in diagonal.get_lines()] == [(pytest.approx(draws()[:, 0].mean()),) * 2,
                                                                          (0.201, 0.201)]
    prior = CENTRES + 3 * SPREADS * np.random.default_rng(1).standard_normal((4000, len(NAMES)))
    fig = marginals_figure(prior, draws(), NAMES, truth, properties=PROPERTIES)
    assert not overlapping_ticks(fig)
    assert [t.get_text() for t in fig.legends[0].get_texts()] == ["prior", "posterior", "posterior mean",
                                                                  "truth (--truth)"]
    assert fig.axes[4].get_xlabel() == "Cmq [1/rad]"


def test_predictive_labels_say_the_unit_once(tmp_path):
    time = np.linspace(0, 1, 11)
    runs = {"alpha_deg": np.ones((3, 11)), "h_ft": 15000 + np.ones((3, 11))}
    path = tmp_path / "predictive.svg"
    predictive_plot(path, time, {k: v[0] for k, v in runs.items()}, runs,
                    {k: (v[0] - 1, v[0] + 1) for k, v in runs.items()}, {"alpha_deg": "deg", "h_ft": "ft"}, 0)
    source = path.read_text()
    texts = re.findall(r"<text[^>]*>([^<]*)</text>", source) + re.findall(r"<!-- (.*?) -->", source)
    assert "angle of attack α [deg]" in texts and "altitude h − median run [ft]" in texts
    assert not any("alpha_deg [deg]" in t for t in texts)


def app():
    """A typer app with `calibrate` and the page `uqflight calibrate` writes."""
    from uqflight.report.calibration_page import write_calibration_page

    application = typer.Typer()
    register(application, page=write_calibration_page)

    @application.callback()
    def main():
        """test app"""

    return application


def test_truth_is_refused_when_malformed_repeated_or_unknown(results, tmp_path):  # noqa: F811
    data = tmp_path / "flight.csv"
    write_csv(data, TIME, synthetic(1))
    for items, message in ((["zz=1"], "--truth zz: not one of the parameters"), (["a=x"], "expected NAME=VALUE"),
                           (["a=1", "a=2"], "--truth a: given twice"), (["a=inf"], "finite VALUE")):
        run = CliRunner().invoke(app(), ["calibrate", str(results), "--data", str(data), "--out", str(tmp_path / "o"),
                                         *(f"--truth={item}" for item in items)])
        assert run.exit_code == 2 and message in run.output, (items, run.output)
    assert not (tmp_path / "o" / "summary.json").exists()


def test_the_cli_registers_the_calibration_page():
    from uqflight.calibration import command

    assert "calibrate" in [c.name for c in uqflight_app.registered_commands] and command._page[0] is not None


@pytest.mark.slow
def test_calibration_page_with_truth(results, tmp_path):  # noqa: F811
    data = tmp_path / "flight.csv"
    write_csv(data, TIME, synthetic(1))
    out = tmp_path / "out"
    run = CliRunner().invoke(app(), ["calibrate", str(results), "--data", str(data), "--out", str(out),
                                     "--noise", f"y={SIGMA}", "--steps", "2000", "--predictive-draws", "20",
                                     "--truth", f"a={TRUTH['a']}", "--truth", f"b={TRUTH['b']}"])
    assert run.exit_code == 0, run.output
    assert "report.html" in run.output
    summary = json.loads((out / "summary.json").read_text())
    assert summary["parameters"]["a"]["truth"] == TRUTH["a"] and summary["parameters"]["a"]["truth_in_ci95"]
    page = (out / "report.html").read_text()
    assert page.count('src="data:image/png;base64,') == 3 and re.findall(r'src="(?!data:)', page) == []
    assert "<th>truth in 95 %</th>" in page and "Sampler diagnostics" in page and f"<td>{TRUTH['b']}</td>" in page
