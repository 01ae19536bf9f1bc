"""Dependent inputs: a Gaussian copula (the Nataf transform) over named parameters.

The standard variables ξ stay independent. The parameters of the group are driven by standard-normal
germs, and κ = T(ξ): z = L ξ_group, L the lower Cholesky factor of the copula's correlation R (rows and
columns in the listed order), then every parameter's own marginal at the rank of its z,
κ_k = F_k⁻¹(Φ(z_k)) (its law's κ of its germ's variable G_k⁻¹(Φ(z_k)); linear for a normal law).
R is the correlation of the normal scores z (Nataf's ρ0): for normal marginals it is the correlation
of κ itself; for others the correlation of κ follows from it (uniform: 6/π · asin(ρ0/2)).
Designs and PCE work in ξ, so the Sobol' indices are those of the independent ξ in the Cholesky order:
ξ of the first listed parameter carries all of it, each later ξ only the part of its parameter that
is independent of the ones listed before.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import solve_triangular

from .germs import GERMS

KIND = "gaussian_copula"
KINDS = (KIND,)
TOLERANCE = 1e-12  # symmetry and unit diagonal, absolute: what a matrix written out in decimals keeps
EIGENVALUE_FLOOR = 1e-10  # smallest eigenvalue accepted: below it L has no reliable inverse (|ρ| → 1)


def correlation_problem(matrix: np.ndarray) -> tuple[str, str] | None:
    """(where, why) a square matrix of finite numbers is not a correlation matrix, or None. `where` is
    the index suffix of the entry (`[i][j]`), or "" for the whole matrix."""
    n = len(matrix)
    for i in range(n):
        for j in range(n):
            value, mirror = float(matrix[i, j]), float(matrix[j, i])
            if i == j and abs(value - 1.0) > TOLERANCE:
                return f"[{i}][{j}]", f"expected 1 on the diagonal (a parameter with itself), got {value!r}"
            if not -1.0 <= value <= 1.0:
                return f"[{i}][{j}]", f"expected a correlation in [-1, 1], got {value!r}"
            if abs(value - mirror) > TOLERANCE:
                return f"[{i}][{j}]", (f"expected a symmetric matrix, but [{i}][{j}] = {value!r} and "
                                       f"[{j}][{i}] = {mirror!r}")
    smallest = float(np.linalg.eigvalsh(matrix).min())
    if smallest <= EIGENVALUE_FLOOR:
        return "", (f"expected a positive definite matrix, but its smallest eigenvalue is {smallest:.3g} "
                    f"(<= {EIGENVALUE_FLOOR:g}): some correlations are ±1 or contradict each other "
                    "(e.g. a-b and b-c strongly positive but a-c negative); correct them or drop a parameter")
    return None


@dataclass
class GaussianCopula:
    """A Gaussian copula R over the parameters `names` (the Cholesky order), see the module."""

    names: tuple[str, ...]
    correlation: np.ndarray  # (n, n) symmetric positive definite, unit diagonal, in the order of names
    kind = KIND

    def __post_init__(self):
        self.names = tuple(self.names)
        self.correlation = np.array(self.correlation, dtype=float)
        problem = correlation_problem(self.correlation)
        if problem:
            raise ValueError(f"correlation{problem[0]}: {problem[1]}")
        self.cholesky = np.linalg.cholesky(self.correlation)

    def columns(self, params) -> list[int]:
        """The column of each of `names` among the parameters `params`."""
        order = {p.name: k for k, p in enumerate(params)}
        return [order[name] for name in self.names]

    def germs(self, params) -> list[str]:
        """The germ of each parameter: standard normal in the group, the law's own outside it."""
        grouped = set(self.names)
        return ["normal" if p.name in grouped else p.germ for p in params]

    def to_physical(self, params, xi: np.ndarray, kappa: np.ndarray) -> np.ndarray:
        """κ = T(ξ) from independent ξ (N, d) and κ (N, d) of the independent maps, columns in the order
        of `params`: the group's columns of κ replaced by the Nataf transform."""
        columns = self.columns(params)
        z = xi[:, columns] @ self.cholesky.T
        for i, k in enumerate(columns):
            law = params[k]
            kappa[:, k] = law.to_physical(GERMS[law.germ].from_normal(z[:, i]))
        return kappa

    def to_standard(self, params, xi: np.ndarray) -> np.ndarray:
        """ξ = T⁻¹(κ) from ξ (N, d) of the independent maps of κ (each marginal's own germ variable):
        the inverse of to_physical."""
        columns = self.columns(params)
        z = np.column_stack([GERMS[params[k].germ].to_normal(xi[:, k]) for k in columns])
        xi[:, columns] = solve_triangular(self.cholesky, z.T, lower=True).T
        return xi

    def mapping(self) -> dict:
        """The `dependence:` block as plain data (YAML, JSON)."""
        return {"kind": self.kind, "parameters": list(self.names), "correlation": self.correlation.tolist()}

    def summary(self) -> dict:
        """What summary.json says of it: the block, and what the Sobol' indices are of."""
        return {**self.mapping(), "sobol_of": sobol_meaning(self.names)}


def sobol_meaning(names) -> str:
    """What the Sobol' indices are of, when `names` are correlated by a Gaussian copula."""
    names = list(names)
    return (f"independent standard variables in the Cholesky order {', '.join(names)}: the index of {names[0]} "
            f"counts all of {names[0]}'s effect, also through its correlation with the others; each later "
            "one only the part of its parameter independent of those listed before it")
