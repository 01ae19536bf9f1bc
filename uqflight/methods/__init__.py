"""Non-intrusive UQ methods (paper section 4): the registry every other part reads.

A method is one module plus one entry in METHODS, which says which designs it accepts, how its PCE
is built, the rule its points must satisfy before it runs, and how its mean and variance follow:

* ``monte_carlo``: sample mean and unbiased variance of the runs, no PCE; sampled designs only;
* ``integration``: weighted sums (Eq. 17); on a grid the PCE for bands, PDFs and Sobol' indices is the
  projection (Eq. 21);
* ``pseudo_galerkin``: projection (Eq. 21), split form (Eq. 24) with x0; moments from the PCE;
* ``interpolation``: moments from the weights (Eq. 32–34), PCE by projection (Eq. 41–42);
* ``regression``: V c = Y by least squares (Eq. 36), the weights ignored; moments from the PCE;
* ``least_squares``: weighted least squares (Eq. 44) with |w|; moments from the PCE;
* ``sparse``: LARS or OMP over q-hyperbolic candidates up to max_order, the basis and order chosen by the
  corrected leave-one-out error (`sparse`); one basis per output for all times; moments from the PCE;
* ``auto``: per output, among the methods the design allows (AUTO_CANDIDATES), the one with the lowest
  validated error (`validation`), or the runs' own statistics when none validates.

Rules before anything runs (`validity.method_problem`): a projection of total order p needs a grid
exact to degree 2p; a fit needs a design matrix of full rank Z on the actual points; a selection (sparse)
needs only a candidate set within the term limit, and refuses at the fit when no basis has a defined
leave-one-out error.

What the statistics are when runs failed (`Method.failed_runs`, the sentence in `FAILED_RUNS`) is a
fact of the method, said once here for every note and report: the statistics of the successful runs
(conditional on success), a fit extrapolated over the failed region, or a projection of the successful
runs, which is of neither law. A grid with failed runs accepts only the fits (`validity`).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from .collocation import least_squares, regression
from .galerkin import pseudo_galerkin
from .pce import PCE
from .sparse import settings_problem, sparse_pce


@dataclass(frozen=True)
class Method:
    """One registered method.

    label: its name in the paper's legends. pce: how its PCE is built from (xi, weights, Y, germs,
    order, x0) -> PCE, or None (no PCE). moments: "sample" (sample moments of the runs, unbiased),
    "weights" (weighted sums of the runs) or "pce" (the expansion's). sampled_only: refuses grids.
    runs_on_sampled: on a sampled design its statistics are those of the runs themselves (no PCE).
    rule: "projection" (needs exactness 2p), "fit" (needs rank Z) or None. split: accepts x0.
    failed_runs: what its statistics are when runs failed, on the designs that accept it (a key of
    FAILED_RUNS). partial: valid on a subset of a design's runs (failed or pending runs left out).
    weighted: its fit (and the rank check and leave-one-out error of a fit) weighs the runs by |w|;
    False: the points alone. linear: linear in the runs, so applied to tSVD factors V and multiplied
    by diag(s) Uᵀ after; False: it is given the factors. exported_as: the kinds whose PCE a surrogate
    (export, calibration) carries on a sampled design and on a grid; None: its own PCE. settings: its
    own keys of `method:` beyond kind and order, with their defaults, passed to its `pce` by name.
    order_key: the `method:` key of its order (sparse: max_order, the largest candidate order).
    settings_problem: (method mapping) -> (key, why) of a bad setting, or None.
    """

    label: str
    pce: Callable | None
    moments: str
    rule: str | None
    failed_runs: str
    sampled_only: bool = False
    runs_on_sampled: bool = False
    split: bool = False
    partial: bool = False
    weighted: bool = True
    linear: bool = True
    exported_as: tuple[str, str] | None = None
    settings: tuple[tuple[str, object], ...] = ()
    order_key: str = "order"
    settings_problem: Callable | None = None


# (what the statistics are, why) when runs failed; `failed_runs_note` fills in the counts.
FAILED_RUNS = {
    "conditional": ("statistics conditional on success",
                    "they are those of the {ok} successful runs alone, not of the whole input law"),
    "extrapolated": ("statistics of a fit extrapolated over the failed region",
                     "{kind} fits its PCE on the {ok} successful runs and its statistics are the PCE's over the "
                     "whole input law, including the region where the model has no value"),
    "chosen": ("statistics of the method chosen per output",
               "auto chose among the methods the {ok} successful runs allow: a fit extrapolates over the failed "
               "region, the runs' own statistics are conditional on success (each output says which it took)"),
    "projected": ("statistics of a projection of the successful runs, of neither law",
                  "{kind} projects the {ok} successful runs alone: its mean is the mean conditional on success, "
                  "but its PCE (the bands, PDFs and Sobol' indices, and pseudo_galerkin's variance) is that of "
                  "the output divided by the success rate where runs succeeded and 0 where they failed; use "
                  "monte_carlo for statistics conditional on success or least_squares for a fit"),
}


def failed_runs_note(kind: str, failed: int, done: int) -> str:
    """The note that says what `kind`'s statistics are when `failed` of the `done` runs failed."""
    headline, why = FAILED_RUNS[method_entry(kind).failed_runs]
    return f"{headline}: {failed} of {done} runs failed; {why.format(ok=done - failed, kind=kind)}"


def _regression(xi, weights, Y, germs, order, x0=None) -> PCE:
    return regression(xi, Y, germs, order)


def _least_squares(xi, weights, Y, germs, order, x0=None) -> PCE:
    return least_squares(xi, weights, Y, germs, order)


METHODS: dict[str, Method] = {
    "integration": Method("Int", pseudo_galerkin, "weights", "projection", "conditional", runs_on_sampled=True,
                          split=True, exported_as=("least_squares", "pseudo_galerkin")),
    "pseudo_galerkin": Method("PG", pseudo_galerkin, "pce", "projection", "projected", split=True),
    "interpolation": Method("interpolation", pseudo_galerkin, "weights", "projection", "projected", split=True,
                            exported_as=("pseudo_galerkin", "pseudo_galerkin")),
    "regression": Method("regression", _regression, "pce", "fit", "extrapolated", partial=True, weighted=False),
    "least_squares": Method("least squares", _least_squares, "pce", "fit", "extrapolated", partial=True),
    "monte_carlo": Method("MC", None, "sample", None, "conditional", sampled_only=True, runs_on_sampled=True,
                          partial=True, weighted=False, exported_as=("least_squares", "pseudo_galerkin")),
    "sparse": Method("sparse", sparse_pce, "pce", "selection", "extrapolated", partial=True, weighted=False,
                     linear=False, settings=(("selection", "lars"), ("q", 1.0)), order_key="max_order",
                     settings_problem=settings_problem),
    # per output, the method of AUTO_CANDIDATES with the lowest validated error (statistics.auto_method)
    "auto": Method("auto", None, "pce", None, "chosen", partial=True, weighted=False,
                   exported_as=("least_squares", "pseudo_galerkin")),
}
# what `auto` chooses among, in this order of preference at equal error; the runs' own statistics
# (monte_carlo on a sampled design, integration's weighted runs on a grid of weights >= 0) when none validates
AUTO_CANDIDATES = ("pseudo_galerkin", "least_squares", "sparse")
METHOD_KINDS = tuple(METHODS)


@dataclass
class Result:
    """Mean and variance per time (each (T,)), and the PCE when the method builds one (None: the
    statistics are those of the runs themselves, `from_runs`)."""

    mean: np.ndarray
    variance: np.ndarray
    pce: PCE | None

    @property
    def from_runs(self) -> bool:
        return self.pce is None


def fit(kind: str, xi, weights, Y, germs, order: int = 2, x0=None, *, scale=None, sampled: bool = False,
        settings: dict | None = None) -> Result:
    """Apply method ``kind`` to the runs Y = rows @ scale at points xi (N, d) with weights (N,): the one
    dispatch the statistics, the surrogate export and the calibration use.

    Y: the runs (N, T), or with ``scale`` (r, T) the rows (N, r) of tSVD factors (a linear method is
    applied to them and its coefficients multiplied by scale). ``order`` is the PCE's total degree;
    x0 ((T,) or (N, 1)) selects the split form of the projections (see galerkin). ``sampled``: the
    points are random draws, where a method that `runs_on_sampled` gives the runs' own moments.
    ``settings``: the method's other keys (its entry's). Moments follow the method's entry in METHODS.
    """
    from ..analysis.moments import as_runs_by_time, weighted_moments

    method = method_entry(kind)
    if kind == "auto":  # the candidate that validates on these runs, or the runs' own moments (validation)
        from .validation import auto_choice

        Y = as_runs_by_time(Y)
        taken = auto_choice(xi, weights, Y, scale, germs, order, sampled)[0]
        fallback = "monte_carlo" if sampled else "integration"
        return fit(taken or fallback, xi, weights, Y, germs, order, scale=scale, sampled=sampled or taken is None,
                   settings=method_settings({"kind": taken}) if taken else None)
    if x0 is not None and not method.split:
        split = " and ".join(k for k, m in METHODS.items() if m.split)
        raise ValueError(f"x0 (the split form x = x0 + S) applies to {split}; {kind!r} either builds no "
                         "PCE or fits the constant term itself, so the split would change nothing")
    Y = as_runs_by_time(Y)
    if method.pce is None or (sampled and method.runs_on_sampled):
        sample = method.moments == "sample"
        mean, variance = weighted_moments(Y, None if sample else weights, scale, unbiased=sample)
        return Result(mean, variance, None)
    if method.linear:
        fitted = method.pce(xi, weights, Y, germs, order, x0)
        pce = fitted if scale is None else PCE(fitted.germs, fitted.indices, fitted.coefficients @ scale)
    else:
        pce = method.pce(xi, weights, Y, germs, order, x0, scale=scale, **(settings or {}))
    if method.moments == "weights":  # quadrature moments; the PCE serves bands, PDFs, Sobol'
        mean, variance = weighted_moments(Y, weights, scale)
    else:
        mean, variance = pce.mean(), pce.variance()
    return Result(mean, variance, pce)


def exported_kind(kind: str, sampled: bool) -> str:
    """The kind whose PCE a surrogate of method `kind` carries (its entry's `exported_as`); a kind that
    needs a sampled design stays itself on a grid, for the analysis to refuse (never another method
    in its place)."""
    entry = method_entry(kind)
    if entry.exported_as is None or (entry.sampled_only and not sampled):
        return kind
    return entry.exported_as[0 if sampled else 1]


def method_settings(method: dict) -> dict:
    """The settings of a `method:` mapping its kind takes (its entry's `settings`), defaults filled in."""
    return {key: method.get(key, default) for key, default in method_entry(method["kind"]).settings}


def normalised(method: dict) -> dict:
    """A `method:` mapping with its kind's order key (its entry's `order_key`) as "order"."""
    key = method_entry(method["kind"]).order_key if method.get("kind") in METHODS else "order"
    if key == "order" or key not in method:
        return dict(method)
    method = dict(method)
    method["order"] = method.pop(key)
    return method


def method_entry(kind: str) -> Method:
    """The registry entry of `kind`; an unknown kind is a ValueError listing the kinds."""
    if kind not in METHODS:
        raise ValueError(f"unknown method kind {kind!r}: expected one of {', '.join(METHOD_KINDS)}")
    return METHODS[kind]


__all__ = ["AUTO_CANDIDATES", "FAILED_RUNS", "METHODS", "METHOD_KINDS", "PCE", "Method", "Result", "exported_kind",
           "failed_runs_note", "fit", "method_entry"]
