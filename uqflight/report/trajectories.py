"""The runs themselves: a spaghetti plot of a seeded subset of runs per output with the mean and the 99 %
band, and each output (at one time) and each quantity against the inputs in physical values (κ),
coloured by the most influential other input. The runs come with the statistics
(Statistics.drawn, analysis.drawn): only the drawn runs were read (or rebuilt from the tSVD factors)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.collections import LineCollection
from matplotlib.lines import Line2D
from matplotlib.ticker import MaxNLocator

from ..analysis.drawn import SCATTER_RUNS, SPAGHETTI_RUNS, DrawnRuns
from . import plots

SCATTER_INPUTS = 2  # inputs shown per output: the most influential
COLOR_MAP = "viridis"


def plot_spaghetti(drawn: DrawnRuns, outputs: dict, path: Path, title: str) -> tuple[Path, int]:
    """One panel per output over time: the drawn runs (`drawn.histories`) thin, the mean and the 99 % band
    of `outputs` (the file's statistics) on top. Returns the PNG and the number of runs drawn."""
    names = [name for name, out in outputs.items() if out.time.size > 1]
    rows = drawn.spaghetti_rows
    fig, axes = plots._panels(len(names), title, row_height=2.6)
    for ax, name in zip(axes, names):
        out = outputs[name]
        runs = drawn.histories[name]
        segments = np.stack([np.broadcast_to(out.time, runs.shape), runs], axis=-1)
        ax.add_collection(LineCollection(segments, colors=plots.COLORS[0], linewidths=0.5, alpha=0.45))
        ax.plot(out.time, out.mean, color="k", lw=1.4)
        for bound in out.band99:
            ax.plot(out.time, bound, color="k", lw=0.9, ls="--")
        ax.autoscale_view()
        plots._style(ax, out)
    handles = [Line2D([], [], color=plots.COLORS[0], lw=0.8), Line2D([], [], color="k", lw=1.4),
               Line2D([], [], color="k", lw=0.9, ls="--")]
    labels = [f"{rows.size} runs", "mean", "99 % band"]
    return plots._save(fig, path, (handles, labels), 3), int(rows.size)


def _influence(sobol_total: dict, i: int, kappa: np.ndarray, y: np.ndarray, names: list[str]) -> np.ndarray:
    """Each input's influence on y: its total Sobol' index at time index i, or, without indices, its
    squared correlation with y over the drawn runs."""
    if sobol_total:
        return np.array([np.nan_to_num(float(sobol_total[p][i]), nan=-1.0) if p in sobol_total else -1.0
                         for p in names])
    spread = kappa.std(axis=0) * y.std()
    covariance = ((kappa - kappa.mean(axis=0)) * (y - y.mean())[:, None]).mean(axis=0)
    return np.divide(covariance, spread, out=np.zeros_like(spread), where=spread > 0) ** 2


def scatter_rows(drawn: DrawnRuns, outputs: dict, quantities: dict) -> dict:
    """What `plot_scatter` draws of the drawn runs' scatter subset (`drawn.scatter_rows`): their inputs in
    physical values ("kappa", "names"), and per row ("outputs": each output over time at the recorded time
    nearest the scatter's, labelled "NAME at T s [unit]", or its one value; "quantities": each defined
    quantity, labelled "NAME [unit]") (the runs' values, the total Sobol' indices {parameter: (T,)}, the
    time index)."""
    at_time = {}
    for name, out in outputs.items():
        i, values = drawn.at_time[name]
        at = f" at {plots.shown_time(out.time, i):g} s" if out.time.size > 1 else ""
        at_time[f"{plots.short_label(name)}{at}" + (f" [{out.units}]" if out.units else "")] = (
            values, out.sobol_total, i)
    of_quantities = {plots.label(name, q.units): (drawn.quantities[name], q.output.sobol_total, 0)
                     for name, q in quantities.items() if q.output is not None}
    return {"kappa": drawn.kappa[drawn.scatter_rows], "names": drawn.parameter_names, "outputs": at_time,
            "quantities": of_quantities}


def plot_scatter(kappa: np.ndarray, names: list[str], rows_of: dict, path: Path, title: str) -> Path | None:
    """One row per output or quantity (`rows_of` as `scatter_rows` gives them), one panel per input among
    its SCATTER_INPUTS most influential, against the input's physical value; each panel coloured by the
    most influential other input, from its low to its high value among the drawn runs (one input: one
    panel per row, in one colour, with no colour bar). None without rows."""
    if not rows_of:
        return None
    shown = min(SCATTER_INPUTS, len(names))
    fig, axes = plots.plt.subplots(len(rows_of), shown, figsize=(max(3.6 * shown + 2.0, 8.0), 2.2 * len(rows_of) + 1.0),
                                   squeeze=False)
    for row, (text, (values, sobol_total, i)) in zip(axes, rows_of.items()):
        keep = np.isfinite(values)
        x, y = kappa[keep], values[keep]
        influence = _influence(sobol_total, i, x, y, names)
        ranked = list(np.argsort(-influence, kind="stable"))
        for ax, j in zip(row, ranked[:shown]):
            other = next((k for k in ranked if k != j), None)
            if other is None:
                ax.scatter(x[:, j], y, color=plots.COLORS[0], s=9, lw=0)
            else:
                low, high = x[:, other].min(initial=np.inf), x[:, other].max(initial=-np.inf)
                shade = (x[:, other] - low) / (high - low) if high > low else np.full(len(x), 0.5)
                ax.scatter(x[:, j], y, c=shade, cmap=COLOR_MAP, vmin=0, vmax=1, s=9, lw=0)
                ax.set_title(f"colour: {names[other]}", fontsize=8)
            ax.set_xlabel(names[j], fontsize=8)
            ax.tick_params(labelsize=7)
            ax.xaxis.set_major_locator(MaxNLocator(4))
            ax.yaxis.set_major_locator(MaxNLocator(4))
            ax.grid(alpha=0.3)
        row[0].set_ylabel(text, fontsize=8)
    fig.suptitle(title, fontsize=12)  # 8 in wide at least: the title fits above one panel
    fig.panel_grid = axes.shape
    if len(names) < 2:
        return plots._save(fig, path)
    bar = fig.colorbar(plots.plt.cm.ScalarMappable(cmap=COLOR_MAP), cax=fig.add_axes((1 - 0.9 / fig.get_size_inches()[0], 0.15, 0.012, 0.7)))
    bar.set_ticks([0, 1], labels=["low", "high"])
    bar.set_label("the colouring input, named above each panel", fontsize=8)
    return plots._save(fig, path, right=1.4)  # the colour bar in the right margin


def trajectories_section(entries: list, times: list[float], out_dir: Path):
    """Per results file: the spaghetti plot and the scatter of the outputs at the last of `times` and of the
    quantities against the inputs, seeded by the campaign's seed (the same runs on every report); None
    when there is nothing to draw (no output and no quantity)."""
    from .loading import file_name_within, one_per_file
    from .blocks import Figure, Section, _rel

    blocks = []
    for e in one_per_file(entries):
        drawn, stem, seed = e.stats.drawn, e.file_stem, e.stats.seed
        nodes = ("" if e.stats.sampled else
                 f" The points are the {e.stats.design_kind}'s nodes, not random draws: how they spread says "
                 "nothing of the inputs' distribution.")
        if any(out.time.size > 1 for out in e.outputs.values()):
            path, count = plot_spaghetti(drawn, e.outputs, out_dir / "plots" / file_name_within(f"spaghetti_{stem}.png"),
                                         f"Runs, mean and 99 % band: {e.label}")
            blocks.append(Figure(_rel(path, out_dir), f"{count} of the {e.stats.completed} successful runs of {stem} "
                                 f"(drawn with the campaign's seed {seed}, at most {SPAGHETTI_RUNS}), thin, with "
                                 f"the mean (solid) and the 99 % band (dashed) of {e.label}." + nodes))
        rows = scatter_rows(drawn, e.outputs, e.stats.quantities)
        single = len(rows["names"]) < 2
        against = "its one input" if single else f"its {SCATTER_INPUTS} most influential inputs"
        how = "" if single else (", each panel coloured by " + (
            "the other input with the largest total Sobol' index" if e.has_sobol else
            "the other input most correlated with it (squared correlation; the file has no Sobol' indices)")
            + ", low to high")
        path = plot_scatter(rows["kappa"], rows["names"], {**rows["outputs"], **rows["quantities"]},
                            out_dir / "plots" / file_name_within(f"scatter_{stem}.png"), f"Outputs and quantities against the "
                            f"inputs: {e.label}")
        if path is not None:
            blocks.append(Figure(_rel(path, out_dir), "Each output (at the last selected time)"
                                 + (" and each quantity of interest" if rows["quantities"] else "")
                                 + f" of {stem} (a row each) against {against} in physical values, "
                                 f"{len(rows['kappa'])} runs (at most {SCATTER_RUNS}, seed {seed}){how}." + nodes))
    if not blocks:
        return None
    return Section("Trajectories and scatter", "trajectories", "The runs themselves: what the statistics "
                   "summarise, and where the outliers are.", blocks)
