"""Monte Carlo pick-freeze estimators of Sobol' indices from a Saltelli design, with bootstrap CIs.

The design's runs are stacked [A (n); B (n); AB_1 (n); …; AB_d (n)], AB_i being A with
column i taken from B. Per time, with V the variance of [f(A); f(B)]:
first order (Saltelli 2010)  S_i  = mean(f(B) (f(AB_i) − f(A))) / V,
total (Jansen 1999)          ST_i = mean((f(A) − f(AB_i))²) / (2 V).

With failed runs the estimators use the complete base rows only (`complete_rows`: the rows j whose
A_j, B_j and every AB_i,j ran), which are a Saltelli design of their own of fewer rows. An index is
unresolved (`unresolved`) where its interval is wider than half the unit interval, or where the whole
interval lies outside [0, 1]: the estimate then says nothing about the share, and n is too small.
"""
import numpy as np

from .moments import as_runs_by_time


def _split_design(Y, d: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """f(A) (n, T), f(B) (n, T) and f(AB) (d, n, T), centred by the mean of [f(A); f(B)].

    The indices do not depend on a shift of f, but the Saltelli numerator's sampling error
    does: centring keeps an output like altitude (10⁴ ft ± a few) from drowning it.
    """
    Y = as_runs_by_time(Y)
    n, remainder = divmod(len(Y), d + 2)
    if remainder or n < 2:
        raise ValueError(f"{len(Y)} runs do not form a Saltelli design [A; B; AB_1..AB_{d}] of n >= 2 rows each")
    blocks = Y.reshape(d + 2, n, Y.shape[1])
    blocks = blocks - blocks[:2].mean(axis=(0, 1))
    return blocks[0], blocks[1], blocks[2:]


UNRESOLVED_WIDTH = 0.5  # an interval wider than this (half of [0, 1]) does not resolve a share
NEGLIGIBLE = 1e-4  # a variance below this share of its largest over time (std < 1 % of its largest) is negligible:
#                    an index there is the share of almost nothing, and is not flagged


def complete_rows(ok, d: int) -> np.ndarray:
    """Where the complete base rows' runs sit among the `ok` runs (bool (N,), N = n (d + 2), design order):
    indices into the ok runs, in the order [A; B; AB_1 … AB_d] of the base rows j whose d + 2 runs are all
    ok. Their count divided by d + 2 is the number of complete rows."""
    ok = np.asarray(ok, dtype=bool)
    n, remainder = divmod(ok.size, d + 2)
    if remainder:
        raise ValueError(f"{ok.size} runs do not form a Saltelli design [A; B; AB_1..AB_{d}]")
    complete = np.flatnonzero(ok.reshape(d + 2, n).all(axis=0))
    runs = (np.arange(d + 2)[:, None] * n + complete[None, :]).ravel()
    return (np.cumsum(ok) - 1)[runs]


def unresolved(index, ci) -> np.ndarray:
    """bool, shaped as `index`: the estimate is no share, its 95 % interval (`ci`: (lower, upper), each
    shaped as `index`) being wider than UNRESOLVED_WIDTH or lying wholly outside [0, 1]. An interval of no
    width is none (`bootstrap: 0` gives the estimate twice): it resolves nothing and flags nothing."""
    index = np.asarray(index, dtype=float)
    lower, upper = (np.asarray(bound, dtype=float) for bound in ci)
    with np.errstate(invalid="ignore"):
        width = upper - lower
        return np.isfinite(index) & ((width > UNRESOLVED_WIDTH) | ((width > 0) & ((lower > 1.0) | (upper < 0.0))))


def pick_freeze_indices(Y, d: int, n_boot: int = 200, seed=0, confidence: float = 0.95) -> dict[str, np.ndarray]:
    """First and total Sobol' indices per time with percentile-bootstrap confidence intervals.

    Returns {"first": (d, T), "total": (d, T), "first_ci": (2, d, T), "total_ci": (2, d, T)},
    the CIs as (lower, upper) from ``n_boot`` seeded resamplings of the n base rows (a row of A
    travels with its rows of B and AB_i). Every replicate is a row of resampling counts, so each
    mean the estimators need is one matrix product over all replicates. Where V = 0 the indices are 0.
    """
    f_a, f_b, f_ab = _split_design(Y, d)
    n = len(f_a)
    rng = np.random.default_rng(seed)
    counts = np.vstack([np.ones(n), rng.multinomial(n, np.full(n, 1.0 / n), size=n_boot)])

    def resampled_mean(per_row):
        """Mean over the rows of per_row (n, ...) for the full sample, then each replicate: (1 + n_boot, ...)."""
        return (counts @ per_row.reshape(n, -1) / n).reshape(-1, *per_row.shape[1:])

    first_sum = resampled_mean((f_b * (f_ab - f_a)).transpose(1, 0, 2))
    total_sum = resampled_mean((0.5 * (f_a - f_ab) ** 2).transpose(1, 0, 2))
    mean, mean_square = resampled_mean(0.5 * (f_a + f_b)), resampled_mean(0.5 * (f_a**2 + f_b**2))
    variance = (mean_square - mean**2)[:, None, :]

    def share(numerator):
        return np.divide(numerator, variance, out=np.zeros_like(numerator), where=variance > 0)

    first, total = share(first_sum), share(total_sum)
    tails = [0.5 * (1.0 - confidence), 0.5 * (1.0 + confidence)]

    def interval(replicates):
        """Percentile interval; without replicates (n_boot = 0) the estimate itself, twice."""
        return np.quantile(replicates[1:], tails, axis=0) if n_boot else np.stack([replicates[0]] * 2)

    return {"first": first[0], "total": total[0], "first_ci": interval(first), "total_ci": interval(total)}
