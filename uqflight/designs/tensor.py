"""Full tensor-product grids of 1-D rules."""
from __future__ import annotations

from functools import reduce

import numpy as np

from . import rules as rule_catalog
from .spec import check_keys, given_count, integer


def tensor_product(node_sets, weight_sets) -> tuple[np.ndarray, np.ndarray]:
    """All combinations of the 1-D nodes (rows, last dimension fastest) and their weight products."""
    grids = np.meshgrid(*node_sets, indexing="ij")
    points = np.stack([grid.ravel() for grid in grids], axis=1)
    weights = reduce(np.multiply.outer, weight_sets).ravel()
    return points, weights


def tensor_grid_size(spec: dict, germs: list[str]) -> float | None:
    """Runs of `tensor_grid`: points^d (a float: it may be far beyond any integer a run could reach)."""
    n = given_count(spec, "points")
    return None if n is None else float(n) ** len(germs)


def tensor_grid_design(spec: dict, germs: list[str], seed: int):
    """`tensor_grid` {rule, points}: the same number of points in every dimension; seed unused."""
    check_keys(spec, "tensor_grid", ("rule", "points"))
    size = integer(spec, "points", "tensor_grid", minimum=1)
    rules = rule_catalog.rules_by_dimension(spec.get("rule"), germs, nested=None)
    for rule in dict.fromkeys(rules):
        sizes = rule_catalog.allowed_sizes(rule)
        if sizes is not None and size not in sizes:
            raise ValueError(
                f"design.points: rule {rule} comes in {', '.join(map(str, sizes))} points, got {size}"
            )
    one_dimensional = {rule: rule_catalog.nodes_weights(rule, size) for rule in set(rules)}
    xi, weights = tensor_product(
        [one_dimensional[rule][0] for rule in rules], [one_dimensional[rule][1] for rule in rules]
    )
    info = {
        "rule": rule_catalog.rule_names(rules),
        "points_per_dimension": size,
        "degree": min(rule_catalog.degree(rule, size) for rule in rules),
    }
    return xi, weights, info
