"""Designs: the points ξ_j in standard variables and their weights w_j, from a campaign's `design:`.

Each kind is a `DesignKind` subclass (designs.base) in its module, registered in REGISTRY by its name: montecarlo
(monte_carlo, sobol, halton, latin_hypercube), smolyak (sparse_grid), tensor (tensor_grid), pickfreeze
(pick_freeze), morris, adaptive (adaptive_sparse_grid), rare (subset_simulation, importance_sampling,
active_learning). A `design:` mapping is checked once into a `DesignSpec` (designs.spec), which builds the `Design`.
"""
from __future__ import annotations

import numpy as np

# each module registers its kinds, in this order: that of the help and the key reference
from . import montecarlo, smolyak, tensor, pickfreeze, morris, adaptive, rare  # noqa: F401,I001
from .base import REGISTRY, DesignKind
from .spec import Design, DesignSpec

DESIGN_KINDS = tuple(REGISTRY)


def design_size(spec: dict, germs: list[str]) -> float:
    """The runs the `design:` mapping `spec` builds over `germs`, from the spec alone: the mapping checked once
    (DesignSpec.checked), then its `DesignSpec.size` (see there)."""
    return DesignSpec.checked(spec).size(germs)


def build_design(spec: dict, germs: list[str], seed: int, redrawn: tuple[int, ...] = ()) -> Design:
    """The design a campaign's `design:` mapping asks for: the mapping checked once (DesignSpec.checked), then
    its `DesignSpec.build` (see there for the arguments, the result and the refusals)."""
    return DesignSpec.checked(spec).build(germs, seed, redrawn)


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
