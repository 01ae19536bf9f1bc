"""Designs: the points ξ_j in standard variables and their weights w_j, from a campaign's `design:`.

Kinds (keys in braces):
- monte_carlo {samples}; sobol {samples, scramble}; halton {samples, scramble};
  latin_hypercube {samples}: samples mapped to the germs, equal weights.
- sparse_grid {level, rule, nested, growth}: Smolyak combination technique on 1-D rules.
- tensor_grid {rule, points}: full tensor product.
- pick_freeze {samples}: Saltelli's [A; B; AB_1; …; AB_d] for Sobol' index estimators.
- morris {trajectories, levels}: Morris's trajectories for elementary-effects screening.
- adaptive_sparse_grid {rule, budget, tolerance}: Gerstner–Griebel's dimension-adaptive grid, built
  round by round from the results (`adaptive`; the runner refines it).
- subset_simulation {event, budget, samples_per_level, p0}, importance_sampling {event, budget, samples},
  active_learning {event, budget}: the probability of an event, the runs adapted to it round by round
  (`rare`; the runner replays the algorithm over the stored runs).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..parameters.germs import check_germs
from .adaptive import adaptive_design, adaptive_size
from .montecarlo import (halton_design, latin_hypercube_design, monte_carlo_design, samples_size, sobol_design,
                         sobol_size)
from .morris import NOT_DRAWS, morris_design, morris_screening, morris_size
from .pickfreeze import pick_freeze_design, pick_freeze_size
from .rare import active_learning_design, importance_sampling_design, rare_size, subset_simulation_design
from .smolyak import sparse_grid_design, sparse_grid_size
from .spec import is_integer
from .tensor import tensor_grid_design, tensor_grid_size


@dataclass(frozen=True)
class DesignKind:
    """A registered design: its builder (spec, germs, seed) -> (xi, weights, info); its size (spec,
    germs) -> the runs it builds, from the spec alone and without building anything (for the campaign's
    limits; a sparse grid's points before merging; None when the spec is malformed, so that the
    builder's own checks speak); `draws`: how its random points relate to independent draws
    (analysis.proportions), or None for a quadrature grid (its weights are valid only all together);
    `sobol_from_runs`: its runs give Sobol' indices themselves (pick-freeze estimators), without a PCE;
    `adaptive`: the builder gives the first round only; the runner adds the others from the results
    (designs.adaptive), up to `size` runs; `rare`: an adaptive design that estimates the probability of its
    `event` (designs.rare): its builder takes the `redrawn` columns (seed parameters), its runs are not draws
    of the input law (the analysis gives the event's probability only) and `uqflight.rare_rounds` runs it;
    `screening`: (xi, Y, ok, info, bootstrap, seed) -> (its measures per parameter, a note or None), the
    screening its runs give per output and quantity (designs.morris), stored under the kind's name;
    `not_draws`: the note of a design whose points are not draws of the law, so that the runs' own
    statistics are not the law's."""

    build: Callable
    size: Callable
    draws: str | None
    example: dict  # a small `design:` mapping of this kind (help text and tests)
    sobol_from_runs: bool = False
    adaptive: bool = False
    rare: bool = False
    screening: Callable | None = None
    not_draws: str | None = None

    @property
    def sampled(self) -> bool:
        """Random draws: moments are sample averages, valid on any subset of runs."""
        return self.draws is not None


REGISTRY: dict[str, DesignKind] = {
    "monte_carlo": DesignKind(monte_carlo_design, samples_size, "independent",
                              {"kind": "monte_carlo", "samples": 64}),
    "sobol": DesignKind(sobol_design, sobol_size, "net", {"kind": "sobol", "samples": 64}),
    "halton": DesignKind(halton_design, samples_size, "net", {"kind": "halton", "samples": 64}),
    "latin_hypercube": DesignKind(latin_hypercube_design, samples_size, "stratified",
                                  {"kind": "latin_hypercube", "samples": 64}),
    "sparse_grid": DesignKind(sparse_grid_design, sparse_grid_size, None, {"kind": "sparse_grid", "level": 2}),
    "tensor_grid": DesignKind(tensor_grid_design, tensor_grid_size, None, {"kind": "tensor_grid", "points": 4}),
    "pick_freeze": DesignKind(pick_freeze_design, pick_freeze_size, "pick_freeze",
                              {"kind": "pick_freeze", "samples": 16}, sobol_from_runs=True),
    "morris": DesignKind(morris_design, morris_size, "points", {"kind": "morris", "trajectories": 4},
                         screening=morris_screening, not_draws=NOT_DRAWS),
    "adaptive_sparse_grid": DesignKind(adaptive_design, adaptive_size, None,
                                       {"kind": "adaptive_sparse_grid", "budget": 50, "tolerance": 1e-4},
                                       adaptive=True),
    "subset_simulation": DesignKind(subset_simulation_design, rare_size, None,
                                    {"kind": "subset_simulation", "event": {"of": "y", "above": 3.0},
                                     "samples_per_level": 100, "p0": 0.1, "budget": 1000}, adaptive=True, rare=True),
    "importance_sampling": DesignKind(importance_sampling_design, rare_size, None,
                                      {"kind": "importance_sampling", "event": {"of": "y", "above": 3.0},
                                       "samples": 100, "budget": 1000}, adaptive=True, rare=True),
    "active_learning": DesignKind(active_learning_design, rare_size, None,
                                  {"kind": "active_learning", "event": {"of": "y", "above": 3.0}, "budget": 500},
                                  adaptive=True, rare=True),
}
DESIGN_KINDS = tuple(REGISTRY)
SAMPLED_DESIGNS = tuple(kind for kind, entry in REGISTRY.items() if entry.sampled)


def is_adaptive(kind: str) -> bool:
    """Whether the design kind grows round by round from the results (see DesignKind)."""
    return REGISTRY[kind].adaptive


def is_rare(kind: str) -> bool:
    """Whether the design kind estimates the probability of its event (see DesignKind)."""
    return REGISTRY[kind].rare


def is_sampled(kind: str) -> bool:
    """Whether the design kind draws random points (see DesignKind)."""
    return REGISTRY[kind].sampled


@dataclass
class Design:
    """Where to run the model and how to weigh each run."""

    kind: str
    xi: np.ndarray  # (N, d) standard variables, in the order the runs are made
    weights: np.ndarray  # (N,), summing to 1 for the input distribution; may be negative
    info: dict = field(default_factory=dict)  # facts for people: level, rule, degree, n_base, ...


def design_size(spec: dict, germs: list[str]) -> float | None:
    """The runs the design `spec` builds, from its registry entry (see DesignKind.size); None for a spec
    whose kind or keys the builder will refuse. Raises ValueError ("design.KEY: ...") beyond a kind's limit."""
    kind = spec.get("kind") if isinstance(spec, dict) else None
    if not isinstance(kind, str) or kind not in REGISTRY:
        return None
    return REGISTRY[kind].size(spec, germs)


def build_design(spec: dict, germs: list[str], seed: int, redrawn: tuple[int, ...] = ()) -> Design:
    """The design a campaign's `design:` mapping asks for, over the given germs; `redrawn`: the columns that
    are random-stream seeds (a rare-event design treats them apart, see designs.rare)."""
    if not isinstance(spec, dict):
        raise ValueError(f"design: expected a mapping with a kind key, got {spec!r}")
    kind = spec.get("kind")
    if not isinstance(kind, str) or kind not in REGISTRY:
        raise ValueError(f"design.kind: expected one of {', '.join(DESIGN_KINDS)}, got {kind!r}")
    if not is_integer(seed) or seed < 0:
        raise ValueError(f"seed: expected an integer >= 0, got {seed!r}")
    entry = REGISTRY[kind]
    extra = {"redrawn": tuple(redrawn)} if entry.rare else {}
    xi, weights, info = entry.build(spec, check_germs(germs), int(seed), **extra)
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
