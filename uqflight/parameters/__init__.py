"""Uncertain parameters: a law on an interval and the maps between ξ and κ.

Every parameter κ is driven by one standard variable ξ, its germ (`germs`); the interval
[lower, upper] fixes the law (`distributions`, one class each, paper Sec. 3.1).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from numbers import Real

import numpy as np

from .distributions import DISTRIBUTIONS, Distribution
from .germs import GERMS


@dataclass(frozen=True)
class Parameter:
    """One uncertain property: its law on [lower, upper] and the ξ ↔ κ maps."""

    name: str
    property: str
    distribution: str
    nominal: float
    lower: float
    upper: float
    law: Distribution = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        where = f"parameter {self.name!r}"
        if self.distribution not in DISTRIBUTIONS:
            raise ValueError(f"{where}: unknown distribution {self.distribution!r}; "
                             f"expected one of {', '.join(DISTRIBUTIONS)}")
        if not all(math.isfinite(v) for v in (self.nominal, self.lower, self.upper)):
            raise ValueError(f"{where}: nominal, lower and upper must be finite, got "
                             f"{self.nominal}, {self.lower}, {self.upper}")
        if not self.lower < self.upper:
            raise ValueError(f"{where}: lower ({self.lower}) must be below upper ({self.upper})")
        law = DISTRIBUTIONS[self.distribution](self.lower, self.upper)
        problem = law.check()
        if problem:
            raise ValueError(f"{where}: {problem}")
        object.__setattr__(self, "law", law)

    @property
    def germ(self) -> str:
        """The standard variable driving κ, a name in GERMS."""
        return self.law.germ

    @property
    def mean(self) -> float:
        """E[κ]."""
        return self.law.mean

    @property
    def std(self) -> float:
        """Standard deviation of κ."""
        return self.law.std

    def to_physical(self, xi: np.ndarray) -> np.ndarray:
        """κ from ξ (any shape), increasing in ξ."""
        return self.law.to_physical(xi)

    def to_standard(self, kappa: np.ndarray) -> np.ndarray:
        """ξ from κ (any shape): the inverse of to_physical."""
        return self.law.to_standard(kappa)


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
    for key, value in (("name", name), ("property", property)):
        if not isinstance(value, str) or not value:
            raise ValueError(f"parameter {name!r}: {key} must be a non-empty string, got {value!r}")
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


def seed_names(params) -> list[str]:
    """The names of the parameters that are random streams' seeds (`distribution: seed`)."""
    return [p.name for p in params if not p.law.polynomial]


def germs_of(params, dependence=None) -> list[str]:
    """The germ of each parameter, in order (standard normal for those a `dependence` correlates)."""
    return dependence.germs(params) if dependence is not None else [p.germ for p in params]


def _map_columns(params, values: np.ndarray, label: str, parameter_map) -> np.ndarray:
    """Apply parameter_map(parameter k, column k) to every column of an (N, d) array."""
    values = np.asarray(values, dtype=float)
    if values.ndim != 2 or values.shape[1] != len(params):
        raise ValueError(f"{label}: expected shape (N, {len(params)}), got {values.shape}")
    mapped = np.empty_like(values)
    for k, p in enumerate(params):
        mapped[:, k] = parameter_map(p, values[:, k])
    return mapped


def to_physical(params, xi: np.ndarray, dependence=None) -> np.ndarray:
    """κ (N, d) from ξ (N, d), column k through parameter k, or by the Nataf transform of a
    `dependence` (`parameters.dependence.GaussianCopula`)."""
    kappa = _map_columns(params, xi, "xi", Parameter.to_physical)
    return kappa if dependence is None else dependence.to_physical(params, np.asarray(xi, dtype=float), kappa)


def to_standard(params, kappa: np.ndarray, dependence=None) -> np.ndarray:
    """ξ (N, d) from κ (N, d): the inverse of to_physical."""
    xi = _map_columns(params, kappa, "kappa", Parameter.to_standard)
    return xi if dependence is None else dependence.to_standard(params, xi)


__all__ = ["DISTRIBUTIONS", "GERMS", "Parameter", "germs_of", "make_parameter", "seed_names", "to_physical",
           "to_standard"]
