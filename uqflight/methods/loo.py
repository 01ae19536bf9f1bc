"""Leave-one-out (LOO) errors of a (weighted) least-squares fit, from one factorisation.

For the fit of Y (N, T) on the design matrix X (N, Z) that minimises Σ_i w_i (y_i − x_i c)²
(w = |weights|; None = equal weights), the hat matrix is H = X (Xᵀ W X)⁻¹ Xᵀ W and the
leave-one-out residual of point i is

    y_i − ŷ_(−i) = e_i / (1 − h_ii),        e = Y − X c (the ordinary residual),

the Sherman–Morrison identity: refitting without point i is never needed. The diagonal h_ii is
‖u_i‖² for the left singular vectors U of √W X (never the Gram matrix Xᵀ W X, whose condition
number is the square of X's). A point with h_ii ≈ 1 is interpolated by the fit: removing it
leaves its coefficient undetermined, so its LOO residual does not exist and we refuse.
"""
from __future__ import annotations

import numpy as np

# 1 − h_ii below this: the fit interpolates point i (its LOO prediction is undefined).
LEVERAGE_TOLERANCE = 1e-8
# Σ w (y − ȳ)² below (this · Σw · scale²): the output does not vary beyond rounding noise.
VARIANCE_NOISE = (1e3 * np.finfo(float).eps) ** 2


def _inputs(matrix, Y, weights):
    X = np.asarray(matrix, dtype=float)
    if X.ndim != 2:
        raise ValueError(f"matrix: expected a 2-D design matrix (N, Z), got shape {X.shape}")
    Y = np.asarray(Y, dtype=float)
    one_column = Y.ndim == 1
    Y = Y.reshape(len(Y), -1) if Y.ndim <= 2 else Y
    if Y.ndim != 2 or Y.shape[0] != X.shape[0]:
        raise ValueError(f"Y: expected {X.shape[0]} rows (one per row of the design matrix), got shape {Y.shape}")
    if weights is None:
        w = np.ones(X.shape[0])
    else:
        w = np.abs(np.asarray(weights, dtype=float).ravel())
        if w.shape != (X.shape[0],) or not np.all(np.isfinite(w)):
            raise ValueError(f"weights: expected {X.shape[0]} finite numbers, got shape {np.shape(weights)}")
        if not w.sum() > 0:
            raise ValueError("weights: all zero")
    return X, Y, w, one_column


def _residuals_and_leverage(X, Y, w):
    """Ordinary residuals e (N, T) and leverages h (N,) of the weighted least-squares fit."""
    n_points, n_terms = X.shape
    if n_points < n_terms:
        raise ValueError(f"N = {n_points} points cannot determine Z = {n_terms} coefficients: "
                         "leave-one-out errors need N > Z")
    root = np.sqrt(w)
    U, s, Vt = np.linalg.svd(root[:, None] * X, full_matrices=False)
    rank = int(np.sum(s > s[0] * max(X.shape) * np.finfo(float).eps)) if s.size and s[0] > 0 else 0
    if rank < n_terms:
        raise ValueError(f"the weighted design matrix has rank {rank} < Z = {n_terms} columns: the fit is "
                         "not determined, so neither are its leave-one-out errors (lower the order or add points)")
    coefficients = Vt.T @ ((U.T @ (root[:, None] * Y)) / s[:, None])
    return Y - X @ coefficients, np.sum(U**2, axis=1)


def loo_residuals(matrix, Y, weights=None) -> np.ndarray:
    """y_i − ŷ_(−i) for every point i and column of Y: (N, T) ((N,) for a 1-D Y).

    ŷ_(−i) is the prediction at point i of the fit (weights |w|) without point i. ValueError when
    the fit is not determined (rank < Z) or interpolates some point (h_ii ≈ 1: LOO undefined).
    """
    X, Y, w, one_column = _inputs(matrix, Y, weights)
    residuals, leverage = _residuals_and_leverage(X, Y, w)
    interpolated = np.flatnonzero(1.0 - leverage < LEVERAGE_TOLERANCE)
    if interpolated.size:
        shown = ", ".join(map(str, interpolated[:10])) + (", ..." if interpolated.size > 10 else "")
        raise ValueError(f"the fit interpolates {interpolated.size} of the {X.shape[0]} points (leverage h_ii = 1 "
                         f"at rows {shown}): without such a point its coefficient is undetermined, so the "
                         "leave-one-out error is undefined; use more points than terms or a lower order")
    loo = residuals / (1.0 - leverage)[:, None]
    return loo[:, 0] if one_column else loo


def relative_loo_error(matrix, Y, weights=None) -> np.ndarray:
    """Σ w_i (y_i − ŷ_(−i))² / Σ w_i (y_i − ȳ_w)² per column of Y: (T,) (a float for a 1-D Y).

    w = |weights| (equal when None), as in the fit; ȳ_w is the w-weighted mean. NaN where the
    denominator is zero or rounding noise (a column that does not vary): the caller reports null.
    """
    X, Y, w, one_column = _inputs(matrix, Y, weights)
    loo = loo_residuals(X, Y, w)
    numerator = w @ loo**2
    mean = (w @ Y) / w.sum()
    denominator = w @ (Y - mean) ** 2
    scale = np.maximum(np.abs(Y).max(axis=0, initial=0.0), np.finfo(float).tiny)
    resolved = denominator > VARIANCE_NOISE * w.sum() * scale**2
    error = np.divide(numerator, denominator, out=np.full(Y.shape[1], np.nan), where=resolved)
    return float(error[0]) if one_column else error


__all__ = ["loo_residuals", "relative_loo_error"]
