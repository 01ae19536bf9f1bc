"""Uncertain parameters: a distribution on an interval and the maps between ξ and κ.

Every parameter κ is driven by one standard variable ξ, its germ: ξ ~ N(0, 1) ("normal") or
ξ ~ U(-1, 1) ("uniform"). The interval [lower, upper] fixes the distribution (paper, Sec. 3.1):

- normal: mean at the midpoint, the interval is the 99.7 % range ±3σ; κ = μ + σξ.
- uniform: on the interval; κ = mid + half·ξ.
- truncated_normal: that normal truncated to the interval; κ = F⁻¹(Φ(ξ)).
- lognormal: the interval is ±3σ in log space (the 0.135 %/99.865 % quantiles); κ = exp(μ + σξ).
  An interval below zero gives the mirror image κ = −exp(μ − σξ), so κ still grows with ξ.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Real

import numpy as np
from scipy import special, stats

DISTRIBUTIONS = ("normal", "uniform", "truncated_normal", "lognormal")
GERM_OF_DISTRIBUTION = {
    "normal": "normal",
    "uniform": "uniform",
    "truncated_normal": "normal",
    "lognormal": "normal",
}
INTERVAL_SIGMAS = 3.0  # the interval spans ±3σ: the paper's 99.7 % range


@dataclass(frozen=True)
class Parameter:
    """One uncertain JSBSim property: its distribution on [lower, upper] and the ξ ↔ κ maps."""

    name: str
    property: str
    distribution: str
    nominal: float
    lower: float
    upper: float

    def __post_init__(self):
        where = f"parameter {self.name!r}"
        if self.distribution not in DISTRIBUTIONS:
            raise ValueError(
                f"{where}: unknown distribution {self.distribution!r}; "
                f"expected one of {', '.join(DISTRIBUTIONS)}"
            )
        if not all(math.isfinite(v) for v in (self.nominal, self.lower, self.upper)):
            raise ValueError(
                f"{where}: nominal, lower and upper must be finite, got "
                f"{self.nominal}, {self.lower}, {self.upper}"
            )
        if not self.lower < self.upper:
            raise ValueError(f"{where}: lower ({self.lower}) must be below upper ({self.upper})")
        if self.distribution == "lognormal" and self.lower * self.upper <= 0:
            raise ValueError(
                f"{where}: a lognormal interval must lie entirely above or entirely below zero, "
                f"got [{self.lower}, {self.upper}]"
            )

    @property
    def germ(self) -> str:
        """The standard variable driving κ: "normal" (N(0,1)) or "uniform" (U(-1,1))."""
        return GERM_OF_DISTRIBUTION[self.distribution]

    @property
    def _midpoint(self) -> float:
        return 0.5 * (self.lower + self.upper)

    @property
    def _sigma(self) -> float:
        """σ of the (untruncated) normal whose ±3σ range is the interval."""
        return (self.upper - self.lower) / (2 * INTERVAL_SIGMAS)

    @property
    def _truncated(self):
        return stats.truncnorm(
            -INTERVAL_SIGMAS, INTERVAL_SIGMAS, loc=self._midpoint, scale=self._sigma
        )

    @property
    def _log_sign_location_scale(self) -> tuple[float, float, float]:
        """(s, μ, σ) of a lognormal with κ = s·exp(μ + sσξ), s = ±1 the sign of the interval."""
        sign = 1.0 if self.lower > 0 else -1.0
        log_lower, log_upper = np.log(sign * self.lower), np.log(sign * self.upper)
        scale = abs(log_upper - log_lower) / (2 * INTERVAL_SIGMAS)
        return sign, 0.5 * (log_lower + log_upper), scale

    @property
    def mean(self) -> float:
        """E[κ]."""
        if self.distribution == "lognormal":
            sign, location, scale = self._log_sign_location_scale
            return sign * math.exp(location + 0.5 * scale**2)
        return self._midpoint

    @property
    def std(self) -> float:
        """Standard deviation of κ."""
        if self.distribution == "normal":
            return self._sigma
        if self.distribution == "uniform":
            return 0.5 * (self.upper - self.lower) / math.sqrt(3.0)
        if self.distribution == "truncated_normal":
            return float(self._truncated.std())
        _, location, scale = self._log_sign_location_scale
        return math.exp(location + 0.5 * scale**2) * math.sqrt(math.expm1(scale**2))

    def to_physical(self, xi: np.ndarray) -> np.ndarray:
        """κ from ξ (any shape), increasing in ξ."""
        xi = np.asarray(xi, dtype=float)
        if self.distribution == "normal":
            return self._midpoint + self._sigma * xi
        if self.distribution == "uniform":
            return self._midpoint + 0.5 * (self.upper - self.lower) * xi
        if self.distribution == "truncated_normal":
            # Each tail from its own side, so that neither loses precision near 1.
            truncated = self._truncated
            return np.where(
                xi > 0, truncated.isf(special.ndtr(-xi)), truncated.ppf(special.ndtr(xi))
            )
        sign, location, scale = self._log_sign_location_scale
        return sign * np.exp(location + sign * scale * xi)

    def to_standard(self, kappa: np.ndarray) -> np.ndarray:
        """ξ from κ (any shape): the inverse of to_physical."""
        kappa = np.asarray(kappa, dtype=float)
        if self.distribution == "normal":
            return (kappa - self._midpoint) / self._sigma
        if self.distribution == "uniform":
            return (kappa - self._midpoint) / (0.5 * (self.upper - self.lower))
        if self.distribution == "truncated_normal":
            truncated = self._truncated
            return np.where(
                kappa > self._midpoint,
                -special.ndtri(truncated.sf(kappa)),
                special.ndtri(truncated.cdf(kappa)),
            )
        sign, location, scale = self._log_sign_location_scale
        return sign * (np.log(sign * kappa) - location) / scale


def _as_float(name: str, field: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, Real):
        raise ValueError(f"parameter {name!r}: {field} must be a number, got {value!r}")
    return float(value)


def make_parameter(
    name: str,
    property: str,
    distribution: str,
    nominal: float,
    interval_pct: float | None = None,
    lower: float | None = None,
    upper: float | None = None,
) -> Parameter:
    """A Parameter from its interval: ±interval_pct percent of |nominal| (the paper's Table 1),
    or the absolute bounds lower and upper. Exactly one of the two forms."""
    for field, value in (("name", name), ("property", property)):
        if not isinstance(value, str) or not value:
            raise ValueError(f"parameter {name!r}: {field} must be a non-empty string, got {value!r}")
    nominal = _as_float(name, "nominal", nominal)
    given_bounds = [bound for bound in (lower, upper) if bound is not None]
    if (interval_pct is None) == (not given_bounds):
        raise ValueError(
            f"parameter {name!r}: give either interval_pct or lower and upper, "
            f"{'not both' if given_bounds else 'got neither'}"
        )
    if interval_pct is None:
        if len(given_bounds) != 2:
            raise ValueError(f"parameter {name!r}: lower and upper must be given together")
        return Parameter(
            name, property, distribution, nominal,
            _as_float(name, "lower", lower), _as_float(name, "upper", upper),
        )
    percent = _as_float(name, "interval_pct", interval_pct)
    if not percent > 0:
        raise ValueError(f"parameter {name!r}: interval_pct must be > 0, got {percent}")
    if nominal == 0:
        raise ValueError(
            f"parameter {name!r}: interval_pct is a percentage of the nominal, which is 0; "
            "give lower and upper instead"
        )
    half_width = abs(nominal) * percent / 100.0
    return Parameter(name, property, distribution, nominal, nominal - half_width, nominal + half_width)


def germs(params) -> list[str]:
    """The germ of each parameter, in order."""
    return [p.germ for p in params]


def _map_columns(params, values: np.ndarray, label: str, parameter_map) -> np.ndarray:
    """Apply parameter_map(parameter k, column k) to every column of an (N, d) array."""
    values = np.asarray(values, dtype=float)
    if values.ndim != 2 or values.shape[1] != len(params):
        raise ValueError(f"{label}: expected shape (N, {len(params)}), got {values.shape}")
    mapped = np.empty_like(values)
    for k, p in enumerate(params):
        mapped[:, k] = parameter_map(p, values[:, k])
    return mapped


def to_physical(params, xi: np.ndarray) -> np.ndarray:
    """κ (N, d) from ξ (N, d), column k through parameter k."""
    return _map_columns(params, xi, "xi", Parameter.to_physical)


def to_standard(params, kappa: np.ndarray) -> np.ndarray:
    """ξ (N, d) from κ (N, d), column k through parameter k."""
    return _map_columns(params, kappa, "kappa", Parameter.to_standard)
