"""One-dimensional quadrature rules, normalised to the probability measure of their germ.

normal germ, N(0, 1):      gauss_hermite (probabilists'), genz_keister (nested; chaospy's variant 24)
uniform germ, U(-1, 1):    gauss_legendre, clenshaw_curtis (nested), gauss_patterson (nested)

Weights sum to 1. Every rule is symmetric about 0, so odd powers integrate exactly at any size.
A rule family is indexed by its size (number of points); a growth law gives the sizes at the 1-D
levels 1, 2, 3, ... used by sparse grids.
"""
from __future__ import annotations

import math

import chaospy
import numpy as np
from numpy.polynomial.hermite_e import hermegauss
from numpy.polynomial.legendre import leggauss

RULE_GERMS = {
    "gauss_hermite": "normal",
    "genz_keister": "normal",
    "gauss_legendre": "uniform",
    "clenshaw_curtis": "uniform",
    "gauss_patterson": "uniform",
}
RULES = tuple(RULE_GERMS)
DEFAULT_RULES = {"normal": "gauss_hermite", "uniform": "gauss_legendre"}
NESTED_VERSIONS = {"gauss_hermite": "genz_keister", "gauss_legendre": "gauss_patterson"}
NESTED_RULES = ("genz_keister", "clenshaw_curtis", "gauss_patterson")
GROWTHS = ("linear", "exponential")

GENZ_KEISTER_SIZES = (1, 3, 9, 19, 43)  # all chaospy tabulates for variant 24; 43 has ~9-digit weights
GENZ_KEISTER_DEGREES = (1, 5, 15, 29, 69)
PATTERSON_SIZES = tuple(2**level - 1 for level in range(1, 10))  # 1, 3, 7, ..., 511


def allowed_sizes(rule: str) -> tuple[int, ...] | None:
    """The sizes a rule exists in, or None when any size >= 1 does."""
    return {"genz_keister": GENZ_KEISTER_SIZES, "gauss_patterson": PATTERSON_SIZES}.get(rule)


def nested_family(rule: str, count: int) -> list[int]:
    """The first `count` sizes (fewer if chaospy tabulates fewer) whose nodes nest in each other."""
    tabulated = allowed_sizes(rule)
    if tabulated is not None:
        return list(tabulated[:count])
    return [1] + [2**k + 1 for k in range(1, count)]  # clenshaw_curtis


def max_level(rule: str, growth: str) -> int | None:
    """The highest 1-D level a rule reaches under a growth law, or None when unbounded."""
    tabulated = allowed_sizes(rule)
    if tabulated is None:
        return None
    if growth == "exponential":
        return len(tabulated)
    return (degree(rule, tabulated[-1]) + 1) // 2


def level_sizes(rule: str, growth: str, levels: int) -> list[int]:
    """Sizes of the rule at 1-D levels 1..levels.

    linear: level i is exact to degree 2i − 1 — Gauss rules have i points, nested rules take
    their smallest member that is exact enough (so a member may repeat: Genz–Keister 1, 3, 3, 9, …).
    exponential: Gauss rules have 2^i − 1 points; nested rules step through their members,
    1, 3, 9, 19, 43 (Genz–Keister), 1, 3, 5, 9, 17, … (Clenshaw–Curtis), 1, 3, 7, 15, … (Patterson).
    """
    level = np.arange(1, levels + 1)
    if rule not in NESTED_RULES:
        return (level if growth == "linear" else 2**level - 1).tolist()
    members = nested_family(rule, levels)
    if growth == "exponential":
        return members
    member_degrees = [degree(rule, size) for size in members]
    return [members[i] for i in np.searchsorted(member_degrees, 2 * level - 1)]


def nodes_weights(rule: str, size: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and probability weights of the size-point rule."""
    if rule == "gauss_hermite":
        nodes, weights = hermegauss(size)
        return nodes, weights / math.sqrt(2 * math.pi)
    if rule == "gauss_legendre":
        nodes, weights = leggauss(size)
        return nodes, weights / 2
    if rule == "genz_keister":
        nodes, weights = chaospy.quadrature.genz_keister_24(GENZ_KEISTER_SIZES.index(size))
        return nodes[0], weights
    if rule == "gauss_patterson":
        nodes, weights = chaospy.quadrature.patterson(PATTERSON_SIZES.index(size), (-1, 1))
        return nodes[0], weights / 2
    nodes, weights = chaospy.quadrature.clenshaw_curtis(size - 1, (-1, 1))
    return nodes[0], weights / 2


def degree(rule: str, size: int) -> int:
    """Polynomial exactness degree of the size-point rule (odd, thanks to symmetry)."""
    if rule in ("gauss_hermite", "gauss_legendre"):
        return 2 * size - 1
    if rule == "genz_keister":
        return GENZ_KEISTER_DEGREES[GENZ_KEISTER_SIZES.index(size)]
    if rule == "gauss_patterson":
        return 1 if size == 1 else (3 * size + 1) // 2
    return size if size % 2 else size - 1


def rules_by_dimension(rule, germs: list[str], nested: bool | None) -> list[str]:
    """The 1-D rule of each dimension from the spec's `rule` and `nested`.

    rule: one name for every dimension, a mapping germ -> name, or None for the Gauss rule of each
    germ. nested: true swaps a Gauss rule for its nested cousin (Hermite -> Genz–Keister,
    Legendre -> Patterson); false forbids nested rules; None keeps the rules as named.
    """
    if rule is None:
        by_germ = DEFAULT_RULES
    elif isinstance(rule, str):
        by_germ = {germ: rule for germ in DEFAULT_RULES}
    elif isinstance(rule, dict):
        unknown = [key for key in rule if key not in DEFAULT_RULES]
        if unknown:
            raise ValueError(
                f"design.rule: a mapping's keys are germs ({', '.join(DEFAULT_RULES)}), "
                f"got {unknown[0]!r}"
            )
        by_germ = rule
    else:
        raise ValueError(
            f"design.rule: expected a rule name or a mapping germ -> rule name, got {rule!r}"
        )
    rules = []
    for dimension, germ in enumerate(germs, start=1):
        if germ not in by_germ:
            raise ValueError(f"design.rule: no rule given for the {germ} germ of dimension {dimension}")
        name = by_germ[germ]
        if not isinstance(name, str) or name not in RULE_GERMS:
            raise ValueError(f"design.rule: expected one of {', '.join(RULES)}, got {name!r}")
        if RULE_GERMS[name] != germ:
            raise ValueError(
                f"design.rule: rule {name} is for {RULE_GERMS[name]} germs, "
                f"but dimension {dimension} has a {germ} germ"
            )
        if nested is False and name in NESTED_RULES:
            raise ValueError(
                f"design.nested: rule {name} is nested; a non-nested grid needs "
                f"{' or '.join(NESTED_VERSIONS)}"
            )
        rules.append(NESTED_VERSIONS.get(name, name) if nested else name)
    return rules


def rule_names(rules: list[str]) -> str:
    """The distinct rules of a grid, in order of first appearance: "gauss_hermite, gauss_legendre"."""
    return ", ".join(dict.fromkeys(rules))
