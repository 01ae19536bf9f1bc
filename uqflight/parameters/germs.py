"""Germs: the standard variables ξ that drive the parameters, one class each.

A germ knows its law (quantile from uniforms u in (0, 1), log-density, support, sampling), the full
three-term recurrence (α, β) of its orthonormal polynomials, and the quadrature rules that integrate against it (the Gauss rule by
default, and its nested cousin). Adding a germ is one class here plus its rules in
`uqflight.designs.rules`.
"""
from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np
from scipy import special

_OPEN_UNIT = (2.0**-53, 1.0 - 2.0**-53)  # keeps Φ⁻¹ finite at u = 0


class Germ(ABC):
    """A standard variable: its name, law (quantile, log-density, support), the full three-term
    recurrence (α, β) of its orthonormal polynomials, and its default rules. Everything that depends on
    the law (designs, bases, calibration priors and starts) asks the germ, so a new germ is one class."""

    name: str
    default_rule: str  # the Gauss rule of the germ's law
    nested_rule: str  # the nested rule that `design.nested: true` swaps in
    support: tuple[float, float]  # where the density is positive

    @abstractmethod
    def quantile(self, u: np.ndarray) -> np.ndarray:
        """ξ from uniforms u in [0, 1)."""

    @abstractmethod
    def log_density(self, xi: np.ndarray) -> np.ndarray:
        """log p(ξ); −inf outside the support."""

    def recurrence_alpha(self, n: np.ndarray) -> np.ndarray:
        """α_n of the orthonormal recurrence x p_n = β_{n+1} p_{n+1} + α_n p_n + β_n p_{n−1} (0 for a
        law symmetric about 0)."""
        return np.zeros_like(np.asarray(n, dtype=float))

    @abstractmethod
    def recurrence_beta(self, n: np.ndarray) -> np.ndarray:
        """β_n of the orthonormal recurrence above."""

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """n independent draws of ξ from `rng`."""
        return self.quantile(rng.random(n))

    @abstractmethod
    def from_normal(self, z: np.ndarray) -> np.ndarray:
        """ξ = F⁻¹(Φ(z)) of a standard normal z: this germ's variable with the same rank (the Nataf map)."""

    @abstractmethod
    def to_normal(self, xi: np.ndarray) -> np.ndarray:
        """z = Φ⁻¹(F(ξ)): the inverse of from_normal."""


class NormalGerm(Germ):
    """ξ ~ N(0, 1); orthonormal Hermite polynomials He_n/√n!."""

    name, default_rule, nested_rule = "normal", "gauss_hermite", "genz_keister"
    support = (-np.inf, np.inf)

    def quantile(self, u):
        return special.ndtri(np.clip(u, *_OPEN_UNIT))

    def log_density(self, xi):
        return -0.5 * np.asarray(xi, dtype=float) ** 2 - 0.5 * np.log(2 * np.pi)

    def recurrence_beta(self, n):
        return np.sqrt(n)

    def sample(self, rng, n):
        return rng.standard_normal(n)

    def from_normal(self, z):
        return np.asarray(z, dtype=float)

    def to_normal(self, xi):
        return np.asarray(xi, dtype=float)


class UniformGerm(Germ):
    """ξ ~ U(−1, 1); orthonormal Legendre polynomials √(2n+1)·P_n."""

    name, default_rule, nested_rule = "uniform", "gauss_legendre", "gauss_patterson"
    support = (-1.0, 1.0)

    def quantile(self, u):
        return 2.0 * u - 1.0

    def log_density(self, xi):
        xi = np.asarray(xi, dtype=float)
        return np.where(np.abs(xi) <= 1.0, np.log(0.5), -np.inf)

    def recurrence_beta(self, n):
        return n / np.sqrt(4.0 * n**2 - 1.0)

    def sample(self, rng, n):
        return rng.uniform(-1.0, 1.0, n)

    def from_normal(self, z):  # each tail from its own side: no loss of precision near ±1
        z = np.asarray(z, dtype=float)
        return np.where(z > 0, 1.0 - 2.0 * special.ndtr(-z), 2.0 * special.ndtr(z) - 1.0)

    def to_normal(self, xi):
        xi = np.asarray(xi, dtype=float)
        return np.where(xi > 0, -special.ndtri(np.clip(0.5 * (1.0 - xi), *_OPEN_UNIT)),
                        special.ndtri(np.clip(0.5 * (1.0 + xi), *_OPEN_UNIT)))


GERMS: dict[str, Germ] = {germ.name: germ for germ in (NormalGerm(), UniformGerm())}


def check_germs(germs) -> list[str]:
    """The germ list of a campaign: non-empty, each a name in GERMS."""
    germs = list(germs)
    if not germs or any(germ not in GERMS for germ in germs):
        raise ValueError(f"germs: expected a non-empty list of {' / '.join(GERMS)}, got {germs!r}")
    return germs


def germ_columns(germs: list[str]) -> list[tuple[str, list[int]]]:
    """(germ, the input columns it drives) for each distinct germ, in order of first use: the inputs
    one vectorised call of that germ can serve together."""
    return [(germ, [k for k, g in enumerate(germs) if g == germ]) for germ in dict.fromkeys(germs)]


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
