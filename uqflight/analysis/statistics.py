"""Statistics of a results file: the method registry applied per output, vectorised over time.

For each output: mean, variance, quantiles and the 99 % band, skewness and kurtosis, PDFs over time,
the modified coefficient of variation, Sobol' indices, a leave-one-out error for the fits, the
difference to the next lower order for the projections, and, against a reference file, the errors of
Eq. 49 with the reference's own noise floor and the Kullback-Leibler divergence of Eq. 50.

A number here is right, refused (`BadInput` naming the file, the count or the order and what to do)
or flagged (`Statistics.notes`, `null` in summary.json):
* pending runs are refused unless `partial`, and then only where a subset of the runs is valid;
* failed runs: a note says what the method's statistics are (`methods.FAILED_RUNS`: conditional on
  success, or a fit extrapolated over the failed region); grids refuse the projections and weighted
  sums, the fits are made on the successful runs after a rank check, and a grid's failure probability
  has no interval (none at all with signed weights: `analysis.failures`);
* a method the points cannot carry is refused (`methods.validity`), aliasing only when allowed;
* Sobol' indices of a variance at rounding noise or below the simulator's own resolution (the file's
  /resolution: two valid trims' drift), and an undefined CoV, are NaN here and null in JSON.

Every method is linear in the runs, so with tSVD storage (Y = V diag(s) Uᵀ) the method is applied to V
(N × r) and the result multiplied by diag(s) Uᵀ: statistics come from the factors without rebuilding
the sample matrix. Samples are rebuilt (in blocks of times) only for quantiles, PDFs and KLDs.
"""
from __future__ import annotations

import math
import os
from collections import deque
from concurrent.futures import Executor, ThreadPoolExecutor
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable

import numpy as np
from threadpoolctl import threadpool_limits

from . import BAND_SAMPLES, BOOTSTRAP, QUANTILES
from .angles import angle_period, branch_shifts, unwrapped_runs
from .density import pdf_over_time
from .divergence import kl_divergence
from .drawn import DrawnRuns, read_drawn
from .errors import error_summary, relative_errors
from .exceedance import exceedance_entry, exceedance_from_pce, exceedance_from_runs, unit_slip
from .failures import grid_failure_probability
from .floors import central_moments, floors_from_moments, kld_estimator_bias, kld_floor
from .moments import (modified_cov, sorted_by_time, standardised_moments, weighted_moments,
                               weighted_quantiles)
from .resolution import RESOLUTION_RTOL, resolved_variance
from .sobol import NEGLIGIBLE, UNRESOLVED_WIDTH, complete_rows, pick_freeze_indices, unresolved
from ..campaign.record import CampaignRecord, check_design_info, read_record
from ..campaign.schema import CampaignError
from ..text import Refusal
from ..text.console import quoted_name
from ..designs import REGISTRY as DESIGNS
from ..designs.adaptive import index_set_summary
from ..text.labels import name_unit
from ..methods import PCE, METHODS, Auto, Method, MethodSpec
from ..methods.basis import orthonormal_basis
from ..methods.pce_moments import pce_standardised_moments, triple_products
from ..methods import validation
from ..methods.validity import method_problem
from ..parameters.distributions import SEED_REFUSAL
from ..parameters.germs import draw_germs
from ..store import CorruptFile, LockHeld, ResultStore, Status
from ..store.results import error_line

PDF_POINTS = 120
TIME_BLOCK = 100  # recorded times whose runs or surrogate draws are rebuilt at once
ANALYSIS_THREADS = min(2, os.cpu_count() or 1)  # time blocks analysed at once (each with one BLAS thread)
MAX_MAGNITUDE = 1e75  # an output's or quantity's values beyond: their fourth powers (kurtosis) leave float64
BAND_LEVEL = 0.99
# The relative spread a JSBSim output can resolve: the same sample flown on a reused model and on a
# freshly loaded one differs by up to 3.7e-9 of the output (JSBSim's trim; 1e-12 with the Newton
# trim), so a spread below 1e-9 of the output's own size is the simulator's noise, not the inputs'.
JSBSIM_RESOLUTION = 1e-9


class BadInput(Refusal):
    """A results file, baseline or request that cannot give right numbers; the message is one line that
    names the file and says what to do."""


@dataclass
class Options:
    """How the statistics are computed (from the campaign's `analysis:` mapping, or defaults). `seed` seeds
    every draw of the analysis (band and PDF draws, bootstrap, exceedance draws, the KLD floor's splits);
    None: the results file's campaign seed."""

    band_samples: int = BAND_SAMPLES
    bootstrap: int = BOOTSTRAP
    seed: int | None = None
    quantiles: tuple[float, ...] = QUANTILES


@dataclass(frozen=True)
class Screening:
    """A screening design's measures of each input's importance from its runs (DesignKind.screening): `name`
    names them in summary.json and the report (the design kind's `screening_name`: Morris's is morris),
    `measures` {input: {measure: (T,) or {lower, upper}}}."""

    name: str
    measures: dict


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
    cov: np.ndarray  # NaN where undefined (a mean that is zero at every time)
    resolved: np.ndarray  # bool (T,): the variance is above rounding noise and the simulator's resolution
    quantiles: dict[float, np.ndarray] = field(default_factory=dict)
    skewness: np.ndarray | None = None
    kurtosis: np.ndarray | None = None
    sobol_first: dict[str, np.ndarray] = field(default_factory=dict)  # NaN where unresolved
    sobol_total: dict[str, np.ndarray] = field(default_factory=dict)
    sobol_first_ci: dict[str, np.ndarray] = field(default_factory=dict)  # (2, T) per parameter
    sobol_total_ci: dict[str, np.ndarray] = field(default_factory=dict)
    loo_error: np.ndarray | None = None  # relative leave-one-out error of a fit, (T,)
    selection: dict | None = None  # what a selecting method (sparse) chose: terms, order, corrected LOO error
    convergence: dict | None = None  # difference to the next lower order of a projection
    validation: dict | None = None  # the expansion checked on its own runs (methods.validation): error, band
    method: dict | None = None  # what `method: {kind: auto}` took for this output (auto_method), None otherwise
    coefficient_decay: dict[int, np.ndarray] | None = None  # degree -> RSS of its PCE coefficients (T,)
    final_samples: np.ndarray | None = None  # runs or surrogate draws at the final time, for the KLD
    fourth_central: np.ndarray | None = None  # of the runs, for a sampled reference's noise floor
    replicate_moments: tuple[np.ndarray, np.ndarray] | None = None  # (R, T) means and variances of RQMC replicates
    errors: dict = field(default_factory=dict)
    pce: PCE | None = None  # the expansion behind the statistics (None: statistics of the runs themselves)
    flags: list[str] = field(default_factory=list)
    unwrapped: bool = False  # an angle whose runs wrap, made continuous before any statistic (analysis.angles)
    screening: Screening | None = None  # a screening design's measures of each input (screen)

    @property
    def std(self) -> np.ndarray:
        return np.sqrt(np.maximum(self.variance, 0.0))


@dataclass
class Statistics:
    path: str
    record: CampaignRecord  # the campaign the file records (campaign.record)
    method: MethodSpec  # the method applied (the campaign's, or the one asked for instead: MethodSpec.analysed)
    parameter_names: list[str]
    runs: int  # the design's runs
    completed: int
    failed: int
    pending: int
    outputs: dict[str, OutputStatistics]
    failure_probability: dict | None = None
    failures: list[dict] = field(default_factory=list)
    partial: bool = False
    notes: list[str] = field(default_factory=list)
    reference: str | None = None
    from_runs: bool = False  # statistics of the runs themselves (a sampled design), not of a PCE
    replicates: int = 1  # independent randomised-QMC replicates of the design
    quantities: dict[str, QuantityStatistics] = field(default_factory=dict)
    index_set: dict | None = None  # an adaptive grid's refinement (designs.adaptive.index_set_summary)
    rare_event: dict | None = None  # a rare-event design's estimate and rounds (rare_statistics)
    rare_runs: dict | None = None  # its runs for the report's figures (not in summary.json)
    drawn: DrawnRuns | None = None  # the runs the report draws (read_statistics with a scatter time; not in summary.json)
    seed: int = 0  # what seeded the analysis's draws (the campaign's seed unless Options said otherwise)

    @property
    def campaign_name(self) -> str:
        """The recorded campaign's name."""
        return self.record.campaign.name

    @property
    def design_kind(self) -> str:
        """The recorded design's kind."""
        return self.record.design_kind

    @property
    def design_info(self) -> dict:
        """The design's recorded facts (replicates, n_base, ...)."""
        return self.record.design_info

    @property
    def seeds(self) -> list[str]:
        """The parameters that are random streams' seeds."""
        return self.record.seeds

    @property
    def dependence(self) -> dict | None:
        """The inputs' Gaussian copula as summary.json states it (parameters.dependence.summary); None: independent."""
        return self.record.dependence

    @property
    def method_label(self) -> str:
        """The method as in the paper's legends, e.g. "PG order 2", "MC"."""
        return self.method.label

    @property
    def estimator_label(self) -> str:
        """What gives the numbers: the method's label, or a rare-event design's kind (its runs are not the
        method's draws: it estimates its event's probability only)."""
        return self.design_kind if self.rare_runs else self.method_label

    @property
    def expands(self) -> bool:
        """Whether the statistics are of an expansion (a PCE), not of the runs themselves."""
        return self.method.entry.expands

    @property
    def sampled(self) -> bool:
        """Whether the design's runs are draws of the input law (not a grid's nodes)."""
        return DESIGNS[self.design_kind].sampled

    @property
    def sobol_from_runs(self) -> bool:
        """Whether the design carries Sobol' indices of its own runs (pick-freeze), with their intervals."""
        return DESIGNS[self.design_kind].sobol_from_runs


@dataclass
class QuantityStatistics:
    """A quantity of interest (one number per run) analysed as an output with one time point; `output`
    None when its statistics are undefined (see `quantity_statistics`)."""

    name: str
    missing: int  # successful runs where the quantity is undefined
    output: OutputStatistics | None
    exceedance: list[dict] = field(default_factory=list)
    units: str = ""  # its take's own, or its `of`'s (QuantitySpec.unit)
    flags: list[str] = field(default_factory=list)  # its statistics' (output.flags) and its thresholds' (unit slips)

    def _first(self, attribute: str):
        """The output's `attribute` at its one time point (None when the statistics are undefined)."""
        return None if self.output is None else _at_first_time(getattr(self.output, attribute))

    @property
    def mean(self) -> float | None:
        """The mean (None where undefined), as summary.json's quantities.NAME.mean."""
        return self._first("mean")

    @property
    def variance(self) -> float | None:
        return self._first("variance")

    @property
    def std(self) -> float | None:
        return self._first("std")

    @property
    def band99(self) -> tuple[float, float] | None:
        """(lower, upper) of the 99 % band."""
        return None if self.output is None else (float(self.output.band99[0][0]), float(self.output.band99[1][0]))

    @property
    def quantiles(self) -> dict[float, float]:
        return {} if self.output is None else self._first("quantiles")

    @property
    def skewness(self) -> float | None:
        return None if self.output is None or self.output.skewness is None else self._first("skewness")

    @property
    def kurtosis(self) -> float | None:
        return None if self.output is None or self.output.kurtosis is None else self._first("kurtosis")

    @property
    def sobol_first(self) -> dict[str, float]:
        return {} if self.output is None else self._first("sobol_first")

    @property
    def sobol_total(self) -> dict[str, float]:
        return {} if self.output is None else self._first("sobol_total")


def file_record(store: ResultStore, path) -> CampaignRecord:
    """The campaign the results file `path` records (campaign.record), checked once with the campaign's own
    checks and against the file's runs, parameters and quantities: BadInput naming the file, the attribute
    and the field."""
    try:
        record = read_record(store.attrs, str(path))
        check_design_info(record, str(path), int(store.status.size))
    except CampaignError as exc:
        raise BadInput(str(exc)) from exc
    names, quantities = [p.name for p in record.campaign.parameters], list(record.campaign.quantities)
    if names != list(store.parameter_names) or sorted(quantities) != sorted(store.quantity_names):
        raise BadInput(f"{path}: attribute record: the campaign's parameters ({', '.join(names)}) and quantities "
                       f"({', '.join(quantities) or 'none'}) are not the runs' ({', '.join(store.parameter_names)}; "
                       f"{', '.join(store.quantity_names) or 'none'}): the file is damaged")
    return record


def read_statistics(path, method: MethodSpec | None = None, partial: bool = False,
                    allow_aliasing: bool = False, progress=None,
                    exceedance: dict | None = None, scatter_time: float | None = None) -> tuple[Statistics, dict]:
    """The statistics of a results file (`method` overriding the campaign's) and its root attributes, the
    file opened once; BadInput, one line naming the file, when it cannot give right numbers. `progress`,
    `exceedance`: see analyse. With `scatter_time`, the statistics carry the runs a report draws
    (`Statistics.drawn`, analysis.drawn.read_drawn: its scatter at the recorded time nearest it)."""
    path = Path(path)
    if not path.is_file():
        raise BadInput(f"{path}: no such results file")
    try:
        with ResultStore.open(path) as store:
            stats = analyse_store(store, path, method=method, partial=partial, allow_aliasing=allow_aliasing,
                                  progress=progress, exceedance=exceedance)
            if scatter_time is not None:
                stats.drawn = read_drawn(store, stats, scatter_time)
            return stats, store.attrs
    except BadInput:
        raise
    except CorruptFile as exc:
        raise BadInput(str(exc) if str(exc).startswith(f"{path}:") else f"{path}: {exc}") from exc
    except LockHeld as exc:  # names the file and the process holding it
        raise BadInput(str(exc)) from exc
    except (OSError, ValueError, KeyError) as exc:
        raise BadInput(f"{path}: cannot analyse the results file ({error_line(exc)})") from exc


def analyse(path, reference: str | None = None, options: Options | None = None, method: MethodSpec | None = None,
            partial: bool = False, allow_aliasing: bool = False, progress=None,
            exceedance: dict | None = None) -> Statistics:
    """All statistics of the results file `path` (and errors against `reference`): `analyse_store` of the
    file opened once."""
    with ResultStore.open(path) as store:
        return analyse_store(store, path, reference, options, method, partial, allow_aliasing, progress, exceedance)


def analyse_store(store: ResultStore, path, reference: str | None = None, options: Options | None = None,
                  method: MethodSpec | None = None, partial: bool = False, allow_aliasing: bool = False, progress=None,
                  exceedance: dict | None = None, record: CampaignRecord | None = None) -> Statistics:
    """All statistics of the open results file `store` read from `path` (and errors against `reference`).
    `record`: the file's checked campaign (`file_record`) when the caller has it already, so that it is checked once.

    `method` overrides the campaign's (`MethodSpec.analysed`): the runs of one grid serve every method, so
    methods and orders are compared on the same runs. `partial` analyses a file with pending
    runs where a subset of the runs is valid; `allow_aliasing` lets a projection exceed the grid's degree.
    `progress` (a uqflight.running.progress.Progress) gets a stage per file and counts its outputs and quantities.
    `exceedance` ({quantity: [{above: X} | {below: X}]}) replaces the campaign's `analysis.exceedance` of the
    quantities it names (`report --exceedance`: thresholds changed without flying again); BadInput when it
    names a quantity the file does not have.
    """
    # one BLAS thread: the matrices are tall and thin (runs or draws × terms), where several threads are no
    # faster, and 10-20x slower on a loaded machine; the time blocks run in threads instead
    with threadpool_limits(limits=1):
        record = file_record(store, path) if record is None else record
        campaign = record.campaign
        germs, analysis = campaign.germs, campaign.analysis
        method = campaign.method.analysed(method)
        allow_aliasing = allow_aliasing or method.allow_aliasing
        options = options or Options(analysis.band_samples, analysis.bootstrap,
                                     quantiles=analysis.quantiles or QUANTILES)
        if options.seed is None:
            options = replace(options, seed=campaign.seed)
        status, design_kind = store.status, record.design_kind
        sampled = DESIGNS[design_kind].sampled
        ok = status == Status.OK
        pending = int(np.sum(status == Status.PENDING))
        stats = Statistics(str(path), record, method, store.parameter_names, int(status.size), int(ok.sum()),
                           int(np.sum(status > 0)), pending, {}, partial=pending > 0, seed=options.seed)
        if DESIGNS[design_kind].rare:  # its runs are not draws of the input law: its event's probability only
            from .rare_statistics import rare_statistics

            if exceedance:
                raise BadInput(f"{path}: --exceedance: a {design_kind} file estimates the probability of its "
                               "design.event only (its runs are not draws of the input law); fly a campaign per event")
            rare_statistics(store, stats)
            return stats
        _check_runs(store, stats, sampled, partial)
        state = store.index_set()
        stats.index_set = None if state is None else index_set_summary(state, store.parameter_names)
        problem = method_problem(method.kind, method.order, store.xi[ok], store.weights[ok], germs, sampled,
                                 missing=int(status.size - ok.sum()), allow_aliasing=allow_aliasing)
        if record.seeds and not (sampled and method.entry.runs_on_sampled):
            problem = f"parameter {record.seeds[0]} is a seed: {SEED_REFUSAL}"
        if stats.dependence:
            stats.notes.append(f"dependent inputs: {', '.join(stats.dependence['parameters'])} are correlated by a "
                               "Gaussian copula (Nataf); the mean, variance, bands and densities are those of the "
                               f"dependent inputs; the Sobol' indices are of the {stats.dependence['sobol_of']}")
        if problem:
            raise BadInput(f"{path}: method {method.kind} order {method.order}: {problem}")
        _note_runs(store, stats, sampled, allow_aliasing)
        stats.from_runs = method.entry.runs_on_sampled and sampled
        if DESIGNS[design_kind].not_draws:
            stats.notes.append(DESIGNS[design_kind].not_draws)
        if stats.from_runs and DESIGNS[design_kind].sobol_from_runs:
            note = pick_freeze_note(ok, len(store.parameter_names), "pending runs" if not stats.failed else
                                    "failed and pending runs" if stats.pending else "failed runs")
            if note:
                stats.notes.append(note)
        replicates = record.design_info.get("replicates", 1)
        stats.replicates = replicates if stats.from_runs and ok.all() else 1
        if progress is not None:
            progress.stage(f"analysing {Path(path).name} ({method.kind} order {method.order})",
                           len(store.output_names) + len(store.quantity_names), "outputs")
        # one pool of threads for every output's time blocks: each output's serial steps (reading it, the fit,
        # the draws, the exact moments) run here while the blocks of the one before it run in the pool; at
        # most ANALYSIS_THREADS outputs in flight, so that as many outputs' samples are held at once
        with ThreadPoolExecutor(ANALYSIS_THREADS) as pool:
            in_flight: deque = deque()
            basis_cache = BasisCache()

            def finish_oldest():
                name, finish = in_flight.popleft()
                out = stats.outputs[name] = finish()
                if out.unwrapped:
                    stats.notes.append(unwrapped_note(f"output {name}", out.units))
                stats.notes.extend(f"output {name}: {flag}" for flag in out.flags)
                if stats.replicates > 1:
                    out.replicate_moments = _replicate_moments(store, name, stats.replicates)
                if DESIGNS[design_kind].screening is not None:
                    basis, scale = output_basis(store, name, ok)
                    screen(stats, out, store.xi, basis if scale is None else basis @ scale, ok, options, "")
                if progress is not None:
                    progress.advance()

            for name in store.output_names:
                chosen, runs_only, record = auto_method(store, name, method, germs, design_kind, ok, options.seed)
                start = _start_output(store, name, chosen, germs, design_kind, ok, options, pool, basis_cache,
                                      runs_only, record is not None)
                in_flight.append((name, _with_method(record, start)))
                if len(in_flight) >= ANALYSIS_THREADS:
                    finish_oldest()
            while in_flight:
                finish_oldest()
        unknown = [name for name in exceedance or {} if name not in store.quantity_names]
        if unknown:
            raise BadInput(f"{path}: --exceedance {unknown[0]}: no such quantity in the file; its quantities: "
                           + (", ".join(store.quantity_names) or "none"))
        thresholds = {**analysis.exceedance, **(exceedance or {})}
        for name in store.quantity_names:
            stats.quantities[name] = quantity_statistics(store, stats, name, germs, ok, options,
                                                         thresholds.get(name, []))
            if progress is not None:
                progress.advance()
    _note_auto(stats)
    if reference:
        add_reference_errors(stats, analyse(reference, options=Options(
            band_samples=options.band_samples, bootstrap=0, quantiles=options.quantiles)))
    return stats


def _check_runs(store: ResultStore, stats: Statistics, sampled: bool, partial: bool) -> None:
    """Refuse pending runs (unless partial, and then where a subset is valid) and a file with no run done."""
    path, n = stats.path, stats.runs
    if stats.pending and not partial:
        campaign = store.attrs.get("campaign_path") or "CAMPAIGN.yaml"
        raise BadInput(f"{path}: {stats.pending} of {n} runs are pending (interrupted, or still running): resume "
                       f"them with `uqflight run {campaign} --out {path}`, or add --partial to analyse the "
                       f"{stats.completed} completed runs (Monte Carlo, QMC, least squares and regression only)")
    if stats.pending and not sampled and not stats.method.entry.partial:
        raise BadInput(f"{path}: --partial: {stats.method.kind} on a {stats.design_kind} needs every run of "
                       f"the grid ({stats.pending} of {n} pending); use --method least_squares or regression, "
                       f"or resume the campaign")
    if stats.completed == 0:
        raise BadInput(f"{path}: no successful runs to analyse ({stats.failed} failed, {stats.pending} pending)")


def _note_runs(store: ResultStore, stats: Statistics, sampled: bool, allow_aliasing: bool) -> None:
    """Failure probability, the failed runs, and the notes a reader must see."""
    status = store.status
    done = status != Status.PENDING
    failed = status[done] > 0
    if sampled:
        found = DESIGNS[stats.design_kind].sampling.proportion(status > 0, done, stats.design_info, event="failed")
        stats.failure_probability = {**{k: found[k] for k in ("estimate", "lower", "upper", "n_effective")},
                                     "method": found["sentence"]}
    else:
        stats.failure_probability = grid_failure_probability(failed, store.weights[done])
    if stats.failed:
        stats.failures = failed_runs(store)
        stats.notes.append(stats.method.entry.failed_runs_note(stats.failed, int(done.sum())))
        if not sampled:
            stats.notes.append("failure probability: " + _grid_failure_note(stats.failure_probability))
    if stats.pending:
        stats.notes.append(f"partial: {stats.completed} of {stats.runs} runs")
    if allow_aliasing and not sampled and stats.method.entry.projects:
        stats.notes.append("aliasing allowed: the projection's order may exceed what the grid integrates exactly")


def failed_runs(store: ResultStore) -> list[dict]:
    """summary.json's failures: every failed run with its status, reason and physical parameters."""
    status, kappa, reasons, names = store.status, store.kappa, store.reasons, store.parameter_names
    return [{"run": int(i), "status": Status(int(status[i])).name.lower(), "reason": reasons[i],
             "parameters": dict(zip(names, map(float, kappa[i])))} for i in np.flatnonzero(status > 0)]


def _grid_failure_note(probability: dict) -> str:
    """What a grid says of the failure probability, in a few words (analysis.failures)."""
    if math.isnan(probability["estimate"]):
        return "not estimated from a grid with negative weights; a sampled design is needed"
    return (f"{probability['estimate']:.3g}, the grid's quadrature of the failure indicator, without an interval "
            "(the nodes are not random draws); a sampled design gives one")


def too_large(kind: str, name: str, peak: float) -> str | None:
    """Why the values of output or quantity (`kind`) `name`, of magnitude up to `peak`, give no statistics
    (their powers up to the fourth, the variance and the kurtosis, leave float64), or None."""
    if peak <= MAX_MAGNITUDE:
        return None
    return (f"{kind} {name if name.isprintable() else repr(name)} holds values up to {peak:.3g}, beyond the "
            f"{MAX_MAGNITUDE:.0e} its statistics take in float64 (their powers, up to the fourth in the kurtosis, "
            "would overflow): record it in larger units")


def output_basis(store: ResultStore, name: str, ok: np.ndarray,
                 unwrapped: list | None = None) -> tuple[np.ndarray, np.ndarray | None]:
    """The ok runs of `name` as basis @ scale: raw (Y, None), or tSVD (V rows, diag(s) Uᵀ). An angle (deg or
    rad) whose runs wrap is unwrapped (analysis.angles), raw, and its name appended to `unwrapped`. BadInput,
    one line, for values whose statistics would overflow (`too_large`)."""
    period = angle_period(store.units.get(name) or name_unit(name))
    factors = store.output_factors(name)
    if factors is None:
        runs = np.flatnonzero(ok)
        histories = store.output_matrix(name, runs)
        bad = runs[~np.isfinite(histories).all(axis=1)]
        if bad.size:
            raise CorruptFile(f"output {quoted_name(name)}: {bad.size} runs with status ok hold values that are not finite "
                              f"(e.g. run {bad[0]}): the file is damaged (`uqflight info` lists its problems)")
        problem = too_large("output", name, float(np.abs(histories).max(initial=0.0)))
        if problem:
            raise BadInput(f"{store.path}: {problem}")
        return _unwrapped(histories, period, name, unwrapped, histories), None
    U, s, V, columns = factors
    if not (np.isfinite(U).all() and np.isfinite(s).all() and np.isfinite(V).all()):
        raise CorruptFile(f"output {quoted_name(name)}: its tSVD factors hold values that are not finite: the file is damaged")
    row_of = np.full(ok.size, -1)
    row_of[columns] = np.arange(columns.size)
    basis, scale = V[row_of[np.flatnonzero(ok)]], s[:, None] * U.T
    with np.errstate(over="ignore"):  # a bound of every value: sum over the rank of |V| |diag(s) Uᵀ|
        peak = float((np.abs(basis).max(axis=0, initial=0.0) @ np.abs(scale)).max(initial=0.0))
    problem = too_large("output", name, peak)
    if problem:
        raise BadInput(f"{store.path}: {problem}")
    if period is None:
        return basis, scale
    # no step of any run can jump by half a turn when Σ_k max_i |V_ik| |Δ(s Uᵀ)_kt| stays below it, and the
    # runs' first values need no turn: then nothing is rebuilt
    steps = np.abs(basis).max(axis=0, initial=0.0) @ np.abs(np.diff(scale, axis=1))
    if not (steps > 0.5 * period).any() and not branch_shifts(basis @ scale[:, 0], period).any():
        return basis, scale
    found = _unwrapped(basis @ scale, period, name, unwrapped, None)
    return (basis, scale) if found is None else (found, None)


def unwrapped_note(what: str, units: str) -> str:
    """The note of an angle made continuous before its statistics (analysis.angles)."""
    turn = f"{angle_period(units):g} {units}" if units == "deg" else "2π rad"
    return (f"{what} is an angle whose runs jump by about a turn ({turn}): unwrapped along each run and moved by "
            "whole turns onto the first run's branch before any statistic")


def _unwrapped(histories: np.ndarray, period: float | None, name: str, unwrapped: list | None, unchanged):
    """`histories` unwrapped (analysis.angles) when `period` says it is an angle and its runs wrap, `name`
    then appended to `unwrapped`; else `unchanged`."""
    if period is None:
        return unchanged
    found, moved = unwrapped_runs(histories, period)
    if not moved:
        return unchanged
    if unwrapped is not None:
        unwrapped.append(name)
    return found


def _output_statistics(store: ResultStore, name: str, method: MethodSpec, germs: list[str], design_kind: str,
                       ok: np.ndarray, options: Options) -> OutputStatistics:
    """The statistics of output `name` over the `ok` runs, its time blocks in ANALYSIS_THREADS threads."""
    chosen, runs_only, record = auto_method(store, name, method, germs, design_kind, ok, options.seed)
    with ThreadPoolExecutor(ANALYSIS_THREADS) as pool:
        return _with_method(record, _start_output(store, name, chosen, germs, design_kind, ok, options, pool,
                                                  BasisCache(), runs_only, record is not None))()


def _with_method(record: dict | None, finish: Callable[[], OutputStatistics]) -> Callable[[], OutputStatistics]:
    """`finish` whose statistics carry what auto took (`record`, None: the method was given)."""
    def finished() -> OutputStatistics:
        out = finish()
        out.method = record
        return out
    return finished


def auto_method(store: ResultStore, name: str, method: MethodSpec, germs: list[str], design_kind: str,
                ok: np.ndarray, seed: int = 0) -> tuple[MethodSpec, bool, dict | None]:
    """(the method for output `name`, whether its statistics are the runs' own, what auto took or None):
    `method` itself, or for auto what it takes on these runs (validation.Auto.choose, its draws seeded by `seed`)."""
    if not isinstance(method.entry, Auto):
        return method, False, None
    basis, scale = output_basis(store, name, ok)
    kind, runs_only, record = method.entry.choose(
        store.xi[ok], store.weights[ok], basis, scale, germs, method.order, DESIGNS[design_kind].sampled,
        int(ok.size - ok.sum()), seed, name)
    return replace(method, kind=kind), runs_only, record


def _note_auto(stats: Statistics) -> None:
    """One note of what `method: {kind: auto}` took for each output and quantity."""
    taken: dict[str, list[str]] = {}
    entries = [(name, out) for name, out in stats.outputs.items()]
    entries += [(name, q.output) for name, q in stats.quantities.items() if q.output is not None]
    for name, out in entries:
        if out.method is not None:
            own = out.method["kind"] in (Method.of_runs(True).kind, Method.of_runs(False).kind)
            how = out.method["kind"] + (" (the runs' own statistics)" if own else "")
            taken.setdefault(how, []).append(name)
    if taken:
        stats.notes.append("auto took " + "; ".join(f"{how} for {', '.join(names)}" for how, names in taken.items())
                           + " (each output's method in summary.json)")


class BasisCache:
    """What consecutive outputs of one file share when their expansions have the same basis: the band
    draws' basis values and the triple products, each kept for the last basis only (so that the memory
    is one basis's whatever the number of outputs). Used from one thread."""

    def __init__(self):
        self._last: dict[str, tuple] = {}

    def get(self, what: str, key: tuple, compute: Callable[[], np.ndarray]) -> np.ndarray:
        """`compute()`, or its value of the previous call with the same `what` and `key` (read-only)."""
        last = self._last.get(what)
        if last is None or last[0] != key:
            value = compute()
            value.flags.writeable = False
            self._last[what] = last = (key, value)
        return last[1]

    def band_rows(self, germs: list[str], indices: np.ndarray, options: Options) -> np.ndarray:
        """Ψ_α of the `options.band_samples` seeded draws of the germs, (N, Z)."""
        indices = np.asarray(indices, dtype=int)
        key = (tuple(germs), indices.shape, indices.tobytes(), options.band_samples, options.seed)
        return self.get("band rows", key, lambda: orthonormal_basis(
            germs, indices, draw_germs(germs, options.band_samples, options.seed)))

    def triple_products(self, germs: list[str], indices: np.ndarray, square_indices: np.ndarray) -> np.ndarray:
        """methods.pce_moments.triple_products, once per basis."""
        key = (tuple(germs), indices.shape, indices.tobytes(), square_indices.shape, square_indices.tobytes())
        return self.get("triple products", key, lambda: triple_products(germs, indices, square_indices))


def _start_output(store: ResultStore, name: str, method: MethodSpec, germs: list[str], design_kind: str,
                  ok: np.ndarray, options: Options, pool: Executor, basis_cache: BasisCache,
                  runs_only: bool = False, auto: bool = False) -> Callable[[], OutputStatistics]:
    """Read and fit output `name` here and hand its time blocks to `pool`; returns what waits for them
    and gives the output's statistics. `basis_cache`: what the outputs of one analysis share (BasisCache).
    `runs_only`: the statistics of the (weighted) runs themselves, as on a sampled design; `auto`: `method`
    is what auto took (auto_method)."""
    xi, weights = store.xi[ok], store.weights[ok]
    kind, order, entry = method.kind, method.order, method.entry
    unwrapped: list[str] = []
    basis, scale = output_basis(store, name, ok, unwrapped)
    truncation = _tsvd_resolution(store, scale, int(ok.sum()))
    sampled = DESIGNS[design_kind].sampled or runs_only
    x0 = None
    # x = x0 + S with each run's initial value (needs the runs themselves); only the projections use
    # it: the other kinds fit the constant term themselves, where the split would change nothing
    if method.split and not (sampled and entry.runs_on_sampled) and entry.split:
        basis = basis if scale is None else basis @ scale
        scale, x0 = None, basis[:, :1]

    def expand(a):
        return a if scale is None else a @ scale

    result = entry.fit(xi, weights, basis, germs, order, x0, scale=scale, sampled=sampled,
                       settings=dict(method.settings))
    mean, variance, pce, from_runs = result.mean, result.variance, result.pce, result.from_runs
    if from_runs:  # bands, PDFs and pick-freeze indices from the runs themselves
        rows, row_scale, band_weights = basis, scale, (None if entry.run_weights(weights) is None else weights / weights.sum())
    else:
        rows, row_scale, band_weights = basis_cache.band_rows(germs, pce.indices, options), pce.coefficients, None
    d = len(store.parameter_names)
    pick_rows = _pick_freeze_rows(ok, d) if from_runs and DESIGNS[design_kind].sobol_from_runs else None
    pick_freeze = pick_rows is not None
    joined_blocks = _over_time_blocks(rows, row_scale, store.time.size, band_weights, d if pick_freeze else 0,
                                      options, from_runs, pool, pce, basis_cache,
                                      pick_rows=None if pick_freeze and ok.all() else pick_rows)

    def finish() -> OutputStatistics:
        blocks = joined_blocks()
        magnitude = np.max(np.sqrt(mean**2 + np.maximum(variance, 0.0)))  # the output's own size over its history
        rtol = JSBSIM_RESOLUTION if "aircraft_hash" in store.attrs else RESOLUTION_RTOL
        resolution = store.resolution(name)  # the simulator's own resolution: its two valid trims' drift
        atol = truncation if resolution is None else np.maximum(truncation, resolution)
        resolved = resolved_variance(variance, mean, scale=magnitude, rtol=rtol, n=int(ok.sum()),
                                     weights=None if from_runs else weights, atol=atol)
        cov = modified_cov(mean, np.sqrt(np.maximum(variance, 0)))
        stats = OutputStatistics(name, store.units.get(name) or name_unit(name), store.time, mean, variance,
                                 blocks["band"], blocks["support"], blocks["density"], cov, resolved,
                                 quantiles=dict(zip(options.quantiles, blocks["quantiles"])),
                                 skewness=blocks["skewness"], kurtosis=blocks["kurtosis"],
                                 final_samples=blocks["final"], fourth_central=blocks.get("fourth"),
                                 unwrapped=bool(unwrapped))
        names = store.parameter_names

        def masked(indices):
            return np.where(resolved, indices, np.nan)

        if pce is not None:
            stats.pce = pce
            stats.sobol_first = dict(zip(names, masked(pce.sobol_first())))
            stats.sobol_total = dict(zip(names, masked(pce.sobol_total())))
            stats.coefficient_decay = _coefficient_decay(pce)
            stats.selection = pce.selection
            if entry.fits:
                stats.loo_error = _loo_error(entry, xi, weights, expand(basis), germs, pce.indices)
            elif entry.projects and not entry.quadrature and order >= 1:
                stats.convergence = _lower_order_difference(kind, xi, weights, basis, scale, germs, order, x0, pce)
            refit = (validation.refitting(kind, xi, weights, basis, scale, germs, order, sampled,
                                          dict(method.settings)) if entry.selects else None)
            _validate(stats, entry.rule, f"{kind} order {order}" + (" (taken by auto)" if auto else ""), xi, weights,
                      expand(basis), germs, None if isinstance(store, _QuantityView) else store.time, options.seed,
                      refit, auto)
        elif pick_freeze:
            stats.sobol_first = dict(zip(names, masked(blocks["first"])))
            stats.sobol_total = dict(zip(names, masked(blocks["total"])))
            stats.sobol_first_ci = dict(zip(names, np.moveaxis(blocks["first_ci"], 1, 0)))
            stats.sobol_total_ci = dict(zip(names, np.moveaxis(blocks["total_ci"], 1, 0)))
            flag = unresolved_flag(stats)
            if flag:
                stats.flags.append(flag)
        return stats

    return finish


def unresolved_flag(out: OutputStatistics) -> str | None:
    """The flag of pick-freeze indices that resolve no share (analysis.sobol.unresolved), naming the
    parameters and, over time, at how many times; None when every index is resolved. Times where the
    variance is negligible (below analysis.sobol.NEGLIGIBLE of its largest) are not counted: an index
    there is the share of almost nothing, which the plots grey."""
    times: np.ndarray = np.zeros(out.time.size, dtype=bool)
    variance = np.maximum(out.variance, 0.0)
    counted = variance >= NEGLIGIBLE * (variance.max() if variance.size else 0.0)
    named = []
    for parameter in out.sobol_first:
        where = counted & (unresolved(out.sobol_first[parameter], out.sobol_first_ci[parameter])
                           | unresolved(out.sobol_total[parameter], out.sobol_total_ci[parameter]))
        if where.any():
            named.append(parameter)
            times |= where
    if not named:
        return None
    at = f" at {int(times.sum())} of {int(counted.sum())} times of non-negligible variance" if times.size > 1 else ""
    return (f"Sobol' indices of {', '.join(named)} unresolved{at} (n too small): the 95 % interval is wider than "
            f"{UNRESOLVED_WIDTH:g} or lies outside [0, 1]; run more base samples (design.samples)")


def screen(stats: Statistics, out: OutputStatistics, xi: np.ndarray, Y: np.ndarray, ok: np.ndarray, options: Options,
           what: str) -> None:
    """Set `out.screening` to the screening measures of the design (DesignKind.screening), if it has one, of the
    values `Y` (n_ok, T) of the `ok` runs, `xi` every run's germs; its note, after `what`, in stats.notes once.

    Parameters
    ----------
    stats : Statistics
        The file's statistics: its design kind and facts, parameters and notes.
    out : OutputStatistics
        The output's or quantity's statistics, given its `screening` measures.
    xi : numpy.ndarray
        Every run's germs (N, d), in design order.
    Y : numpy.ndarray
        The ok runs' values.
    ok : numpy.ndarray
        bool (N,): the runs that give a value.
    options : Options
        Its bootstrap resamples and seed.
    what : str
        What the note is of ("" for every output).
    """
    kind = DESIGNS[stats.design_kind]
    if kind.screening is None:
        return
    measures, note = kind.screening(xi, Y, ok, stats.design_info, options.bootstrap, options.seed,
                                    stats.parameter_names)
    out.screening = Screening(kind.screening_name, measures)
    if note and what + note not in stats.notes:
        stats.notes.append(what + note)


def _pick_freeze_rows(ok: np.ndarray, d: int) -> np.ndarray | None:
    """The ok runs' rows of a pick-freeze design's complete base rows (analysis.sobol.complete_rows), None when
    fewer than 2 are complete (no index can be estimated)."""
    rows = complete_rows(ok, d)
    return rows if rows.size >= 2 * (d + 2) else None


def pick_freeze_note(ok: np.ndarray, d: int, what: str) -> str | None:
    """The note of a pick-freeze design whose runs `ok` miss some (failed, or `what` undefined in them):
    the indices and the variance split come from the complete base rows, and how many were dropped."""
    n = ok.size // (d + 2)
    complete = complete_rows(ok, d).size // (d + 2)
    if complete == n:
        return None
    if complete < 2:
        return (f"{what}: no Sobol' indices: {complete} of the {n} base rows of the pick-freeze design are complete "
                "(A, B and every AB_i ran), and the estimators need 2")
    return (f"{what}: the pick-freeze Sobol' indices and the variance split are estimated on the {complete} complete "
            f"base rows of {n} (A, B and every AB_i ran): {n - complete} rows dropped")


def _replicate_moments(store: ResultStore, name: str, replicates: int) -> tuple[np.ndarray, np.ndarray]:
    """Sample mean and variance of each randomised-QMC replicate (consecutive equal blocks of runs): (R, T) each."""
    basis, scale = output_basis(store, name, np.ones(store.status.size, dtype=bool))
    blocks = [weighted_moments(rows, None, scale, unbiased=True)
              for rows in np.split(basis, replicates)]
    return np.array([m for m, _ in blocks]), np.array([v for _, v in blocks])


def _tsvd_resolution(store: ResultStore, scale: np.ndarray | None, n: int) -> float:
    """The std a tSVD truncation can hide: tol·σ₁/√n per run, σ₁ the norm of scale = diag(s) Uᵀ's first
    row (0 for raw storage)."""
    if scale is None or not len(scale):
        return 0.0
    return float(store.tsvd_tolerance * np.linalg.norm(scale[0]) / math.sqrt(max(n, 1)))


def _coefficient_decay(pce: PCE) -> dict[int, np.ndarray]:
    """Root-sum-square of the PCE coefficients of each total degree, over time: how fast they decay."""
    degrees = np.asarray(pce.indices).sum(axis=1)
    return {int(p): np.sqrt((pce.coefficients[degrees == p] ** 2).sum(axis=0)) for p in np.unique(degrees)}


def _validate(out: OutputStatistics, rule: str, label: str, xi, weights, Y: np.ndarray, germs,
              time: np.ndarray | None, seed: int, refit=None, auto: bool = False) -> None:
    """Check `out`'s expansion on its own runs Y (methods.validation): its `validation` and its flags."""
    edges = [*out.band99, *out.quantiles.values()]
    found = validation.validate(rule, xi, weights, Y, germs, out.pce, out.loo_error, out.resolved, edges, seed,
                                refit)
    worst, excess = found.worst_error(), found.worst_excess()
    out.validation = {"check": found.check, "threshold": validation.VALIDATION_THRESHOLD,
                      "error": None if worst is None else worst[0],
                      "time": None if worst is None or time is None else float(time[worst[1]]),
                      "band_excess": None if excess is None else excess[0] + validation.BAND_MARGIN,
                      "band_margin": validation.BAND_MARGIN, "validated": found.validates()}
    out.flags.extend(validation.flags(found, rule, label, time, auto))


def _loo_error(entry, xi, weights, Y, germs, indices) -> np.ndarray:
    """The relative leave-one-out error of the fit over time (methods.loo), weighted as the fit is."""
    return validation.leave_one_out(entry.weighted, xi, weights, Y, germs, indices)


def _lower_order_difference(kind, xi, weights, basis, scale, germs, order, x0, pce: PCE) -> dict:
    """ε_m, ε_v (Eq. 49's normalisation) between this projection and the one of order − 1 on the same
    runs: a cheap estimate of the truncation error, with no reference needed."""
    lower = METHODS[kind].fit(xi, weights, basis, germs, order - 1, x0, scale=scale).pce
    eps_m, eps_v = relative_errors(lower.mean(), lower.variance(), pce.mean(), pce.variance())
    return {"against": f"order {order - 1}", "eps_m": eps_m, "eps_v": eps_v}


def _over_time_blocks(rows, scale, n_times: int, weights, pick_freeze_dimensions: int, options: Options,
                      from_runs: bool, pool: Executor, pce: PCE | None, basis_cache: BasisCache,
                      pick_rows: np.ndarray | None = None) -> Callable[[], dict]:
    """Quantiles, 99 % band, skewness and kurtosis, PDFs, final-time samples (the runs' fourth central
    moments, pick-freeze indices) of Y = rows @ scale (scale None: Y = rows), rebuilding Y for
    TIME_BLOCK times at once: the memory stays that of one block per thread whatever the number of runs or
    draws. Every statistic here is per time, so blocks change nothing. A `pce`'s skewness and kurtosis are
    its exact ones (methods.pce_moments), not those of its draws; the KDE's std comes from the factors.
    The blocks are handed to `pool`; returns what waits for them and joins them. `basis_cache`: the triple
    products of outputs before (BasisCache). `pick_rows`: the rows of the pick-freeze estimators (the complete
    base rows', analysis.sobol.complete_rows), None for every row."""
    probabilities = (0.5 * (1 - BAND_LEVEL), 0.5 * (1 + BAND_LEVEL), *options.quantiles)
    exact = None if pce is None else pce_standardised_moments(pce.germs, pce.indices, pce.coefficients,
                                                              basis_cache.triple_products)
    std = None if scale is None else np.sqrt(np.maximum(weighted_moments(rows, None, scale, unbiased=True)[1], 0.0))

    def block(start: int) -> dict:
        stop = min(start + TIME_BLOCK, n_times)
        if scale is None:
            Y = rows[:, start:stop]
        elif from_runs:
            Y = rows @ scale[:, start:stop]
        else:  # a PCE's draws, built time by time (the same products): sorting them copies no transpose
            Y = (scale[:, start:stop].T @ rows.T).T
        ordered = sorted_by_time(Y)  # each time's values sorted once: its quantiles, extremes and bins
        found = {"quantiles": weighted_quantiles(Y, probabilities, weights, ordered), "final": Y[:, -1].copy()}
        found["support"], found["density"] = pdf_over_time(Y, PDF_POINTS, std=None if std is None else std[start:stop],
                                                           ordered=ordered)
        if exact is None:  # summed run by run, as in the runs' own layout
            found["skewness"], found["kurtosis"] = standardised_moments(np.ascontiguousarray(Y), weights)
        if from_runs and weights is None:
            found["fourth"] = central_moments(Y)[2]
        if pick_freeze_dimensions:
            found.update(pick_freeze_indices(Y if pick_rows is None else Y[pick_rows], pick_freeze_dimensions,
                                             n_boot=options.bootstrap, seed=options.seed))
        return found

    # blocks in the pool's threads (numpy's sort, FFTs and BLAS release the GIL); each block's numbers are
    # its own, joined in time order: the same bits in any thread count
    futures = [pool.submit(block, start) for start in range(0, n_times, TIME_BLOCK)]
    return lambda: _joined([future.result() for future in futures], exact, pick_freeze_dimensions)


def _joined(found: list[dict], exact, pick_freeze_dimensions: int) -> dict:
    """The time blocks' statistics (`_over_time_blocks`) joined in time order."""
    parts = {key: [f[key] for f in found] for key in found[0]}
    quantiles = np.concatenate(parts["quantiles"], axis=1)
    skewness, kurtosis = exact or (np.concatenate(parts["skewness"]), np.concatenate(parts["kurtosis"]))
    joined = {"band": (quantiles[0], quantiles[1]), "quantiles": list(quantiles[2:]),
              "support": np.concatenate(parts["support"]), "density": np.concatenate(parts["density"]),
              "skewness": skewness, "kurtosis": kurtosis, "final": found[-1]["final"]}
    if "fourth" in parts:
        joined["fourth"] = np.concatenate(parts["fourth"])
    if pick_freeze_dimensions:
        joined.update({key: np.concatenate(parts[key], axis=-1) for key in ("first", "total", "first_ci", "total_ci")})
    return joined


def add_reference_errors(stats: Statistics, reference: Statistics) -> None:
    """ε_m, ε_v over time (Eq. 49) and the KLD at the final time (Eq. 50) against the reference, with the
    reference's own noise floor in the same normalisation (analysis.floors)."""
    stats.reference = reference.path
    for name, out in stats.outputs.items():
        ref = reference.outputs.get(name)
        if ref is None or ref.time.shape != out.time.shape or not np.allclose(ref.time, out.time):
            continue
        eps_m, eps_v = relative_errors(out.mean, out.variance, ref.mean, ref.variance)
        kld = kl_divergence(out.final_samples, ref.final_samples)
        out.errors = {"eps_m": eps_m, "eps_v": eps_v, "eps_m_summary": error_summary(eps_m),
                      "eps_v_summary": error_summary(eps_v), "kld_final": kld, **_reference_floor(reference, ref, out)}


KLD_FLOOR_NOTE = ("; KLD floor = the KLD of two disjoint parts of the reference plus the estimator's bias for normal "
                  "laws of the method's and the reference's means and spreads")


def _kld_floor(reference: Statistics, ref: OutputStatistics, out: OutputStatistics) -> float:
    """The KLD the reference's sampling noise (analysis.floors.kld_floor) and the estimator's bias
    (kld_estimator_bias: a method's law wider than the reference's is overstated) give, seeded by the reference's
    seed."""
    split = kld_floor(ref.final_samples, n_method=len(out.final_samples), seed=reference.seed)
    return float(split + kld_estimator_bias(out.final_samples, ref.final_samples, seed=reference.seed))


def _reference_floor(reference: Statistics, ref: OutputStatistics, out: OutputStatistics) -> dict:
    """The errors a reference's own noise alone would show, and which floor that is."""
    if ref.replicate_moments is not None:
        means, variances = ref.replicate_moments
        r = len(means)
        se_mean, se_variance = means.std(axis=0, ddof=1) / np.sqrt(r), variances.std(axis=0, ddof=1) / np.sqrt(r)
        peak_mean, peak_variance = np.max(np.abs(ref.mean)) or 1.0, np.max(np.abs(ref.variance)) or 1.0
        note = (f"reference: randomised QMC, {r} replicates of {reference.completed // r} scrambled Sobol' points; "
                "floor = the standard errors of its mean and variance from the spread of the replicates")
        return {"eps_m_floor": se_mean / peak_mean, "eps_v_floor": se_variance / peak_variance,
                "kld_floor": _kld_floor(reference, ref, out), "floor_note": note + KLD_FLOOR_NOTE}
    if reference.from_runs and ref.fourth_central is not None:
        floors = floors_from_moments(ref.mean, ref.variance, ref.fourth_central, reference.completed)
        qmc = not getattr(DESIGNS[reference.design_kind].sampling, "independent", False)  # a grid's too
        note = (f"reference: {reference.completed} {reference.design_kind} runs; floor = its standard errors "
                "(σ/√N for the mean, the distribution-free s.e. of the variance)"
                + ("; QMC converges faster than this Monte Carlo floor, so it is an upper bound" if qmc else ""))
        return {"eps_m_floor": floors["eps_m_floor"], "eps_v_floor": floors["eps_v_floor"],
                "kld_floor": _kld_floor(reference, ref, out), "floor_note": note + KLD_FLOOR_NOTE}
    note = (f"reference: {reference.method.kind} on a {reference.design_kind}, deterministic: it has no sampling "
            "floor; its own truncation error is not included (see its convergence estimate)")
    return {"eps_m_floor": None, "eps_v_floor": None, "kld_floor": None, "floor_note": note}


class _QuantityView:
    """A results file seen with one quantity as its only output, of one time point: what
    `_output_statistics` reads, so a quantity gets the outputs' methods, refusals and flags."""

    def __init__(self, store: ResultStore, name: str, values: np.ndarray, units: str):
        self._store, self._values = store, values
        self.time, self.units = np.zeros(1), {name: units}

    def __getattr__(self, attribute):  # the design, its weights, names and attributes: the file's
        return getattr(self._store, attribute)

    def output_factors(self, name: str):
        return None

    def output_matrix(self, name: str, rows) -> np.ndarray:
        return self._values[np.asarray(rows, dtype=np.int64)][:, None]

    def resolution(self, name: str):
        return None


def quantity_units(store: ResultStore, stats: Statistics, name: str) -> str:
    """The unit of quantity `name`: its take and `of` in the recorded campaign give it (QuantitySpec.unit)."""
    spec = stats.record.campaign.quantities.get(name)
    return (spec.unit(store.units) if spec is not None else "") or name_unit(name)


def quantity_statistics(store: ResultStore, stats: Statistics, name: str, germs: list[str], ok: np.ndarray,
                        options: Options, thresholds: list[dict]) -> QuantityStatistics:
    """Statistics of quantity `name` over the successful runs where it is defined. Undefined in some:
    a sampled design's statistics are conditional on the others (noted); a grid's are None (noted:
    a projection needs every run). Exceedance probabilities from the runs or from the PCE."""
    values = store.quantity(name)
    units = quantity_units(store, stats, name)
    defined = ok & np.isfinite(values)
    period = angle_period(units)
    shifts = None if period is None else branch_shifts(np.where(defined, values, np.nan), period)
    if shifts is not None and shifts.any():
        values = values + shifts
        stats.notes.append(unwrapped_note(f"quantity {name}", units))
    missing = int(ok.sum() - defined.sum())
    sampled = DESIGNS[stats.design_kind].sampled
    why = None
    huge = too_large("quantity", name, float(np.abs(values[defined]).max(initial=0.0)))
    if huge:
        why = f"{huge}; its statistics are null"
    elif not defined.any():
        why = f"quantity {name} is undefined in every successful run: its statistics are null"
    elif missing and not sampled:
        why = (f"quantity {name} is undefined in {missing} of {int(ok.sum())} successful runs: a projection on "
               f"a {stats.design_kind} needs every run, so its statistics are null")
    elif missing:
        problem = method_problem(stats.method.kind, stats.method.order, store.xi[defined],
                                 store.weights[defined], germs, sampled, missing=int((~defined).sum()))
        why = problem and f"quantity {name}: method {stats.method.kind} on the runs where it is defined: {problem}"
        if not why:
            stats.notes.append(f"quantity {name} is undefined in {missing} of {int(ok.sum())} successful runs: "
                               "its statistics are conditional on the runs where it is defined")
    if why:
        stats.notes.append(why)
        nulls = [{**item, "probability": None, "lower": None, "upper": None, "method": None, "flags": [], "note": why}
                 for item in thresholds]
        return QuantityStatistics(name, missing, None, nulls, units)
    view = _QuantityView(store, name, values, units)
    out = _output_statistics(view, name, stats.method, germs, stats.design_kind, defined, options)
    out.unwrapped = shifts is not None and bool(shifts.any())
    screen(stats, out, store.xi, values[defined][:, None], defined, options,
           f"quantity {name} (undefined in some runs): " if missing else "")
    if missing and stats.from_runs and DESIGNS[stats.design_kind].sobol_from_runs:
        note = pick_freeze_note(defined, len(store.parameter_names), f"quantity {name} (undefined in some runs)")
        if note:
            stats.notes.append(note)
    if out.pce is None and not sampled:  # auto's runs' own statistics on a grid: the weighted runs
        exceedance = _grid_exceedance(values, defined, store.weights, thresholds, units)
    elif out.pce is None:
        exceedance = exceedance_from_runs(values, defined, thresholds, DESIGNS[stats.design_kind].sampling,
                                          stats.design_info, units)
    else:
        exceedance = exceedance_from_pce(out.pce.sample(options.band_samples, options.seed)[:, 0],
                                         int(defined.sum()), thresholds, values[defined], units)
    if out.pce is not None:  # a fraction of the expansion's draws: its flags bear on it (an index's do not)
        for item in exceedance:
            item["flags"] += out.flags
    slips = [slip for item in thresholds if (slip := unit_slip(values[defined], next(iter(item.values())), units))]
    flags = [*out.flags, *slips]
    stats.notes.extend(f"quantity {name}: {flag}" for flag in flags)
    return QuantityStatistics(name, missing, out, exceedance, units, flags)


def _grid_exceedance(values: np.ndarray, defined: np.ndarray, weights: np.ndarray,
                     thresholds: list[dict], units: str = "") -> list[dict]:
    """Exceedance probabilities of a grid's weighted runs (weights >= 0): the quadrature of the indicator,
    without an interval (analysis.failures: the nodes are not random draws); a threshold's unit slip flagged."""
    found = []
    for item in thresholds:
        (bound, threshold), = item.items()
        beyond = values[defined] > threshold if bound == "above" else values[defined] < threshold
        p = grid_failure_probability(beyond, weights[defined])
        found.append(exceedance_entry(bound, threshold, p["estimate"], None, None, "grid",
                                      f"the grid's quadrature of the indicator {bound} {threshold:g}, without an "
                                      "interval (the nodes are not random draws); a sampled design gives one",
                                      unit_slip(values[defined], threshold, units)))
    return found


def _quantity_json(quantity: QuantityStatistics, seeds: list[str]) -> dict:
    """summary.json's quantities.NAME: numbers, not lists (null where undefined)."""
    out = quantity.output
    entry = {"units": quantity.units, "missing": quantity.missing, "exceedance": quantity.exceedance,
             "flags": quantity.flags}
    if out is None:
        return {"mean": None, "variance": None, "std": None, "band99": {"lower": None, "upper": None},
                "quantiles": {}, "skewness": None, "kurtosis": None, "sobol_first": {}, "sobol_total": {}, **entry}
    entry.update({
        "mean": out.mean[0], "variance": out.variance[0], "std": out.std[0],
        "band99": {"lower": out.band99[0][0], "upper": out.band99[1][0]},
        "quantiles": {f"{p:g}": values[0] for p, values in out.quantiles.items()},
        "skewness": out.skewness[0], "kurtosis": out.kurtosis[0], "resolved": out.resolved[0],
        "sobol_first": {k: v[0] for k, v in out.sobol_first.items()},
        "sobol_total": {k: v[0] for k, v in out.sobol_total.items()}})
    if out.sobol_first_ci:
        entry["sobol_first_ci"] = {k: {"lower": v[0][0], "upper": v[1][0]} for k, v in out.sobol_first_ci.items()}
        entry["sobol_total_ci"] = {k: {"lower": v[0][0], "upper": v[1][0]} for k, v in out.sobol_total_ci.items()}
        if seeds:
            entry["variance_split"] = _at_first_time(variance_split(out, seeds[0]))
    if out.loo_error is not None:
        entry["loo_error"] = out.loo_error[0]
    if out.selection is not None:
        entry["selection"] = out.selection
    if out.convergence is not None:
        entry["convergence"] = {**out.convergence, "eps_m": out.convergence["eps_m"][0],
                                "eps_v": out.convergence["eps_v"][0]}
    if out.validation is not None:
        entry["validation"] = out.validation
    if out.method is not None:
        entry["method"] = out.method
    if out.screening is not None:
        entry[out.screening.name] = _at_first_time(out.screening.measures)
    return entry


def _at_first_time(value):
    """A mapping of per-time arrays with each array's first value (a quantity's one time point)."""
    if isinstance(value, dict):
        return {k: _at_first_time(v) for k, v in value.items()}
    return value[0] if isinstance(value, np.ndarray) else value


def json_ready(value):
    """`value` with numpy arrays as lists and NaN or infinite floats as None: strict JSON."""
    if isinstance(value, dict):
        return {str(k): json_ready(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        if all(type(v) is float for v in value) and math.isfinite(sum(value)):  # finite floats as they are
            return list(value)
        return [json_ready(v) for v in value]
    if isinstance(value, np.ndarray):
        if value.dtype.kind == "f":  # the floats as they are, NaN and infinity as None
            finite = np.isfinite(value)
            return value.tolist() if finite.all() else np.where(finite, value.astype(object), None).tolist()
        return json_ready(value.tolist())
    if isinstance(value, (np.bool_, bool)):
        return bool(value)
    if isinstance(value, (np.integer, int)):
        return int(value)
    if isinstance(value, (np.floating, float)):
        return float(value) if math.isfinite(value) else None
    return value


def variance_split(out: OutputStatistics, seed: str) -> dict:
    """The shares of the variance due to the seed's random stream (aleatory) and to the other inputs
    (epistemic), first-order and total, with the pick-freeze intervals: the others' first-order share is the
    closed index of the complement, 1 − S_T(seed), and their total share 1 − S(seed)."""
    first, total = out.sobol_first[seed], out.sobol_total[seed]
    (first_low, first_high), (total_low, total_high) = (
        np.where(np.isnan(index), np.nan, ci) for index, ci in ((first, out.sobol_first_ci[seed]),
                                                                (total, out.sobol_total_ci[seed])))  # unresolved
    return {"seed": seed,
            "seeds": {"first": first, "total": total, "first_ci": {"lower": first_low, "upper": first_high},
                      "total_ci": {"lower": total_low, "upper": total_high}},
            "other_parameters": {"first": 1 - total, "total": 1 - first,
                                 "first_ci": {"lower": 1 - total_high, "upper": 1 - total_low},
                                 "total_ci": {"lower": 1 - first_high, "upper": 1 - first_low}}}


def summary_json(stats: Statistics) -> dict:
    """summary.json: the fixed schema of docs/summary-json.md plus the run counts, the failure probability, the
    notes, and per output std, CoV, quantiles, skewness, kurtosis, resolution, the fits' leave-one-out
    error, the projections' convergence estimate, and the errors against a reference with their floors.
    Undefined values are None (null): the result dumps as strict JSON."""
    outputs = {}
    for name, out in stats.outputs.items():
        entry = {
            "time": out.time, "units": out.units, "flags": out.flags, "mean": out.mean, "variance": out.variance,
            "std": out.std,
            "band99": {"lower": out.band99[0], "upper": out.band99[1]},
            "quantiles": {f"{p:g}": values for p, values in out.quantiles.items()},
            "skewness": out.skewness, "kurtosis": out.kurtosis, "cov": out.cov, "resolved": out.resolved,
            "sobol_first": out.sobol_first, "sobol_total": out.sobol_total,
        }
        if out.sobol_first_ci:
            entry["sobol_first_ci"] = {k: {"lower": v[0], "upper": v[1]} for k, v in out.sobol_first_ci.items()}
            entry["sobol_total_ci"] = {k: {"lower": v[0], "upper": v[1]} for k, v in out.sobol_total_ci.items()}
        if stats.seeds and out.sobol_first_ci:
            entry["variance_split"] = variance_split(out, stats.seeds[0])
        if out.loo_error is not None:
            entry["loo_error"] = out.loo_error
        if out.selection is not None:
            entry["selection"] = out.selection
        if out.convergence is not None:
            entry["convergence"] = out.convergence
        if out.validation is not None:
            entry["validation"] = out.validation
        if out.method is not None:
            entry["method"] = out.method
        if out.screening is not None:
            entry[out.screening.name] = out.screening.measures
        if out.errors:
            errors = out.errors
            entry["errors"] = {"eps_m": errors["eps_m"], "eps_v": errors["eps_v"],
                               "eps_m_max": errors["eps_m_summary"]["max"], "eps_v_max": errors["eps_v_summary"]["max"],
                               "kld_final": errors["kld_final"], "eps_m_floor": errors["eps_m_floor"],
                               "eps_v_floor": errors["eps_v_floor"], "kld_floor": errors["kld_floor"],
                               "floor_note": errors["floor_note"]}
        outputs[name] = entry
    return json_ready({
        "results": stats.path, "campaign": stats.campaign_name, "method": stats.method.summary(),
        "design": stats.design_kind, "runs": stats.runs, "completed": stats.completed, "failed": stats.failed, "pending": stats.pending,
        "failure_probability": stats.failure_probability, "partial": stats.partial, "notes": stats.notes,
        "failures": stats.failures, "parameters": stats.parameter_names, "reference": stats.reference,
        **({"dependence": stats.dependence} if stats.dependence else {}),
        "outputs": outputs,
        "quantities": {name: _quantity_json(quantity, stats.seeds) for name, quantity in stats.quantities.items()},
        **({"index_set": stats.index_set} if stats.index_set else {}),
        **({"rare_event": stats.rare_event} if stats.rare_event else {})})
