"""Full tensor-product grids of 1-D rules."""
from __future__ import annotations

from . import rules as rule_catalog
from .base import DesignKind, Key, count
from .rules import RULE
from .smolyak import tensor_product
from ..text import FieldError


class TensorGrid(DesignKind):
    """`tensor_grid` {rule, points}: the same number of points in every dimension; seed unused.

    Examples
    --------
    >>> from uqflight.designs import build_design, design_size
    >>> spec = {"kind": "tensor_grid", "points": 3}
    >>> design_size(spec, ["normal"] * 3)  # points ** d
    27.0
    >>> design = build_design(spec, ["normal", "uniform"], seed=0)
    >>> design.xi.shape, design.info["degree"]  # 3 Gauss points are exact to degree 2 × 3 − 1
    ((9, 2), 5)
    >>> [round(float(design.weights @ design.xi[:, k] ** 4), 12) for k in (0, 1)]  # E[ξ⁴]: 3 normal, 1/5 uniform
    [3.0, 0.2]
    """

    kind = "tensor_grid"
    keys = {"rule": Key(description=RULE), "points": count(1, description="Points per dimension, >= 1. `points: 5`")}
    example = {"kind": "tensor_grid", "points": 4}
    sampling = None

    def size(self, spec, germs):
        """points^d (a float: it may be far beyond any integer a run could reach)."""
        return float(spec["points"]) ** len(germs)

    def points(self, spec, germs, seed):
        size = spec["points"]
        rules = rule_catalog.rules_by_dimension(spec["rule"], germs, nested=None)
        for rule in dict.fromkeys(rules):
            sizes = rule_catalog.allowed_sizes(rule)
            if sizes is not None and size not in sizes:
                raise FieldError("design.points",
                                 f"rule {rule} comes in {', '.join(map(str, sizes))} points, got {size}")
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
