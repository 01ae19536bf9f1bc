"""Dimension-adaptive sparse grids (Gerstner & Griebel 2003) on nested 1-D rules.

A multi-index j (one 1-D level j_k ≥ 0 per dimension) stands for the tensor difference rule
Δ_j = ⊗_k (U^{j_k} − U^{j_k − 1}), U^{−1} = 0, U^l the rule's l-th nested member (exponential growth:
Genz–Keister 1, 3, 9, 19, 43; Patterson 1, 3, 7, 15, …; Clenshaw–Curtis 1, 3, 5, 9, 17, …). The rule
of a downward-closed index set I is Σ_{j∈I} Δ_j: the combination technique with signed weights, exact
on Σ_{j∈I} ⊗_k P_{deg(j_k)}. Nested members make every Δ_j live on the nodes of U^{j}, so a refinement
flies only the new points.

The set is split into old indices (refined) and active ones (the maximal indices, not refined yet).
Each active j has an error indicator g_j: how much the mean and the variance (over time, of every
output and quantity) change when Δ_j is added, normalised like ε_m and ε_v (`analysis.errors`:
by the peak over time of the estimate with j). A step refines the active index with the largest g_j:
it becomes old and its forward neighbours j + e_k whose backward neighbours are all old become active.
It stops when η = Σ_active g_j ≤ tolerance ("tolerance"), when the next step's new points would take
the runs beyond the budget ("budget"), or when no index can be refined further ("levels": every
rule is at its last tabulated member).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import reduce

import numpy as np

from ..analysis.errors import relative_errors
from . import rules as rule_catalog
from .base import DesignKind, Key, count, number
from .smolyak import _indexed_nodes
from .spec import DesignSpec
from ..text import FieldError

ADAPTIVE_RULES = ("genz_keister", "gauss_patterson", "clenshaw_curtis")
MAX_LEVELS = 10  # 1-D levels of a rule without a tabulated end (Clenshaw–Curtis: up to 513 points)
STOP_REASONS = ("budget", "tolerance", "levels", "failed")  # failed: a run failed, the grid's rule is void


class Grid:
    """The nested 1-D rules of every dimension: node ids (equal for shared nodes), values and the
    difference weights w^l − w^{l−1} on the nodes of level l."""

    def __init__(self, rules: list[str]):
        self.rules = list(rules)
        self.ids, self.values, self.differences = [], [], []
        self._tensors = {}
        for rule in self.rules:
            top = rule_catalog.max_level(rule, "exponential") or MAX_LEVELS
            sizes = rule_catalog.level_sizes(rule, "exponential", min(top, MAX_LEVELS))
            members = [rule_catalog.nodes_weights(rule, size) for size in sizes]
            ids, values = _indexed_nodes([nodes for nodes, _ in members])
            differences = []
            for level, (_, weights) in enumerate(members):
                difference = np.zeros(len(values))
                difference[ids[level]] = weights
                if level:
                    difference[ids[level - 1]] -= members[level - 1][1]
                differences.append(difference[ids[level]])
            self.ids.append(ids)
            self.values.append(values)
            self.differences.append(differences)

    @property
    def levels(self) -> list[int]:
        """The 1-D levels each dimension has."""
        return [len(ids) for ids in self.ids]

    def tensor(self, index) -> tuple[np.ndarray, np.ndarray]:
        """Node ids (n, d) of the tensor grid of `index` (last dimension fastest) and Δ_index's weights (n,)."""
        if index not in self._tensors:
            self._tensors[index] = self._tensor(index)
        return self._tensors[index]

    def _tensor(self, index) -> tuple[np.ndarray, np.ndarray]:
        grids = np.meshgrid(*[self.ids[k][level] for k, level in enumerate(index)], indexing="ij")
        ids = np.stack([grid.ravel() for grid in grids], axis=1)
        weights = reduce(np.multiply.outer, [self.differences[k][level] for k, level in enumerate(index)])
        return ids, np.ravel(weights)

    def points(self, ids: np.ndarray) -> np.ndarray:
        """ξ (n, d) of node-id rows."""
        return np.column_stack([self.values[k][ids[:, k]] for k in range(len(self.rules))])


@dataclass
class IndexSet:
    """The adaptive state: indices in the order they were added, whether each is old (refined), the
    round that added it, its last indicator (NaN before its points ran), the rounds so far and why the
    refinement stopped ("" while it goes on)."""

    indices: list[tuple[int, ...]]
    old: list[bool]
    added: list[int]
    indicator: list[float]
    rounds: int = 0
    stopped: str = ""
    eta: float = float("nan")

    @classmethod
    def initial(cls, d: int) -> IndexSet:
        return cls([(0,) * d], [False], [0], [float("nan")])

    def active(self) -> list[int]:
        return [i for i, old in enumerate(self.old) if not old]


@dataclass
class Points:
    """The rows of a grid: node ids (N, d) in run order, ξ (N, d), and the row of each id tuple."""

    ids: np.ndarray
    xi: np.ndarray
    row: dict = field(default_factory=dict)
    differences: dict = field(default_factory=dict)  # index -> Δ_index's weights on the rows (N,)


def grid_points(grid: Grid, state: IndexSet) -> Points:
    """Every point of the set's tensor grids, in run order: round by round (the points an index of round r
    adds beyond the earlier rounds'), sorted by node ids within a round. A function of the state alone,
    so that a resumed campaign finds its rows where it left them."""
    row, order = {}, []
    for round_ in range(state.rounds + 1):
        new = set()
        for index, added in zip(state.indices, state.added):
            if added == round_:
                new.update(map(tuple, grid.tensor(index)[0].tolist()))
        for key in sorted(new - row.keys()):
            row[key] = len(order)
            order.append(key)
    ids = np.array(order, dtype=int).reshape(-1, len(grid.rules))
    return Points(ids, grid.points(ids), row)


def _rows(points: Points, ids: np.ndarray) -> np.ndarray:
    return np.array([points.row[tuple(key)] for key in ids.tolist()], dtype=int)


def difference_weights(grid: Grid, points: Points, index) -> np.ndarray:
    """Δ_index's weights on the rows (N,)."""
    if index not in points.differences:
        ids, weights = grid.tensor(index)
        out = np.zeros(len(points.ids))
        np.add.at(out, _rows(points, ids), weights)
        points.differences[index] = out
    return points.differences[index]


def combination_weights(grid: Grid, points: Points, indices) -> np.ndarray:
    """The weights (N,) of the rule Σ_{j ∈ indices} Δ_j on the rows: the combination technique's."""
    return sum((difference_weights(grid, points, index) for index in indices), np.zeros(len(points.ids)))


def indicators(grid: Grid, state: IndexSet, points: Points, values: list[np.ndarray]) -> dict[int, float]:
    """g_j of every active index j: max over the `values` (each (N, T): an output's histories or a
    quantity as (N, 1)) and their times of ε_m and ε_v between the rules of I and I ∖ {j}, normalised by
    the peak over time of I's mean and variance. The runs are centred on the first row (the centre point)
    so that E[Y²] − E[Y]² does not cancel a large mean (I ∖ {j} is empty, its weights summing to 0, only
    for the centre index itself)."""
    full = combination_weights(grid, points, state.indices)
    found = {}
    for i in state.active():
        without = full - difference_weights(grid, points, state.indices[i])
        worst = 0.0
        for Y in values:
            Y = np.asarray(Y, dtype=float).reshape(len(full), -1)
            centred = Y - Y[0]
            moments = []
            for weights in (full, without):  # E[Y] and E[Y²] − E[Y]² of the rule, whose weights sum to 1 or 0
                total, mean = weights.sum(), weights @ centred
                moments.append((mean + total * Y[0], weights @ centred**2 - mean**2
                                + (total - total**2) * Y[0]**2 + 2 * (1 - total) * Y[0] * mean))
            (mean_i, var_i), (mean_o, var_o) = moments
            eps_m, eps_v = relative_errors(mean_o, var_o, mean_i, var_i)
            worst = max(worst, float(np.max(eps_m)), float(np.max(eps_v)))
        found[i] = worst
    return found


def _admissible(state: IndexSet, candidate: tuple[int, ...]) -> bool:
    """Every backward neighbour of `candidate` is old (and it is not in the set yet)."""
    old = {index for index, is_old in zip(state.indices, state.old) if is_old}
    if candidate in state.indices:
        return False
    for k, level in enumerate(candidate):
        if level and candidate[:k] + (level - 1,) + candidate[k + 1:] not in old:
            return False
    return True


def refine(grid: Grid, state: IndexSet, points: Points, values: list[np.ndarray], budget: int,
           tolerance: float) -> IndexSet:
    """The next state once every run of `points` is done (`values` their results, see `indicators`):
    the same set with a stop reason, or the set with its largest indicator refined (one round). Indices
    refined without admissible neighbours are refined in the same round (no runs needed)."""
    state = IndexSet(list(state.indices), list(state.old), list(state.added), list(state.indicator),
                     state.rounds, state.stopped, state.eta)
    while True:
        found = indicators(grid, state, points, values)
        for i, value in found.items():
            state.indicator[i] = value
        if not found:
            state.stopped = "levels"
            return state
        state.eta = float(sum(found.values()))
        if state.eta <= tolerance:
            state.stopped = "tolerance"
            return state
        best = max(found, key=lambda i: (found[i], -i))  # the largest; the earliest added on a tie
        chosen = state.indices[best]
        state.old[best] = True
        forward = [chosen[:k] + (chosen[k] + 1,) + chosen[k + 1:] for k in range(len(chosen))
                   if chosen[k] + 1 < grid.levels[k]]
        new_indices = [candidate for candidate in forward if _admissible(state, candidate)]
        if not new_indices:
            continue
        new_points = set()
        for index in new_indices:
            new_points.update(key for key in map(tuple, grid.tensor(index)[0].tolist()) if key not in points.row)
        if len(points.ids) + len(new_points) > budget:
            state.old[best] = False
            state.stopped = "budget"
            return state
        state.rounds += 1
        for index in new_indices:
            state.indices.append(index)
            state.old.append(False)
            state.added.append(state.rounds)
            state.indicator.append(float("nan"))
        return state


def adaptive_grid(spec: DesignSpec, germs: list[str]) -> Grid:
    """The grid of an `adaptive_sparse_grid` spec over `germs`: the nested rule of every dimension from its
    `rule` (a name, a mapping germ -> name, or None for each germ's nested rule); FieldError naming
    design.rule when they are not nested."""
    rules = rule_catalog.rules_by_dimension(spec["rule"], germs, nested=None if spec["rule"] else True)
    plain = [rule for rule in rules if rule not in ADAPTIVE_RULES]
    if plain:
        raise FieldError("design.rule", f"an adaptive grid needs nested rules ({', '.join(ADAPTIVE_RULES)}), "
                         f"got {plain[0]}")
    return Grid(rules)


class AdaptiveSparseGrid(DesignKind):
    """`adaptive_sparse_grid` {rule, budget, tolerance}: round 0, the centre point; the rounds that follow
    are made by the runner from the results (`execution`); seed unused.

    Examples
    --------
    >>> from uqflight.designs import build_design, design_size
    >>> spec = {"kind": "adaptive_sparse_grid", "budget": 50, "tolerance": 1e-4}
    >>> design = build_design(spec, ["normal", "normal", "uniform"], seed=0)
    >>> design.xi.tolist(), design.weights.tolist()  # round 0: the centre point alone, weight 1
    ([[0.0, 0.0, 0.0]], [1.0])
    >>> design.info["rule"], design_size(spec, ["normal"] * 3)  # nested rules; the budget
    ('genz_keister, gauss_patterson', 50)
    """

    kind = "adaptive_sparse_grid"
    keys = {"rule": Key(description="The 1-D rule (`design.rule`) for every dimension, or a mapping germ -> rule; "
                                     "nested rules only. Default: each germ's nested rule (Genz–Keister for normal "
                                     "inputs, Patterson for uniform ones)."),
            "budget": count(1, description="Required: the most runs; the refinement stops before a round would "
                                           "pass it (stopped: budget). `budget: 300`"),
            "tolerance": number("a number >= 0", lambda v: 0 <= v < float("inf"),
                                description="Required: stop when the sum of the active indices' indicators (change "
                                            "of mean and variance, normalised like ε_m and ε_v) is at most this "
                                            "(stopped: tolerance). `tolerance: 1e-5`")}
    example = {"kind": "adaptive_sparse_grid", "budget": 50, "tolerance": 1e-4}
    sampling = None
    adaptive = True

    def size(self, spec, germs):
        """At most `budget` (a refinement that would pass it is not made)."""
        return spec["budget"]

    def points(self, spec, germs, seed):
        grid = adaptive_grid(spec, germs)
        points = grid_points(grid, IndexSet.initial(len(germs)))
        info = {"rule": rule_catalog.rule_names(grid.rules), "budget": spec["budget"],
                "tolerance": float(spec["tolerance"]), "rounds": "refined from the results, up to the budget"}
        return points.xi, np.ones(1), info


def index_set_summary(state: IndexSet, parameter_names: list[str]) -> dict:
    """The refinement for people and summary.json: rounds, why it stopped, η, the highest 1-D level
    reached per parameter, and every index with its state, round and last indicator (None before its
    points ran)."""
    levels = np.array(state.indices, dtype=int).reshape(-1, len(parameter_names))
    return {"rounds": state.rounds, "stopped": state.stopped or None,
            "eta": None if np.isnan(state.eta) else state.eta,
            "max_level": dict(zip(parameter_names, levels.max(axis=0).tolist())),
            "indices": levels.tolist(), "old": list(state.old), "round": list(state.added),
            "indicator": [None if np.isnan(value) else value for value in state.indicator]}
