"""Orthonormal polynomial chaos basis: total-degree multi-indices and their polynomials.

Each input is driven by a standard variable ξ_k, its germ (`uqflight.parameters.germs`), whose
three-term recurrence gives 1-D polynomials orthonormal under its law (He_n/√n! for N(0, 1),
√(2n+1)·P_n for U(−1, 1)), so the products satisfy E[Ψ_α Ψ_β] = δ_αβ.
"""
from itertools import combinations_with_replacement

import numpy as np

from ..parameters.germs import GERMS, check_germs


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
    x = np.asarray(x, dtype=float)
    values = np.empty((x.size, order + 1))
    values[:, 0] = 1.0
    if order >= 1:  # x p_n = β_{n+1} p_{n+1} + α_n p_n + β_n p_{n−1}, p_{−1} = 0
        alpha = GERMS[germ].recurrence_alpha(np.arange(order, dtype=float))
        beta = GERMS[germ].recurrence_beta(np.arange(1, order + 1, dtype=float))
        values[:, 1] = (x - alpha[0]) / beta[0]
        for n in range(1, order):
            values[:, n + 1] = ((x - alpha[n]) * values[:, n] - beta[n - 1] * values[:, n - 1]) / beta[n]
    return values


def orthonormal_basis(germs, indices: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """Ψ_α(ξ_j) for every point ξ_j (rows of xi, (N, d)) and multi-index α (rows of indices): (N, Z)."""
    germs = check_germs(germs)
    xi = np.asarray(xi, dtype=float).reshape(-1, len(germs))
    indices = np.asarray(indices, dtype=int)
    basis = np.ones((xi.shape[0], indices.shape[0]))
    for k, germ in enumerate(germs):
        table = orthonormal_polynomials(germ, xi[:, k], int(indices[:, k].max(initial=0)))
        basis *= table[:, indices[:, k]]
    return basis
