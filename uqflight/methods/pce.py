"""A polynomial chaos expansion per recorded time: x(t, ξ) ≈ Σ_α c_α(t) Ψ_α(ξ) (Eq. 19)."""
from dataclasses import dataclass

import numpy as np

from ..parameters.germs import draw_germs
from .basis import orthonormal_basis

@dataclass
class PCE:
    """Coefficients (Z, T) of the orthonormal basis named by ``indices`` (Z, d) over ``germs``.

    Because the basis is orthonormal, the mean is the constant coefficient and the variance
    the sum of the other coefficients squared (Eq. 53 without the β! of unnormalised Hermite).
    ``selection``: what a selecting method (sparse) chose, for summary.json; None otherwise.
    """

    germs: list[str]
    indices: np.ndarray
    coefficients: np.ndarray
    selection: dict | None = None

    def _is_constant(self) -> np.ndarray:
        return ~np.asarray(self.indices).any(axis=1)

    def mean(self) -> np.ndarray:
        """E[x] per time, (T,)."""
        return self.coefficients[self._is_constant()].sum(axis=0)

    def variance(self) -> np.ndarray:
        """var[x] per time, (T,)."""
        return (self.coefficients[~self._is_constant()] ** 2).sum(axis=0)

    def evaluate(self, xi: np.ndarray) -> np.ndarray:
        """The expansion at points xi (M, d): (M, T)."""
        return orthonormal_basis(self.germs, self.indices, xi) @ self.coefficients

    def sample(self, n: int, seed=0) -> np.ndarray:
        """The expansion at n seeded draws of the germs: (n, T), e.g. for PDFs and bands."""
        return self.evaluate(draw_germs(self.germs, n, seed))

    def _variance_share(self, terms: np.ndarray) -> np.ndarray:
        """Σ c_α² over the terms of each row of ``terms`` (d, Z), divided by the variance: (d, T)."""
        partial = terms.astype(float) @ self.coefficients**2
        variance = self.variance()
        return np.divide(partial, variance, out=np.full_like(partial, np.nan), where=variance > 0)

    def sobol_first(self) -> np.ndarray:
        """First-order Sobol' indices (Eq. 53), (d, T): terms in ξ_i alone; NaN where the variance is 0
        (whether a variance is above rounding noise is judged by the caller: analysis.resolution)."""
        involved = np.asarray(self.indices).T > 0
        return self._variance_share(involved & (involved.sum(axis=0) == 1))

    def sobol_total(self) -> np.ndarray:
        """Total Sobol' indices, (d, T): every term involving ξ_i; NaN where the variance is 0."""
        return self._variance_share(np.asarray(self.indices).T > 0)
