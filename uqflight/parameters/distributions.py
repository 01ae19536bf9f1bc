"""The laws a parameter can follow on its interval [lower, upper], one class each (paper, Sec. 3.1).

Each class names its germ and gives κ(ξ) (its quantile in the germ's variable, increasing in ξ),
the inverse ξ(κ), and its mean and standard deviation. The germ carries the orthogonal polynomials
and the default quadrature rule (`uqflight.parameters.germs`). Adding a law is one class here,
listed in DISTRIBUTIONS.
"""
from __future__ import annotations

import math
from abc import ABC, abstractmethod

import numpy as np

INTERVAL_SIGMAS = 3.0  # the interval spans ±3σ: the paper's 99.7 % range


class Distribution(ABC):
    """A law on [lower, upper]; subclasses set `name` and `germ` and the four maps."""

    name: str
    germ: str
    polynomial = True  # κ(ξ) is smooth: a PCE in ξ can represent what it drives

    def __init__(self, lower: float, upper: float):
        self.lower, self.upper = float(lower), float(upper)

    @property
    def midpoint(self) -> float:
        return 0.5 * (self.lower + self.upper)

    def check(self) -> str | None:
        """Why the interval does not suit the law, or None."""
        return None

    @abstractmethod
    def to_physical(self, xi: np.ndarray) -> np.ndarray:
        """κ from ξ."""

    @abstractmethod
    def to_standard(self, kappa: np.ndarray) -> np.ndarray:
        """ξ from κ."""

    @property
    @abstractmethod
    def mean(self) -> float:
        """E[κ]."""

    @property
    @abstractmethod
    def std(self) -> float:
        """The standard deviation of κ."""


class Normal(Distribution):
    """Mean at the midpoint, the interval is the 99.7 % range ±3σ; κ = μ + σξ."""

    name, germ = "normal", "normal"

    @property
    def sigma(self) -> float:
        return (self.upper - self.lower) / (2 * INTERVAL_SIGMAS)

    def to_physical(self, xi):
        return self.midpoint + self.sigma * np.asarray(xi, dtype=float)

    def to_standard(self, kappa):
        return (np.asarray(kappa, dtype=float) - self.midpoint) / self.sigma

    @property
    def mean(self):
        return self.midpoint

    @property
    def std(self):
        return self.sigma


class Uniform(Distribution):
    """Uniform on the interval; κ = mid + half·ξ with ξ ~ U(−1, 1)."""

    name, germ = "uniform", "uniform"

    def to_physical(self, xi):
        return self.midpoint + 0.5 * (self.upper - self.lower) * np.asarray(xi, dtype=float)

    def to_standard(self, kappa):
        return (np.asarray(kappa, dtype=float) - self.midpoint) / (0.5 * (self.upper - self.lower))

    @property
    def mean(self):
        return self.midpoint

    @property
    def std(self):
        return 0.5 * (self.upper - self.lower) / math.sqrt(3.0)


class TruncatedNormal(Normal):
    """The normal above truncated to the interval; κ = F⁻¹(Φ(ξ))."""

    name, germ = "truncated_normal", "normal"

    @property
    def _law(self):
        from scipy import stats

        return stats.truncnorm(-INTERVAL_SIGMAS, INTERVAL_SIGMAS, loc=self.midpoint, scale=self.sigma)

    def to_physical(self, xi):
        from scipy import special

        xi = np.asarray(xi, dtype=float)
        law = self._law  # each tail from its own side, so that neither loses precision near 1
        return np.where(xi > 0, law.isf(special.ndtr(-xi)), law.ppf(special.ndtr(xi)))

    def to_standard(self, kappa):
        from scipy import special

        kappa = np.asarray(kappa, dtype=float)
        law = self._law
        return np.where(kappa > self.midpoint, -special.ndtri(law.sf(kappa)), special.ndtri(law.cdf(kappa)))

    @property
    def std(self):
        return float(self._law.std())


class Lognormal(Distribution):
    """The interval is ±3σ in log space (the 0.135 %/99.865 % quantiles); κ = exp(μ + σξ). An interval
    below zero gives the mirror image κ = −exp(μ − σξ), so κ still grows with ξ."""

    name, germ = "lognormal", "normal"

    def check(self):
        if self.lower * self.upper <= 0:
            return (f"a lognormal interval must lie entirely above or entirely below zero, "
                    f"got [{self.lower}, {self.upper}]")
        return None

    @property
    def _sign_location_scale(self) -> tuple[float, float, float]:
        """(s, μ, σ) with κ = s·exp(μ + sσξ), s = ±1 the sign of the interval."""
        sign = 1.0 if self.lower > 0 else -1.0
        log_lower, log_upper = np.log(sign * self.lower), np.log(sign * self.upper)
        scale = abs(log_upper - log_lower) / (2 * INTERVAL_SIGMAS)
        return sign, 0.5 * (log_lower + log_upper), scale

    def to_physical(self, xi):
        sign, location, scale = self._sign_location_scale
        return sign * np.exp(location + sign * scale * np.asarray(xi, dtype=float))

    def to_standard(self, kappa):
        sign, location, scale = self._sign_location_scale
        return sign * (np.log(sign * np.asarray(kappa, dtype=float)) - location) / scale

    @property
    def mean(self):
        sign, location, scale = self._sign_location_scale
        return sign * math.exp(location + 0.5 * scale**2)

    @property
    def std(self):
        _, location, scale = self._sign_location_scale
        return math.exp(location + 0.5 * scale**2) * math.sqrt(math.expm1(scale**2))


SEED_COUNT = 2**31  # seeds 0 .. 2^31 − 1: what JSBSim's atmosphere/randomseed (an int) holds
SEED_REFUSAL = ("a seed's random stream cannot be expanded in polynomials: use method monte_carlo, and a "
                "pick_freeze design for the share of the variance due to the seed")


class Seed(Uniform):
    """A random stream's integer seed, drawn uniformly from 0 .. 2^31 − 1: κ = ⌊(ξ + 1)/2 · 2^31⌋. Its
    interval is fixed (no interval_pct, lower or upper); every κ is an integer, exact in float64. Designs
    draw, freeze and swap its ξ like any input's, so a run's seed follows from the campaign's seed and the
    run's design index alone. A seed has no polynomial expansion (`polynomial` false): grids and PCE
    methods over it are refused."""

    name, germ, polynomial = "seed", "uniform", False

    def __init__(self, lower: float = 0.0, upper: float = float(SEED_COUNT)):
        super().__init__(lower, upper)

    def check(self):
        if (self.lower, self.upper) != (0.0, float(SEED_COUNT)):
            return f"a seed takes no interval (its seeds are 0 to {SEED_COUNT - 1}), got [{self.lower}, {self.upper}]"
        return None

    def to_physical(self, xi):
        u = 0.5 * (np.asarray(xi, dtype=float) + 1.0)
        return np.clip(np.floor(u * SEED_COUNT), 0, SEED_COUNT - 1)

    def to_standard(self, kappa):  # the middle of the seed's slice of ξ
        return 2.0 * (np.asarray(kappa, dtype=float) + 0.5) / SEED_COUNT - 1.0

    @property
    def mean(self):  # of the discrete uniform law on 0 .. n − 1
        return 0.5 * (SEED_COUNT - 1)

    @property
    def std(self):
        return math.sqrt((float(SEED_COUNT) ** 2 - 1.0) / 12.0)


DISTRIBUTIONS: dict[str, type[Distribution]] = {
    law.name: law for law in (Normal, Uniform, TruncatedNormal, Lognormal, Seed)}
