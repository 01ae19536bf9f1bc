"""One-dimensional quadrature rules, normalised to the probability measure of their germ: one table.

normal germ, N(0, 1):      gauss_hermite (probabilists'), genz_keister (nested; chaospy's variant 24)
uniform germ, U(-1, 1):    gauss_legendre, clenshaw_curtis (nested), gauss_patterson (nested)

Weights sum to 1. Every rule is symmetric about 0, so odd powers integrate exactly at any size.
A rule family is indexed by its size (number of points); a growth law gives the sizes at the 1-D
levels 1, 2, 3, ... used by sparse grids. A new rule is one entry of RULE_TABLE; there is no fallback.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np
from numpy.polynomial.hermite_e import hermegauss
from numpy.polynomial.legendre import leggauss

from ..parameters.germs import GERMS
from ..text import FieldError

GROWTHS = ("linear", "exponential")
# the `rule` key of the grids that take any rule (sparse_grid, tensor_grid), for the key reference
RULE = ("The 1-D rule (below) for every dimension, or a mapping germ -> rule (`rule: {normal: gauss_hermite, "
        "uniform: clenshaw_curtis}`). Default: each germ's Gauss rule (Gauss–Hermite for normal inputs, "
        "Gauss–Legendre for uniform ones).")
GENZ_KEISTER_SIZES = (1, 3, 9, 19, 43)  # all chaospy tabulates for variant 24; 43 has ~9-digit weights
GENZ_KEISTER_DEGREES = (1, 5, 15, 29, 69)
PATTERSON_SIZES = tuple(2**level - 1 for level in range(1, 10))  # 1, 3, 7, ..., 511


def _gauss_hermite(size):
    nodes, weights = hermegauss(size)
    return nodes, weights / math.sqrt(2 * math.pi)


def _gauss_legendre(size):
    nodes, weights = leggauss(size)
    return nodes, weights / 2


def _genz_keister(size):
    import chaospy

    nodes, weights = chaospy.quadrature.genz_keister_24(GENZ_KEISTER_SIZES.index(size))
    return nodes[0], weights


def _gauss_patterson(size):
    import chaospy

    nodes, weights = chaospy.quadrature.patterson(PATTERSON_SIZES.index(size), (-1, 1))
    return nodes[0], weights / 2


def _clenshaw_curtis(size):
    import chaospy

    nodes, weights = chaospy.quadrature.clenshaw_curtis(size - 1, (-1, 1))
    return nodes[0], weights / 2


@dataclass(frozen=True)
class Rule:
    """A 1-D rule: its germ, nodes and weights by size, exactness degree by size, and the sizes it
    exists in (None: any size >= 1). A nested rule's members nest in each other."""

    germ: str
    nodes_weights: Callable[[int], tuple[np.ndarray, np.ndarray]]
    degree: Callable[[int], int]
    nested: bool = False
    sizes: tuple[int, ...] | None = None


RULE_TABLE: dict[str, Rule] = {
    "gauss_hermite": Rule("normal", _gauss_hermite, lambda n: 2 * n - 1),
    "genz_keister": Rule("normal", _genz_keister, lambda n: GENZ_KEISTER_DEGREES[GENZ_KEISTER_SIZES.index(n)],
                         nested=True, sizes=GENZ_KEISTER_SIZES),
    "gauss_legendre": Rule("uniform", _gauss_legendre, lambda n: 2 * n - 1),
    "clenshaw_curtis": Rule("uniform", _clenshaw_curtis, lambda n: n if n % 2 else n - 1, nested=True),
    "gauss_patterson": Rule("uniform", _gauss_patterson, lambda n: 1 if n == 1 else (3 * n + 1) // 2,
                            nested=True, sizes=PATTERSON_SIZES),
}
RULES = tuple(RULE_TABLE)
NESTED_RULES = tuple(name for name, rule in RULE_TABLE.items() if rule.nested)


def rule(name: str) -> Rule:
    """The table entry of `name`; an unknown name is a ValueError listing the rules."""
    try:
        return RULE_TABLE[name]
    except KeyError:
        raise ValueError(f"unknown quadrature rule {name!r}: expected one of {', '.join(RULES)}") from None


def allowed_sizes(name: str) -> tuple[int, ...] | None:
    """The sizes a rule exists in, or None when any size >= 1 does."""
    return rule(name).sizes


def nested_family(name: str, count: int) -> list[int]:
    """The first `count` sizes (fewer if the rule is tabulated for fewer) whose nodes nest in each other."""
    tabulated = allowed_sizes(name)
    if tabulated is not None:
        return list(tabulated[:count])
    return [1] + [2**k + 1 for k in range(1, count)]  # clenshaw_curtis


def max_level(name: str, growth: str) -> int | None:
    """The highest 1-D level a rule reaches under a growth law, or None when unbounded."""
    tabulated = allowed_sizes(name)
    if tabulated is None:
        return None
    if growth == "exponential":
        return len(tabulated)
    return (degree(name, tabulated[-1]) + 1) // 2


def level_sizes(name: str, growth: str, levels: int) -> list[int]:
    """Sizes of the rule at 1-D levels 1..levels.

    linear: level i is exact to degree 2i − 1 — Gauss rules have i points, nested rules take
    their smallest member that is exact enough (so a member may repeat: Genz–Keister 1, 3, 3, 9, …).
    exponential: Gauss rules have 2^i − 1 points; nested rules step through their members,
    1, 3, 9, 19, 43 (Genz–Keister), 1, 3, 5, 9, 17, … (Clenshaw–Curtis), 1, 3, 7, 15, … (Patterson).
    """
    level = np.arange(1, levels + 1)
    if not rule(name).nested:
        return (level if growth == "linear" else 2**level - 1).tolist()
    members = nested_family(name, levels)
    if growth == "exponential":
        return members
    member_degrees = [degree(name, size) for size in members]
    return [members[i] for i in np.searchsorted(member_degrees, 2 * level - 1)]


def nodes_weights(name: str, size: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and probability weights of the size-point rule."""
    return rule(name).nodes_weights(size)


def degree(name: str, size: int) -> int:
    """Polynomial exactness degree of the size-point rule (odd, thanks to symmetry)."""
    return rule(name).degree(size)


def rules_by_dimension(named, germs: list[str], nested: bool | None) -> list[str]:
    """The 1-D rule of each dimension from the spec's `rule` (here `named`) and `nested`.

    named: one rule name for every dimension, a mapping germ -> name, or None for each germ's
    default (Gauss) rule. nested: true swaps a default rule for its germ's nested rule (Hermite ->
    Genz–Keister, Legendre -> Patterson); false forbids nested rules; None keeps the rules as named.
    """
    defaults = {name: germ.default_rule for name, germ in GERMS.items()}
    nested_versions = {germ.default_rule: germ.nested_rule for germ in GERMS.values()}
    if named is None:
        by_germ = defaults
    elif isinstance(named, str):
        by_germ = {germ: named for germ in defaults}
    elif isinstance(named, dict):
        unknown = [key for key in named if key not in defaults]
        if unknown:
            raise FieldError("design.rule", f"a mapping's keys are germs ({', '.join(defaults)}), got {unknown[0]!r}")
        by_germ = named
    else:
        raise FieldError("design.rule", f"expected a rule name or a mapping germ -> rule name, got {named!r}")
    rules = []
    for dimension, germ in enumerate(germs, start=1):
        if germ not in by_germ:
            raise FieldError("design.rule", f"no rule given for the {germ} germ of dimension {dimension}")
        name = by_germ[germ]
        if not isinstance(name, str) or name not in RULE_TABLE:
            raise FieldError("design.rule", f"expected one of {', '.join(RULES)}, got {name!r}")
        if RULE_TABLE[name].germ != germ:
            raise FieldError("design.rule", f"rule {name} is for {RULE_TABLE[name].germ} germs, "
                             f"but dimension {dimension} has a {germ} germ")
        if nested is False and RULE_TABLE[name].nested:
            raise FieldError("design.nested", f"rule {name} is nested; a non-nested grid needs "
                             f"{' or '.join(nested_versions)}")
        rules.append(nested_versions.get(name, name) if nested else name)
    return rules


def rule_names(rules: list[str]) -> str:
    """The distinct rules of a grid, in order of first appearance: "gauss_hermite, gauss_legendre"."""
    return ", ".join(dict.fromkeys(rules))
