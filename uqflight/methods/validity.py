"""Whether a method of a given order can be applied to a design's points, checked before anything runs.

* A projection (pseudo-Galerkin, and the PCE behind integration and interpolation on a grid) of total
  order p needs a grid exact to degree 2p: otherwise the discrete Gram matrix Σ w Ψ_α Ψ_β is not the
  identity and high-order coefficients alias into low ones (θ std 14.7° instead of 0.215° for order 4
  on the 15-point grid). Measured on the points (`exactness`), not taken from theory.
* A fit (regression, least squares) needs its design matrix to have rank Z on the actual points:
  N ≥ Z is not enough (3-D Gauss–Legendre level 2 has 25 points but rank 19 of 20 at order 3).
* A selection (sparse) needs at least 3 points; whether some basis it selects has a defined
  leave-one-out error is known only at the fit, which refuses otherwise.
* Grid weights are a quadrature only all together: a grid with failed or missing runs refuses the
  projections and the weighted sums; the fits are made on the runs that exist, after the rank check.

Each rule is its kind's `Method.points_problem`. `method_problem` returns the refusal as one sentence that names the order, what the points allow and
what to do, or None.
"""
from __future__ import annotations

import math

from .kind import Method

MAX_TERMS = 100_000  # PCE terms beyond which a fit is refused before any basis is built (campaign: limits.max_pce_terms)


def method_problem(kind: str, order: int, xi, weights, germs: list[str], sampled: bool,
                   missing: int = 0, allow_aliasing: bool = False) -> str | None:
    """Why method `kind` of total `order` cannot be applied to the points xi (N, d) with weights (the
    runs that exist), or None. `sampled`: the design draws random points. `missing`: the design's runs
    that are absent (failed or pending). `allow_aliasing` waives the projection's exactness rule."""
    method = Method.of(kind)
    d, n = len(germs), len(xi)
    if method.sampled_only and not sampled:
        return (f"{kind} needs a sampled design (Monte Carlo, QMC, pick-freeze); a grid needs its weights: "
                "use integration, pseudo_galerkin, interpolation, regression or least_squares")
    if not method.builds_pce(sampled):
        return None
    terms = math.comb(d + order, order)
    if terms > MAX_TERMS:
        return f"order {order} in {d} dimensions has {terms} PCE terms, more than the limit of {MAX_TERMS}"
    if missing and not sampled and not method.partial:
        return (f"{kind} needs every run of the grid (its weights are a quadrature only all together), but "
                f"{missing} of {n + missing} runs are missing; use least_squares or regression on the "
                "runs that exist, or rerun the campaign")
    return method.points_problem(order, xi, weights, germs, sampled, allow_aliasing)

