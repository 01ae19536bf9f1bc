"""Germs: the standard variables ξ that drive the parameters, one class each.

A germ knows its law's quantile (uniforms u in (0, 1) to ξ), the three-term recurrence of its
orthonormal polynomials, and the quadrature rules that integrate against it (the Gauss rule by
default, and its nested cousin). Adding a germ is one class here plus its rules in
`uqflight.designs.rules`.
"""
from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np
from scipy import special

_OPEN_UNIT = (2.0**-53, 1.0 - 2.0**-53)  # keeps Φ⁻¹ finite at u = 0


class Germ(ABC):
    """A standard variable: its name, quantile, polynomial recurrence and default rules."""

    name: str
    default_rule: str  # the Gauss rule of the germ's law
    nested_rule: str  # the nested rule that `design.nested: true` swaps in

    @abstractmethod
    def quantile(self, u: np.ndarray) -> np.ndarray:
        """ξ from uniforms u in [0, 1)."""

    @abstractmethod
    def recurrence_beta(self, n: np.ndarray) -> np.ndarray:
        """β_n of the orthonormal recurrence x p_n = β_{n+1} p_{n+1} + β_n p_{n−1}."""


class NormalGerm(Germ):
    """ξ ~ N(0, 1); orthonormal Hermite polynomials He_n/√n!."""

    name, default_rule, nested_rule = "normal", "gauss_hermite", "genz_keister"

    def quantile(self, u):
        return special.ndtri(np.clip(u, *_OPEN_UNIT))

    def recurrence_beta(self, n):
        return np.sqrt(n)


class UniformGerm(Germ):
    """ξ ~ U(−1, 1); orthonormal Legendre polynomials √(2n+1)·P_n."""

    name, default_rule, nested_rule = "uniform", "gauss_legendre", "gauss_patterson"

    def quantile(self, u):
        return 2.0 * u - 1.0

    def recurrence_beta(self, n):
        return n / np.sqrt(4.0 * n**2 - 1.0)


GERMS: dict[str, Germ] = {germ.name: germ for germ in (NormalGerm(), UniformGerm())}


def check_germs(germs) -> list[str]:
    """The germ list of a campaign: non-empty, each a name in GERMS."""
    germs = list(germs)
    if not germs or any(germ not in GERMS for germ in germs):
        raise ValueError(f"germs: expected a non-empty list of {' / '.join(GERMS)}, got {germs!r}")
    return germs


def germ_quantiles(u: np.ndarray, germs: list[str]) -> np.ndarray:
    """ξ (N, d) from uniforms u (N, d): column k through the quantile of germ k."""
    u = np.asarray(u, dtype=float)
    xi = np.empty_like(u)
    for k, name in enumerate(germs):
        xi[:, k] = GERMS[name].quantile(u[:, k])
    return xi


def draw_germs(germs, n: int, seed) -> np.ndarray:
    """n seeded independent draws of the standard variables, (n, d): the Monte Carlo design's points."""
    germs = check_germs(germs)
    return germ_quantiles(np.random.default_rng(seed).random((n, len(germs))), germs)
