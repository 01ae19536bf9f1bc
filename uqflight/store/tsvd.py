"""Incremental thin SVD of a T×N data matrix grown by blocks of columns (one column per run).

The paper (section 4.1.1, Table 2) compresses the time histories of a campaign on the fly: a thin SVD
of the first group of samples, then an update with each new group (Brand, "Fast low-rank modifications
of the thin singular value decomposition", 2006). Means and variances come straight from the factors
(`uqflight.analysis.moments.weighted_moments`); samples are rebuilt block by block only where a
quantile or a PDF needs them.
"""
from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import scipy.linalg

_EPS = np.finfo(float).eps


class IncrementalSVD:
    """A ≈ U diag(s) Vᵀ, keeping the singular values σ_k > tol·σ_1.

    `update` appends columns to A; U (T, r) and V (N, r) are re-orthogonalised whenever
    ‖UᵀU − I‖_F or ‖VᵀV − I‖_F exceeds `ortho_tol`, so hundreds of updates stay stable.
    """

    def __init__(self, tol: float, ortho_tol: float = 1e-12):
        if not 0 <= tol < 1:
            raise ValueError(f"tSVD tolerance must lie in [0, 1), got {tol}")
        self.tol = tol
        self.ortho_tol = ortho_tol
        self.U = np.zeros((0, 0))
        self.s = np.zeros(0)
        self.V = np.zeros((0, 0))

    @classmethod
    def from_factors(cls, U, s, V, tol: float, ortho_tol: float = 1e-12) -> IncrementalSVD:
        """Resume from stored factors."""
        svd = cls(tol, ortho_tol)
        svd.U, svd.s, svd.V = (np.asarray(x, dtype=float) for x in (U, s, V))
        if svd.U.shape[1] != svd.s.size or svd.V.shape[1] != svd.s.size:
            raise ValueError(f"factor shapes disagree: U {svd.U.shape}, s {svd.s.shape}, V {svd.V.shape}")
        return svd

    @property
    def rank(self) -> int:
        return self.s.size

    @property
    def n_columns(self) -> int:
        return self.V.shape[0]

    def update(self, columns) -> None:
        """Append the columns (T, n) to A and truncate to the tolerance."""
        C = np.asarray(columns, dtype=float)
        if self.rank == 0:  # nothing spans the columns yet: start from an empty basis of the right height
            self.U = np.zeros((C.shape[0], 0))
        if C.ndim != 2 or C.shape[0] != self.U.shape[0]:
            raise ValueError(f"expected columns of shape ({self.U.shape[0]}, n), got {C.shape}")
        r, n = self.rank, C.shape[1]
        # Project on the basis, twice ("twice is enough"), so the residual is orthogonal to U to rounding.
        L = self.U.T @ C
        H = C - self.U @ L
        L2 = self.U.T @ H
        H -= self.U @ L2
        L += L2
        # Pivoted QR of the residual; directions below the rounding error of C carry no information
        # (and an arbitrary J): they are dropped.
        J, K, piv = scipy.linalg.qr(H, mode="economic", pivoting=True)
        k = np.count_nonzero(np.abs(np.diag(K)) > _EPS * np.linalg.norm(C))
        K_unpivoted = np.empty((k, n))
        K_unpivoted[:, piv] = K[:k]
        core = np.block([[np.diag(self.s), L], [np.zeros((k, r)), K_unpivoted]])
        Uc, sc, Vct = np.linalg.svd(core, full_matrices=False)
        m = np.count_nonzero(sc > self.tol * sc[0]) if sc.size and sc[0] > 0 else 0
        self.U = np.hstack([self.U, J[:, :k]]) @ Uc[:, :m]
        self.V = np.vstack([self.V @ Vct[:m, :r].T, Vct[:m, r:].T])
        self.s = sc[:m]
        if max(orthogonality_loss(self.U), orthogonality_loss(self.V)) > self.ortho_tol:
            self._reorthogonalise()

    def _reorthogonalise(self) -> None:
        """Replace U and V by orthonormal bases of their spans, keeping the product U diag(s) Vᵀ."""
        Qu, Ru = np.linalg.qr(self.U)
        Qv, Rv = np.linalg.qr(self.V)
        W, self.s, Zt = np.linalg.svd((Ru * self.s) @ Rv.T)
        self.U, self.V = Qu @ W, Qv @ Zt.T


def orthogonality_loss(Q: np.ndarray) -> float:
    """‖QᵀQ − I‖_F: how far the columns of Q are from orthonormal."""
    return float(np.linalg.norm(Q.T @ Q - np.eye(Q.shape[1])))


def iter_column_blocks(U, s, V, block: int = 1000) -> Iterator[np.ndarray]:
    """The columns of A rebuilt `block` at a time, each block as a (n_block, T) row-major array."""
    for start in range(0, V.shape[0], block):
        yield (V[start:start + block] * s) @ U.T
