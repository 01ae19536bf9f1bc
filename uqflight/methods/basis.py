"""Orthonormal polynomial chaos basis: total-degree multi-indices and their polynomials.

Each input is driven by a standard variable ξ_k with germ ``"normal"`` (N(0, 1)) or
``"uniform"`` (U(−1, 1)). The 1-D polynomials are orthonormal under the germ's law
(He_n/√n! and √(2n+1)·P_n), so the products satisfy E[Ψ_α Ψ_β] = δ_αβ.
"""
from itertools import combinations_with_replacement

import numpy as np

from ..designs.montecarlo import germ_quantiles
from ..designs.spec import check_germs


def _recurrence_beta(germ: str, n: np.ndarray) -> np.ndarray:
    """β_n of the orthonormal three-term recurrence x p_n = β_{n+1} p_{n+1} + β_n p_{n−1}."""
    if germ == "normal":
        return np.sqrt(n)
    return n / np.sqrt(4.0 * n**2 - 1.0)


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
    if order >= 1:
        beta = _recurrence_beta(germ, np.arange(1, order + 1, dtype=float))
        values[:, 1] = x / beta[0]
        for n in range(1, order):
            values[:, n + 1] = (x * values[:, n] - beta[n - 1] * values[:, n - 1]) / beta[n]
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


def draw_germs(germs, n: int, seed) -> np.ndarray:
    """n seeded independent draws of the standard variables, (n, d): the Monte Carlo design's points."""
    germs = check_germs(germs)
    return germ_quantiles(np.random.default_rng(seed).random((n, len(germs))), germs)
