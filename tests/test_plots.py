"""The report's figures are readable: plain log labels, the KLD floor, informative error decades,
methods told apart, differences instead of overlapping bands, the design in physical values, std
for offset-datum outputs, white PDF backgrounds, coefficient decay from degree 1 and the pulse on,
and the figure formats. Checked on the saved files (SVG text, PNG pixels), not on golden images."""
import html
import re
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from matplotlib.image import imread

from conftest import cli_in_process
from test_report import run
from uqflight.analysis.statistics import read_statistics
from uqflight.report import plots, write_report
from uqflight.report.formats import exporting
from uqflight.report.loading import load_entries
from uqflight.report.render import figure_html
from uqflight.report.blocks import Figure

PHUGOID = """
name: phugoid-{name}
seed: {seed}
simulator: {{kind: python, function: "uqflight.simulators.models:phugoid"}}
parameters:
  a: {{distribution: normal, lower: -3, upper: 3}}
  b: {{distribution: normal, lower: -3, upper: 3}}
  c: {{distribution: normal, lower: -3, upper: 3}}
design: {design}
method: {method}
analysis: {{band_samples: 1000}}
"""


@pytest.fixture(scope="module")
def files(tmp_path_factory) -> dict[str, Path]:
    root = tmp_path_factory.mktemp("phugoid")
    mc = "{kind: monte_carlo, samples: %d}"
    return {"grid": run(PHUGOID, root / "grid.h5", name="grid", design="{kind: sparse_grid, rule: gauss_hermite, level: 2}",
                        method="{kind: pseudo_galerkin, order: 2}", seed=1),
            "mc": run(PHUGOID, root / "mc.h5", name="mc", design=mc % 120, method="{kind: monte_carlo}", seed=2)}


@pytest.fixture(scope="module")
def entries(files, tmp_path_factory):
    """The grid (PG) and a Monte Carlo file against a larger Monte Carlo file (flown for these only)."""
    ref = run(PHUGOID, tmp_path_factory.mktemp("reference") / "ref.h5", name="ref",
              design="{kind: monte_carlo, samples: 300}", method="{kind: monte_carlo}", seed=3)
    return load_entries([files["grid"], files["mc"]], ref, None)


def svg_texts(path: Path) -> list[str]:
    """Every text of an SVG figure: <text> elements (svg.fonttype none) and mathtext's comments."""
    source = path.read_text(encoding="utf-8")
    return [html.unescape(t) for t in re.findall(r"<text[^>]*>([^<]*)</text>", source)] + \
        re.findall(r"<!-- (.*?) -->", source)


def drawn_runs(results: Path):
    """The runs the report draws of `results` (Statistics.drawn)."""
    return read_statistics(results, scatter_time=float("inf"))[0].drawn


def draw_svg(function, *args, **kwargs) -> Path:
    with exporting("svg"):
        return function(*args, **kwargs)


def test_tick_text_is_plain():
    assert [plots.tick_text(v) for v in (0.002, 60, 113, 1.0, 2e-5, 1e8, 0.0)] == \
        ["0.002", "60", "113", "1", "2×10⁻⁵", "10⁸", ""]


@pytest.mark.slow
def test_log_axes_have_plain_majors_and_the_kld_floor(entries, tmp_path):
    grid, mc = entries[0][0], entries[0][1]
    points = [(e.label, e.stats.runs, {n: (o.errors["kld_final"], o.errors["kld_floor"])
                                        for n, o in e.outputs.items()}) for e in (grid, mc)]
    texts = svg_texts(draw_svg(plots.plot_kld_vs_runs, points, tmp_path / "kld.png", "KLD"))
    assert not any("times" in t or "mathdefault" in t for t in texts), texts  # no mathtext 6×10¹ minor labels
    assert {str(grid.stats.runs), str(mc.stats.runs)} <= set(texts)  # the run counts are the runs axis's ticks
    assert "reference KLD floor (below it: sampling noise)" in texts
    points = [(e.label, e.stats.runs, {n: (o.errors["eps_m_summary"]["max"], o.errors["eps_v_summary"]["max"],
                                           None, None) for n, o in e.outputs.items()}) for e in (grid, mc)]
    texts = svg_texts(draw_svg(plots.plot_convergence, points, tmp_path / "convergence.png", "convergence"))
    assert not any("times" in t or "mathdefault" in t for t in texts)


def test_error_axes_span_the_lines_only():
    time = np.linspace(0, 50, 1001)
    high, low = np.full_like(time, 1e8), 0.1 + 0.05 * np.sin(time)
    low[0] = 1e-14  # a deterministic instant (t = 0): not allowed to stretch the axis
    bottom, top = plots.informative_limits([high, low])
    # the lowest line's 2 % quantile (about 0.05) halved, and 1.5 × the top: no empty decades below
    assert 0.02 < bottom < 0.05 and top == pytest.approx(1.5e8)
    assert plots.informative_limits([np.zeros(3)]) is None


def test_methods_differ_in_marker_and_dash():
    styles = [plots.method_style(k) for k in range(6)]
    assert len({s["marker"] for s in styles}) == 6 and len({s["color"] for s in styles}) == 6
    assert all(styles[k]["ls"] != styles[k + 1]["ls"] for k in range(5))


@pytest.mark.slow
def test_band_comparison_is_a_difference_plot(entries, tmp_path):
    labelled = [(e.label, e.outputs) for e in entries[0]]
    texts = svg_texts(draw_svg(plots.plot_band_comparison, labelled, tmp_path / "bands.png", "bands"))
    assert "altitude h: mean − the first file's" in texts
    assert "altitude h: 99 % band edges − the first file's" in texts
    assert f"{labelled[0][0]} (first: the zero line)" in texts


def test_offset_datum_rule():
    time = np.linspace(0, 50, 1001)
    assert plots.offset_datum(SimpleNamespace(mean=15000 + 50 * np.sin(time)))  # 15000 > 10 × 100
    assert not plots.offset_datum(SimpleNamespace(mean=5 + 0.3 * np.sin(time)))  # 4.7 < 10 × 0.6
    assert not plots.offset_datum(SimpleNamespace(mean=np.array([15000.0])))  # a scalar output keeps its CoV


@pytest.mark.slow
def test_cov_draws_offset_datum_outputs_as_std(entries, tmp_path):
    outputs = entries[0][0].outputs
    datum = {name for name, out in outputs.items() if plots.offset_datum(out)}
    assert {"h_ft", "vtas_kt"} <= datum and not {"theta_deg", "q_degps"} & datum
    texts = svg_texts(draw_svg(plots.plot_cov, outputs, tmp_path / "cov.png", "spread"))
    assert "std(t) in the output's unit (log scale)" in texts and "std(t) / max |mean| [%] (log scale)" in texts
    assert texts.index("std(t) in the output's unit (log scale)") < texts.index("altitude h [ft]")  # in the right panel, with its unit


@pytest.mark.slow
def test_pdf_heat_map_is_white_where_density_is_low(entries, tmp_path):
    out = entries[0][0].outputs["alpha_deg"]
    image = imread(plots.plot_pdf_over_time(out, tmp_path / "pdf.png", "PDF", [10.0]))
    dark = (image[..., :3].max(axis=2) < 0.15).mean()
    assert dark < 0.05, dark  # magma drew low density black: about a third of the picture


@pytest.mark.slow
def test_coefficient_decay_from_degree_one_and_the_pulse(entries, tmp_path):
    texts = svg_texts(draw_svg(plots.plot_coefficient_decay, entries[0][0].outputs, tmp_path / "decay.png", "decay",
                               start_s=1.0))
    assert "degree 1" in texts and "degree 0" not in texts


def test_coefficient_decay_times_start_at_the_pulse():
    time = np.linspace(0, 10, 101)
    rising = np.where(time < 2.0, 1e-12, 1.0)
    assert plots._decay_times(time, [rising], 1.0).nonzero()[0][0] == 10  # t = 1.0 s, the pulse's start
    assert plots._decay_times(time, [rising], None).nonzero()[0][0] == 20  # where the variation starts


@pytest.mark.slow
def test_symmetric_grid_design_is_drawn_once_with_physical_values(files, tmp_path):
    path = draw_svg(plots.plot_design_pairs, drawn_runs(files["grid"]), tmp_path / "design.png", "Design: sparse_grid")
    texts = svg_texts(path)
    assert "all 3 pairs of the 3 inputs coincide: drawn once" in texts
    assert "physical value κ of each input at each ξ level" in texts
    assert any(t.startswith("negative weight: ") for t in texts) and "failed run: 0" in texts
    path = draw_svg(plots.plot_design_pairs, drawn_runs(files["mc"]), tmp_path / "design_mc.png", "Design: monte_carlo, 120 points")
    width = float(re.search(r'<svg[^>]* width="([\d.]+)pt"', path.read_text()).group(1))
    assert width >= 7 * 72  # wide enough for its title (a 2-input design was 2.9 in: "esign: monte_carlo…")
    assert any("physical values κ" in t for t in svg_texts(path))


@pytest.mark.slow
def test_report_format_svg_embeds_svg_and_pdf_links_pdf(files, tmp_path):
    out = tmp_path / "report"
    write_report([files["grid"]], out, fmt="svg")
    assert not list((out / "plots").glob("*.png")) and list((out / "plots").glob("*.svg"))
    page = (out / "report.html").read_text()
    assert page.count("data:image/svg+xml;base64,") == len(list((out / "plots").glob("*.svg")))
    with exporting("pdf"):
        shown = plots.plot_cov(load_entries([files["grid"]], None, None)[0][0].outputs, tmp_path / "cov.png", "c")
    assert shown.suffix == ".png" and shown.with_suffix(".pdf").read_bytes().startswith(b"%PDF")
    assert 'href="cov.pdf">PDF</a>' in figure_html("f", Figure(shown.name, "caption"), tmp_path)


def test_report_refuses_an_unknown_format(files, tmp_path):
    result = cli_in_process("report", files["grid"], "--out", tmp_path / "r", "--format", "gif")
    assert result.returncode == 2 and "--format" in result.stderr and "gif" in result.stderr
    assert not (tmp_path / "r").exists()


@pytest.mark.slow
def test_pdfs_drawn_on_one_figure_have_the_pixels_of_a_figure_each(decay_results, tmp_path):
    # the reused figure must forget the previous output: its limits, labels, legend and title
    import dataclasses

    (entry,), _ = load_entries([decay_results], None)
    x = entry.outputs["x"]
    scale = 1000.0  # an output far from the first one's range, in another unit, drawn about its mean
    big = dataclasses.replace(x, name="h_ft", units="ft", mean=15000 + scale * x.mean, variance=scale**2 * x.variance,
                              band99=tuple(15000 + scale * b for b in x.band99), pdf_support=15000 + scale * x.pdf_support,
                              pdf_density=x.pdf_density / scale)
    alone = {out.name: imread(plots.plot_pdf_over_time(out, tmp_path / f"alone_{out.name}.png", f"PDF {out.name}",
                                                       [1.0, 3.0])) for out in (x, big)}
    for order in ((x, big), (big, x)):
        shared = plots.plot_pdfs_over_time([(out, tmp_path / f"shared_{out.name}.png", f"PDF {out.name}")
                                            for out in order], [1.0, 3.0])
        for out, path in zip(order, shared):
            np.testing.assert_array_equal(imread(path), alone[out.name])


def test_the_cycle_collector_is_off_while_drawing_and_collects_on_leaving():
    import gc
    import weakref

    class Node:
        pass

    assert gc.isenabled()
    with plots.collecting_at_the_end():
        assert not gc.isenabled()
        node = Node()
        node.me = node  # a cycle: only the collector frees it
        alive = weakref.ref(node)
        del node
        assert alive() is not None
    assert gc.isenabled() and alive() is None
