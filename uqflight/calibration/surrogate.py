"""The calibration's view of a results file: the campaign, the PCE surrogate per output and time (the
export's, `uqflight.analysis.surrogate`) with its leave-one-out error model, and the helpers it needs from the
rest of uqflight (the simulator runs from `execution`, the campaign's text from `campaign.reading`, the
parameters' summaries from `parameters.summaries`), re-exported here.

This is the ONLY module of uqflight.calibration that imports other uqflight modules, but for the
command line's helpers in command.py and the memory limit in size.py: after a restructure of the
package, retarget the imports here.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..campaign import Campaign, CampaignError
from ..text.bounded import OutsideBounds, read_bounded
from ..campaign.schema import MAX_FILE_BYTES
from ..campaign.reading import campaign_folder, check_campaign_text, portable_mapping
from ..campaign.record import CampaignRecord
from ..text.console import listed
from ..designs import REGISTRY as DESIGNS
from ..running.runner import simulate
from ..methods import DEFAULT_ORDER, METHOD_KINDS, MethodSpec
from ..methods.basis import Basis, orthonormal_basis
from ..methods.loo import loo_residuals, relative_loo_error
from ..parameters import Parameter
from ..parameters import to_physical as _to_physical
from ..parameters import to_standard as _to_standard
from ..parameters.summaries import parameter_specs, prior_summaries
from ..analysis.statistics import Options, file_record, output_basis
from ..store import ResultStore, Status
from ..analysis.surrogate import fit_store_surrogate
from ..text import Refusal
from .likelihood import error_factors_of

__all__ = ["CalibrationSurrogate", "CampaignError", "calibration_surrogate", "campaign_folder", "check_campaign_text",
           "open_results", "parameter_specs", "portable_mapping", "prior_summaries", "results_record", "simulate",
           "surrogate_of", "to_physical", "to_standard"]


@dataclass
class CalibrationSurrogate:
    """The surrogate (`uqflight.analysis.surrogate.fit_surrogate`, the export's) as the calibration uses it:
    x_o(t, ξ) ≈ Σ_α c_α,o(t) Ψ_α(ξ) per output o, with its error variance per time.

    `coefficients[o]` is (Z, T) on the results file's `time`. The surrogate error is a random
    function of time with covariance F Fᵀ, `error_factors[o]` = F (T, r): the weighted leave-one-out
    residual curves √w_i (y_i − ŷ_(−i)) of the least-squares fit of the same basis on the same runs
    (or the surrogate's own misfit curves at the runs, when larger), compressed by an SVD.
    `error_variance[o]` (T,) is its diagonal: the mean square error per time (absolute units²).
    Each output has its own basis (`output_indices[o]`: a sparse PCE's selected terms); `indices` is
    their union and `coefficients[o]` is on it, zero for the terms of other outputs, so that one
    evaluation of the basis serves every output.
    """

    campaign: Campaign
    results: str
    method: MethodSpec
    germs: list[str]
    indices: np.ndarray
    time: np.ndarray
    coefficients: dict[str, np.ndarray]
    error_variance: dict[str, np.ndarray]
    error_factors: dict[str, np.ndarray]
    units: dict[str, str]
    runs: int
    relative_error: dict[str, np.ndarray]  # relative LOO error per time (NaN where the output does not vary)
    output_indices: dict[str, np.ndarray]  # each output's own basis; `indices` is their union, for evaluating all at once

    @property
    def parameters(self) -> list[Parameter]:
        return self.campaign.parameters

    @property
    def names(self) -> list[str]:
        return [p.name for p in self.campaign.parameters]

    @property
    def outputs(self) -> list[str]:
        return list(self.coefficients)

    def basis(self, xi: np.ndarray) -> np.ndarray:
        """Ψ_α(ξ) at the rows of xi (M, d): (M, Z)."""
        if getattr(self, "_basis", None) is None:
            self._basis = Basis(self.germs, self.indices)
        return self._basis(xi)


def to_physical(parameters, xi, dependence=None) -> np.ndarray:
    """κ (M, d) from ξ (M, d) (by the Nataf transform of the campaign's `dependence`, if any)."""
    return _to_physical(parameters, np.atleast_2d(xi), dependence)


def to_standard(parameters, kappa, dependence=None) -> np.ndarray:
    """ξ (M, d) from κ (M, d): the inverse of to_physical."""
    return _to_standard(parameters, np.atleast_2d(kappa), dependence)


def open_results(results: Path) -> ResultStore:
    """The results file opened for reading; a Refusal naming it when it cannot be (damaged, held, not HDF5)."""
    try:
        return ResultStore.open(results)
    except (OSError, ValueError) as exc:  # CorruptFile's message names the file already
        raise Refusal(str(exc) if str(exc).startswith(f"{results}:") else f"{results}: {exc}") from exc


def results_record(store: ResultStore, results: Path, campaign_path: Path | None) -> CampaignRecord:
    """The campaign the results file records (campaign.record), read without running any of its code (a
    python model is imported only by the predictive runs, from beside the results file), or from beside the
    campaign file given, which must be the same text."""
    source = str(results)
    if campaign_path is not None:
        try:
            text = read_bounded(campaign_path, MAX_FILE_BYTES, "a campaign").decode("utf-8")
        except (OSError, UnicodeDecodeError, OutsideBounds) as exc:
            raise Refusal(f"--campaign: cannot read {campaign_path} ({exc})") from exc
        if text != store.campaign_text:
            raise Refusal(f"{campaign_path} is not the campaign {results} was run from (the texts differ)")
        source = str(campaign_path)
    record = file_record(store, source)
    campaign = record.campaign
    module, _, _ = campaign.simulator.get("function", "").partition(":")
    if module.endswith(".py"):  # looked for, not imported
        folder = campaign_folder(campaign)
        if campaign_path is None and not (folder / module).resolve().is_relative_to(folder):
            raise Refusal(f"{results}: simulator.function: the python model {module} is outside the results "
                          "file's folder, and a results file names only a model beside it; pass the campaign "
                          "file with --campaign to fly a model elsewhere")
        if not (folder / module).is_file():
            raise Refusal(f"the python model {module} that the posterior-predictive runs call is not beside "
                          f"{source}; pass the campaign file with --campaign (its model file is looked up "
                          "beside it)")
    return record


def calibration_surrogate(results, method: str | None = None, order: int | None = None,
                          campaign_path=None, outputs: list[str] | None = None) -> CalibrationSurrogate:
    """The surrogate of every output (or of `outputs`) of a results file, with its error model, as `calibrate`
    builds it: the file opened once, its record checked once (`results_record`, `surrogate_of`)."""
    results = Path(results)
    with open_results(results) as store:
        record = results_record(store, results, Path(campaign_path) if campaign_path else None)
        return surrogate_of(store, results, record, method, order, outputs)


def surrogate_of(store: ResultStore, results: Path, record: CampaignRecord, method: str | None = None,
                 order: int | None = None, outputs: list[str] | None = None) -> CalibrationSurrogate:
    """The surrogate of the open results file `store` (read from `results`, its campaign `record`).

    Default: the file's method and order. The PCE is the export's (`uqflight.analysis.surrogate.fit_surrogate`):
    a method without a PCE of its own is fitted as its registry entry's `exported_as` says.
    """
    campaign = record.campaign
    stored, germs = campaign.method, campaign.germs
    sampled = DESIGNS[record.design_kind].sampled
    kind = method or stored.kind
    order = (DEFAULT_ORDER if stored.order is None else stored.order) if order is None else order
    if kind not in METHOD_KINDS:
        raise Refusal(f"--method: expected one of {', '.join(METHOD_KINDS)}, got {kind!r}")
    ok = store.status == Status.OK
    names = store.output_names if outputs is None else outputs
    missing = [name for name in names if name not in store.output_names]
    if missing:
        raise Refusal(f"{results} has no output {', '.join(map(repr, missing))} "
                      f"(it has {listed(store.output_names)})")
    # the statistics' own PCE, after their checks (pending or failed runs, aliasing, rank)
    fitted = fit_store_surrogate(store, results, record, MethodSpec(kind, order),
                                 options=Options(band_samples=200, bootstrap=0))
    xi, weights = store.xi[ok], store.weights[ok]
    own = {name: fitted.indices[name] for name in names}
    indices = _union(list(own.values()))
    error_weights = np.full(len(xi), 1.0) if sampled else np.abs(weights)
    error_weights = error_weights / error_weights.sum()
    coefficients, error_variance, error_factors, relative = {}, {}, {}, {}
    for name in names:
        rows, scale = output_basis(store, name, ok)
        Y = rows if scale is None else rows @ scale
        design = orthonormal_basis(germs, own[name], xi)  # the output's own basis (sparse: its terms)
        try:
            loo = loo_residuals(design, Y, error_weights)
            relative[name] = relative_loo_error(design, Y, error_weights)
        except ValueError as exc:
            raise Refusal(f"{results}: output {name!r}: {exc}") from exc
        misfit = Y - design @ fitted.coefficients[name]
        coefficients[name] = _on_basis(indices, own[name], fitted.coefficients[name])
        curves = loo if error_weights @ (loo**2).sum(axis=1) >= error_weights @ (misfit**2).sum(axis=1) else misfit
        error_factors[name] = error_factors_of(np.sqrt(error_weights)[:, None] * curves)
        error_variance[name] = (error_factors[name] ** 2).sum(axis=1)
    return CalibrationSurrogate(campaign, str(results), fitted.method,
                                list(germs), indices, store.time, coefficients, error_variance, error_factors,
                                store.units, int(ok.sum()), relative, own)


def _union(bases: list[np.ndarray]) -> np.ndarray:
    """The rows of every basis, each once, in the order first met (one basis: itself)."""
    seen: dict[tuple, None] = {}
    for basis in bases:
        seen.update(dict.fromkeys(map(tuple, basis.tolist())))
    return np.array(list(seen), dtype=int).reshape(len(seen), bases[0].shape[1])


def _on_basis(indices: np.ndarray, own: np.ndarray, coefficients: np.ndarray) -> np.ndarray:
    """Coefficients (Z_own, T) of the basis `own` as coefficients of `indices` (zero for the other terms)."""
    row_of = {row: i for i, row in enumerate(map(tuple, indices.tolist()))}
    out = np.zeros((len(indices), coefficients.shape[1]))
    out[[row_of[row] for row in map(tuple, own.tolist())]] = coefficients
    return out
