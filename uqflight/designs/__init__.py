"""Designs: the points ξ_j in standard variables and their weights w_j, from a campaign's `design:`.

Each kind is a `DesignKind` subclass (designs.base) in its module, registered in REGISTRY by its name: montecarlo
(monte_carlo, sobol, halton, latin_hypercube), smolyak (sparse_grid), tensor (tensor_grid), pickfreeze
(pick_freeze), morris, adaptive (adaptive_sparse_grid), rare (subset_simulation, importance_sampling,
active_learning).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..parameters.germs import check_germs
# each module registers its kinds, in this order: that of the help and the key reference
from . import montecarlo, smolyak, tensor, pickfreeze, morris, adaptive, rare  # noqa: F401,I001
from .base import REGISTRY, DesignKind, is_integer
from ..text import FieldError

DESIGN_KINDS = tuple(REGISTRY)


@dataclass
class Design:
    """Where to run the model and how to weigh each run."""

    kind: str
    xi: np.ndarray  # (N, d) standard variables, in the order the runs are made
    weights: np.ndarray  # (N,), summing to 1 for the input distribution; may be negative
    info: dict = field(default_factory=dict)  # facts for people: level, rule, degree, n_base, ...


def design_size(spec: dict, germs: list[str]) -> float | None:
    """The runs the design `spec` builds, from its kind (see DesignKind.size); None for a spec
    whose kind or keys the builder will refuse. Raises ValueError ("design.KEY: ...") beyond a kind's limit."""
    kind = spec.get("kind") if isinstance(spec, dict) else None
    if not isinstance(kind, str) or kind not in REGISTRY:
        return None
    return REGISTRY[kind].size(spec, germs)


def build_design(spec: dict, germs: list[str], seed: int, redrawn: tuple[int, ...] = ()) -> Design:
    """The design a campaign's `design:` mapping asks for, over the given germs; `redrawn`: the columns that
    are random-stream seeds (a rare-event design treats them apart, see designs.rare)."""
    if not isinstance(spec, dict):
        raise FieldError("design", f"expected a mapping with a kind key, got {spec!r}")
    kind = spec.get("kind")
    if not isinstance(kind, str) or kind not in REGISTRY:
        raise FieldError("design.kind", f"expected one of {', '.join(DESIGN_KINDS)}, got {kind!r}")
    if not is_integer(seed) or seed < 0:
        raise FieldError("seed", f"expected an integer >= 0, got {seed!r}")
    xi, weights, info = REGISTRY[kind].build(spec, check_germs(germs), int(seed), tuple(redrawn))
    return Design(kind, xi, weights, info)


def describe(design: Design) -> str:
    """A few lines on the design for `uqflight plan`."""
    n, d = design.xi.shape
    lines = [f"{design.kind}: {n} points in {d} dimension{'s' if d > 1 else ''}"]
    lines += [f"  {key}: {value}" for key, value in design.info.items()]
    negative = int(np.count_nonzero(design.weights < 0))
    lines.append(
        f"  weights: sum {design.weights.sum():.12g}"
        + (f", {negative} negative" if negative else ", all positive")
    )
    return "\n".join(lines)
