"""Smolyak sparse grids by the combination technique on 1-D rules (nested or not).

With q = d + level and 1-D level indices i ≥ 1,

    A(q, d) = Σ_{q−d+1 ≤ |i| ≤ q} (−1)^{q−|i|} C(d−1, q−|i|) U^{i_1} ⊗ … ⊗ U^{i_d}.

Level 0 is the single centre point; non-nested Gauss–Hermite with linear growth gives 15, 113, 589
and 2437 points in 7 dimensions at levels 1–4 (the paper's grids). Points whose weights happen to
cancel are kept: they belong to the grid, and interpolation or regression on it can use them.
"""
from __future__ import annotations

from functools import reduce
from itertools import combinations
from math import comb

import numpy as np

from . import rules as rule_catalog
from .base import DesignKind, Key, choice, count, flag
from ..text import FieldError

MERGE_TOLERANCE = 1e-12  # relative: 1-D nodes closer than this are one point
MAX_LEVEL = 1000  # levels beyond this are refused before any size is estimated


def tensor_product(node_sets, weight_sets) -> tuple[np.ndarray, np.ndarray]:
    """All combinations of the 1-D nodes (rows, last dimension fastest) and their weight products."""
    grids = np.meshgrid(*node_sets, indexing="ij")
    points = np.stack([grid.ravel() for grid in grids], axis=1)
    weights = reduce(np.multiply.outer, weight_sets).ravel()
    return points, weights


def multi_indices(d: int, level: int) -> np.ndarray:
    """Rows j = i − 1 ≥ 0 of the combination technique: max(0, level − d + 1) ≤ |j| ≤ level."""
    rows = []
    for total in range(max(0, level - d + 1), level + 1):
        # Stars and bars: d − 1 bar positions among total + d − 1 slots.
        bars = list(combinations(range(total + d - 1), d - 1))
        edges = np.empty((len(bars), d + 1), dtype=int)
        edges[:, 0], edges[:, -1] = -1, total + d - 1
        edges[:, 1:-1] = np.array(bars, dtype=int).reshape(len(bars), d - 1)
        rows.append(np.diff(edges, axis=1) - 1)
    return np.concatenate(rows)


def _indexed_nodes(node_sets) -> tuple[list[np.ndarray], np.ndarray]:
    """Integer ids for the nodes of several 1-D rules, equal for nodes within MERGE_TOLERANCE,
    and the value of each id; ids keep the merging of grid points exact."""
    nodes = np.concatenate(node_sets)
    order = np.argsort(nodes, kind="stable")
    ordered = nodes[order]
    starts_group = np.ones(len(nodes), dtype=bool)
    starts_group[1:] = np.diff(ordered) > MERGE_TOLERANCE * np.maximum(1.0, np.abs(ordered[1:]))
    ids = np.empty(len(nodes), dtype=int)
    ids[order] = np.cumsum(starts_group) - 1
    sizes = [len(node_set) for node_set in node_sets]
    return np.split(ids, np.cumsum(sizes)[:-1]), ordered[starts_group]


def smolyak_rule(sequences, level: int) -> tuple[np.ndarray, np.ndarray]:
    """Points (N, d) and weights (N,) of the Smolyak rule.

    sequences[k][j] = (nodes, weights) of dimension k's rule at 1-D level j + 1, j = 0..level.
    A point shared by several tensor rules appears once with the sum of their weights, which may
    be negative. Rows are sorted lexicographically by coordinate.
    """
    d = len(sequences)
    indexed = [_indexed_nodes([nodes for nodes, _ in sequence]) for sequence in sequences]
    all_ids, all_weights = [], []
    for j in multi_indices(d, level):
        excess = level - int(j.sum())
        ids, weights = tensor_product(
            [indexed[k][0][j[k]] for k in range(d)], [sequences[k][j[k]][1] for k in range(d)]
        )
        all_ids.append(ids)
        all_weights.append((-1) ** excess * comb(d - 1, excess) * weights)
    unique_ids, inverse = np.unique(np.concatenate(all_ids), axis=0, return_inverse=True)
    weights = np.bincount(inverse.reshape(-1), weights=np.concatenate(all_weights))
    points = np.column_stack([indexed[k][1][unique_ids[:, k]] for k in range(d)])
    return points, weights


def smolyak_degree(degrees, level: int) -> int:
    """The largest D such that the rule integrates every monomial of total degree ≤ D exactly.

    degrees[k][j]: exactness degree of dimension k's 1-D rule at level j + 1 (increasing in j).
    The Smolyak rule is exact on Σ_{|j| ≤ level} ⊗_k P_{degrees[k][j_k]} (Novak & Ritter 1996), and
    on symmetric grids every monomial with an odd power integrates to 0 exactly, so only even powers
    α matter: ξ^α is covered when Σ_k min{j : degrees[k][j] ≥ α_k} ≤ level. D + 1 is the first even
    total degree with an uncovered α, found by a max-plus convolution over the dimensions.
    """
    top = min(int(sequence[-1]) for sequence in degrees) + 1  # ξ_k^top is beyond every level
    evens = np.arange(0, top + 1, 2)
    worst = np.full(len(evens), -np.inf)
    worst[0] = 0.0
    for sequence in degrees:
        cost = np.searchsorted(np.asarray(sequence), evens).astype(float)
        worst = np.array([np.max(worst[: e + 1][::-1] + cost[: e + 1]) for e in range(len(evens))])
    return int(evens[np.argmax(worst > level)]) - 1


class SparseGrid(DesignKind):
    """`sparse_grid` {level, rule, nested, growth (default linear)}; deterministic, seed unused.

    With linear growth every rule's level L is exact to total degree >= 2L + 1, so nested and
    non-nested grids of one level compare at equal accuracy (the nested one has fewer points
    from level 2 on).

    Examples
    --------
    >>> from uqflight.designs import build_design, design_size
    >>> spec = {"kind": "sparse_grid", "level": 2}  # normal germs: Gauss-Hermite, linear growth
    >>> design = build_design(spec, ["normal"] * 7, seed=0)
    >>> len(design.xi), design.info["degree"], round(float(design.weights.sum()), 12)
    (113, 5, 1.0)
    >>> design_size(spec, ["normal"] * 7)  # before merging: the centre is in 8 tensor rules
    120.0
    >>> round(float(design.weights @ (design.xi[:, 0] ** 2 * design.xi[:, 1] ** 2)), 12)  # E[ξ1² ξ2²] = 1
    1.0
    """

    kind = "sparse_grid"
    keys = {"level": count(0, description=f"Sparse-grid level, 0-{MAX_LEVEL}. `level: 2`"),
            "rule": Key(description=rule_catalog.RULE),
            "nested": flag(None, "True swaps each default rule for its germ's nested one (Hermite -> Genz–Keister, "
                                 "Legendre -> Patterson); false refuses nested rules. Default: the rules as named. "
                                 "`nested: true`"),
            "growth": choice(rule_catalog.GROWTHS, "linear", "`linear` (default; level i exact to degree 2i−1) or "
                                                             "`exponential` (the rules' own nested sequences).")}
    example = {"kind": "sparse_grid", "level": 2}
    sampling = None

    def size(self, spec, germs):
        """The points the combination technique builds before merging the tensor rules' shared points
        (an upper bound on the runs, and the size of the arrays built), computed without building anything:
        Σ over the multi-indices of Π_k size_k(j_k), a polynomial product over the dimensions. Refuses a
        level beyond MAX_LEVEL, the rules that do not fit the germs and a level beyond a rule's end."""
        level = spec["level"]
        if level > MAX_LEVEL:
            raise FieldError("design.level", f"expected at most {MAX_LEVEL}, got {level}")
        rules = rule_catalog.rules_by_dimension(spec["rule"], germs, spec["nested"])
        sizes = self._sizes(rules, spec["growth"], level)
        # coefficient s of the product polynomial = the points of all tensor rules with |j| = s
        total = np.array([1.0])
        for rule in rules:
            total = np.convolve(total, np.array(sizes[rule], dtype=float))[: level + 1]
        return float(total[max(0, level - len(germs) + 1): level + 1].sum())

    @staticmethod
    def _sizes(rules: list[str], growth: str, level: int) -> dict:
        """{rule: its 1-D sizes at levels 1 … level + 1}; ValueError naming design.level beyond a rule's end."""
        sizes = {}
        for rule in dict.fromkeys(rules):
            top = rule_catalog.max_level(rule, growth)
            if top is not None and level + 1 > top:
                raise FieldError("design.level", f"rule {rule} with {growth} growth reaches level {top - 1} at most, "
                                 f"got {level}")
            sizes[rule] = rule_catalog.level_sizes(rule, growth, level + 1)
        return sizes

    def points(self, spec, germs, seed):
        level, growth = spec["level"], spec["growth"]
        rules = rule_catalog.rules_by_dimension(spec["rule"], germs, spec["nested"])
        sizes = self._sizes(rules, growth, level)
        one_dimensional = {rule: [rule_catalog.nodes_weights(rule, size) for size in sizes[rule]] for rule in sizes}
        points, weights = smolyak_rule([one_dimensional[rule] for rule in rules], level)
        degree = smolyak_degree([[rule_catalog.degree(rule, size) for size in sizes[rule]] for rule in rules], level)
        info = {"level": level, "rule": rule_catalog.rule_names(rules),
                "nested": all(rule in rule_catalog.NESTED_RULES for rule in rules), "growth": growth,
                "points_per_level": "; ".join(f"{rule}: {', '.join(map(str, counts))}" for rule, counts in sizes.items()),
                "degree": degree}
        return points, weights, info
