"""The report's section on the quantities of interest: a table of their statistics, their PDFs, their
Sobol' indices as bars, and the exceedance probabilities asked for (`analysis.exceedance`)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.patches import Patch

from ..analysis.sobol import unresolved
from . import plots
from .sensitivity import N_TOO_SMALL, UNRESOLVED
from .loading import AnalysedFile, file_name_within
from .blocks import Figure, Section, Table, _rel
from .headline import interval_text, probability_text


def _top_index(out) -> tuple[str, float | str] | tuple[None, None]:
    """The parameter with the largest total Sobol' index and that index (None where there are none); among
    pick-freeze indices those their interval resolves (analysis.sobol.unresolved), the index text
    "unresolved (n too small)" when none is."""
    finite = {p: float(v[0]) for p, v in (out.sobol_total or {}).items() if np.isfinite(v[0])}
    if out.sobol_total_ci:
        loose = {p for p in finite if unresolved(finite[p], out.sobol_total_ci[p][:, 0])}
        if loose and len(loose) == len(finite):
            return ", ".join(sorted(loose)), f"{UNRESOLVED} ({N_TOO_SMALL})"
        finite = {p: v for p, v in finite.items() if p not in loose}
    if not finite:
        return None, None
    top = max(finite, key=finite.get)
    return top, finite[top]


THRESHOLD_COLOR = "#c0392b"


def threshold_label(item: dict) -> str:
    """A threshold's label on a PDF: "P(> 4.5) = 0.021" (its event and probability)."""
    bound = "above" if "above" in item else "below"
    p = item.get("probability")
    shown = "null" if p is None or not np.isfinite(p) else f"{p:.3g}"
    return f"P({'>' if bound == 'above' else '<'} {item[bound]:g}) = {shown}"


def plot_quantity_pdfs(quantities: dict, path: Path, title: str, thresholds: dict | None = None) -> Path:
    """One panel per quantity: its PDF, the mean and the 99 % band marked, and each exceedance threshold
    (`thresholds`: {name: [exceedance items]}) as a labelled vertical line with its probability."""
    thresholds = thresholds or {}
    fig, axes = plots._panels(len(quantities), title, row_height=2.7)
    for ax, (name, out) in zip(axes, quantities.items()):
        ax.plot(out.pdf_support[0], out.pdf_density[0], color=plots.COLORS[0], lw=1.3)
        ax.axvline(out.mean[0], color="k", lw=1.0, label="mean")
        for bound in out.band99:
            ax.axvline(bound[0], color="k", lw=0.9, ls="--")
        for item in thresholds.get(name, []):
            value = item["above" if "above" in item else "below"]
            ax.axvline(value, color=THRESHOLD_COLOR, lw=1.3, ls=":")
            ax.annotate(threshold_label(item), (value, 1.0), xycoords=("data", "axes fraction"), xytext=(3, -3),
                        textcoords="offset points", ha="left", va="top", fontsize=7, color=THRESHOLD_COLOR,
                        rotation=90, bbox={"facecolor": "white", "edgecolor": "none", "alpha": 0.8, "pad": 0.5})
        ax.set_title(name, fontsize=10)
        ax.set_xlabel(plots.label(name, out.units), fontsize=8)
        ax.set_ylabel(f"probability density [1/{out.units}]" if out.units else "probability density", fontsize=8)
        ax.tick_params(labelsize=8)
        ax.grid(alpha=0.3)
    return plots._save(fig, path)


def plot_quantity_sobol(quantities: dict, path: Path, title: str) -> Path:
    """One panel per quantity: first-order and total Sobol' indices per parameter, as bars (unresolved
    variance: none), with their pick-freeze 95 % intervals unclipped and the indices those intervals do
    not resolve hatched, "n too small" (plots.index_bars)."""
    fig, axes = plots._panels(len(quantities), title, row_height=2.7)
    for ax, (name, out) in zip(axes, quantities.items()):
        parameters = list(out.sobol_first)
        x = np.arange(len(parameters))
        drawn = []
        for shift, color, indices, intervals in ((-0.2, plots.COLORS[0], out.sobol_first, out.sobol_first_ci),
                                                 (0.2, plots.COLORS[1], out.sobol_total, out.sobol_total_ci)):
            drawn += plots.index_bars(ax, x + shift, [indices[p] for p in parameters],
                                      [intervals[p] for p in parameters] if intervals else None, color, 0.4)
        ax.set_xticks(x, parameters, fontsize=8, rotation=30 if max(map(len, parameters)) > 4 else 0)
        plots.index_axis(ax, drawn)
        ax.set_title(name, fontsize=10)
        ax.set_ylabel("Sobol' index [-]", fontsize=8)
        ax.tick_params(labelsize=8)
        ax.grid(alpha=0.3, axis="y")
    handles = [plots.Line2D([], [], color=plots.COLORS[k], lw=6) for k in (0, 1)]
    handles.append(Patch(facecolor="white", edgecolor="k", hatch=plots.UNRESOLVED_HATCH))
    return plots._save(fig, path, (handles, ["first order S_i", "total S_Ti", "95 % interval wider than 0.5 or "
                                             "outside [0, 1]: n too small"]), legend_columns=3)


def quantities_section(entries: list[AnalysedFile], out_dir: Path) -> Section:
    """The quantities of every file: statistics table, PDFs, Sobol' bars, exceedance table."""
    blocks, statistics, exceedance = [], [], []
    for entry in entries:
        quantities = entry.stats.quantities
        for name, quantity in quantities.items():
            out = quantity.output
            if out is None:
                statistics.append([entry.label, name, quantity.missing, *[None] * 6])
            else:
                top, index = _top_index(out)
                statistics.append([entry.label, name, quantity.missing, out.mean[0], out.std[0], out.band99[0][0],
                                   out.band99[1][0], top, index])
            for item in quantity.exceedance:
                bound = "above" if "above" in item else "below"
                exceedance.append([entry.label, name, f"{bound} {item[bound]:g}", item["probability"], item["lower"],
                                   item["upper"], item["method"], item["note"]])
        defined = {name: q.output for name, q in quantities.items() if q.output is not None}
        if defined:
            thresholds = {name: q.exceedance for name, q in quantities.items() if q.exceedance}
            path = plot_quantity_pdfs(defined, out_dir / "plots" / file_name_within(f"quantity_pdfs_{entry.stem}.png"),
                                      f"Quantities of interest: {entry.label}", thresholds)
            blocks.append(Figure(_rel(path, out_dir), f"PDFs of the quantities of {entry.label} (kernel density "
                                                      "estimate), the mean solid, the 99 % band dashed"
                                 + (", each exceedance threshold dotted red with its probability." if thresholds
                                    else ".")))
        with_sobol = {name: out for name, out in defined.items() if out.sobol_first}
        if with_sobol:
            path = plot_quantity_sobol(with_sobol, out_dir / "plots" / file_name_within(f"quantity_sobol_{entry.stem}.png"),
                                       f"Sobol' indices of the quantities: {entry.label}")
            blocks.append(Figure(_rel(path, out_dir), f"First-order and total Sobol' indices of the quantities of "
                                                      f"{entry.label}, with their 95 % bootstrap intervals (pick-freeze) drawn "
                                                      "unclipped; an index whose interval is wider than 0.5 or lies "
                                                      "outside [0, 1] is hatched, 'n too small'; the index of an "
                                                      "unresolved variance is drawn as none."))
    blocks.insert(0, Table("Quantities of interest: one number per run", [
        "file", "quantity", "missing runs", "mean", "std", "band99 lower", "band99 upper",
        "top total Sobol' index", "its value"], statistics, "tables/quantities.csv"))
    if exceedance:
        page = [[label, name, event, probability_text(p), interval_text(lower, upper), method or "", note]
                for label, name, event, p, lower, upper, method, note in exceedance]
        blocks.insert(1, Table("Exceedance probabilities (analysis.exceedance, report --exceedance)", [
            "file", "quantity", "event", "probability", "lower", "upper", "method", "note"],
            exceedance, "tables/exceedance.csv",
            page=(["file", "quantity", "event", "probability", "95 % interval", "method", "note"], page)))
    return Section("Quantities of interest", "quantities",
                   "Computed in the worker at every integration step (or time point of a Python model); "
                   "their statistics are those of an output with one time point. Missing runs: successful runs "
                   "where the quantity is undefined (its condition never held).", blocks)
