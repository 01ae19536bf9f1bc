"""Saltelli's pick-freeze design for Monte Carlo estimators of Sobol' indices."""
from __future__ import annotations

import numpy as np

from ..analysis import proportions
from ..parameters.germs import germ_quantiles
from .base import DesignKind, count, equal_weights, is_integer
from .montecarlo import sobol_points


def pick_freeze_rows(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rows [A; B; AB_1; …; AB_d], n each, where AB_i is A with column i taken from B."""
    n, d = a.shape
    ab = np.repeat(a[np.newaxis], d, axis=0)
    columns = np.arange(d)
    ab[columns, :, columns] = b.T
    return np.concatenate([a, b, ab.reshape(d * n, d)])


class PickFreeze(DesignKind):
    """`pick_freeze` {samples: n}: N = n(d + 2) rows.

    A and B are the two halves of one scrambled Sobol' sequence in 2d dimensions (seeded), mapped
    to the germs; QMC keeps the estimators' variance below that of plain Monte Carlo.

    Examples
    --------
    >>> from uqflight.designs import build_design, design_size
    >>> spec, germs = {"kind": "pick_freeze", "samples": 4}, ["normal", "normal", "uniform"]
    >>> design_size(spec, germs)  # N = n (d + 2) = 4 × 5
    20
    >>> xi = build_design(spec, germs, seed=0).xi
    >>> A, B, AB1 = xi[:4], xi[4:8], xi[8:12]  # rows [A; B; AB_1; AB_2; AB_3]
    >>> len(xi), bool((AB1[:, 0] == B[:, 0]).all() and (AB1[:, 1:] == A[:, 1:]).all())  # AB_1: A, column 1 of B
    (20, True)
    """

    kind = "pick_freeze"
    keys = {"samples": count(1, description="Base rows n, >= 1: N = n(d + 2) runs. `samples: 1024`")}
    example = {"kind": "pick_freeze", "samples": 16}
    sampling = proportions.PickFreeze()
    sobol_from_runs = True

    def size(self, spec, germs):
        return spec["samples"] * (len(germs) + 2)

    def points(self, spec, germs, seed):
        n, d = spec["samples"], len(germs)
        ab = germ_quantiles(sobol_points(n, 2 * d, scramble=True, seed=seed), germs + germs)
        xi = pick_freeze_rows(ab[:, :d], ab[:, d:])
        info = {"n_base": n, "samples": len(xi), "base_sequence": "scrambled Sobol'", "seed": seed}
        return xi, equal_weights(len(xi)), info

    def info_problem(self, info, runs, d):
        if not (is_integer(info.get("n_base")) and info["n_base"] * (d + 2) == runs):
            return "n_base", f"expected the base rows n of the {runs} runs, n ({d} parameters + 2)"
        return None
