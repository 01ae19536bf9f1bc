"""Sparse PCE: least-angle regression (LARS) or orthogonal matching pursuit (OMP) with the basis and
order chosen by the corrected leave-one-out error (Blatman & Sudret 2011), as UQLab and OpenTURNS do.

Candidates: for each order p = 1..max_order, the hyperbolic set {α : (Σ_k α_k^q)^(1/q) ≤ p} (q = 1:
total degree). The points are fitted as they are, unweighted (a grid by its points, as regression).
The path (scikit-learn's `lars_path` or `orthogonal_mp`, on the centred, unit-norm columns) orders
the non-constant candidates by when they enter; each prefix of that order, with the constant, is
fitted by least squares and scored by its corrected leave-one-out error (Chapelle's correction)

    ε* = ε_LOO · N / (N − Z) · (1 + tr((ΨᵀΨ)⁻¹)),    ε_LOO = Σ_i (e_i / (1 − h_ii))² / Σ_i (y_i − ȳ)²,

every prefix from one QR factorisation of the ordered columns (a prefix's Q and R are leading blocks).

One basis per output for all its times: the runs (N, T) are reduced to their principal time modes
(all but MODE_TOLERANCE of the centred variance, at most MAX_MODES); each mode's scores get their own
path and best prefix, and the output's basis is the union of these prefixes, fitted by least squares at
every time. The union's ε* summed over time (Σ_t of the squared LOO residuals over Σ_t of the squared
deviations: the variance-weighted mean of the per-time errors) picks the order. Errors below ROUNDING
count as equal, so among exact fits the fewest terms and the lowest order win.
"""
from __future__ import annotations

import warnings

import numpy as np

from ..parameters.germs import check_germs
from .kind import DEFAULT_ORDER, METHODS, Key, Method
from .basis import orthonormal_basis, total_degree_indices
from .pce import PCE

SELECTIONS = ("lars", "omp")
MAX_MODES = 20  # principal time modes of an output that get their own path
MODE_TOLERANCE = 1e-10  # share of an output's centred variance its ignored modes may hold
ROUNDING = 1e-20  # corrected LOO errors below this are rounding: an exact fit
LEVERAGE_TOLERANCE = 1e-8  # 1 − h_ii below this: the prefix interpolates a point (LOO undefined)


def hyperbolic_indices(dim: int, order: int, q: float) -> np.ndarray:
    """Multi-indices with (Σ α_k^q)^(1/q) ≤ order, graded as total_degree_indices, constant first."""
    indices = total_degree_indices(dim, order)
    if q >= 1:
        return indices
    norms = ((indices.astype(float) ** q).sum(axis=1)) ** (1.0 / q)
    return indices[norms <= order * (1 + 1e-12)]


def _reduced(Y: np.ndarray, scale) -> np.ndarray:
    """Y @ scale's geometry over time in r columns: Y @ P diag(σ) for scale = P diag(σ) Qᵀ (Q orthonormal)."""
    if scale is None:
        return Y
    P, sigma, _ = np.linalg.svd(np.asarray(scale, dtype=float), full_matrices=False)
    return Y @ (P * sigma)


def _modes(Y: np.ndarray) -> np.ndarray:
    """The scores (N, k) of the principal time modes of the centred Y that hold all but MODE_TOLERANCE
    of its variance (at most MAX_MODES); (N, 0) for an output that does not vary."""
    centred = Y - Y.mean(axis=0)
    W, s, _ = np.linalg.svd(centred, full_matrices=False)
    energy = np.cumsum(s**2)
    if not energy.size or energy[-1] <= 0:
        return np.zeros((len(Y), 0))
    count = min(int(np.searchsorted(energy, (1 - MODE_TOLERANCE) * energy[-1])) + 1, MAX_MODES, len(s))
    return W[:, :count] * s[:count]


def _path(selection: str, columns: np.ndarray, target: np.ndarray, steps: int) -> list[int]:
    """The candidates (columns of `columns`, centred and of unit norm) in the order the path enters them."""
    from sklearn.linear_model import lars_path, orthogonal_mp

    if selection == "lars":
        _, active, _ = lars_path(columns, target, method="lar", max_iter=steps)
        return [int(j) for j in active]
    with warnings.catch_warnings():  # it stops early where the dictionary turns dependent: that is the path's end
        warnings.simplefilter("ignore", RuntimeWarning)
        path = np.atleast_2d(orthogonal_mp(columns, target, n_nonzero_coefs=steps, return_path=True).T)
    order: list[int] = []
    for coefficients in path.reshape(-1, columns.shape[1]):
        order += [int(j) for j in np.flatnonzero(coefficients) if j not in order]
    return order


def _corrected_loo(matrix: np.ndarray, Y: np.ndarray) -> np.ndarray:
    """ε* (Chapelle's correction) of the least-squares fit of Y (N, T) on every prefix of the columns of
    matrix (N, M): (M,), the error summed over Y's columns; inf where a prefix is rank deficient or
    interpolates a point."""
    n, m = matrix.shape
    Q, R = np.linalg.qr(matrix)
    diagonal = np.abs(np.diag(R))
    independent = np.cumprod(diagonal > max(n, m) * np.finfo(float).eps * diagonal.max(initial=0.0)).astype(bool)
    Y = Y.reshape(n, -1)
    deviations = ((Y - Y.mean(axis=0)) ** 2).sum()
    coordinates = Q.T @ Y  # (M, T)
    leverage = np.cumsum(Q**2, axis=1)  # (N, M): h_ii of each prefix
    errors = np.full(m, np.inf)
    fitted = np.zeros_like(Y)
    inverse = np.linalg.inv(R[: int(independent.sum()), : int(independent.sum())]) if independent.any() else None
    trace = np.cumsum((inverse**2).sum(axis=0)) if inverse is not None else np.zeros(0)
    for z in range(m):
        fitted = fitted + Q[:, z : z + 1] * coordinates[z]
        size = z + 1
        if not independent[z] or size >= n or np.any(1 - leverage[:, z] < LEVERAGE_TOLERANCE):
            continue
        loo = ((Y - fitted) / (1 - leverage[:, z])[:, None]) ** 2
        ratio = loo.sum() / deviations if deviations > 0 else 0.0
        errors[z] = ratio * n / (n - size) * (1 + trace[z])
    return errors


def _order_basis(candidates: np.ndarray, points: np.ndarray, germs, Y: np.ndarray, selection: str):
    """The union basis (row numbers into candidates, constant first) and its ε* for one candidate set."""
    n = len(points)
    matrix = orthonormal_basis(germs, candidates, points)
    columns = matrix[:, 1:] - matrix[:, 1:].mean(axis=0)
    norms = np.linalg.norm(columns, axis=0)
    usable = np.flatnonzero(norms > 1e-12 * max(norms.max(initial=0.0), 1.0))
    steps = min(len(usable), n - 2)
    chosen = {0}
    if steps > 0:
        unit = columns[:, usable] / norms[usable]
        for scores in _modes(Y).T:
            entered = [int(usable[j]) + 1 for j in _path(selection, unit, scores, steps)]
            errors = _corrected_loo(matrix[:, [0, *entered]], scores)
            best = int(np.argmin(np.maximum(errors, ROUNDING)))
            if np.isfinite(errors[best]):
                chosen.update(entered[:best])
    terms = sorted(chosen)
    error = _corrected_loo(matrix[:, terms], Y)[-1] if len(terms) < n else np.inf
    return terms, float(error)


def _q_problem(q) -> str | None:
    if isinstance(q, bool) or not isinstance(q, (int, float)) or not 0 < q <= 1:
        return f"expected a number in (0, 1] (1: total degree; below 1: hyperbolic truncation), got {q!r}"
    return None


def sparse_pce(xi, weights, Y, germs, order: int = 3, x0=None, *, scale=None, selection: str = "lars",
               q: float = 1.0) -> PCE:
    """The sparse PCE of Y = rows @ scale (scale None: Y (N, T)) at the points xi (N, d): orders 1..order,
    q-hyperbolic candidates, `selection` lars or omp; its `selection` record says what was chosen.
    ValueError when no candidate order gives a defined leave-one-out error (too few points)."""
    problem = METHODS["sparse"].problem({"selection": selection, "q": q})
    if problem:
        raise ValueError(f"{problem[0]}: {problem[1]}")
    germs = check_germs(germs)
    points = np.asarray(xi, dtype=float).reshape(-1, len(germs))
    rows = np.asarray(Y, dtype=float).reshape(len(points), -1)
    reduced = _reduced(rows, scale)
    found = {}
    for p in range(1, order + 1):
        candidates = hyperbolic_indices(len(germs), p, q)
        terms, error = _order_basis(candidates, points, germs, reduced, selection)
        found[p] = (candidates[terms], error)
    errors = {p: error for p, (_, error) in found.items()}
    best = min(errors, key=lambda p: (max(errors[p], ROUNDING), p))
    if not np.isfinite(errors[best]):
        raise ValueError(f"sparse PCE: the {len(points)} points give no candidate basis of order 1 to {order} a "
                         "defined leave-one-out error (every basis the path selects interpolates them): add points")
    indices = found[best][0]
    matrix = orthonormal_basis(germs, indices, points)
    coefficients = np.linalg.lstsq(matrix, rows, rcond=None)[0]
    if scale is not None:
        coefficients = coefficients @ np.asarray(scale, dtype=float)
    record = {"selection": selection, "q": float(q), "max_order": int(order), "order": int(indices.sum(axis=1).max()),
              "candidate_order": int(best), "terms": indices.tolist(), "loo_error": errors[best],
              "loo_error_by_order": {str(p): e for p, e in errors.items()}}
    return PCE(germs, indices, coefficients, selection=record)


class Sparse(Method):
    """Sparse PCE: candidate terms up to `max_order` (q-hyperbolic), ordered by LARS or OMP, the basis and
    order chosen by the corrected leave-one-out error; on any design (see [methods](../methods.md)).

    Examples
    --------
    >>> import numpy as np
    >>> from uqflight.methods import Method
    >>> xi = np.random.default_rng(0).standard_normal((20, 3))  # 20 draws of 3 normal germs
    >>> y = 3 + 2 * xi[:, :1] + (xi[:, 1:2] ** 2 - 1)  # 3 + 2 He₁(ξ₁) + He₂(ξ₂): 3 of 10 candidates
    >>> result = Method.of("sparse").fit(xi, np.full(20, 0.05), y, ["normal"] * 3, order=2, sampled=True)
    >>> result.pce.selection["terms"]
    [[0, 0, 0], [1, 0, 0], [0, 2, 0]]
    >>> round(float(result.mean[0]), 12), round(float(result.variance[0]), 12)  # 3 and 2² + Var[ξ²] = 4 + 2
    (3.0, 6.0)
    """

    kind, label, rule, failed_runs, partial, weighted = "sparse", "sparse", "selection", "extrapolated", True, False
    order_key = "max_order"
    keys = {"max_order": Key(DEFAULT_ORDER, "sparse only: the largest total degree of the candidate terms, >= 1. "
                                            "Default 2. `max_order: 5`", minimum=1),
            "selection": Key("lars", "sparse only: `lars` (least-angle regression, the default) or `omp` (orthogonal "
                                     "matching pursuit) orders the candidate terms.", choices=SELECTIONS),
            "q": Key(1.0, "sparse only: the hyperbolic truncation ‖α‖_q ≤ max_order, 0 < q ≤ 1; 1 (the default) "
                          "is total degree, smaller keeps fewer interactions. `q: 0.75`", check=_q_problem)}

    def points_problem(self, order: int, xi, weights, germs: list[str], sampled: bool,
                       allow_aliasing: bool = False) -> str | None:
        """At least 3 points; whether a basis it selects has a defined leave-one-out error is known at the fit."""
        if len(xi) >= 3:
            return None
        return (f"{self.kind} needs at least 3 points to choose a basis by its leave-one-out error, but there are "
                f"{len(xi)}: add points")

    def expansion(self, xi, weights, Y, germs, order: int, x0=None, scale=None, **settings) -> PCE:
        return sparse_pce(xi, weights, Y, germs, order, x0, scale=scale, **settings)


__all__ = ["SELECTIONS", "Sparse", "hyperbolic_indices", "sparse_pce"]
