"""The report's section on a rare-event design (designs.rare): the event's probability with its 95 % interval,
c.o.v., runs and reliability index β; its convergence round by round; and the runs in the input space, those
in the event marked, with the most probable failure point (the design point)."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from . import plots
from .blocks import Figure, Section, Table, _rel
from .loading import AnalysedFile, file_name_within


def _g(value, digits: int = 3) -> str:
    return "null" if value is None or not math.isfinite(value) else f"{value:.{digits}g}"


def estimate_text(record: dict, event: str) -> str:
    """"P(y > 3) = 1.2e-06 (95 %: 9.1e-07 to 1.6e-06), c.o.v. 0.11, 4000 runs, β = 4.71"."""
    return (f"P({event}) = {_g(record['probability'])} (95 %: {_g(record['lower'])} to {_g(record['upper'])}), "
            f"c.o.v. {_g(record['cov'], 2)}, {record['runs']} runs, β = {_g(record['beta'])}")


def headline_rows(entry: AnalysedFile) -> tuple[list, list] | None:
    """(CSV rows, page rows) of the estimate for the headline, or None for another design."""
    runs = getattr(entry.stats, "rare_runs", None)
    if not runs:
        return None
    record = runs["record"]
    csv = [[entry.label, record["method"], runs["event"], record["probability"], record["lower"], record["upper"],
            record["cov"], record["runs"], record["beta"], record["stopped"]]]
    page = [[record["method"], f"P({runs['event']})", _g(record["probability"]),
             f"{_g(record['lower'])} to {_g(record['upper'])}", _g(record["cov"], 2), str(record["runs"]),
             _g(record["beta"]), record["stopped"]]]
    return csv, page


HEADLINE_HEADER = (["file", "method", "event", "probability", "lower (95 %)", "upper (95 %)", "cov", "runs", "beta",
                    "stopped"],
                   ["method", "event", "probability", "95 % interval", "c.o.v.", "runs", "β", "stopped by"])


def headline_table(entry: AnalysedFile) -> Table | None:
    """The headline's table of a rare-event design's estimate (tables/rare_event.csv), None for another design."""
    rows = headline_rows(entry)
    if rows is None:
        return None
    return Table(f"The event's probability, {entry.label}", HEADLINE_HEADER[0], rows[0], "tables/rare_event.csv",
                 page=(HEADLINE_HEADER[1], rows[1]))


def plot_convergence(record: dict, event: str, path: Path, title: str) -> Path:
    """The estimate after each round against the runs so far (log scale), with p·(1 ± 1.96 c.o.v.) where the
    c.o.v. is known, and the final 95 % interval."""
    fig, ax = plots.plt.subplots(figsize=(7.5, 4.2))
    runs, p, cov = (np.asarray(record[k], dtype=float) for k in ("round_runs", "round_probability", "round_cov"))
    shown = np.isfinite(p) & (p > 0)
    ax.plot(runs[shown], p[shown], "o-", color=plots.COLORS[0], ms=4, lw=1.2, label="estimate after the round")
    band = shown & np.isfinite(cov)
    if band.any():
        low = np.maximum(p[band] * (1 - 1.96 * cov[band]), p[band] * 1e-3)
        ax.fill_between(runs[band], low, p[band] * (1 + 1.96 * cov[band]), color=plots.COLORS[0], alpha=0.2,
                        label="± 1.96 c.o.v.")
    zero = np.isfinite(p) & (p == 0)
    if zero.any():
        for x in runs[zero]:
            ax.axvline(x, color="0.6", lw=0.8, ls=":")
    if record["upper"] > 0 and record["lower"] > 0:
        ax.errorbar([record["runs"]], [record["probability"]], yerr=[[record["probability"] - record["lower"]],
                                                                      [record["upper"] - record["probability"]]],
                    fmt="s", color="k", ms=5, capsize=4, label="final estimate, 95 % interval")
    elif record["upper"] > 0:  # no run in the event: the estimate is 0, its upper bound is what the runs say
        ax.plot([record["runs"]], [record["upper"]], "v", color="k", ms=7, label="upper bound (estimate 0)")
    if shown.any() or record["upper"] > 0:
        ax.set_yscale("log")
    ax.set_xlabel("runs so far", fontsize=9)
    ax.set_ylabel(f"P({event})", fontsize=9)
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3, which="both")
    ax.tick_params(labelsize=8)
    ax.legend(fontsize=8, loc="best")
    return plots._save(fig, path)


def input_pairs(importance: np.ndarray, d: int) -> list[tuple[int, int]]:
    """The pairs of inputs to draw: among the (up to) three largest shares of the design point, or the first
    inputs when there is none; one pair for two inputs, none for one."""
    if d < 2:
        return []
    order = list(np.argsort(-np.nan_to_num(importance, nan=-1.0), kind="stable")) if np.isfinite(importance).any() \
        else list(range(d))
    top = order[:3]
    return [(top[0], top[1])] if len(top) == 2 else [(top[0], top[1]), (top[0], top[2]), (top[1], top[2])]


def plot_runs(runs: dict, names: list[str], path: Path, title: str) -> Path:
    """The runs in the input space (physical values) of the inputs that weigh most in the design point: those
    outside the event grey, in the event red, failed runs black crosses, the design point a star. One input:
    its value against the margin."""
    record, kappa, status, margin = runs["record"], runs["kappa"], runs["status"], runs["margin"]
    d = kappa.shape[1]
    pairs = input_pairs(record["importance"], d)
    panels = max(1, len(pairs))
    fig, axes = plots.plt.subplots(1, panels, figsize=(4.6 * panels + 0.6, 4.4), squeeze=False)
    inside, failed = np.nan_to_num(margin, nan=-np.inf) > 0, status > 0
    outside = ~inside & ~failed & np.isfinite(margin)
    point = record["design_point"]
    nearest = None if inside.any() or not outside.any() else int(np.nanargmax(np.where(outside, margin, np.nan)))

    def share(k: int) -> str:
        return f" (share {_g(record['importance'][k], 2)})" if np.isfinite(record["importance"][k]) else ""

    for ax, pair in zip(axes[0], pairs or [None]):
        if pair is None:
            x, y, px, py = kappa[:, 0], margin, point[0], 0.0
            ax.set_xlabel(names[0], fontsize=9)
            ax.set_ylabel("margin (> 0: in the event)", fontsize=9)
        else:
            (i, j) = pair
            x, y, px, py = kappa[:, i], kappa[:, j], point[i], point[j]
            ax.set_xlabel(names[i] + share(i), fontsize=9)
            ax.set_ylabel(names[j] + share(j), fontsize=9)
        order = np.flatnonzero(outside)[np.argsort(margin[outside], kind="stable")]  # nearest the event on top
        ax.scatter(x[order], y[order], s=5, c=margin[order], cmap="Greys", alpha=0.7, lw=0,
                           vmin=np.min(margin[order]) - 0.3 * np.ptp(margin[order]) if order.size else None,
                           label="outside the event (darker: nearer)")
        ax.scatter(x[inside], y[inside], s=9, color="tab:red", alpha=0.8, lw=0, label="in the event")
        if nearest is not None:
            ax.plot([x[nearest]], [y[nearest]], "D", color="tab:blue", mec="k", ms=7, label="run nearest the event")
        if failed.any():
            ax.scatter(x[failed], y[failed], s=18, marker="x", color="k", lw=0.8, label="failed run")
        if np.isfinite(px) and np.isfinite(py):
            ax.plot([px], [py], "*", color="gold", mec="k", ms=15, label="design point")
        ax.grid(alpha=0.3)
        ax.tick_params(labelsize=8)
    axes[0][0].legend(fontsize=7, loc="best")
    fig.suptitle(title, fontsize=11)
    return plots._save(fig, path)


def rare_event_section(entries: list[AnalysedFile], out_dir: Path) -> Section | None:
    """Per file of a rare-event design: the estimate, its rounds (table and figure) and the runs in the inputs."""
    blocks, facts, rounds = [], [], []
    for entry in entries:
        runs = getattr(entry.stats, "rare_runs", None)
        if not runs:
            continue
        record, event, names = runs["record"], runs["event"], entry.stats.parameter_names
        facts.append(f"{entry.label}: {estimate_text(record, event)}; {record['method']}, stopped by "
                     f"{record['stopped']}, {record['failed']} failed runs")
        rounds += [[entry.label, k + 1, int(r), p, c] for k, (r, p, c) in
                   enumerate(zip(record["round_runs"], record["round_probability"], record["round_cov"]))]
        path = plot_convergence(record, event, out_dir / "plots" / file_name_within(f"rare_convergence_{entry.stem}.png"),
                                f"{record['method']}: the estimate round by round, {entry.label}")
        blocks.append(Figure(_rel(path, out_dir), f"The estimate of P({event}) after each round of the "
                                                  f"{record['method']} against the runs so far, with ± 1.96 times its "
                                                  "c.o.v. where known, and the final 95 % interval (square)."))
        path = plot_runs(runs, names, out_dir / "plots" / file_name_within(f"rare_runs_{entry.stem}.png"),
                         f"The runs in the inputs, {entry.label}")
        point = record["design_point"]
        where = ("; the design point (star): " + ", ".join(f"{n} = {_g(v, 5)}" for n, v in zip(names, point))
                 if np.isfinite(point).all() else "; no run reached the event: no design point, the run nearest "
                 "the event a diamond")
        blocks.append(Figure(_rel(path, out_dir), f"The {record['runs']} runs of {entry.label} in the physical "
                                                  "values of the inputs that weigh most in the design point (each "
                                                  "axis with its share α² of it): in the event red, outside grey, "
                                                  f"failed runs crosses, the others shaded by their margin{where}. The runs were "
                                                  "placed by the algorithm: their density is not the input law's."))
    if not facts:
        return None
    blocks.insert(0, Table("The estimate after each round", ["file", "round", "runs so far", "probability", "cov"],
                           rounds, "tables/rare_event_rounds.csv"))
    return Section("Rare event: the probability", "rare-event",
                   "The probability of the event, estimated by a design that adapts its runs to it (see "
                   "docs/rare-events.md): the 95 % interval is the algorithm's own, from its estimator's spread. "
                   + "; ".join(facts) + ".", blocks)
