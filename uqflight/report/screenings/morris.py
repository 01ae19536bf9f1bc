"""The report's section on a Morris design's screening: per file, μ* (with its bootstrap 95 % interval) against
σ per input, one panel for each quantity and each output at the selected times (the classic Morris plot),
and a table of μ*, its interval, μ and σ; and the headline's ranking of the inputs by μ*."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .. import plots
from ..blocks import Figure, Section, Table, _rel
from ..loading import AnalysedFile, file_name_within
from ...text.labels import shown_time
from . import SCREENINGS, ScreeningPage


def ranked_text(morris: dict, i: int) -> str:
    """The inputs ranked by μ* at time index `i`, e.g. "x2 6, x3 2, x1 1.1 (μ*)"; those undefined last.

    Parameters
    ----------
    morris : dict
        An output's or quantity's Morris measures (OutputStatistics.screening.measures).
    i : int
        The time index.

    Returns
    -------
    str
        The page's text.
    """
    values = {name: float(measures["mu_star"][i]) for name, measures in morris.items()}
    order = sorted(values, key=lambda name: (not np.isfinite(values[name]), -values[name]))
    return ", ".join(f"{name} {_number(values[name])}" for name in order) + " (μ*)"


def _number(value) -> str:
    return "null" if value is None or not np.isfinite(value) else f"{value:.3g}"


def _panels_of(entry: AnalysedFile, times: list[float]) -> list[tuple[str, dict, int]]:
    """(panel title, measures, time index) for each quantity and each output at the selected times."""
    panels = [(f"quantity {name}", q.output.screening.measures, 0) for name, q in entry.stats.quantities.items()
              if q.output is not None and q.output.screening]
    for name, out in entry.outputs.items():
        if out.screening:
            panels += [(f"{name} at t = {shown_time(out.time, i):g} s", out.screening.measures, i)
                       for i in plots.time_indices(out.time, times)]
    return panels


def plot_morris(panels: list[tuple[str, dict, int]], path: Path, title: str) -> Path:
    """μ* (its interval as a horizontal bar) against σ per input, one panel each, the line σ = μ* dashed: inputs
    far right matter, and those high above the axis act through interactions or nonlinearly."""
    fig, axes = plots._panels(len(panels), title, row_height=3.4)
    names = list(panels[0][1])
    for ax, (caption, morris, i) in zip(axes, panels):
        top = 0.0
        for k, name in enumerate(names):
            measures = morris[name]
            mu_star, sigma = float(measures["mu_star"][i]), float(measures["sigma"][i])
            lower, upper = float(measures["mu_star_ci"]["lower"][i]), float(measures["mu_star_ci"]["upper"][i])
            if not (np.isfinite(mu_star) and np.isfinite(sigma)):
                continue
            color = plots.COLORS[k % len(plots.COLORS)]
            ax.errorbar(mu_star, sigma, xerr=[[max(mu_star - lower, 0.0)], [max(upper - mu_star, 0.0)]], fmt="o",
                        color=color, ms=5, capsize=3, label=name)
            ax.annotate(name, (mu_star, sigma), textcoords="offset points", xytext=(4, 4), fontsize=7, color=color)
            top = max(top, upper, sigma)
        top = top or 1.0
        ax.plot([0, 1.05 * top], [0, 1.05 * top], "--", color="grey", lw=0.8)
        ax.set_xlim(0, 1.08 * top)
        ax.set_ylim(0, 1.08 * top)
        ax.set_xlabel("μ* (mean |elementary effect|)", fontsize=8)
        ax.set_ylabel("σ of the elementary effects", fontsize=8)
        ax.set_title(caption, fontsize=9)
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3)
    handles = [plots.Line2D([], [], marker="o", ls="", color=plots.COLORS[k % len(plots.COLORS)])
               for k in range(len(names))]
    return plots._save(fig, path, (handles, names), legend_columns=6)


def morris_section(entries: list[AnalysedFile], times: list[float], out_dir: Path) -> Section:
    """The Morris screening of the entries whose statistics carry it (OutputStatistics.screening)."""
    blocks, rows, page = [], [], []
    for entry in entries:
        panels = _panels_of(entry, times)
        if not panels:
            continue
        path = plot_morris(panels, out_dir / "plots" / file_name_within(f"morris_{entry.stem}.png"),
                           f"Morris screening: {entry.label}")
        blocks.append(Figure(_rel(path, out_dir), f"μ* against σ of the elementary effects per input, for each "
                             f"quantity and each output at the selected times, of {entry.label}; the bars are μ*'s "
                             "bootstrap 95 % intervals (resampling the trajectories), the dashed line σ = μ*."))
        for caption, morris, i in panels:
            for name in sorted(morris, key=lambda p: -np.nan_to_num(float(morris[p]["mu_star"][i]), nan=-np.inf)):
                m = morris[name]
                values = [float(m["mu_star"][i]), float(m["mu_star_ci"]["lower"][i]),
                          float(m["mu_star_ci"]["upper"][i]), float(m["mu"][i]), float(m["sigma"][i])]
                rows.append([entry.label, caption, name, *values])
                page.append([entry.label, caption, name, *map(_number, values)])
    header = ["file", "output or quantity", "parameter", "mu_star", "mu_star 95 % lower", "mu_star 95 % upper", "mu",
              "sigma"]
    blocks.append(Table("Morris measures, inputs by decreasing μ*", header, rows, "tables/morris.csv",
                        page=(["file", "output or quantity", "parameter", "μ*", "μ* 95 % lower", "μ* 95 % upper",
                               "μ", "σ"], page), grouped=True))
    return Section("Morris screening", "morris",
                   "Elementary effects EE = Δy/Δ of each input's move by the grid jump Δ in its probability scale "
                   "(docs/designs.md): μ* = mean |EE| ranks the inputs, μ = mean EE keeps the sign, σ > 0 marks "
                   "interactions or nonlinearity. A Morris design gives no Sobol' indices.", blocks)


SCREENINGS["morris"] = ScreeningPage(
    morris_section, ranked_text, "inputs ranked by μ* (Morris)",
    "; with a Morris design, the inputs ranked by μ*, the mean absolute elementary effect, instead of Sobol' shares",
    "drawing the Morris screening")
