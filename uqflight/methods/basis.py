"""Orthonormal polynomial chaos basis: total-degree multi-indices and their polynomials.

Each input is driven by a standard variable ξ_k, its germ (`uqflight.parameters.germs`), whose
three-term recurrence gives 1-D polynomials orthonormal under its law (He_n/√n! for N(0, 1),
√(2n+1)·P_n for U(−1, 1)), so the products satisfy E[Ψ_α Ψ_β] = δ_αβ.
"""
from itertools import combinations_with_replacement

import numpy as np

from ..parameters.germs import GERMS, check_germs, germ_columns


def total_degree_indices(dim: int, order: int) -> np.ndarray:
    """Multi-indices α with |α| ≤ order, shape (Z, dim), graded by degree, constant first.

    Z = C(dim + order, order). Within one degree the order is reverse lexicographic
    (ξ_1² before ξ_1ξ_2 before ξ_2²), as in chaospy's graded ordering.
    """
    rows = [
        np.bincount(np.asarray(choice, dtype=int), minlength=dim)
        for degree in range(order + 1)
        for choice in combinations_with_replacement(range(dim), degree)
    ]
    return np.array(rows, dtype=int).reshape(-1, dim)


def orthonormal_polynomials(germ: str, x: np.ndarray, order: int) -> np.ndarray:
    """Values of the orthonormal 1-D polynomials p_0..p_order of ``germ`` at x, shape (N, order+1)."""
    return _Recurrence(germ, order)(np.ravel(x))


def orthonormal_basis(germs, indices: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """Ψ_α(ξ_j) for every point ξ_j (rows of xi, (N, d)) and multi-index α (rows of indices): (N, Z)."""
    return Basis(germs, indices)(xi)


class Basis:
    """Ψ_α for fixed germs and multi-indices, its recurrences worked out once: a callable
    ξ (N, d) → (N, Z), for evaluating the same basis many times (a sampler's every step). The inputs
    of one germ run through their recurrence together; the product over inputs is taken in input order."""

    def __init__(self, germs, indices: np.ndarray):
        self.germs = check_germs(germs)
        self.indices = np.asarray(indices, dtype=int)
        self._groups = [(columns, _Recurrence(germ, int(self.indices[:, columns].max(initial=0))))
                        for germ, columns in germ_columns(self.germs)]  # (input columns, recurrence) per germ

    def __call__(self, xi: np.ndarray) -> np.ndarray:
        xi = np.asarray(xi, dtype=float).reshape(-1, len(self.germs))
        tables = [None] * len(self.germs)
        for columns, polynomials in self._groups:
            values = polynomials(xi[:, columns])  # (N, inputs of the germ, order + 1)
            for position, k in enumerate(columns):
                tables[k] = values[:, position]
        basis = np.ones((xi.shape[0], self.indices.shape[0]))
        for k, table in enumerate(tables):
            basis *= table[:, self.indices[:, k]]
        return basis


class _Recurrence:
    """p_0..p_order of one germ by its three-term recurrence x p_n = β_{n+1} p_{n+1} + α_n p_n + β_n p_{n−1},
    p_{−1} = 0, with α and β looked up once; values (..., order + 1) at x of any shape."""

    def __init__(self, germ: str, order: int):
        self.order = order
        self.alpha = GERMS[germ].recurrence_alpha(np.arange(order, dtype=float))
        self.beta = GERMS[germ].recurrence_beta(np.arange(1, order + 1, dtype=float))

    def __call__(self, x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        values = np.empty(x.shape + (self.order + 1,))
        values[..., 0] = 1.0
        alpha, beta = self.alpha, self.beta
        if self.order >= 1:
            values[..., 1] = (x - alpha[0]) / beta[0]
            for n in range(1, self.order):
                values[..., n + 1] = ((x - alpha[n]) * values[..., n] - beta[n - 1] * values[..., n - 1]) / beta[n]
        return values
