"""Skewness and kurtosis of a PCE in closed form, from the triple products of its orthonormal basis.

With Z = x − E[x] = Σ_{α≠0} c_α Ψ_α of total degree p, the square Z² has degree 2p and is exactly
Σ_κ e_κ Φ_κ in the orthonormal basis Φ of total degree 2p, e_κ = Σ_αβ c_α c_β E[Ψ_α Ψ_β Φ_κ].
Orthonormality gives E[Z⁴] = Σ_κ e_κ² and E[Z³] = E[Z · Z²] = Σ_κ e_κ z_κ (z: Z's coefficients
in Φ). The triple products factor over the inputs into 1-D ones, E[p_i p_j p_k] per germ, which the
germ's Gauss rule of 2p + 1 points integrates exactly (degree 4p ≤ 4p + 1). No draws, no sampling error.
"""
from __future__ import annotations

import numpy as np

from ..designs.rules import nodes_weights
from ..parameters.germs import GERMS
from .basis import orthonormal_polynomials, total_degree_indices

MAX_TENSOR_ENTRIES = 20_000_000  # Z² × Z(2p) triple products held at once (160 MB); beyond: None


def triple_products(germs: list[str], indices: np.ndarray, square_indices: np.ndarray) -> np.ndarray:
    """E[Ψ_α Ψ_β Φ_κ] for α, β rows of `indices` (Z, d) and κ rows of `square_indices` (K, d): (Z, Z, K)."""
    indices, square_indices = np.asarray(indices, dtype=int), np.asarray(square_indices, dtype=int)
    products = np.ones((len(indices), len(indices), len(square_indices)))
    for k, germ in enumerate(germs):
        top = int(square_indices[:, k].max(initial=0))
        nodes, weights = nodes_weights(GERMS[germ].default_rule, top + 1)  # exact to degree 2·top + 1
        values = orthonormal_polynomials(germ, nodes, top)  # (n, top + 1)
        table = np.einsum("n,ni,nj,nk->ijk", weights, values, values, values)
        products *= table[np.ix_(indices[:, k], indices[:, k], square_indices[:, k])]
    return products


def pce_standardised_moments(germs: list[str], indices, coefficients,
                             products=triple_products) -> tuple[np.ndarray, np.ndarray] | None:
    """Skewness E[Z³]/σ³ and Pearson's kurtosis E[Z⁴]/σ⁴ of the PCE (coefficients (Z, T)), each (T,),
    NaN where σ = 0; None when the triple products would exceed MAX_TENSOR_ENTRIES (sample instead).
    `products`: what gives the triple products (triple_products, or a memo of it where many expansions
    share a basis)."""
    indices = np.asarray(indices, dtype=int)
    coefficients = np.asarray(coefficients, dtype=float).reshape(len(indices), -1)
    varying = indices.any(axis=1)
    indices, centred = indices[varying], coefficients[varying]
    if not len(indices):  # a constant: no spread
        return np.full(coefficients.shape[1], np.nan), np.full(coefficients.shape[1], np.nan)
    order = int(indices.sum(axis=1).max())
    square_indices = total_degree_indices(indices.shape[1], 2 * order)
    if len(indices) ** 2 * len(square_indices) > MAX_TENSOR_ENTRIES:
        return None
    products = products(germs, indices, square_indices).reshape(len(indices) ** 2, -1)
    position = {tuple(row): k for k, row in enumerate(square_indices)}
    linear_rows = [position[tuple(row)] for row in indices]  # where Z's terms sit in the basis Φ
    third, fourth = np.empty(centred.shape[1]), np.empty(centred.shape[1])
    step = max(1, MAX_TENSOR_ENTRIES // max(products.shape))  # times at once: pairs and square stay bounded
    for start in range(0, centred.shape[1], step):
        c = centred[:, start:start + step]
        pairs = (c[:, None, :] * c[None, :, :]).reshape(len(products), -1)  # c_α c_β per time
        square = products.T @ pairs  # e_κ (K, times)
        third[start:start + step] = (square[linear_rows] * c).sum(axis=0)
        fourth[start:start + step] = (square**2).sum(axis=0)
    variance = (centred**2).sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        skewness = np.where(variance > 0, third / variance**1.5, np.nan)
        kurtosis = np.where(variance > 0, fourth / variance**2, np.nan)
    return skewness, kurtosis
