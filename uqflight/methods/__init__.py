"""Non-intrusive UQ methods (paper section 4): the registry every other part reads.

A method is one module plus one entry in METHODS, which says which designs it accepts, how its PCE
is built, the rule its points must satisfy before it runs, and how its mean and variance follow:

* ``monte_carlo``: sample mean and unbiased variance of the runs, no PCE; sampled designs only;
* ``integration``: weighted sums (Eq. 17); on a grid the PCE for bands, PDFs and Sobol' indices is the
  projection (Eq. 21);
* ``pseudo_galerkin``: projection (Eq. 21), split form (Eq. 24) with x0; moments from the PCE;
* ``interpolation``: moments from the weights (Eq. 32–34), PCE by projection (Eq. 41–42);
* ``regression``: V c = Y by least squares (Eq. 36), the weights ignored; moments from the PCE;
* ``least_squares``: weighted least squares (Eq. 44) with |w|; moments from the PCE.

Rules before anything runs (`validity.method_problem`): a projection of total order p needs a grid
exact to degree 2p; a fit needs a design matrix of full rank Z on the actual points.

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


# (what the statistics are, why) when runs failed; `failed_runs_note` fills in the counts.
FAILED_RUNS = {
    "conditional": ("statistics conditional on success",
                    "they are those of the {ok} successful runs alone, not of the whole input law"),
    "extrapolated": ("statistics of a fit extrapolated over the failed region",
                     "{kind} fits its PCE on the {ok} successful runs and its statistics are the PCE's over the "
                     "whole input law, including the region where the model has no value"),
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
                          split=True),
    "pseudo_galerkin": Method("PG", pseudo_galerkin, "pce", "projection", "projected", split=True),
    "interpolation": Method("interpolation", pseudo_galerkin, "weights", "projection", "projected", split=True),
    "regression": Method("regression", _regression, "pce", "fit", "extrapolated", partial=True),
    "least_squares": Method("least squares", _least_squares, "pce", "fit", "extrapolated", partial=True),
    "monte_carlo": Method("MC", None, "sample", None, "conditional", sampled_only=True, runs_on_sampled=True,
                          partial=True),
}
METHOD_KINDS = tuple(METHODS)


@dataclass
class Result:
    """Mean and variance per time (each (T,)), and the PCE when the method builds one."""

    mean: np.ndarray
    variance: np.ndarray
    pce: PCE | None


def fit(kind: str, xi, weights, Y, germs, order: int = 2, x0=None) -> Result:
    """Apply method ``kind`` to the runs Y (N, T) at points xi (N, d) with weights (N,).

    ``order`` is the total degree of the PCE; x0 ((T,) or (N, 1)) selects the split form of the
    projections (see galerkin). Moments follow the method's entry in METHODS.
    """
    from ..analysis.moments import as_runs_by_time, weighted_moments

    method = method_entry(kind)
    if x0 is not None and not method.split:
        split = " and ".join(k for k, m in METHODS.items() if m.split)
        raise ValueError(f"x0 (the split form x = x0 + S) applies to {split}; {kind!r} either builds no "
                         "PCE or fits the constant term itself, so the split would change nothing")
    Y = as_runs_by_time(Y)
    pce = method.pce(xi, weights, Y, germs, order, x0) if method.pce and method.moments != "sample" else None
    if method.moments == "pce":
        return Result(pce.mean(), pce.variance(), pce)
    mean, variance = weighted_moments(Y, None if method.moments == "sample" else weights,
                                      unbiased=method.moments == "sample")
    return Result(mean, variance, pce)


def method_entry(kind: str) -> Method:
    """The registry entry of `kind`; an unknown kind is a ValueError listing the kinds."""
    if kind not in METHODS:
        raise ValueError(f"unknown method kind {kind!r}: expected one of {', '.join(METHOD_KINDS)}")
    return METHODS[kind]


__all__ = ["FAILED_RUNS", "METHODS", "METHOD_KINDS", "PCE", "Method", "Result", "failed_runs_note", "fit",
           "method_entry"]
