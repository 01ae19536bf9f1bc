"""Sobol' indices as the report shows them: compact index text, the top contributors of a variance, the
partial variances S_i(t)·Var(t), and one figure per file of partial variances beside the first-order and
total indices, with the times where the variance is negligible greyed."""
from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.patches import Patch

from ..analysis.sobol import NEGLIGIBLE, unresolved  # noqa: F401 (NEGLIGIBLE: the report's too)
from . import plots

TINY_INDEX = 1e-3  # indices below this print as "<0.001"
TOP = 3  # contributors the headline names
SHOWN_SHARE = 0.01  # ... each with at least 1 % of the variance
INTERACTIONS_SHOWN = 0.05  # the interactions' share is named from 5 % on
UNRESOLVED = "unresolved"
N_TOO_SMALL = "n too small"  # a pick-freeze index whose interval resolves no share
GREY = "0.9"  # the times of negligible variance, on the indices
INTERACTIONS = "0.6"  # the interactions' part of the stack


def index_text(value) -> str:
    """A Sobol' index for the page: 3 significant digits, "<0.001" below 0.001 in magnitude (estimator
    noise or nothing), "unresolved" where the variance is not resolved (NaN or None); text as it is."""
    if isinstance(value, str):  # "" for a parameter the file does not have, or already text
        return value
    if value is None or not np.isfinite(value):
        return UNRESOLVED
    value = float(value)
    return f"<{TINY_INDEX:g}" if abs(value) < TINY_INDEX else f"{value:#.3g}".rstrip(".")


def _percent(share: float) -> str:
    """A share as a percentage within [0, 100] (an estimate or bound beyond it is sampling noise)."""
    return f"{100 * min(max(share, 0.0), 1.0):.0f}"


def top_contributors(first: dict[str, np.ndarray], i: int, first_ci: dict[str, np.ndarray] | None = None) -> str:
    """The largest first-order shares of the variance at time index i, e.g. "CL0 62 %, k2 21 %", the
    interactions' share (1 − Σ S_i) appended when it is 5 % or more; "unresolved" where the variance is.
    With pick-freeze intervals (`first_ci`: (2, T) per parameter) each share carries its 95 % interval,
    "CL0 62 % (55–70 %)", and an index its interval does not resolve (analysis.sobol.unresolved) reads
    "CL0 unresolved (−0.4 to 9.3, n too small)": no share is shown beyond [0, 100] %."""
    values = {p: float(v[i]) for p, v in first.items()}
    if not values or not all(np.isfinite(list(values.values()))):
        return UNRESOLVED
    intervals = {p: (float(first_ci[p][0][i]), float(first_ci[p][1][i])) for p in values} if first_ci else {}
    loose = [p for p in values if p in intervals and unresolved(values[p], intervals[p])]
    ranked = sorted(((p, s) for p, s in values.items() if p not in loose), key=lambda item: -item[1])
    named = []
    for p, s in ranked[:TOP]:
        if s >= SHOWN_SHARE:
            interval = f" ({_percent(intervals[p][0])}–{_percent(intervals[p][1])} %)" if p in intervals else ""
            named.append(f"{p} {_percent(s)} %{interval}")
    rest = 1.0 - sum(values.values())
    if not loose and rest >= INTERACTIONS_SHOWN:
        named.append(f"interactions {_percent(rest)} %")
    named += [f"{p} {UNRESOLVED} ({intervals[p][0]:.2g} to {intervals[p][1]:.2g}, {N_TOO_SMALL})" for p in loose]
    return ", ".join(named) or "none above 1 %"


def negligible(out) -> np.ndarray:
    """(T,) bool: times where the variance is below NEGLIGIBLE of its largest over time, or unresolved."""
    variance = np.asarray(out.variance, dtype=float)
    top = np.max(variance) if variance.size else 0.0
    return (variance < NEGLIGIBLE * top) | ~np.asarray(out.resolved, dtype=bool)


def partial_variances(out) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """S_i(t)·Var(t) per parameter, in the output's unit squared (0 where the index is unresolved), and
    the rest Var(t) − Σ_i S_i(t)·Var(t): the interactions' variance (negative only by estimator noise)."""
    variance = np.maximum(np.asarray(out.variance, dtype=float), 0.0)
    parts = {p: np.nan_to_num(np.asarray(s, dtype=float)) * variance for p, s in out.sobol_first.items()}
    return parts, variance - sum(parts.values())


def _spans(mask: np.ndarray, time: np.ndarray) -> list[tuple[float, float]]:
    """(start, end) times of each run of True in mask, half a step wide beyond the ends."""
    if not mask.any():
        return []
    edges = np.concatenate([[time[0]], 0.5 * (time[1:] + time[:-1]), [time[-1]]])
    change = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(np.int8), [0]])))
    return [(edges[a], edges[b]) for a, b in zip(change[::2], change[1::2])]


def _indices_panel(ax, out, grey: list) -> None:
    """First-order (solid) and total (dashed) indices over time, the spans in `grey` shaded."""
    low, high = -0.05, 1.05
    for color, parameter in zip(plots.COLORS, out.sobol_first):
        for indices, style in ((out.sobol_first, "-"), (out.sobol_total, "--")):
            values = np.asarray(indices[parameter], dtype=float)
            ax.plot(out.time, values, color=color, lw=1.0, ls=style)
            finite = values[np.isfinite(values)]
            if finite.size:  # estimator noise outside [0, 1] is shown, not clipped
                low, high = min(low, finite.min() - 0.05), max(high, finite.max() + 0.05)
    for start, end in grey:
        ax.axvspan(start, end, color=GREY, lw=0, zorder=0)
    ax.set_ylim(low, high)
    plots._style(ax, out, ylabel="Sobol' index [-]")
    ax.set_title(f"{plots.short_label(out.name)}: S_i solid, S_Ti dashed", fontsize=10)


def plot_sensitivity(outputs: dict, path: Path, title: str) -> Path | None:
    """Per output over time (a row each): the stacked partial variances S_i·Var with the interactions on
    top (the stack's height is Var(t)), and beside them the first-order indices S_i and the total
    indices S_Ti, the times of negligible variance greyed. None when no output over time has indices."""
    names = [name for name, out in outputs.items() if out.sobol_first and out.time.size > 1]
    if not names:
        return None
    fig, axes = plots.plt.subplots(len(names), 2, figsize=(12.4, 2.5 * len(names) + 1.2), squeeze=False)
    parameters = list(outputs[names[0]].sobol_first)
    for row, name in zip(axes, names):
        out = outputs[name]
        parts, rest = partial_variances(out)
        row[0].stackplot(out.time, *parts.values(), np.maximum(rest, 0.0),
                         colors=[*plots.COLORS[:len(parts)], INTERACTIONS], lw=0)
        row[0].plot(out.time, np.maximum(out.variance, 0.0), color="k", lw=0.8)
        plots._style(row[0], out, ylabel=f"S_i·Var [{out.units}²]" if out.units else "S_i·Var [-]")
        row[0].set_title(f"{plots.short_label(name)}: partial variances", fontsize=10)
        row[0].ticklabel_format(axis="y", style="sci", scilimits=(-3, 4))  # 1.2e-4 as 1.2 ×1e-4
        _indices_panel(row[1], out, _spans(negligible(out), out.time))
    handles = [Patch(color=c) for c in (*plots.COLORS[:len(parameters)], INTERACTIONS, "k", GREY)]
    labels = [*parameters, "interactions", "Var(t)", f"variance < {NEGLIGIBLE:g} of its max, or unresolved"]
    fig.suptitle(title, fontsize=12)
    fig.panel_grid = axes.shape
    return plots._save(fig, path, (handles, labels), legend_columns=6)
