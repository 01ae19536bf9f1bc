"""Saltelli's pick-freeze design for Monte Carlo estimators of Sobol' indices."""
from __future__ import annotations

import numpy as np

from ..parameters.germs import germ_quantiles
from .montecarlo import equal_weights, sobol_points
from .spec import check_keys, given_count, integer


def pick_freeze_rows(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rows [A; B; AB_1; …; AB_d], n each, where AB_i is A with column i taken from B."""
    n, d = a.shape
    ab = np.repeat(a[np.newaxis], d, axis=0)
    columns = np.arange(d)
    ab[columns, :, columns] = b.T
    return np.concatenate([a, b, ab.reshape(d * n, d)])


def pick_freeze_size(spec: dict, germs: list[str]) -> int | None:
    """Runs of `pick_freeze`: n(d + 2)."""
    n = given_count(spec, "samples")
    return None if n is None else n * (len(germs) + 2)


def pick_freeze_design(spec: dict, germs: list[str], seed: int):
    """`pick_freeze` {samples: n}: N = n(d + 2) rows.

    A and B are the two halves of one scrambled Sobol' sequence in 2d dimensions (seeded), mapped
    to the germs; QMC keeps the estimators' variance below that of plain Monte Carlo.
    """
    check_keys(spec, "pick_freeze", ("samples",))
    n = integer(spec, "samples", "pick_freeze", minimum=1)
    d = len(germs)
    ab = germ_quantiles(sobol_points(n, 2 * d, scramble=True, seed=seed), germs + germs)
    xi = pick_freeze_rows(ab[:, :d], ab[:, d:])
    info = {"n_base": n, "samples": len(xi), "base_sequence": "scrambled Sobol'", "seed": seed}
    return xi, equal_weights(len(xi)), info
