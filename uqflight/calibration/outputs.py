"""What `calibrate` writes: posterior.h5, summary.json (strict JSON), calibrated.yaml and the plots."""
from __future__ import annotations

import json
import math
from pathlib import Path

import h5py
import numpy as np
import yaml

from ..campaign.schema import LAW_KEYS
from ..running.forking import FORKS, Child, ChildFailed, wait_all
from ..text.labels import label, parameter_label, short_label
from ..analysis.statistics import json_ready as strict

OUTPUT_FILES = ("posterior.h5", "summary.json", "calibrated.yaml", "plots/corner.png", "plots/marginals.png",
                "plots/predictive.png")
INFORMED = 0.9  # posterior std below this fraction of the prior's: the parameter gets the posterior marginal
DEPENDENT = 0.1  # a posterior correlation (of normal scores) this large puts both parameters in dependence:
STRONG = 0.3  # correlations listed in calibrated.yaml's comments
EIGENVALUE_LIFT = 1e-8  # the written correlation's smallest eigenvalue at least this (the schema refuses <= 1e-10)


def informed(post: dict, prior: dict) -> bool:
    """Whether the data narrowed a parameter enough for calibrated.yaml to give it its posterior marginal."""
    return post["std"] < INFORMED * prior["std"]


def copula_correlation(scores: np.ndarray) -> tuple[np.ndarray, float]:
    """The correlation of normal scores (M, d), symmetric with a unit diagonal, and the share s of the
    identity mixed in ((1 − s) R + s I) to keep its smallest eigenvalue >= EIGENVALUE_LIFT (0: none)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        r = np.corrcoef(scores, rowvar=False) if scores.shape[1] > 1 else np.ones((1, 1))
    r = np.where(np.isfinite(r), 0.5 * (r + r.T), 0.0)  # a parameter that does not vary: uncorrelated
    np.fill_diagonal(r, 1.0)
    smallest = float(np.linalg.eigvalsh(r).min())
    share = 0.0 if smallest >= EIGENVALUE_LIFT else (EIGENVALUE_LIFT - smallest) / (1.0 - smallest)
    return (1.0 - share) * r + share * np.eye(len(r)), share


def marginal(values: np.ndarray) -> dict:
    """mean, std and the central 95 % interval [2.5 %, 97.5 % quantiles] of draws (M,)."""
    lower, upper = np.quantile(values, [0.025, 0.975])
    return {"mean": float(np.mean(values)), "std": float(np.std(values, ddof=1)), "ci95": [float(lower), float(upper)]}


def write_json(path: Path, data: dict) -> None:
    path.write_text(json.dumps(strict(data), indent=2, allow_nan=False) + "\n", encoding="utf-8")


def is_posterior_file(path: Path) -> bool:
    """Whether `path` is a posterior.h5 that write_posterior wrote (its draws and chain)."""
    if path.is_symlink() or not path.is_file() or not h5py.is_hdf5(path):
        return False
    try:
        with h5py.File(path, "r") as f:
            return isinstance(f.get("draws"), h5py.Group) and isinstance(f.get("chain"), h5py.Dataset)
    except OSError:
        return False


def write_posterior(path: Path, names, properties, xi, kappa, noise_names, sigma, log_prob, chain, labels,
                    burn: int, attrs: dict) -> None:
    """Posterior draws (kept part of the chain, walkers interleaved) in standard and physical variables."""
    with h5py.File(path, "w") as f:
        draws = f.create_group("draws")
        d = draws.create_dataset("xi", data=xi)
        d.attrs["names"] = list(names)
        d.attrs["dimensions"] = ["draw", "parameter"]
        d.attrs["description"] = "standard variables: N(0, 1) or U(-1, 1) germs of the campaign's parameters"
        d = draws.create_dataset("kappa", data=kappa)
        d.attrs["names"] = list(names)
        d.attrs["properties"] = list(properties)
        d.attrs["dimensions"] = ["draw", "parameter"]
        d.attrs["description"] = "physical values of the parameters"
        d = draws.create_dataset("sigma", data=sigma)
        d.attrs["names"] = list(noise_names)
        d.attrs["dimensions"] = ["draw", "output"]
        d.attrs["description"] = "noise standard deviation per output, in its unit (constant when given)"
        draws.create_dataset("log_prob", data=log_prob).attrs["description"] = "log posterior, up to a constant"
        c = f.create_dataset("chain", data=chain, compression="gzip")
        c.attrs["labels"] = list(labels)
        c.attrs["dimensions"] = ["step", "walker", "label"]
        c.attrs["burn_in"] = burn
        c.attrs["description"] = "the whole chain, burn-in included; sigma_* labels are log sigma"
        for key, value in attrs.items():
            f.attrs[key] = value


def calibrated_campaign(mapping: dict, specs: dict, posterior: dict, prior: dict, scores: np.ndarray,
                        names: list[str], source: str) -> str:
    """The campaign text with the posterior marginals as its parameters (normal, mean ± 3σ) and their
    posterior dependence as a Gaussian copula (`dependence:`).

    Parameters whose posterior std is not below INFORMED × the prior's keep their prior: the data
    say nothing about them, and a normal approximation would only change their shape. `scores` (M, d)
    are the posterior draws as normal scores under those marginals (`run.normal_scores`): their
    correlation is the copula's; the parameters with a correlation of at least DEPENDENT with another
    form the `dependence:` group (the others stay independent; an earlier `dependence:` is replaced).
    An informed parameter keeps every key but its law (LAW_KEYS): its `property`, or the `function` and
    `perturbation` it perturbs, and any other."""
    mapping = dict(mapping)
    name = str(mapping.get("name", "campaign"))
    mapping["name"] = f"{name}-calibrated"
    storage = dict(mapping.get("storage") or {})
    storage["path"] = f"results/{name}-calibrated.h5"
    mapping["storage"] = storage
    parameters = {}
    kept = []
    for pname in names:
        original = dict(mapping["parameters"][pname])
        post, pri = posterior[pname], prior[pname]
        if not informed(post, pri):
            parameters[pname] = original
            kept.append(pname)
            continue
        mean, std = post["mean"], post["std"]
        entry = {key: value for key, value in original.items() if key not in LAW_KEYS}  # property, function, ...
        entry.update({"distribution": "normal", "nominal": float(mean),
                      "lower": float(mean - 3 * std), "upper": float(mean + 3 * std)})
        parameters[pname] = entry
    correlation, lift = copula_correlation(scores)
    d = len(names)
    group = [k for k in range(d) if any(abs(correlation[k, j]) >= DEPENDENT for j in range(d) if j != k)]
    rebuilt = {}
    for key, value in mapping.items():
        if key == "dependence":
            continue
        rebuilt[key] = parameters if key == "parameters" else value
        if key == "parameters" and group:
            rebuilt["dependence"] = {"kind": "gaussian_copula", "parameters": [names[k] for k in group],
                                     "correlation": correlation[np.ix_(group, group)].tolist()}
    lines = [f"# {name}, calibrated by `uqflight calibrate` ({source}).",
             "# Informed parameters: normal with the posterior mean as nominal and [lower, upper] = mean ± 3 posterior std",
             "# (the campaign schema's 99.7 % interval)."]
    if kept:
        lines.append(f"# Kept at their prior (posterior std ≥ {INFORMED:g} × prior std): {', '.join(kept)}.")
    strong = [(names[i], names[j], correlation[i, j]) for i in range(d) for j in range(i + 1, d)
              if abs(correlation[i, j]) >= STRONG]
    if group:
        lines.append(f"# dependence: the posterior's Gaussian copula over the parameters with a correlation |r| ≥ "
                     f"{DEPENDENT:g} (r of the draws' normal scores under the marginals below; for normal ones, "
                     "of the draws themselves).")
        lines += [f"#   {a} - {b}: r = {r:+.2f}" for a, b, r in sorted(strong, key=lambda x: -abs(x[2]))]
        if lift:
            lines.append(f"# (mixed with {lift:.2g} of the identity to keep the matrix positive definite)")
    else:
        lines.append(f"# No posterior correlation reaches |r| = {DEPENDENT:g}: the parameters stay independent.")
    lines.append("# The joint posterior is in posterior.h5 (draws/kappa); summary.json has the full matrix.")
    body = yaml.safe_dump(rebuilt, sort_keys=False, default_flow_style=None, allow_unicode=True, width=100)
    return "\n".join(lines) + "\n" + body


# -- plots --------------------------------------------------------------------------------------------
def draw_all(plots: list) -> None:
    """Call every plot function, each in a forked child at once where the system forks (they are
    independent); RuntimeError when one fails (its traceback is printed)."""
    if not FORKS:
        for plot in plots:
            plot()
        return
    pyplot()  # imported once here, not in each child
    failed = [str(outcome) if isinstance(outcome, ChildFailed) else f"raised {outcome}"
              for outcome in wait_all([Child(plot) for plot in plots]) if isinstance(outcome, (ChildFailed, OSError))]
    if failed:
        raise RuntimeError(f"cannot write a calibration plot: its process {failed[0]} (the error is printed above)")


def pyplot():
    """matplotlib.pyplot on the Agg backend (imported on first use: a second on this machine)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def corner_plot(path: Path, draws: np.ndarray, names: list[str], truth=None, bins: int = 40,
                properties: list[str] | None = None) -> None:
    """Write `corner_figure` to `path`."""
    _write(corner_figure(draws, names, truth, bins, properties), path)


def _write(fig, path: Path) -> None:
    fig.savefig(path, dpi=90)
    pyplot().close(fig)


def corner_figure(draws: np.ndarray, names: list[str], truth=None, bins: int = 40, properties: list[str] | None = None):
    """A lower-triangle corner plot in physical values, axes labelled with the parameters' units:
    histograms on the diagonal, 2-D histograms below; the posterior mean dashed (+ below the
    diagonal) and the truth (`truth`, NaN where unknown) red."""
    plt = pyplot()
    d = draws.shape[1]
    labels = _labels(names, properties)
    size = min(2.0 * d + 0.6, 16.0)
    fig = plt.figure(figsize=(size, size))
    # fixed margins in inches (tick labels, names, title) instead of a layout pass over d² panels
    grid = fig.add_gridspec(d, d, left=0.8 / size, right=1 - 0.15 / size, bottom=0.9 / size, top=1 - 0.5 / size,
                            wspace=0.1, hspace=0.1)
    lows, highs = np.quantile(draws, 0.001, axis=0), np.quantile(draws, 0.999, axis=0)
    spans = np.where(highs > lows, highs - lows, 1.0)
    lows, highs = lows - 0.05 * spans, highs + 0.05 * spans
    mean = draws.mean(axis=0)
    known = truth is not None and np.isfinite(truth).any()
    for i in range(d):
        for j in range(i + 1):
            ax = fig.add_subplot(grid[i, j])
            if i == j:
                counts, edges = np.histogram(draws[:, i], bins=bins, range=(lows[i], highs[i]))
                ax.stairs(counts, edges, color="C0", fill=True, alpha=0.6)
                ax.set_xlim(lows[i], highs[i])
                ax.axvline(mean[i], color="k", ls="--", lw=1)
                ax.set_yticks([])
                if known and np.isfinite(truth[i]):
                    ax.axvline(truth[i], color="C3")
            else:
                counts, _, _ = np.histogram2d(draws[:, j], draws[:, i], bins=bins,
                                              range=[[lows[j], highs[j]], [lows[i], highs[i]]])
                ax.imshow(counts.T, origin="lower", extent=(lows[j], highs[j], lows[i], highs[i]), aspect="auto",
                          cmap="Blues", interpolation="nearest")
                ax.plot(mean[j], mean[i], "+", color="k", ms=8)
                if known and np.isfinite(truth[i]) and np.isfinite(truth[j]):
                    ax.plot(truth[j], truth[i], "s", color="C3", ms=4)
                _ticks(ax.yaxis)
            _ticks(ax.xaxis, rotate=True)
            if i == d - 1:
                ax.set_xlabel(labels[j], fontsize=8)
            else:
                ax.tick_params(labelbottom=False)
            if j == 0 and i > 0:
                ax.set_ylabel(labels[i], fontsize=8)
            elif j > 0 and i != j:
                ax.tick_params(labelleft=False)  # hides them without building the ticks now
            ax.tick_params(labelsize=6)
    fig.legend(handles=_marks(known), loc="upper right", fontsize=9, frameon=False)
    fig.suptitle("posterior (physical values)")
    return fig


def marginals_plot(path: Path, prior: np.ndarray, posterior: np.ndarray, names: list[str], truth=None,
                   properties: list[str] | None = None) -> None:
    """Write `marginals_figure` to `path`."""
    _write(marginals_figure(prior, posterior, names, truth, properties), path)


def marginals_figure(prior: np.ndarray, posterior: np.ndarray, names: list[str], truth=None,
                     properties: list[str] | None = None):
    """Prior against posterior histogram of every parameter (physical values with their units,
    densities), the posterior mean dashed and the truth (when given) red."""
    plt = pyplot()
    d = posterior.shape[1]
    cols = min(d, 4)
    rows = math.ceil(d / cols)
    labels = _labels(names, properties)
    fig, axes = plt.subplots(rows, cols, figsize=(3.3 * cols, 2.8 * rows), squeeze=False)
    for k in range(rows * cols):
        ax = axes.flat[k]
        if k >= d:
            ax.axis("off")
            continue
        lo = min(np.quantile(prior[:, k], 0.001), np.quantile(posterior[:, k], 0.001))
        hi = max(np.quantile(prior[:, k], 0.999), np.quantile(posterior[:, k], 0.999))
        ax.hist(prior[:, k], bins=60, range=(lo, hi), density=True, histtype="step", color="0.4", label="prior")
        ax.hist(posterior[:, k], bins=60, range=(lo, hi), density=True, histtype="stepfilled", alpha=0.6,
                color="C0", label="posterior")
        ax.axvline(posterior[:, k].mean(), color="k", ls="--", lw=1, label="posterior mean")
        if truth is not None and np.isfinite(truth[k]):
            ax.axvline(truth[k], color="C3", label="truth (--truth)")
        ax.set_xlabel(labels[k], fontsize=8)
        ax.set_yticks([])
        _ticks(ax.xaxis, count=4, rotate=True)
        ax.tick_params(labelsize=7)
    handles, texts = [], []
    for ax in axes.flat[:d]:
        for handle, text in zip(*ax.get_legend_handles_labels()):
            if text not in texts:
                handles.append(handle)
                texts.append(text)
    fig.legend(handles, texts, loc="lower center", ncol=len(texts), fontsize=8, frameon=False)
    fig.suptitle("prior and posterior of each parameter (physical values)", fontsize=11)
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    return fig


def predictive_plot(path: Path, time, data: dict, runs: dict, band: dict, units: dict, failed: int) -> None:
    """Per output: the data, the simulator runs of the posterior draws and the 95 % predictive band
    (left), and the same about the runs' median (right), where the noise can be seen."""
    plt = pyplot()
    outputs = list(data)
    fig, axes = plt.subplots(len(outputs), 2, figsize=(13, 2.4 * len(outputs) + 0.6), squeeze=False, sharex=True)
    for row, name in enumerate(outputs):
        median = np.median(runs[name], axis=0) if len(runs[name]) else np.zeros_like(time)
        lower, upper = band[name]
        unit = units.get(name, "")
        for col, offset in enumerate((0.0, median)):
            ax = axes[row, col]
            ax.fill_between(time, lower - offset, upper - offset, color="C0", alpha=0.3, lw=0,
                            label="95 % predictive (runs + noise)")
            ax.plot(time, (runs[name] - offset).T, color="C0", lw=0.4, alpha=0.5)
            ax.plot(time, data[name] - offset, ".", color="k", ms=1.5, label="data")
            text = label(name, unit) if col == 0 else \
                f"{short_label(name)} − median run" + (f" [{unit}]" if unit else "")
            ax.set_ylabel(text, fontsize=8)
            ax.tick_params(labelsize=7)
    axes[0, 0].legend(fontsize=7, loc="best")
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    title = f"posterior predictive: {len(next(iter(runs.values())))} simulator runs of posterior draws"
    fig.suptitle(title + (f" ({failed} failed)" if failed else ""))
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def _ticks(axis, count: int = 3, rotate: bool = False) -> None:
    """At most `count` plain tick labels (no offset: -22.04, not 0.04 - 22), slanted when asked,
    so that long values such as -0.01052 do not run into each other."""
    from matplotlib.ticker import MaxNLocator, ScalarFormatter

    axis.set_major_locator(MaxNLocator(count))
    formatter = ScalarFormatter(useOffset=False)
    formatter.set_powerlimits((-5, 6))
    axis.set_major_formatter(formatter)
    if rotate:
        for text in axis.get_ticklabels():
            text.set_rotation(35)
            text.set_horizontalalignment("right")


def _marks(truth: bool):
    """Legend handles of the posterior mean and (when given) the truth."""
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color="k", ls="--", marker="+", label="posterior mean")]
    if truth:
        handles.append(Line2D([], [], color="C3", marker="s", ms=4, label="truth (--truth)"))
    return handles


def _labels(names: list[str], properties: list[str] | None) -> list[str]:
    return [parameter_label(n, p) for n, p in zip(names, properties)] if properties else list(names)
