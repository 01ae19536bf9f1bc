"""Statistics of a results file: the campaign's method applied per output, vectorised over time.

For each output: mean, variance, the 99 % band, PDFs over time, the modified coefficient of
variation, Sobol' indices, and, against a Monte Carlo reference file, the errors of Eq. 49 and the
Kullback-Leibler divergence of Eq. 50.

Every method is linear in the runs, so with tSVD storage (Y = V diag(s) Uᵀ) the method is applied
to V (N × r) and the result multiplied by diag(s) Uᵀ: statistics come from the factors without
rebuilding the sample matrix. Samples are rebuilt (in blocks, by the store) only for Monte Carlo
quantiles and PDFs.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field

import numpy as np

from .analysis.density import pdf_over_time
from .analysis.divergence import kl_divergence
from .analysis.errors import error_summary, relative_errors
from .analysis.moments import modified_cov, quantile_band, weighted_moments
from .analysis.sobol import pick_freeze_indices
from .designs import is_sampled
from .methods import PCE, method_entry
from .methods.basis import orthonormal_basis
from .parameters.germs import draw_germs
from .store import ResultStore, Status

PDF_POINTS = 120
TIME_BLOCK = 100  # recorded times whose runs or surrogate draws are rebuilt at once


@dataclass
class Options:
    """How the statistics are computed (from the campaign's `analysis:` mapping, or defaults)."""

    band_samples: int = 20000
    bootstrap: int = 200
    seed: int = 0


@dataclass
class OutputStatistics:
    name: str
    units: str
    time: np.ndarray
    mean: np.ndarray
    variance: np.ndarray
    band99: tuple[np.ndarray, np.ndarray]
    pdf_support: np.ndarray
    pdf_density: np.ndarray
    cov: np.ndarray
    sobol_first: dict[str, np.ndarray] = field(default_factory=dict)
    sobol_total: dict[str, np.ndarray] = field(default_factory=dict)
    sobol_first_ci: dict[str, np.ndarray] = field(default_factory=dict)
    final_samples: np.ndarray | None = None  # runs or surrogate draws at the final time, for the KLD
    errors: dict = field(default_factory=dict)

    @property
    def std(self) -> np.ndarray:
        return np.sqrt(np.maximum(self.variance, 0.0))


@dataclass
class Statistics:
    path: str
    campaign_name: str
    method: dict
    design_kind: str
    parameter_names: list[str]
    runs: int
    failed: int
    outputs: dict[str, OutputStatistics]
    reference: str | None = None


def campaign_facts(store: ResultStore) -> tuple[dict, list[str], dict]:
    """The method, the germs and the analysis options a results file was made with."""
    attrs = store.attrs
    return (json.loads(attrs["method"]), json.loads(attrs["germs"]),
            json.loads(attrs.get("analysis", "{}")))


def analyse(path, reference: str | None = None, options: Options | None = None,
            method: dict | None = None) -> Statistics:
    """All statistics of the results file `path` (and errors against `reference`, a Monte Carlo file).

    `method` ({"kind", "order", "split"}) overrides the campaign's: the runs of one grid serve
    every method, so methods and orders are compared on the same runs.
    """
    with ResultStore.open(path) as store:
        stored_method, germs, analysis = campaign_facts(store)
        method = {**stored_method, **(method or {})}
        options = options or Options(**{k: analysis[k] for k in ("band_samples", "bootstrap")
                                        if k in analysis})
        status = store.status
        ok = status == Status.OK
        if not ok.any():
            raise ValueError(f"{path}: no successful runs to analyse")
        design_kind = store.attrs.get("design_kind", "")
        outputs = {name: _output_statistics(store, name, method, germs, design_kind, ok, options)
                   for name in store.output_names}
        stats = Statistics(str(path), store.attrs.get("campaign_name", ""), method, design_kind,
                           store.parameter_names, int(status.size), int((status > 0).sum()), outputs)
    if reference:
        add_reference_errors(stats, analyse(reference, options=Options(
            band_samples=options.band_samples, bootstrap=0, seed=options.seed)))
    return stats


def output_basis(store: ResultStore, name: str, ok: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """The ok runs of `name` as basis @ scale: raw (Y, None), or tSVD (V rows, diag(s) Uᵀ)."""
    factors = store.output_factors(name)
    if factors is None:
        return store.output_matrix(name, np.flatnonzero(ok)), None
    U, s, V, columns = factors
    row_of = np.full(ok.size, -1)
    row_of[columns] = np.arange(columns.size)
    return V[row_of[np.flatnonzero(ok)]], s[:, None] * U.T


def _output_statistics(store: ResultStore, name: str, method: dict, germs: list[str], design_kind: str,
                       ok: np.ndarray, options: Options) -> OutputStatistics:
    xi, weights = store.xi[ok], store.weights[ok]
    kind, order = method["kind"], method["order"]
    entry = method_entry(kind)
    basis, scale = output_basis(store, name, ok)
    from_runs = entry.runs_on_sampled and is_sampled(design_kind)
    x0 = None
    # x = x0 + S with each run's initial value (needs the runs themselves); only the projections use
    # it: the other kinds fit the constant term themselves, where the split would change nothing
    if method.get("split") and not from_runs and entry.split:
        basis = basis if scale is None else basis @ scale
        scale, x0 = None, basis[:, :1]

    def expand(a):
        return a if scale is None else a @ scale

    pce = None
    if from_runs:  # sample moments; bands, PDFs and pick-freeze indices from the runs themselves
        sample = entry.moments == "sample"
        mean, variance = weighted_moments(basis, None if sample else weights, scale, unbiased=sample)
        rows, row_scale, band_weights = basis, scale, (None if sample else weights / weights.sum())
    else:
        fitted = entry.pce(xi, weights, basis, germs, order, x0)
        pce = PCE(fitted.germs, fitted.indices, expand(fitted.coefficients))
        if entry.moments == "weights":  # quadrature moments; the PCE serves bands, PDFs, Sobol'
            mean, variance = weighted_moments(basis, weights, scale)
        else:
            mean, variance = pce.mean(), pce.variance()
        draws = draw_germs(germs, options.band_samples, options.seed)
        rows, row_scale, band_weights = orthonormal_basis(germs, pce.indices, draws), pce.coefficients, None
    pick_freeze = pce is None and design_kind == "pick_freeze" and ok.all()
    blocks = _over_time_blocks(rows, row_scale, store.time.size, band_weights,
                               len(store.parameter_names) if pick_freeze else 0, options)
    std = np.sqrt(np.maximum(variance, 0.0))
    stats = OutputStatistics(name, store.units.get(name, ""), store.time, mean, variance, blocks["band"],
                             blocks["support"], blocks["density"], modified_cov(mean, std),
                             final_samples=blocks["final"])
    names = store.parameter_names
    if pce is not None:
        stats.sobol_first = dict(zip(names, pce.sobol_first()))
        stats.sobol_total = dict(zip(names, pce.sobol_total()))
    elif pick_freeze:
        stats.sobol_first = dict(zip(names, blocks["first"]))
        stats.sobol_total = dict(zip(names, blocks["total"]))
        stats.sobol_first_ci = dict(zip(names, np.moveaxis(blocks["first_ci"], 1, 0)))
    return stats


def _over_time_blocks(rows, scale, n_times: int, weights, pick_freeze_dimensions: int, options: Options) -> dict:
    """99 % band, PDFs, final-time samples (and pick-freeze indices) of Y = rows @ scale (scale None:
    Y = rows), rebuilding Y for TIME_BLOCK times at once: the memory stays that of one block
    whatever the number of runs or draws. Every statistic here is per time, so blocks change nothing."""
    parts: dict[str, list] = {key: [] for key in ("lower", "upper", "support", "density", "first", "total",
                                                  "first_ci")}
    for start in range(0, n_times, TIME_BLOCK):
        stop = min(start + TIME_BLOCK, n_times)
        Y = rows[:, start:stop] if scale is None else rows @ scale[:, start:stop]
        lower, upper = quantile_band(Y, weights)
        support, density = pdf_over_time(Y, PDF_POINTS)
        for key, value in (("lower", lower), ("upper", upper), ("support", support), ("density", density)):
            parts[key].append(value)
        if pick_freeze_dimensions:
            indices = pick_freeze_indices(Y, pick_freeze_dimensions, n_boot=options.bootstrap, seed=options.seed)
            for key in ("first", "total", "first_ci"):
                parts[key].append(indices[key])
    joined = {"band": (np.concatenate(parts["lower"]), np.concatenate(parts["upper"])),
              "support": np.concatenate(parts["support"]), "density": np.concatenate(parts["density"]),
              "final": Y[:, -1].copy()}
    if pick_freeze_dimensions:
        joined.update(first=np.concatenate(parts["first"], axis=-1), total=np.concatenate(parts["total"], axis=-1),
                      first_ci=np.concatenate(parts["first_ci"], axis=-1))
    return joined


def add_reference_errors(stats: Statistics, reference: Statistics) -> None:
    """ε_m, ε_v over time (Eq. 49) and the KLD at the final time (Eq. 50) against the reference."""
    stats.reference = reference.path
    for name, out in stats.outputs.items():
        ref = reference.outputs.get(name)
        if ref is None or ref.time.shape != out.time.shape or not np.allclose(ref.time, out.time):
            continue
        eps_m, eps_v = relative_errors(out.mean, out.variance, ref.mean, ref.variance)
        kld = kl_divergence(out.final_samples, ref.final_samples)
        out.errors = {"eps_m": eps_m, "eps_v": eps_v, "eps_m_summary": error_summary(eps_m),
                      "eps_v_summary": error_summary(eps_v), "kld_final": kld}


def summary_json(stats: Statistics) -> dict:
    """The fixed summary.json schema of DESIGN.md (plus std, cov and errors when present)."""
    outputs = {}
    for name, out in stats.outputs.items():
        entry = {
            "time": out.time.tolist(), "units": out.units,
            "mean": out.mean.tolist(), "variance": out.variance.tolist(), "std": out.std.tolist(),
            "band99": {"lower": out.band99[0].tolist(), "upper": out.band99[1].tolist()},
            "cov": out.cov.tolist(),
            "sobol_first": {k: v.tolist() for k, v in out.sobol_first.items()},
            "sobol_total": {k: v.tolist() for k, v in out.sobol_total.items()},
        }
        if out.errors:
            entry["errors"] = {"eps_m": out.errors["eps_m"].tolist(), "eps_v": out.errors["eps_v"].tolist(),
                               "eps_m_max": out.errors["eps_m_summary"]["max"],
                               "eps_v_max": out.errors["eps_v_summary"]["max"],
                               "kld_final": out.errors["kld_final"]}
        outputs[name] = entry
    return {"results": stats.path, "campaign": stats.campaign_name, "method": stats.method,
            "design": stats.design_kind, "runs": stats.runs, "failed": stats.failed,
            "parameters": stats.parameter_names, "reference": stats.reference, "outputs": outputs}
