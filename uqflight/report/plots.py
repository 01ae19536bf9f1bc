"""Matplotlib figures (PNG, headless): one flight's time histories and the statistics of campaigns.

The statistics figures take `OutputStatistics` objects (see uqflight.analysis.statistics) keyed by output
name and draw one panel per output, like the paper's Figs. 6-8, 10-21. A scalar output (one time
point) is drawn as markers instead of lines.
"""
from __future__ import annotations

import gc
from contextlib import contextmanager
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
matplotlib.rcParams["axes.formatter.useoffset"] = False  # 15000.5 ft, not 0.5 + 1.5e4
matplotlib.rcParams["svg.fonttype"] = "none"  # SVG text stays text: editable, searchable, smaller
# titles sit just above their panel (nothing of ours is drawn above an axes): placed, not searched for
matplotlib.rcParams["axes.titley"] = 1.0
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.ticker import FixedLocator, FuncFormatter, LogLocator, MaxNLocator, NullFormatter  # noqa: E402

from ..analysis.drawn import nearest_time_index  # noqa: E402
from ..analysis.sobol import unresolved  # noqa: E402
from ..text.labels import label, short_label, shown_time  # noqa: E402,F401 (plots.label: the report's captions)
from .formats import export_format, shown_path  # noqa: E402
from .png import write_png  # noqa: E402

TIME_LABEL = "time [s]"
DPI = 110
COLORS = plt.get_cmap("tab10").colors
MARKERS = "osD^vPX*<>"
LINESTYLES = ("-", "--", "-.", ":")
NARROW_BAND = 0.2  # a band narrower than this share of the mean's excursion is also drawn about the mean
COV_DECADES = 1e-4  # the CoV plot shows four decades below the largest value
LOW_QUANTILE = 0.02  # error and decay axes start below the lowest line's 2 % quantile (`informative_limits`)
OFFSET_DATUM = 10.0  # min|mean| above this many times the mean's excursion: an offset datum (h, V), no CoV
DECAY_ONSET = 1e-3  # without a known pulse start, coefficient decay is drawn from where degree >= 1 reaches
#                     this share of its largest value


def write_figure(fig, path: Path, dpi: int = DPI, rect=None) -> Path:
    """Lay `fig` out (tight_layout within `rect`, when given), save it as `path` in the export format and
    close it. Returns the file the page shows (the SVG for svg, the PNG for png and pdf: a pdf is
    written beside it)."""
    path = Path(path)
    if rect is not None:
        fig.tight_layout(rect=rect)
    _save_as(fig, path, dpi)
    plt.close(fig)
    return shown_path(path)


def _save_as(fig, path: Path, dpi: int = DPI) -> None:
    """Write `fig` as the page's file of `path` (and a PDF beside it when the export format is pdf)."""
    shown = shown_path(path)
    if shown.suffix == ".png":
        write_png(fig, shown, dpi)
    else:
        fig.savefig(shown, dpi=dpi)
    if export_format() == "pdf":
        fig.savefig(Path(path).with_suffix(".pdf"))


SUPERSCRIPTS = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def tick_text(value: float, _position=None) -> str:
    """A log axis's tick label in plain text: 0.002, 60, 2×10⁻⁵, 10⁸ (no mathtext, no minor labels)."""
    if not value > 0:
        return ""
    exponent = int(np.floor(np.log10(value) + 1e-9))
    if -3 <= exponent <= 4:
        return f"{value:.6g}"
    mantissa = value / 10.0 ** exponent
    head = "" if abs(mantissa - 1) < 1e-6 else f"{mantissa:.3g}×"
    return f"{head}10{str(exponent).translate(SUPERSCRIPTS)}"


def log_axis(axis, at=None) -> None:
    """Readable log ticks on `axis` (ax.xaxis or ax.yaxis), for its current limits: labelled major
    ticks at 1-9 × 10^k within one decade, 1, 2, 5 × 10^k within 2.5 decades, else decades; minor
    ticks unlabelled. `at`: label these values instead (e.g. the run counts, when few)."""
    low, high = sorted(axis.get_view_interval())
    decades = np.log10(high / low) if low > 0 else np.inf
    subs = np.arange(1.0, 10.0) if decades < 1 else (1.0, 2.0, 5.0) if decades < 2.5 else (1.0,)
    axis.set_major_locator(FixedLocator(sorted(at)) if at is not None else LogLocator(subs=subs, numticks=10))
    axis.set_major_formatter(FuncFormatter(tick_text))
    axis.set_minor_formatter(NullFormatter())


RUN_TICKS = 6  # up to this many distinct run counts are the runs axis's ticks


def runs_axis(ax, runs) -> None:
    """A log runs axis labelled at the run counts themselves when there are few of them."""
    ax.set_xscale("log")
    distinct = sorted(set(int(n) for n in runs))
    log_axis(ax.xaxis, distinct if len(distinct) <= RUN_TICKS else None)


def method_style(k: int, points: int = 0) -> dict:
    """Line style of the k-th file or method: colour, marker and dash pattern all differ, so that
    lines stay apart in grey print and where they coincide; `points`: the line's length, for
    markers every tenth of it (staggered per method)."""
    style = {"color": COLORS[k % len(COLORS)], "marker": MARKERS[k % len(MARKERS)], "ms": 5, "mfc": "none",
             "ls": LINESTYLES[k % len(LINESTYLES)]}
    if points > 12:
        step = points // 10
        style["markevery"] = ((k * step) // 7 % step, step)
    return style


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
    fig.savefig(path, dpi=DPI)  # the user's file name and format (`simulate --plot`)
    plt.close(fig)
    return Path(path)


def _panels(count: int, title: str, row_height: float = 2.9):
    """A figure with one panel per output: one column up to two outputs, else two, the last row's free
    places left empty (no axes is built there)."""
    columns = 1 if count <= 2 else 2
    rows = -(-count // columns)
    fig = plt.figure(figsize=(6.2 * columns, row_height * rows + 0.9))
    axes = [fig.add_subplot(rows, columns, k + 1) for k in range(count)]
    fig.suptitle(title, fontsize=12)
    fig.panel_grid = (rows, columns)  # laid out by _save with fixed margins, not a layout pass
    return fig, axes


# margins of a panel grid, in inches: tick labels and the axis label on the left of each panel; its title
# above and its tick labels and time label below; the figure's title on top
PANEL_MARGINS = {"left": 0.9, "right": 0.25, "column_gap": 1.0, "top": 0.72, "row_gap": 0.85, "bottom": 0.6,
                 "legend_row": 0.22}


def _fix_panel_layout(fig, legend_rows: int, right: float | None = None) -> None:
    """Place the panels of a figure with a `panel_grid` (rows, columns) with PANEL_MARGINS (and room for
    `legend_rows` of legend below, `right` inches on the right, e.g. for a colour bar): what tight_layout
    would find for these fonts, without measuring every text."""
    rows, columns = fig.panel_grid
    width, height = fig.get_size_inches()
    m = PANEL_MARGINS
    right = m["right"] if right is None else right
    bottom = m["bottom"] + m["legend_row"] * legend_rows
    panel_width = (width - m["left"] - right - (columns - 1) * m["column_gap"]) / columns
    panel_height = (height - m["top"] - bottom - (rows - 1) * m["row_gap"]) / rows
    fig.subplots_adjust(left=m["left"] / width, right=1 - right / width, top=1 - m["top"] / height,
                        bottom=bottom / height, wspace=m["column_gap"] / panel_width,
                        hspace=m["row_gap"] / panel_height)


def _save(fig, path: Path, legend_handles=None, legend_columns: int = 3, right: float | None = None) -> Path:
    """Place a shared legend under the panels (when given) and write the figure: a `panel_grid` figure
    laid out by _fix_panel_layout (`right`: its right margin in inches), any other by tight_layout."""
    rect, legend_rows = (0, 0, 1, 1), 0
    if legend_handles:
        handles, labels = legend_handles
        fig.legend(handles, labels, loc="lower center", ncol=min(legend_columns, len(labels)), fontsize=8,
                   frameon=False)
        legend_rows = 1 + (len(labels) - 1) // legend_columns
        rect = (0, 0.04 + 0.025 * (legend_rows - 1), 1, 1)
    if hasattr(fig, "panel_grid"):
        _fix_panel_layout(fig, legend_rows, right)
        return write_figure(fig, path)
    return _write(fig, path, rect)


@contextmanager
def collecting_at_the_end():
    """Python's cycle collector off inside, one collection on leaving. A figure is thousands of artists
    that reference each other; collecting every 700 allocations (and scanning every long-lived object
    now and then) costs a third of building them. The closed figures' memory is freed on leaving; forked
    children drawing sections inherit the setting and end with os._exit."""
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()
        gc.collect()


_warmed = False  # warm_text_caches has drawn in this process


def warm_text_caches() -> None:
    """Draw a small figure with the report's fonts and digits, once per process, so that a child forked
    afterwards inherits the loaded fonts and their glyph caches instead of building them again. Without
    pyplot: any one thread may call it."""
    global _warmed
    if _warmed:
        return
    fig = Figure(figsize=(2, 1))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    for size in (6, 7, 8, 9, 10, 11, 12):
        ax.text(0, 0, "0123456789.−-×⁰¹²³⁴⁵⁶⁷⁸⁹ time [s] deg ft kt", fontsize=size)
    ax.set_title("warm", fontsize=10)
    fig.canvas.draw()
    _warmed = True


def _write(fig, path: Path, rect=(0, 0, 1, 1)) -> Path:
    """tight_layout within `rect`, then `write_figure`."""
    return write_figure(fig, path, rect=rect)


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
        fig.panel_grid = (1, 1)
        return _save(fig, path)
    return plot_pdfs_over_time([(out, path, title)], slice_times)[0]


def plot_pdfs_over_time(figures: list, slice_times: list[float]) -> list[Path]:
    """plot_pdf_over_time of each (output over time, path, title) in `figures`, drawn on one figure whose
    data, labels and legends are replaced from one output to the next: its axes, ticks and colour bar are
    built once (a third less CPU than a figure each, the same pixels). Returns the files the page shows."""
    if not figures:
        return []
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(9, 8.2), gridspec_kw={"height_ratios": [3, 2]})
    fig.panel_grid = (2, 1)
    for k, (out, path, title) in enumerate(figures):
        for ax in (top, bottom):  # the previous output's data go; the axes' limits follow the new data
            for artist in [*ax.lines, *ax.collections]:
                artist.remove()
            ax.ignore_existing_data_limits = True
        mesh = _pdf_heat_map(top, out)
        if k == 0:
            fig.colorbar(mesh, ax=top, label="density / peak density at that time")
        for color, index in zip(COLORS, time_indices(out.time, slice_times)):
            bottom.plot(out.pdf_support[index], out.pdf_density[index], color=color,
                        label=f"t = {shown_time(out.time, index):g} s")
        bottom.set_xlabel(label(out.name, out.units), fontsize=9)
        bottom.set_ylabel(f"probability density [1/{out.units}]" if out.units else "probability density",
                          fontsize=9)
        bottom.set_title("density at selected times", fontsize=10)
        bottom.legend(fontsize=8)
        bottom.grid(alpha=0.3)
        fig.suptitle(title, fontsize=12)
        _fix_panel_layout(fig, 0)
        _save_as(fig, path)
    plt.close(fig)
    return [shown_path(path) for _, path, _ in figures]


def _pdf_heat_map(ax, out):
    """Each time's density scaled to its peak, over its own support, white where it is low; drawn as
    deviation from the mean when the band is too narrow to see against the mean's excursion over time.
    Returns the mesh (for a colour bar)."""
    peak = out.pdf_density.max(axis=1, keepdims=True)
    scaled = np.divide(out.pdf_density, peak, out=np.zeros_like(out.pdf_density), where=peak > 0)
    about_mean = narrow_band(out)
    support = out.pdf_support - out.mean[:, None] if about_mean else out.pdf_support
    mesh = ax.pcolormesh(*_cell_edges(out.time, support), scaled, shading="flat", cmap="Blues", vmin=0.0, vmax=1.0,
                         rasterized=True)
    line = {"color": COLORS[3], "lw": 0.9}
    if about_mean:
        ax.plot(out.time, out.band99[0] - out.mean, ls="--", label="99 % band", **line)
        ax.plot(out.time, out.band99[1] - out.mean, ls="--", **line)
        unit = f" [{out.units}]" if out.units else ""
        ax.set_ylabel(f"{short_label(out.name)} − mean(t){unit}", fontsize=9)
        ax.set_title("density about the mean over time, each time scaled to its peak", fontsize=10)
    else:
        ax.plot(out.time, out.mean, label="mean", **line)
        ax.set_ylabel(label(out.name, out.units), fontsize=9)
        ax.set_title("density over time, each time scaled to its peak", fontsize=10)
    ax.set_xlabel(TIME_LABEL, fontsize=9)
    ax.legend(loc="upper right", fontsize=8)
    return mesh


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
    return sorted({nearest_time_index(time, t) for t in times})


def plot_cov(outputs: dict, path: Path, title: str) -> Path:
    """The modified coefficient of variation std(t) / max|mean| (Fig. 8) of the outputs without an
    offset datum (left), and the std in its own unit of those with one (`offset_datum`, right)."""
    groups = [(False, [n for n, o in outputs.items() if not offset_datum(o)]),
              (True, [n for n, o in outputs.items() if offset_datum(o)])]
    groups = [(datum, names) for datum, names in groups if names]
    fig, axes = plt.subplots(1, len(groups), figsize=(6.6 * len(groups) + 1.6, 4.8), squeeze=False)
    for ax, (datum, names) in zip(axes[0], groups):
        series = []
        for k, name in enumerate(names):
            out = outputs[name]
            values = out.std if datum else 100 * out.cov
            text = f"{short_label(name)} [{out.units}]" if datum and out.units else short_label(name)
            ax.plot(out.time, values, lw=1.3, label=text, **method_style(k, out.time.size))
            series.append(values)
        ax.set_yscale("log")
        _floor_log_axis(ax, series, COV_DECADES)
        log_axis(ax.yaxis)
        ax.set_xlabel(TIME_LABEL, fontsize=9)
        ax.set_ylabel("std(t) in the output's unit (log scale)" if datum else "std(t) / max |mean| [%] (log scale)",
                      fontsize=9)
        ax.set_title(f"std: offset datum (min|mean| > {OFFSET_DATUM:g} × its excursion)" if datum
                     else "modified coefficient of variation", fontsize=10)
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8, loc="best")
    fig.suptitle(title, fontsize=12)
    fig.panel_grid = (1, len(groups))
    return _save(fig, path)


def _floor_log_axis(ax, series: list, decades: float) -> None:
    """Start a log y-axis `decades` below the largest value, so that near-zero errors at a
    deterministic instant (e.g. t = 0) do not squeeze the rest."""
    finite = [v[np.isfinite(v)] for v in (np.asarray(values, dtype=float) for values in series)]
    top = max((v.max() for v in finite if v.size), default=0.0)  # an all-NaN CoV (zero mean): none
    if top > 0:
        ax.set_ylim(bottom=decades * top)


def plot_errors(curves: list[tuple[str, dict]], key: str, path: Path, title: str) -> Path:
    """ε_m or ε_v (`key` "eps_m"/"eps_v", Eq. 49) over time, one panel per output, one line per
    file (`curves`: (label, outputs)) in its own colour, marker and dash; log y-axis over the decades
    the lines occupy, exact zeros left out."""
    names = list(dict.fromkeys(name for _, outputs in curves for name, out in outputs.items() if out.errors))
    symbol = {"eps_m": "ε_m (error of the mean)", "eps_v": "ε_v (error of the variance)"}[key]
    fig, axes = _panels(len(names), title)
    floors = any(out.errors.get(f"{key}_floor") is not None for _, outputs in curves
                 for out in outputs.values() if out.errors)
    for ax, name in zip(axes, names):
        series, drawn_floor = [], False
        for k, (_, outputs) in enumerate(curves):
            out = outputs.get(name)
            if out is not None and out.errors:
                errors = np.asarray(out.errors[key], dtype=float)
                series.append(errors)
                ax.plot(out.time, np.where(errors > 0, errors, np.nan), lw=1.1, **method_style(k, out.time.size))
                floor = out.errors.get(f"{key}_floor")
                if floor is not None and not drawn_floor:
                    floor = np.broadcast_to(np.asarray(floor, dtype=float), out.time.shape)
                    ax.plot(out.time, np.where(floor > 0, floor, np.nan), color="gray", lw=1.0, ls=(0, (5, 3)))
                    series.append(floor)
                    drawn_floor = True
                shown = out
        ax.set_yscale("log")
        _set_log_limits(ax, series)
        _style(ax, shown, ylabel=f"{symbol} [-]")
    handles, labels = _file_legend(curves)
    if floors:
        handles, labels = handles + [Line2D([], [], color="gray", ls=(0, (5, 3)))], labels + ["reference floor"]
    return _save(fig, path, (handles, labels), legend_columns=2)


def _file_legend(entries: list[tuple[str, dict]]) -> tuple[list, list[str]]:
    """Legend handles and labels for one line per file, in file order (`method_style`)."""
    labels = [file_label for file_label, _ in entries]
    return [Line2D([], [], **method_style(k)) for k in range(len(labels))], labels


def plot_kld_vs_runs(points: list[tuple[str, int, dict]], path: Path, title: str) -> Path:
    """KLD at the final time against the number of runs (Fig. 20), one panel per output and one line
    per method (hollow markers, so that coinciding methods stay visible), and the reference's KLD
    floor (the KLD its own sampling noise gives, `analysis.floors.kld_floor`; the largest over the
    methods) dashed: a KLD below it is noise. `points`: (method label, runs, {output: (KLD, floor or None)})."""
    names = list(dict.fromkeys(name for _, _, values in points for name in values))
    methods = list(dict.fromkeys(method for method, _, _ in points))
    fig, axes = _panels(len(names), title, row_height=2.7)
    floors = False
    for ax, name in zip(axes, names):
        series = []
        for k, method in enumerate(methods):
            found = sorted((n, values[name][0]) for m, n, values in points if m == method and name in values)
            if found:
                ax.plot(*zip(*found), mew=1.5, **{**method_style(k), "ms": 7})
                series.append([v for _, v in found])
        floor = [values[name][1] for _, _, values in points if name in values and values[name][1] is not None
                 and np.isfinite(values[name][1])]
        if floor:
            ax.axhline(max(floor), color="gray", ls=(0, (5, 3)), lw=1.0)
            series.append([max(floor)])
            floors = True
        runs_axis(ax, [n for _, n, values in points if name in values])
        ax.set_yscale("log")
        _set_log_limits(ax, series)
        ax.set_title(short_label(name), fontsize=10)
        ax.set_xlabel("runs (simulator calls)", fontsize=8)
        ax.set_ylabel("KLD at the final time [nat]", fontsize=8)
        ax.tick_params(labelsize=8)
        ax.grid(alpha=0.3, which="both")
    handles = [Line2D([], [], mew=1.5, **{**method_style(k), "ms": 7}) for k in range(len(methods))]
    labels = list(methods)
    if floors:
        handles.append(Line2D([], [], color="gray", ls=(0, (5, 3))))
        labels.append("reference KLD floor (below it: sampling noise)")
    return _save(fig, path, (handles, labels), legend_columns=3)


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
    """The first-order indices of a scalar output as bars, with their bootstrap intervals if any (unclipped,
    an unresolved index hatched: index_bars)."""
    parameters = list(out.sobol_first)
    x = np.arange(len(parameters))
    ci = ([out.sobol_first_ci[p] for p in parameters] if out.sobol_first_ci else None)
    found = index_bars(ax, x, [out.sobol_first[p] for p in parameters], ci, COLORS[:len(parameters)], 0.8)
    index_axis(ax, found)
    ax.set_xticks(x, parameters, fontsize=8)
    ax.set_title(short_label(out.name), fontsize=10)
    ax.set_ylabel("first-order Sobol' index S_i [-]", fontsize=8)
    ax.grid(alpha=0.3, axis="y")


UNRESOLVED_HATCH = "//"


def index_bars(ax, x, values, ci, color, width: float) -> list[float]:
    """Bars of Sobol' indices (a scalar output's or quantity's: each value's first entry) at `x`, with their
    95 % intervals (`ci`: per bar a (2, 1) array, or None) drawn as they are, never clipped to [0, 1]; a bar
    whose interval resolves no share (analysis.sobol.unresolved) hatched and marked "n too small" (NaN: no
    bar). Returns the values and bounds drawn, for `index_axis`."""
    values = np.array([float(np.asarray(v).ravel()[0]) for v in values])
    drawn = list(values[np.isfinite(values)])
    bars = ax.bar(x, np.nan_to_num(values), width=width, color=color)
    if ci is None:
        return drawn
    lower, upper = (np.array([float(np.asarray(c)[k].ravel()[0]) for c in ci]) for k in (0, 1))
    shown = np.isfinite(values) & np.isfinite(lower) & np.isfinite(upper)
    ax.vlines(np.asarray(x)[shown], lower[shown], upper[shown], color="k", lw=1.0)
    for bound in (lower, upper):
        ax.plot(np.asarray(x)[shown], bound[shown], ls="none", marker="_", color="k", ms=8)
    drawn += [*lower[shown], *upper[shown]]
    for bar, loose, top in zip(bars, unresolved(values, (lower, upper)), np.fmax(values, upper)):
        if loose:
            bar.set_hatch(UNRESOLVED_HATCH)
            bar.set_alpha(0.5)
            ax.annotate("n too small", (bar.get_x() + 0.5 * bar.get_width(), top), textcoords="offset points",
                        xytext=(0, 3), ha="center", fontsize=6)
    return drawn


def index_axis(ax, drawn: list[float]) -> None:
    """The y limits of Sobol' indices: [−0.05, 1.05] widened to every value drawn, the parts beyond [0, 1]
    (where only sampling noise lies) greyed."""
    finite = np.asarray(drawn, dtype=float)
    finite = finite[np.isfinite(finite)]
    low, high = -0.05, 1.05
    if finite.size:
        low, high = min(low, finite.min() - 0.05), max(high, finite.max() + 0.15)
    ax.set_ylim(low, high)
    if high > 1.05 or low < -0.05:
        ax.axhspan(1.0, high, color="0.9", zorder=0)
        ax.axhspan(low, min(0.0, high), color="0.9", zorder=0)


def plot_band_comparison(entries: list[tuple[str, dict]], path: Path, title: str) -> Path:
    """Each file's mean (left) and 99 % band edges (right, lower and upper alike) minus the first
    file's, over the first file's times (others interpolated), one row per output: the first file is
    the zero line, and files that agree lie on it instead of hiding each other (Figs. 4-5 as differences)."""
    _, first = entries[0]
    names = list(first)
    fig, axes = plt.subplots(len(names), 2, figsize=(12.4, 2.5 * len(names) + 1.2), squeeze=False)
    for row, name in zip(axes, names):
        base = first[name]
        for k, (_, outputs) in enumerate(entries):
            out = outputs.get(name)
            if out is None:
                continue
            style = method_style(k, base.time.size)
            row[0].plot(base.time, _on_times(out, out.mean, base) - base.mean, lw=1.2, **style)
            for bound, base_bound in zip(out.band99, base.band99):
                row[1].plot(base.time, _on_times(out, bound, base) - base_bound, lw=1.0, **style)
        unit = f" [{base.units}]" if base.units else ""
        for ax, what in zip(row, ("mean", "99 % band edges")):
            _style(ax, base, ylabel=f"difference{unit}")
            ax.set_title(f"{short_label(name)}: {what} − the first file's", fontsize=10)
    fig.suptitle(title, fontsize=12)
    handles, labels = _file_legend(entries)
    labels[0] = f"{labels[0]} (first: the zero line)"
    return _save(fig, path, (handles, labels), legend_columns=2)


def plot_final_pdfs(entries: list[tuple[str, dict]], path: Path, title: str) -> Path:
    """Each file's PDF of every output at the final time, overlaid, one panel per output."""
    first = entries[0][1]
    fig, axes = _panels(len(first), title, row_height=2.7)
    for ax, (name, out) in zip(axes, first.items()):
        for k, (_, outputs) in enumerate(entries):
            if name in outputs:
                support = outputs[name].pdf_support[-1]
                ax.plot(support, outputs[name].pdf_density[-1], lw=1.3, **method_style(k, support.size))
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
    fig, axes = plt.subplots(len(names), 2, figsize=(11, 2.6 * len(names) + 0.9), squeeze=False)
    floors = False
    for row, name in zip(axes, names):
        for column, (ax, symbol) in enumerate(zip(row, ("max ε_m [-]", "max ε_v [-]"))):
            series = []
            for k, method in enumerate(methods):
                found = sorted((n, values[name][column]) for m, n, values in points
                               if m == method and name in values and values[name][column] > 0)
                if found:
                    ax.plot(*zip(*found), mew=1.4, **method_style(k))
                    series.append([v for _, v in found])
            floor = [values[name][column + 2] for _, _, values in points
                     if name in values and values[name][column + 2] is not None]
            if floor:
                ax.axhline(max(floor), color="gray", ls=(0, (5, 3)), lw=1.0)
                series.append([max(floor)])
                floors = True
            runs_axis(ax, [n for _, n, values in points if name in values])
            ax.set_yscale("log")
            limits = informative_limits(series)
            if limits is not None:
                low, high = limits
                if high / low < 10:  # at least a decade, so that log ticks stay readable
                    middle = np.sqrt(low * high)
                    low, high = middle / np.sqrt(10), middle * np.sqrt(10)
                ax.set_ylim(low, high)
            log_axis(ax.yaxis)
            ax.set_title(f"{short_label(name)}: {symbol.split(' [')[0]}", fontsize=10)
            ax.set_xlabel("runs (simulator calls)", fontsize=8)
            ax.set_ylabel(symbol, fontsize=8)
            ax.tick_params(labelsize=8)
            ax.grid(alpha=0.3, which="both")
    fig.suptitle(title, fontsize=12)
    handles = [Line2D([], [], mew=1.4, **method_style(k)) for k in range(len(methods))]
    labels = list(methods)
    if floors:
        handles.append(Line2D([], [], color="gray", ls=(0, (5, 3))))
        labels.append("reference floor")
    return _save(fig, path, (handles, labels), legend_columns=3)


def plot_coefficient_decay(outputs: dict, path: Path, title: str, start_s: float | None = None) -> Path:
    """Root-sum-square of the PCE coefficients of each total degree from 1 on (degree 0 is the mean)
    over time, log y, one panel per output (`OutputStatistics.coefficient_decay`: {degree: array over
    time}); from the excitation's start `start_s` on (before it every run flies the same trim), or,
    unknown, from where degree >= 1 first reaches DECAY_ONSET of its largest value."""
    names = [n for n, o in outputs.items() if getattr(o, "coefficient_decay", None)]
    fig, axes = _panels(max(len(names), 1), title)
    degrees: list = []
    for ax, name in zip(axes, names):
        out = outputs[name]
        shown = sorted(((int(d), np.asarray(v, dtype=float)) for d, v in out.coefficient_decay.items() if int(d) >= 1))
        keep = _decay_times(out.time, [v for _, v in shown], start_s)
        series = []
        for degree, values in shown:
            if degree not in degrees:
                degrees.append(degree)
            values = np.where(values[keep] > 0, values[keep], np.nan)
            series.append(values)
            ax.plot(out.time[keep], values, lw=1.1, **method_style(degrees.index(degree), int(keep.sum())))
        ax.set_yscale("log")
        _set_log_limits(ax, series)
        _style(ax, out, ylabel=f"RSS of coefficients [{out.units}]" if out.units else "RSS of coefficients")
    handles = [Line2D([], [], **method_style(k)) for k in range(len(degrees))]
    return _save(fig, path, (handles, [f"degree {d}" for d in degrees]), legend_columns=6)


MAX_PAIRS = 8  # parameters drawn in the design scatter (the first ones)


def plot_design_pairs(drawn, path: Path, title: str) -> Path | None:
    """The design points on every pair of inputs (lower triangle) in physical values κ (paper Fig. 9,
    which is in ξ); marker area by |weight| for a grid, negative weights orange, failed runs as red
    crosses, each in the legend with its count. A design whose pairs all coincide in ξ (a symmetric
    grid) is drawn once in ξ, with each input's κ at the grid's ξ levels in a table. None for one input.
    `drawn`: the file's runs (analysis.drawn.DrawnRuns, Statistics.drawn)."""
    xi, kappa, weights = drawn.xi, drawn.kappa, drawn.weights
    status, names = drawn.status, drawn.parameter_names
    d = min(xi.shape[1], MAX_PAIRS)
    if d < 2:
        return None
    pairs = [(i, j) for i in range(1, d) for j in range(i)]
    failed = status > 0
    signed = not np.allclose(weights, weights[0])
    key = _pair_key(xi, weights, failed, *pairs[0])
    if len(pairs) > 1 and all(_pair_key(xi, weights, failed, i, j) == key for i, j in pairs[1:]):
        fig, (ax, table) = plt.subplots(1, 2, figsize=(11, 4.8), gridspec_kw={"width_ratios": [1, 1.3]})
        handles = _design_points(ax, xi[:, 0], xi[:, 1], weights, failed, signed, xi.shape[0])
        ax.set_xlabel("ξ of any input", fontsize=9)
        ax.set_ylabel("ξ of any other input", fontsize=9)
        ax.set_title(f"all {len(pairs)} pairs of the {d} inputs coincide: drawn once", fontsize=10)
        ax.grid(alpha=0.3)
        _kappa_table(table, xi, kappa, names[:d])
        fig.legend(*handles, loc="lower center", ncol=3, fontsize=8, frameon=False)
        fig.suptitle(title, fontsize=11)
        # fixed margins in inches: tick labels and names left of and below the scatter, the legend under it
        fig.subplots_adjust(left=0.75 / 11, right=1 - 0.2 / 11, bottom=0.95 / 4.8, top=1 - 0.7 / 4.8,
                            wspace=0.3 / 4.9)
        return write_figure(fig, path)
    side = max(1.7 * (d - 1) + 1.2, 7.0)
    fig = plt.figure(figsize=(side, side - 0.2))
    # fixed margins in inches: names and 6-pt tick labels outside the grid, none between its panels
    grid = fig.add_gridspec(d - 1, d - 1, left=0.75 / side, right=1 - 0.2 / side, bottom=0.6 / side,
                            top=1 - 0.85 / side, wspace=0.12, hspace=0.12)
    for i in range(1, d):
        for j in range(i):  # the lower triangle only: no hidden panels to build
            ax = fig.add_subplot(grid[i - 1, j])
            handles = _design_points(ax, kappa[:, j], kappa[:, i], weights, failed, signed, xi.shape[0])
            ax.tick_params(labelsize=6)
            ax.xaxis.set_major_locator(MaxNLocator(3))
            ax.yaxis.set_major_locator(MaxNLocator(3))
            if j == 0:
                ax.set_ylabel(names[i], fontsize=8)
            else:
                ax.tick_params(labelleft=False)  # hides them without building the ticks now
            if i == d - 1:
                ax.set_xlabel(names[j], fontsize=8)
            else:
                ax.tick_params(labelbottom=False)
            ax.grid(alpha=0.3)
    fig.legend(*handles, loc="upper right", fontsize=8, frameon=False)
    fig.suptitle(f"{title}\nphysical values κ", fontsize=11)
    return write_figure(fig, path)


def offset_datum(out) -> bool:
    """Whether an output over time sits on an offset datum (an altitude of 15,000 ft, an airspeed of
    200 kt): min|mean| more than OFFSET_DATUM times the mean's excursion max − min. Its std / max|mean|
    is then the std over a constant that says where zero is, not how uncertain the output is.
    A scalar output keeps its CoV."""
    mean = np.asarray(out.mean, dtype=float)
    if mean.size < 2 or not np.isfinite(mean).all():
        return False
    return bool(np.min(np.abs(mean)) > OFFSET_DATUM * (mean.max() - mean.min()))


def informative_limits(series: list) -> tuple[float, float] | None:
    """Log-axis limits that show every line and no empty decades: from half the lowest line's 2 %
    quantile (so that a dip to zero at one instant does not stretch the axis) to 1.5 × the largest
    value, at most 12 decades. None when no value is positive."""
    positive = [v[np.isfinite(v) & (v > 0)] for v in (np.atleast_1d(np.asarray(s, dtype=float)) for s in series)]
    positive = [v for v in positive if v.size]
    if not positive:
        return None
    top = max(v.max() for v in positive)
    low = min(np.quantile(v, LOW_QUANTILE) for v in positive)
    return max(low / 2, top * 1e-12), top * 1.5


def _set_log_limits(ax, series: list) -> None:
    limits = informative_limits(series)
    if limits is not None:
        ax.set_ylim(*limits)
    log_axis(ax.yaxis)


def _on_times(out, values, base) -> np.ndarray:
    """`values` of `out` at the times of `base` (linear interpolation; a scalar output as it is)."""
    values = np.asarray(values, dtype=float)
    if out.time.size == 1 or np.array_equal(out.time, base.time):
        return values
    return np.interp(base.time, out.time, values)


def _decay_times(time: np.ndarray, series: list, start_s: float | None) -> np.ndarray:
    """The times the decay plot shows: from `start_s` on, or from the onset of the variation."""
    if time.size == 1:
        return np.ones(1, dtype=bool)
    if start_s is not None:
        keep = time >= start_s
        return keep if keep.any() else np.ones_like(time, dtype=bool)
    total = np.nanmax(series, axis=0) if series else np.zeros_like(time)
    peak = np.nanmax(total) if np.isfinite(total).any() else 0.0
    onset = np.flatnonzero(total >= DECAY_ONSET * peak) if peak > 0 else np.zeros(1, dtype=int)
    return time >= time[onset[0]]


def _pair_key(xi, weights, failed, i, j) -> list:
    """The points of the pair (ξ_j, ξ_i) as a sorted list of (x, y, weight, failed): equal keys, equal panels."""
    return sorted(zip(np.round(xi[:, j], 9), np.round(xi[:, i], 9), np.round(weights, 12), failed))


def _design_points(ax, x, y, weights, failed, signed: bool, count: int) -> tuple[list, list[str]]:
    """Scatter the runs: area by |weight| for a grid (`signed`), negative weights in orange, failed
    runs as red crosses; returns the legend's (handles, labels) with their counts."""
    sizes = 6 + 40 * np.abs(weights) / np.abs(weights).max() if signed else np.full(len(x), 8.0)
    alpha = 0.8 if count <= 500 else 0.25
    negative = (weights < 0) & ~failed
    positive = ~negative & ~failed
    if signed:
        ax.scatter(x[positive], y[positive], s=sizes[positive], color=COLORS[0], alpha=alpha, lw=0)
        ax.scatter(x[negative], y[negative], s=sizes[negative], color=COLORS[1], alpha=alpha, lw=0)
    else:  # one marker size: drawn as a line's markers (one stamp repeated), many times faster for 10^4 runs
        ax.plot(x[positive], y[positive], ls="", marker="o", ms=np.sqrt(8.0), mew=0, color=COLORS[0], alpha=alpha)
    ax.scatter(x[failed], y[failed], s=18, color="red", marker="x", lw=1)
    run = "run (area ∝ |weight|)" if signed else "run"
    handles = [Line2D([], [], ls="", marker="o", color=COLORS[0]), Line2D([], [], ls="", marker="x", color="red")]
    labels = [f"{run}: {int(positive.sum())}", f"failed run: {int(failed.sum())}"]
    if signed:
        handles.insert(1, Line2D([], [], ls="", marker="o", color=COLORS[1]))
        labels.insert(1, f"negative weight: {int(negative.sum())}")
    return handles, labels


def _kappa_table(ax, xi, kappa, names) -> None:
    """Each input's physical value κ at the grid's ξ levels, as a table on `ax`."""
    levels = np.unique(np.round(xi[:, 0], 9))
    rows = []
    for p, name in enumerate(names):
        cells = []
        for level in levels:
            at = np.flatnonzero(np.isclose(xi[:, p], level, atol=1e-9))
            cells.append(f"{kappa[at[0], p]:.4g}" if at.size else "")
        rows.append([name, *cells])
    ax.axis("off")
    ax.set_title("physical value κ of each input at each ξ level", fontsize=10)
    table = ax.table(cellText=rows, colLabels=["input", *(f"ξ = {v:.3g}" for v in levels)], loc="center")
    table.auto_set_font_size(False)
    table.set_fontsize(7 if len(levels) > 5 else 8)
    table.scale(1.0, 1.3)
