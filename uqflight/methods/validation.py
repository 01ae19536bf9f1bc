"""Every expansion checked on its own runs: an error estimated out of sample, and the band and quantiles
against the range the runs themselves span. Beyond the thresholds below the output or quantity is flagged
with the remedy that helps.

The out-of-sample error is a share of the runs' own variance, per time, each run counting once:

* a fit (least squares, regression): its leave-one-out error (`loo`, weighted as the fit);
* a selection (sparse): CV_FOLDS-fold cross-validation with the selection redone in each fold (its
  leave-one-out error on the basis it chose is optimistic: the choice saw every run);
* a projection (pseudo-Galerkin, integration, interpolation on a grid): the larger of the projection's own
  residual at the grid's runs, Σ(yᵢ − PCE(ξᵢ))² / Σ(yᵢ − ȳ)², and the leave-one-out error of a least-squares
  fit of the same basis on the same runs (when the grid has more runs than terms). A projection does not
  interpolate its nodes: where the runs hold what the basis cannot carry (a kink, a max(), a wrap) the
  projection misses them at its own nodes, and the least-squares fit misses the left-out run.

The band check: at each judged time the 99 % band's edges and the quantiles must lie within the runs'
range [min, max] widened to take in the 99 % band of the runs' own additive quadratic least-squares fit (a
smooth output over many inputs spreads beyond the few runs a grid puts on its axes, as that fit says), plus
BAND_MARGIN times the runs' range.

A time is judged when its variance is resolved and the runs' std there is at least JUDGED_SPREAD of the
output's largest: where the output hardly varies, a relative error of its rounding is no error of a
statistic.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..analysis.moments import as_runs_by_time
from ..parameters.germs import draw_germs
from .kind import DEFAULT_ORDER, METHODS, Method, Result
from .basis import orthonormal_basis
from .loo import relative_loo_error
from .pce import PCE
from .validity import method_problem

# An expansion that leaves more than 5 % of the runs' variance unexplained out of sample (an RMS error
# above 22 % of their std) is flagged: the smooth flights and closed forms of the tests stay below 1e-2,
# an output with a kink or a max() (a peak bank) is above 0.1.
VALIDATION_THRESHOLD = 0.05
# A band edge or quantile more than 1.5 ranges of the runs beyond their range (and their additive quadratic
# fit's band) is flagged as an extrapolation: the 737 rudder kick's altitude at 14.9 s, whose band 200 Monte
# Carlo runs confirm, reaches 1.1 (its 85 grid runs understate the tail).
BAND_MARGIN = 1.5
JUDGED_SPREAD = 1e-2
# folds of the cross-validation of a selection (sparse): its leave-one-out error on the basis it chose saw
# every run in the choice (0.04 where the error on fresh points is 0.145); redone per fold it does not
CV_FOLDS = 5
ALLOWANCE_DRAWS = 4000  # draws of the runs' additive quadratic fit whose 99 % band widens their range
AUTO_BAND_DRAWS = 2000  # draws of a candidate's PCE whose 99 % band auto checks against the runs
# what `auto` chooses among, in this order of preference at equal error; the runs' own statistics
# (monte_carlo on a sampled design, integration's weighted runs on a grid of weights >= 0) when none validates
AUTO_CANDIDATES = ("pseudo_galerkin", "least_squares", "sparse")


@dataclass
class Validation:
    """What the check of an expansion on its own runs found.

    Attributes
    ----------
    error : numpy.ndarray
        (T,) out-of-sample error, a share of the runs' variance (NaN where undefined).
    check : str
        How the error was estimated, in words.
    judged : numpy.ndarray
        (T,) bool: the times the flags judge.
    least_squares : numpy.ndarray or None
        (T,) leave-one-out error of least squares of the same basis on the same runs (projections).
    band_excess : numpy.ndarray
        (T,) how far the band or a quantile lies beyond the allowed range, in ranges of the runs
        (<= 0: within it).
    allowed : tuple of numpy.ndarray
        (lower, upper) of the allowed range per time.
    """

    error: np.ndarray
    check: str
    judged: np.ndarray
    least_squares: np.ndarray | None
    band_excess: np.ndarray
    allowed: tuple[np.ndarray, np.ndarray]

    def worst_error(self) -> tuple[float, int] | None:
        """The largest error over the judged times and its time index; None when no time is judged or
        the error is undefined at every judged one."""
        error = np.where(self.judged, self.error, np.nan)
        if not np.isfinite(error).any():
            return None
        at = int(np.nanargmax(error))
        return float(error[at]), at

    def worst_excess(self) -> tuple[float, int] | None:
        """The largest band excess over the judged times and its time index (None: no time judged)."""
        if not self.judged.any():
            return None
        excess = np.where(self.judged, self.band_excess, -np.inf)
        at = int(np.argmax(excess))
        return float(excess[at]), at

    def validates(self) -> bool:
        """The error is defined and below VALIDATION_THRESHOLD at every judged time, and the band within
        its allowed range (no time judged: nothing varies, nothing to flag)."""
        worst = self.worst_error()
        excess = self.worst_excess()
        if excess is None:
            return True
        return worst is not None and worst[0] <= VALIDATION_THRESHOLD and excess[0] <= 0.0


def judged_times(Y: np.ndarray, resolved: np.ndarray) -> np.ndarray:
    """(T,) bool: resolved times where the runs' std is at least JUDGED_SPREAD of its largest."""
    std = Y.std(axis=0)
    peak = std.max(initial=0.0)
    return np.asarray(resolved, dtype=bool) & (std > 0) & (std >= JUDGED_SPREAD * peak)


def cross_validated_error(refit: Callable[[np.ndarray], PCE], xi, Y: np.ndarray,
                          folds: int = CV_FOLDS) -> np.ndarray:
    """Σ(yᵢ − ŷᵢ)² / Σ(yᵢ − ȳ)² per column of Y (N, T), ŷᵢ the prediction of `refit(train)` (the method redone,
    its selection included, on the runs of the bool mask `train`) for the fold that left run i out: run i is
    in fold i mod `folds` (nothing drawn). NaN where a fold cannot be fitted or the runs do not vary."""
    n = len(Y)
    fold = np.arange(n) % max(1, min(folds, n))
    residual = np.zeros(Y.shape[1])
    for f in np.unique(fold):
        test = fold == f
        try:
            predicted = refit(~test).evaluate(np.asarray(xi)[test])
        except ValueError:  # too few runs left to fit: no out-of-sample error
            return np.full(Y.shape[1], np.nan)
        residual += np.sum((Y[test] - predicted) ** 2, axis=0)
    spread = np.sum((Y - Y.mean(axis=0)) ** 2, axis=0)
    return np.divide(residual, spread, out=np.full(Y.shape[1], np.nan), where=spread > 0)


def out_of_sample_error(rule: str, xi, weights, Y: np.ndarray, germs, pce: PCE, loo_error: np.ndarray | None,
                        refit: Callable[[np.ndarray], PCE] | None = None
                        ) -> tuple[np.ndarray, str, np.ndarray | None]:
    """(error (T,), how it was estimated, least squares' LOO error of the same basis or None) of the
    expansion `pce` built by a method of `rule` from the runs Y (N, T) at xi; `loo_error`: the fit's own;
    `refit`: the method redone on a subset of the runs (cross_validated_error), for a selection."""
    if rule == "selection" and refit is not None:
        return (cross_validated_error(refit, xi, Y),
                f"{CV_FOLDS}-fold cross-validation, the selection redone in each fold", None)
    if rule in ("fit", "selection"):
        how = "leave-one-out" + (" on the basis it selected" if rule == "selection" else "")
        return (np.full(Y.shape[1], np.nan) if loo_error is None else loo_error), how, None
    spread = np.sum((Y - Y.mean(axis=0)) ** 2, axis=0)
    residual = np.sum((Y - pce.evaluate(xi)) ** 2, axis=0)
    own = np.divide(residual, spread, out=np.full(Y.shape[1], np.nan), where=spread > 0)
    matrix = orthonormal_basis(germs, pce.indices, xi)
    least_squares = None
    if matrix.shape[0] > matrix.shape[1]:
        try:
            least_squares = relative_loo_error(matrix, Y)
        except ValueError:  # rank-deficient or interpolating: no out-of-sample error of the fit
            least_squares = None
    if least_squares is None:
        return own, "the projection's residual at the grid's runs", None
    return (np.fmax(own, least_squares),
            "the projection's residual at the grid's runs and the leave-one-out error of least squares "
            "of the same basis on them, the larger", least_squares)


def allowed_range(xi, Y: np.ndarray, germs, edges: list[np.ndarray],
                  seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(lower, upper, range) per time: the runs' [min, max] widened to the 99 % band of their additive quadratic
    least-squares fit (its linear fit when the runs are too few; ALLOWANCE_DRAWS draws seeded by `seed`), then
    by BAND_MARGIN ranges; range = max − min. The fit's band is drawn only at the times where one of `edges`
    (each (T,)) lies beyond the runs' range and the margin: elsewhere it could only widen what already holds."""
    low, high = Y.min(axis=0), Y.max(axis=0)
    span = high - low
    outside = np.max([np.maximum(low - BAND_MARGIN * span - edge, edge - high - BAND_MARGIN * span)
                      for edge in edges], axis=0) > 0
    d = len(germs)
    indices = np.vstack([np.zeros((1, d), dtype=int), np.eye(d, dtype=int), 2 * np.eye(d, dtype=int)])
    if len(Y) <= len(indices):  # too few runs for the quadratic terms (a level-1 grid): the linear fit
        indices = indices[:d + 1]
    matrix = orthonormal_basis(germs, indices, xi)
    if outside.any() and matrix.shape[0] > matrix.shape[1]:
        coefficients, _, rank, _ = np.linalg.lstsq(matrix, Y[:, outside], rcond=None)
        if rank == matrix.shape[1]:
            draws = orthonormal_basis(germs, indices, draw_germs(germs, ALLOWANCE_DRAWS, seed)) @ coefficients
            band = np.quantile(draws, [0.005, 0.995], axis=0)
            low, high = low.copy(), high.copy()
            low[outside], high[outside] = np.minimum(low[outside], band[0]), np.maximum(high[outside], band[1])
    return low - BAND_MARGIN * span, high + BAND_MARGIN * span, span


def validate(rule: str, xi, weights, Y: np.ndarray, germs, pce: PCE, loo_error, resolved,
             edges: list[np.ndarray], seed: int = 0,
             refit: Callable[[np.ndarray], PCE] | None = None) -> Validation:
    """Check the expansion `pce` (of a method of `rule`) on its runs Y (N, T) at xi: its out-of-sample
    error and its band edges and quantiles `edges` (each (T,)) against the runs' range (`seed`: allowed_range)."""
    error, how, least_squares = out_of_sample_error(rule, xi, weights, Y, germs, pce, loo_error, refit)
    lower, upper, span = allowed_range(xi, Y, germs, edges, seed)
    beyond = np.max([np.maximum(lower - edge, edge - upper) for edge in edges], axis=0)
    excess = np.divide(beyond, span, out=np.zeros_like(beyond), where=span > 0)
    return Validation(error, how, judged_times(Y, resolved), least_squares, excess, (lower, upper))


def remedy(rule: str, least_squares_error: float | None, auto: bool = False) -> str:
    """What helps an expansion of a method of `rule` that does not validate on its runs (`auto`: the method
    `method: {kind: auto}` took, the lowest error among those the runs allow)."""
    if auto:
        return ("auto took the lowest error among the methods these runs allow: run a sampled design "
                "(latin_hypercube, sobol, monte_carlo), whose runs' own statistics need no expansion")
    sampled = ("or a sampled design (latin_hypercube, sobol, monte_carlo), whose runs' own statistics need "
               "no expansion; `method: {kind: auto}` takes the method that validates")
    if rule == "projection":
        first = ("least squares of the same basis validates on these runs (`report --method least_squares`)"
                 if least_squares_error is not None and least_squares_error <= VALIDATION_THRESHOLD else
                 "use least squares or sparse on the same runs (`report --method least_squares`, "
                 "`method: {kind: sparse}`)")
        return f"{first}, {sampled}"
    if rule == "fit":
        return f"use sparse on the same runs (`method: {{kind: sparse}}`) or another order, {sampled}"
    return f"use another max_order or more runs, {sampled}"


def flags(validation: Validation, rule: str, label: str, time: np.ndarray | None, auto: bool = False,
          band_of: str = "99 % band") -> list[str]:
    """The flag texts of a check (empty when it validates); `label` names the method, `time` the output's
    times (None: a quantity, one value)."""
    found = []

    def when(at: int) -> str:
        return "" if time is None else f" at t = {time[at]:.6g} s"

    worst = validation.worst_error()
    excess = validation.worst_excess()
    if excess is None:
        return found
    ls = validation.least_squares
    ls_error = None if ls is None or not np.isfinite(ls[validation.judged]).any() else float(
        np.nanmax(np.where(validation.judged, ls, np.nan)))
    fix = remedy(rule, ls_error, auto)
    if worst is None:
        found.append(f"{label}: no out-of-sample error could be estimated on these runs, so its statistics "
                     f"are not validated; {fix}")
    elif worst[0] > VALIDATION_THRESHOLD:
        found.append(f"{label} misses its own runs: out-of-sample error {worst[0]:.3g} of their variance"
                     f"{when(worst[1])} ({validation.check}), above {VALIDATION_THRESHOLD:g}: its mean, "
                     f"spread, band and Sobol' indices are not to be trusted; {fix}")
    if excess[0] > 0.0:
        at = excess[1]
        lower, upper = validation.allowed
        found.append(f"{label} extrapolates: its {band_of} or a quantile{when(at)} lies "
                     f"{excess[0] + BAND_MARGIN:.3g} ranges of the runs beyond what they span (more than "
                     f"{BAND_MARGIN:g} beyond their range and their additive quadratic fit's band, [{lower[at]:.6g}, "
                     f"{upper[at]:.6g}] with that margin): an extrapolation these runs can neither confirm nor "
                     f"refute; {fix}")
    return found


def leave_one_out(weighted: bool, xi, weights, Y: np.ndarray, germs, indices) -> np.ndarray:
    """The relative leave-one-out error over time (`loo`) of the fit of basis `indices`, weighted by |w|
    when the fit is; NaN where undefined (a point the fit interpolates)."""
    matrix = orthonormal_basis(germs, indices, xi)
    try:
        return relative_loo_error(matrix, Y, np.abs(weights) if weighted else None)
    except ValueError:  # a point the fit interpolates: leaving it out is undefined
        return np.full(Y.shape[1], np.nan)


def auto_choice(xi, weights, basis, scale, germs, order: int, sampled: bool, missing: int = 0,
                seed: int = 0) -> tuple[str | None, dict[str, float | None], list[str]]:
    """What `method: {kind: auto}` takes on the runs Y = basis @ scale (scale None: Y = basis) at xi: (the kind
    of AUTO_CANDIDATES with the lowest out-of-sample error over the judged times, at most VALIDATION_THRESHOLD,
    whose 99 % band (of AUTO_BAND_DRAWS draws seeded by `seed`) stays within the runs' allowed range, ties
    (below 1e-12: exact) to the first; None when none validates, {kind: its error, None: undefined}).
    Candidates the design and its runs refuse (methods.validity) are left out."""
    Y = basis if scale is None else basis @ scale
    judged = judged_times(Y, np.ones(Y.shape[1], dtype=bool))
    errors: dict[str, float | None] = {}
    band_outside: set[str] = set()
    for kind in AUTO_CANDIDATES:
        entry = METHODS[kind]
        if (entry.projects and sampled) or method_problem(kind, order, xi, weights, germs, sampled, missing=missing):
            continue
        try:
            pce = entry.fit(xi, weights, basis, germs, order, scale=scale, sampled=sampled).pce
        except ValueError:  # e.g. sparse with no basis of a defined leave-one-out error
            continue
        loo = None if entry.projects else leave_one_out(entry.weighted, xi, weights, Y, germs,
                                                                    pce.indices)
        refit = refitting(kind, xi, weights, basis, scale, germs, order, sampled)
        found = out_of_sample_error(entry.rule, xi, weights, Y, germs, pce, loo, refit)[0]
        error = np.where(judged, found, np.nan)
        errors[kind] = 0.0 if not judged.any() else (float(np.nanmax(error)) if np.isfinite(error).any() else None)
        if errors[kind] is not None and errors[kind] <= VALIDATION_THRESHOLD and judged.any():
            draws = pce.sample(AUTO_BAND_DRAWS, seed)
            edges = list(np.quantile(draws, [0.005, 0.995], axis=0))
            lower, upper, span = allowed_range(xi, Y, germs, edges, seed)
            beyond = np.max([np.maximum(lower - edge, edge - upper) for edge in edges], axis=0)
            if np.any(judged & (beyond > 0)):
                band_outside.add(kind)
    valid = [(max(e, 1e-12), i, k) for i, (k, e) in enumerate(errors.items())
             if e is not None and e <= VALIDATION_THRESHOLD and k not in band_outside]
    return (min(valid)[2] if valid else None), errors, sorted(band_outside)


def refitting(kind: str, xi, weights, basis, scale, germs, order: int, sampled: bool,
           settings: dict | None = None) -> Callable[[np.ndarray], PCE]:
    """train (bool (N,)) -> the PCE of method `kind` fitted on those runs alone (cross_validated_error)."""
    method = Method.of(kind)
    return lambda train: method.fit(xi[train], weights[train], basis[train], germs, order, scale=scale,
                                    sampled=sampled, settings=settings).pce


class Auto(Method):
    """Per output and quantity, among pseudo_galerkin (grids), least_squares and sparse of `order`, the one
    with the lowest error validated on the runs; the runs' own statistics when none validates. Each output's
    `method` in summary.json says which it took (see [methods](../methods.md)).

    Examples
    --------
    >>> import numpy as np
    >>> from uqflight.methods import Method
    >>> auto, xi, w = Method.of("auto"), np.random.default_rng(0).standard_normal((10, 2)), np.full(10, 0.1)
    >>> line, step = 1 + 2 * xi[:, :1] + 3 * xi[:, 1:], np.sign(xi[:, :1])  # 10 draws of 2 normal germs
    >>> auto.choose(xi, w, line, None, ["normal"] * 2, 1, sampled=True)[0]  # both fits exact: a tie, the first
    'least_squares'
    >>> auto.choose(xi, w, step, None, ["normal"] * 2, 1, sampled=True)[0]  # no fit validates: the runs' own
    'monte_carlo'
    >>> result = auto.fit(xi, w, line, ["normal"] * 2, order=1, sampled=True)
    >>> round(float(result.mean[0]), 12), round(float(result.variance[0]), 12)  # 1 and 2² + 3² = 13
    (1.0, 13.0)
    """

    kind, label, failed_runs, partial, weighted = "auto", "auto", "chosen", True, False
    exported_as = ("least_squares", "pseudo_galerkin")

    def choose(self, xi, weights, basis, scale, germs, order: int, sampled: bool, missing: int = 0, seed: int = 0,
               name: str = "the runs") -> tuple[str, bool, dict]:
        """(the kind it takes on the runs Y = basis @ scale, whether its statistics are the runs' own weighted
        by a grid, the record of what it took and why). Among AUTO_CANDIDATES of `order` that the design and
        its runs allow (validity), the one whose out-of-sample error over the judged times is the lowest and
        below VALIDATION_THRESHOLD and whose band stays within the runs' allowed range (`auto_choice`, draws
        seeded by `seed`); when none validates, the runs' own statistics: monte_carlo on a sampled design, the
        weighted runs on a grid of weights >= 0; a grid with signed weights has no statistics of its runs
        alone, so it keeps the expansion of lowest error, flagged by its own check (ValueError naming output
        `name` when there is none)."""
        taken, errors, band_outside = auto_choice(xi, weights, basis, scale, germs, order, sampled, missing, seed)
        record = {"chosen_by": "auto", "order": order, "errors": errors, "threshold": VALIDATION_THRESHOLD,
                  "band_beyond_runs": band_outside}
        if taken is not None:
            return taken, False, {**record, "kind": taken, "why": f"the lowest validated error, {errors[taken]:.3g}, "
                                                                 "its band within the runs' range"}
        why, own = "no expansion validates on these runs", Method.of_runs(sampled).kind
        if sampled or (np.asarray(weights) >= 0).all():
            return own, not sampled, {**record, "kind": own, "why": f"{why}: the runs' own statistics"
                                                                   + ("" if sampled else ", weighted by the grid")}
        if not [e for e in errors.values() if e is not None]:
            raise ValueError(f"method auto: for {name}, no candidate ({', '.join(AUTO_CANDIDATES)}) of order "
                             f"{order} can be applied to these runs, and a grid with negative weights gives no "
                             "statistics of its runs alone: run a sampled design, or choose a method and order")
        kind = min((e, i, k) for i, (k, e) in enumerate(errors.items()) if e is not None)[2]
        return kind, False, {**record, "kind": kind, "why": f"{why}, and a grid with negative weights has no "
                                                           "statistics of its runs alone: the expansion of lowest "
                                                           "error, flagged; run a sampled design"}

    def fit(self, xi, weights, Y, germs, order: int = DEFAULT_ORDER, x0=None, *, scale=None, sampled: bool = False,
            settings: dict | None = None) -> Result:
        """The fit of the kind it takes on these runs (`choose`)."""
        Y = as_runs_by_time(Y)
        kind, runs_only, _ = self.choose(xi, weights, Y, scale, germs, order, sampled)
        return METHODS[kind].fit(xi, weights, Y, germs, order, scale=scale, sampled=sampled or runs_only)
