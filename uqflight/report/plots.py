"""Matplotlib figures (PNG, headless): one flight's time histories and the statistics of campaigns.

The statistics figures take `OutputStatistics` objects (see uqflight.statistics) keyed by output
name and draw one panel per output, like the paper's Figs. 6-8, 10-21. A scalar output (one time
point) is drawn as markers instead of lines.
"""
from __future__ import annotations

import os
import traceback
from contextlib import contextmanager
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
matplotlib.rcParams["axes.formatter.useoffset"] = False  # 15000.5 ft, not 0.5 + 1.5e4
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402

LABELS = {
    "alpha_deg": "angle of attack α [deg]",
    "theta_deg": "pitch attitude θ [deg]",
    "h_ft": "altitude h [ft]",
    "q_degps": "pitch rate q [deg/s]",
    "vtas_kt": "true airspeed V_TAS [kt]",
}
TIME_LABEL = "time [s]"
DPI = 110
COLORS = plt.get_cmap("tab10").colors
MARKERS = "osD^vPX*<>"
NARROW_BAND = 0.2  # a band narrower than this share of the mean's excursion is also drawn about the mean
COV_DECADES = 1e-4  # the CoV plot shows four decades below the largest value
ERROR_DECADES = 1e-6  # error plots show six decades below the largest error


def label(name: str, units: str = "") -> str:
    """Axis label of an output: its description and unit, e.g. "pitch attitude θ [deg]"."""
    if name in LABELS:
        return LABELS[name]
    return f"{name} [{units}]" if units else name


def short_label(name: str) -> str:
    """A panel title: the label without its unit, e.g. "pitch attitude θ"."""
    return label(name).split(" [")[0]


def plot_flight(time: np.ndarray, outputs: dict[str, np.ndarray], path: Path, title: str = "") -> Path:
    """One panel per output against time, like the paper's Fig. 2."""
    names = list(outputs)
    fig, axes = plt.subplots(len(names), 1, figsize=(8, 1.9 * len(names) + 0.6), sharex=True, squeeze=False)
    for ax, name in zip(axes[:, 0], names):
        ax.plot(time, outputs[name], lw=1.2)
        ax.set_ylabel(label(name), fontsize=8)
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel("time [s]")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)


def _panels(count: int, title: str, row_height: float = 2.9):
    """A figure with one panel per output: one column up to two outputs, else two; unused panels hidden."""
    columns = 1 if count <= 2 else 2
    rows = -(-count // columns)
    fig, axes = plt.subplots(rows, columns, figsize=(6.2 * columns, row_height * rows + 0.9), squeeze=False)
    for ax in axes.flat[count:]:
        ax.set_visible(False)
    fig.suptitle(title, fontsize=12)
    return fig, list(axes.flat[:count])


def _save(fig, path: Path, legend_handles=None, legend_columns: int = 3) -> Path:
    """Place a shared legend under the panels (when given) and write the PNG."""
    rect = (0, 0, 1, 1)
    if legend_handles:
        handles, labels = legend_handles
        fig.legend(handles, labels, loc="lower center", ncol=min(legend_columns, len(labels)), fontsize=8,
                   frameon=False)
        rect = (0, 0.04 + 0.025 * ((len(labels) - 1) // legend_columns), 1, 1)
    return _write(fig, path, rect)


_background: dict | None = None  # inside background_rendering(): "children" (pid, figure), "limit", "failed"


@contextmanager
def background_rendering(processes: int | None = None):
    """Inside, each figure is laid out and written by a forked child while the caller builds the next
    (at most `processes` children at once, default the CPU count): the same PNG bytes, in a fraction of
    the time on several cores. Leaving waits for every child; RuntimeError names a figure that failed."""
    global _background
    if not hasattr(os, "fork") or _background is not None:
        yield
        return
    _background = {"children": [], "limit": processes or os.cpu_count() or 1, "failed": []}
    try:
        yield
    except BaseException:
        _wait_all()
        raise
    failed = _wait_all()
    if failed:
        raise RuntimeError(f"cannot write the plot {failed[0]} (its error is printed above)")


def _wait_all() -> list[str]:
    """Wait for every child writing a figure; the figures that failed. Ends background rendering."""
    global _background
    state, _background = _background, None
    return state["failed"] + _failures(state["children"])


def _failures(children: list) -> list[str]:
    """Wait for the (pid, figure) children; the figures whose child failed."""
    return [path for pid, path in children if os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1]) != 0]


def _write(fig, path: Path, rect=(0, 0, 1, 1)) -> Path:
    """tight_layout within `rect`, then the PNG: here, or in a forked child (background_rendering)."""
    if _background is not None:
        children = _background["children"]
        while len(children) >= _background["limit"]:
            _background["failed"] += _failures([children.pop(0)])
        pid = os.fork()
        if pid:
            children.append((pid, str(path)))
            plt.close(fig)
            return Path(path)
        try:  # the child: write the figure and leave at once, running no handler of the parent's
            fig.tight_layout(rect=rect)
            fig.savefig(path, dpi=DPI)
        except BaseException:
            traceback.print_exc()
            os._exit(1)
        os._exit(0)
    fig.tight_layout(rect=rect)
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return Path(path)


def _style(ax, out, ylabel: str | None = None) -> None:
    """Title, labels and grid of an output's panel over time (no time axis for a scalar output)."""
    ax.set_title(short_label(out.name), fontsize=10)
    if out.time.size == 1:
        ax.set_xticks([])
    else:
        ax.set_xlabel(TIME_LABEL, fontsize=8)
    ax.set_ylabel(ylabel or label(out.name, out.units), fontsize=8)
    ax.tick_params(labelsize=8)
    ax.grid(alpha=0.3)


def _line(ax, time, values, **style):
    """A line over time, or a marker for a scalar output."""
    return ax.plot(time, values, marker="o" if np.size(time) == 1 else None, **style)[0]


def _band(ax, time, lower, upper, color, alpha=0.25, label=None):
    """The 99 % band: shaded over time, or an error bar for a scalar output."""
    if np.size(time) == 1:
        middle = 0.5 * (lower + upper)
        return ax.errorbar(time, middle, yerr=0.5 * (upper - lower), fmt="none", color=color, capsize=6,
                           label=label)
    return ax.fill_between(time, lower, upper, color=color, alpha=alpha, lw=0, label=label)


def narrow_band(out) -> bool:
    """Whether the 99 % band is too narrow to see against the mean's excursion over time."""
    width = np.max(out.band99[1] - out.band99[0])
    return width < NARROW_BAND * (np.max(out.band99[1]) - np.min(out.band99[0]))


def _band_panels(outputs: dict) -> list[tuple[str, bool]]:
    """(output, about the mean?) per panel: every output, then those with a narrow band about their mean."""
    return [(name, False) for name in outputs] + [(name, True) for name, out in outputs.items() if narrow_band(out)]


def _style_band_panel(ax, out, about_mean: bool) -> None:
    if about_mean:
        _style(ax, out, ylabel=f"{short_label(out.name)} − mean(t)" + (f" [{out.units}]" if out.units else ""))
        ax.set_title(f"{short_label(out.name)}: 99 % band about the mean", fontsize=10)
    else:
        _style(ax, out)


def plot_mean_band(outputs: dict, path: Path, title: str, reference: dict | None = None) -> Path:
    """Mean and 99 % band of every output over time (Figs. 6-7); the reference's dashed when given.
    An output whose band is too narrow to see gets a second panel about its mean."""
    panels = _band_panels(outputs)
    fig, axes = _panels(len(panels), title)
    for ax, (name, about_mean) in zip(axes, panels):
        out = outputs[name]
        offset = out.mean if about_mean else 0.0
        band = _band(ax, out.time, *(bound - offset for bound in out.band99), COLORS[0], label="99 % band")
        mean = _line(ax, out.time, out.mean - offset, color=COLORS[0], lw=1.4, label="mean")
        handles = [mean, band]
        ref = (reference or {}).get(name)
        if ref is not None:
            ref_offset = np.interp(ref.time, out.time, out.mean) if about_mean else 0.0
            handles.append(_line(ax, ref.time, ref.mean - ref_offset, color="black", lw=1.0, ls="--",
                                 label="reference mean"))
            handles.append(_line(ax, ref.time, ref.band99[0] - ref_offset, color="black", lw=0.8, ls=":",
                                 label="reference 99 % band"))
            _line(ax, ref.time, ref.band99[1] - ref_offset, color="black", lw=0.8, ls=":")
        _style_band_panel(ax, out, about_mean)
    return _save(fig, path, (handles, [h.get_label() for h in handles]), legend_columns=4)


def plot_pdf_over_time(out, path: Path, title: str, slice_times: list[float]) -> Path:
    """The PDF over time as a heat map (each time's density scaled to its peak) with the mean, and
    the PDF itself at `slice_times` below it. A scalar output gets the PDF alone."""
    if out.time.size == 1:
        fig, ax = plt.subplots(figsize=(8, 4))
        ax.plot(out.pdf_support[0], out.pdf_density[0], color=COLORS[0])
        ax.set_xlabel(label(out.name, out.units), fontsize=9)
        ax.set_ylabel("probability density", fontsize=9)
        ax.grid(alpha=0.3)
        fig.suptitle(title, fontsize=12)
        return _save(fig, path)
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(9, 8.2), gridspec_kw={"height_ratios": [3, 2]})
    _pdf_heat_map(fig, top, out)
    for color, index in zip(COLORS, time_indices(out.time, slice_times)):
        bottom.plot(out.pdf_support[index], out.pdf_density[index], color=color, label=f"t = {out.time[index]:g} s")
    bottom.set_xlabel(label(out.name, out.units), fontsize=9)
    bottom.set_ylabel(f"probability density [1/{out.units}]" if out.units else "probability density", fontsize=9)
    bottom.set_title("density at selected times", fontsize=10)
    bottom.legend(fontsize=8)
    bottom.grid(alpha=0.3)
    fig.suptitle(title, fontsize=12)
    return _save(fig, path)


def _pdf_heat_map(fig, ax, out) -> None:
    """Each time's density scaled to its peak, over its own support; drawn as deviation from the mean
    when the band is too narrow to see against the mean's excursion over time."""
    peak = out.pdf_density.max(axis=1, keepdims=True)
    scaled = np.divide(out.pdf_density, peak, out=np.zeros_like(out.pdf_density), where=peak > 0)
    about_mean = narrow_band(out)
    support = out.pdf_support - out.mean[:, None] if about_mean else out.pdf_support
    mesh = ax.pcolormesh(*_cell_edges(out.time, support), scaled, shading="flat", cmap="magma", rasterized=True)
    if about_mean:
        ax.plot(out.time, out.band99[0] - out.mean, color="cyan", lw=0.8, ls="--", label="99 % band")
        ax.plot(out.time, out.band99[1] - out.mean, color="cyan", lw=0.8, ls="--")
        unit = f" [{out.units}]" if out.units else ""
        ax.set_ylabel(f"{short_label(out.name)} − mean(t){unit}", fontsize=9)
        ax.set_title("density about the mean over time, each time scaled to its peak", fontsize=10)
    else:
        ax.plot(out.time, out.mean, color="cyan", lw=0.9, label="mean")
        ax.set_ylabel(label(out.name, out.units), fontsize=9)
        ax.set_title("density over time, each time scaled to its peak", fontsize=10)
    ax.set_xlabel(TIME_LABEL, fontsize=9)
    ax.legend(loc="upper right", fontsize=8)
    fig.colorbar(mesh, ax=ax, label="density / peak density at that time")


def _cell_edges(time: np.ndarray, support: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Corners (T + 1, G + 1) of the cells centred on each time's support points (T, G): flat cells
    draw in a fifth of the time of Gouraud triangles and look the same at 1000 times × 120 points."""
    def edges(centres, axis):
        inner = 0.5 * (np.take(centres, range(1, centres.shape[axis]), axis)
                       + np.take(centres, range(centres.shape[axis] - 1), axis))
        first = 2 * np.take(centres, [0], axis) - np.take(inner, [0], axis)
        last = 2 * np.take(centres, [-1], axis) - np.take(inner, [-1], axis)
        return np.concatenate([first, inner, last], axis)

    along_time = edges(np.broadcast_to(time[:, None], support.shape), 0)
    return edges(along_time, 1), edges(edges(support, 1), 0)


def time_indices(time: np.ndarray, times: list[float]) -> list[int]:
    """Indices of the recorded times nearest to `times` (inf: the final time), ascending, without repeats."""
    return sorted({int(np.argmin(np.abs(time - np.clip(t, time[0], time[-1])))) for t in times})


def plot_cov(outputs: dict, path: Path, title: str) -> Path:
    """The modified coefficient of variation std(t) / max|mean| of all outputs in one plot (Fig. 8)."""
    fig, ax = plt.subplots(figsize=(9, 4.8))
    for color, (name, out) in zip(COLORS, outputs.items()):
        _line(ax, out.time, 100 * out.cov, color=color, lw=1.3, label=short_label(name))
    ax.set_yscale("log")
    _floor_log_axis(ax, [100 * out.cov for out in outputs.values()], COV_DECADES)
    ax.set_xlabel(TIME_LABEL, fontsize=9)
    ax.set_ylabel("std(t) / max |mean| [%] (log scale)", fontsize=9)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8, loc="center left", bbox_to_anchor=(1.01, 0.5))
    ax.set_title(title, fontsize=12)
    return _save(fig, path)


def _floor_log_axis(ax, series: list, decades: float) -> None:
    """Start a log y-axis `decades` below the largest value, so that near-zero errors at a
    deterministic instant (e.g. t = 0) do not squeeze the rest."""
    top = max((np.max(values) for values in series), default=0.0)
    if top > 0:
        ax.set_ylim(bottom=decades * top)


def plot_errors(curves: list[tuple[str, dict]], key: str, path: Path, title: str) -> Path:
    """ε_m or ε_v (`key` "eps_m"/"eps_v", Eq. 49) over time, one panel per output, one line per
    file (`curves`: (label, outputs)); log y-axis, exact zeros left out."""
    names = list(dict.fromkeys(name for _, outputs in curves for name, out in outputs.items() if out.errors))
    symbol = {"eps_m": "ε_m (error of the mean)", "eps_v": "ε_v (error of the variance)"}[key]
    fig, axes = _panels(len(names), title)
    floors = any(out.errors.get(f"{key}_floor") is not None for _, outputs in curves
                 for out in outputs.values() if out.errors)
    for ax, name in zip(axes, names):
        errors, drawn_floor = [], False
        for color, (_, outputs) in zip(COLORS, curves):
            out = outputs.get(name)
            if out is not None and out.errors:
                errors.append(out.errors[key])
                _line(ax, out.time, np.where(errors[-1] > 0, errors[-1], np.nan), color=color, lw=1.1)
                floor = out.errors.get(f"{key}_floor")
                if floor is not None and not drawn_floor:
                    floor = np.broadcast_to(np.asarray(floor, dtype=float), out.time.shape)
                    ax.plot(out.time, np.where(floor > 0, floor, np.nan), color="gray", lw=1.0, ls="--")
                    drawn_floor = True
                shown = out
        ax.set_yscale("log")
        _floor_log_axis(ax, errors, ERROR_DECADES)
        _style(ax, shown, ylabel=f"{symbol} [-]")
    handles, labels = _file_legend(curves)
    if floors:
        handles, labels = handles + [Line2D([], [], color="gray", ls="--")], labels + ["reference floor"]
    return _save(fig, path, (handles, labels), legend_columns=2)


def _file_legend(entries: list[tuple[str, dict]], **style) -> tuple[list, list[str]]:
    """Legend handles and labels for one line per file, coloured in file order."""
    labels = [file_label for file_label, _ in entries]
    return [Line2D([], [], color=color, **style) for color, _ in zip(COLORS, labels)], labels


def plot_kld_vs_runs(points: list[tuple[str, int, dict]], path: Path, title: str) -> Path:
    """KLD at the final time against the number of runs (Fig. 20), one panel per output and one line
    per method (hollow markers, so that coinciding methods stay visible); `points` are
    (method label, runs, {output: KLD})."""
    names = list(dict.fromkeys(name for _, _, values in points for name in values))
    methods = list(dict.fromkeys(method for method, _, _ in points))
    style = {"ms": 7, "mfc": "none", "mew": 1.5}
    fig, axes = _panels(len(names), title, row_height=2.7)
    for ax, name in zip(axes, names):
        for color, marker, method in zip(COLORS, MARKERS, methods):
            found = sorted((n, values[name]) for m, n, values in points if m == method and name in values)
            if found:
                ax.plot(*zip(*found), marker=marker, color=color, **style)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(short_label(name), fontsize=10)
        ax.set_xlabel("runs (simulator calls)", fontsize=8)
        ax.set_ylabel("KLD at the final time [nat]", fontsize=8)
        ax.tick_params(labelsize=8)
        ax.grid(alpha=0.3, which="both")
    handles = [Line2D([], [], color=c, marker=m, **style) for c, m, _ in zip(COLORS, MARKERS, methods)]
    return _save(fig, path, (handles, methods), legend_columns=3)


def plot_sobol(outputs: dict, path: Path, title: str) -> Path:
    """First-order Sobol' indices over time, one panel per output, one line per parameter (Fig. 21);
    bootstrap 95 % intervals shaded when the file has them (pick-freeze). A scalar output gets bars."""
    names = [name for name, out in outputs.items() if out.sobol_first]
    fig, axes = _panels(len(names), title)
    handles = []
    for ax, name in zip(axes, names):
        out = outputs[name]
        if out.time.size == 1:
            _sobol_bars(ax, out)
            continue
        handles = []
        low, high = -0.05, 1.05
        for color, (parameter, index) in zip(COLORS, out.sobol_first.items()):
            text = parameter
            ci = out.sobol_first_ci.get(parameter) if out.sobol_first_ci else None
            if ci is not None:
                _band(ax, out.time, *ci, color, alpha=0.2)
                text = f"{parameter} (95 % CI shaded)"
            handles.append(_line(ax, out.time, index, color=color, lw=1.2, label=text))
            finite = np.asarray(index, dtype=float)[np.isfinite(index)]
            if ci is not None:
                finite = np.concatenate([finite, *(np.asarray(b, dtype=float)[np.isfinite(b)] for b in ci)])
            if finite.size:  # values above 1 or below 0 (estimator noise) are shown, not clipped
                low, high = min(low, finite.min() - 0.05), max(high, finite.max() + 0.05)
        _style(ax, out, ylabel="first-order Sobol' index S_i [-]")
        ax.set_ylim(low, high)
        if high > 1.05 or low < -0.05:
            ax.axhspan(1.0, high, color="0.9", zorder=0)
            ax.axhspan(low, min(0.0, high), color="0.9", zorder=0)
    return _save(fig, path, (handles, [h.get_label() for h in handles]) if handles else None, legend_columns=7)


def _sobol_bars(ax, out) -> None:
    """The first-order indices of a scalar output as bars, with their bootstrap intervals if any."""
    parameters = list(out.sobol_first)
    values = np.array([out.sobol_first[p][0] for p in parameters])
    errors = None
    if out.sobol_first_ci:
        lower, upper = (np.array([out.sobol_first_ci[p][k][0] for p in parameters]) for k in (0, 1))
        errors = np.clip([values - lower, upper - values], 0.0, None)
    ax.bar(parameters, values, color=COLORS[:len(parameters)], yerr=errors, capsize=6)
    ax.set_title(short_label(out.name), fontsize=10)
    ax.set_ylabel("first-order Sobol' index S_i [-]", fontsize=8)
    ax.grid(alpha=0.3, axis="y")


def plot_band_comparison(entries: list[tuple[str, dict]], path: Path, title: str) -> Path:
    """Mean (solid) and 99 % band (dashed) of every output for several files overlaid (Figs. 4-5);
    an output with a narrow band gets a second panel about the first file's mean."""
    first = entries[0][1]
    panels = _band_panels(first)
    fig, axes = _panels(len(panels), title)
    for ax, (name, about_mean) in zip(axes, panels):
        for k, (color, (_, outputs)) in enumerate(zip(COLORS, entries)):
            out = outputs.get(name)
            if out is None:
                continue
            # earlier files drawn wider, so that coinciding methods stay visible under later ones
            widen = 1.0 + 0.9 * (len(entries) - 1 - k)
            offset = np.interp(out.time, first[name].time, first[name].mean) if about_mean else 0.0
            _line(ax, out.time, out.mean - offset, color=color, lw=1.3 * widen)
            for bound in out.band99:
                _line(ax, out.time, bound - offset, color=color, lw=0.9 * widen, ls="--")
        _style_band_panel(ax, first[name], about_mean)
    return _save(fig, path, _file_legend(entries), legend_columns=2)


def plot_final_pdfs(entries: list[tuple[str, dict]], path: Path, title: str) -> Path:
    """Each file's PDF of every output at the final time, overlaid, one panel per output."""
    first = entries[0][1]
    fig, axes = _panels(len(first), title, row_height=2.7)
    for ax, (name, out) in zip(axes, first.items()):
        for color, (_, outputs) in zip(COLORS, entries):
            if name in outputs:
                ax.plot(outputs[name].pdf_support[-1], outputs[name].pdf_density[-1], color=color, lw=1.3)
        ax.set_title(f"{short_label(name)} at t = {out.time[-1]:g} s", fontsize=10)
        ax.set_xlabel(label(name, out.units), fontsize=8)
        ax.set_ylabel("probability density", fontsize=8)
        ax.tick_params(labelsize=8)
        ax.grid(alpha=0.3)
    return _save(fig, path, _file_legend(entries), legend_columns=2)


def plot_sobol_compared(entries: list[tuple[str, dict]], path: Path, title: str) -> Path:
    """First-order indices of several files or methods overlaid: one colour per parameter, one line
    style per file (NaN where unresolved: gaps)."""
    names = list(dict.fromkeys(n for _, outputs in entries for n, o in outputs.items()
                               if o.sobol_first and o.time.size > 1))
    styles = ["-", "--", ":", "-."]
    fig, axes = _panels(max(len(names), 1), title)
    parameters: list[str] = []
    for ax, name in zip(axes, names):
        low, high = -0.05, 1.05
        for style, (_, outputs) in zip(styles * 3, entries):
            out = outputs.get(name)
            if out is None:
                continue
            for parameter, index in out.sobol_first.items():
                if parameter not in parameters:
                    parameters.append(parameter)
                color = COLORS[parameters.index(parameter) % len(COLORS)]
                ax.plot(out.time, index, color=color, lw=1.1 + 0.8 * (len(entries) - 1 - entries.index(
                    next(e for e in entries if e[1] is outputs))), ls=style)
                finite = np.asarray(index, dtype=float)[np.isfinite(index)]
                if finite.size:
                    low, high = min(low, finite.min() - 0.05), max(high, finite.max() + 0.05)
        ax.set_ylim(low, high)
        _style(ax, next(o[name] for _, o in entries if name in o), ylabel="first-order Sobol' index S_i [-]")
    handles = [Line2D([], [], color=COLORS[k % len(COLORS)]) for k in range(len(parameters))]
    handles += [Line2D([], [], color="black", ls=style) for style, _ in zip(styles * 3, entries)]
    labels = parameters + [file_label for file_label, _ in entries]
    return _save(fig, path, (handles, labels), legend_columns=4)


def plot_convergence(points: list[tuple[str, int, dict]], path: Path, title: str) -> Path:
    """max over time of ε_m (left) and ε_v (right) against the number of runs, log-log, one row per
    output and one line per method; `points` are (method label, runs, {output: (eps_m max, eps_v max,
    eps_m floor, eps_v floor)}); the reference's floor dashed when known."""
    names = list(dict.fromkeys(name for _, _, values in points for name in values))
    methods = list(dict.fromkeys(method for method, _, _ in points))
    style = {"ms": 6, "mfc": "none", "mew": 1.4}
    fig, axes = plt.subplots(len(names), 2, figsize=(11, 2.6 * len(names) + 0.9), squeeze=False)
    floors = False
    for row, name in zip(axes, names):
        for column, (ax, symbol) in enumerate(zip(row, ("max ε_m [-]", "max ε_v [-]"))):
            for color, marker, method in zip(COLORS, MARKERS, methods):
                found = sorted((n, values[name][column]) for m, n, values in points
                               if m == method and name in values and values[name][column] > 0)
                if found:
                    ax.plot(*zip(*found), marker=marker, color=color, **style)
            floor = [values[name][column + 2] for _, _, values in points
                     if name in values and values[name][column + 2] is not None]
            if floor:
                ax.axhline(max(floor), color="gray", ls="--", lw=1.0)
                floors = True
            ax.set_xscale("log")
            ax.set_yscale("log")
            low, high = ax.get_ylim()
            if low > 0 and high / low < 10:  # at least a decade, so that log ticks stay readable
                middle = np.sqrt(low * high)
                ax.set_ylim(middle / np.sqrt(10), middle * np.sqrt(10))
            ax.set_title(f"{short_label(name)}: {symbol.split(' [')[0]}", fontsize=10)
            ax.set_xlabel("runs (simulator calls)", fontsize=8)
            ax.set_ylabel(symbol, fontsize=8)
            ax.tick_params(labelsize=8)
            ax.grid(alpha=0.3, which="both")
    fig.suptitle(title, fontsize=12)
    handles = [Line2D([], [], color=c, marker=m, **style) for c, m, _ in zip(COLORS, MARKERS, methods)]
    labels = list(methods)
    if floors:
        handles.append(Line2D([], [], color="gray", ls="--"))
        labels.append("reference floor")
    return _save(fig, path, (handles, labels), legend_columns=3)


def plot_coefficient_decay(outputs: dict, path: Path, title: str) -> Path:
    """Root-sum-square of the PCE coefficients of each total degree over time, log y, one panel per
    output (`OutputStatistics.coefficient_decay`: {degree: array over time})."""
    names = [n for n, o in outputs.items() if getattr(o, "coefficient_decay", None)]
    fig, axes = _panels(max(len(names), 1), title)
    degrees: list = []
    for ax, name in zip(axes, names):
        out = outputs[name]
        for degree, values in sorted(out.coefficient_decay.items(), key=lambda kv: int(kv[0])):
            if degree not in degrees:
                degrees.append(degree)
            values = np.asarray(values, dtype=float)
            _line(ax, out.time, np.where(values > 0, values, np.nan), color=COLORS[degrees.index(degree) % 10], lw=1.1)
        ax.set_yscale("log")
        _style(ax, out, ylabel=f"RSS of coefficients [{out.units}]" if out.units else "RSS of coefficients")
    handles = [Line2D([], [], color=COLORS[k % 10]) for k in range(len(degrees))]
    return _save(fig, path, (handles, [f"degree {d}" for d in degrees]), legend_columns=6)


MAX_PAIRS = 8  # parameters drawn in the design scatter (the first ones)


def plot_design_pairs(results, path: Path, title: str) -> Path | None:
    """The design points on every pair of inputs (lower triangle), in standard variables ξ (paper
    Fig. 9), marker size by |weight| for a grid; failed runs as red crosses. None for one input."""
    from ..store import ResultStore

    with ResultStore.open(results) as store:
        xi, weights, status, names = store.xi, store.weights, store.status, store.parameter_names
    d = min(xi.shape[1], MAX_PAIRS)
    if d < 2:
        return None
    failed = status > 0
    sizes = 8.0 if np.allclose(weights, weights[0]) else 6 + 40 * np.abs(weights) / np.abs(weights).max()
    fig, axes = plt.subplots(d - 1, d - 1, figsize=(1.7 * (d - 1) + 1.2, 1.7 * (d - 1) + 1.0), squeeze=False)
    alpha = 0.8 if xi.shape[0] <= 500 else 0.25
    for i in range(1, d):
        for j in range(d - 1):
            ax = axes[i - 1, j]
            if j >= i:
                ax.set_visible(False)
                continue
            ax.scatter(xi[~failed, j], xi[~failed, i], s=sizes if np.ndim(sizes) == 0 else sizes[~failed],
                       color=COLORS[0], alpha=alpha, lw=0)
            if failed.any():
                ax.scatter(xi[failed, j], xi[failed, i], s=18, color="red", marker="x", lw=1)
            ax.tick_params(labelsize=6)
            if j == 0:
                ax.set_ylabel(f"ξ {names[i]}", fontsize=8)
            else:
                ax.set_yticklabels([])
            if i == d - 1:
                ax.set_xlabel(f"ξ {names[j]}", fontsize=8)
            else:
                ax.set_xticklabels([])
            ax.grid(alpha=0.3)
    fig.suptitle(title, fontsize=11)
    return _write(fig, path)
