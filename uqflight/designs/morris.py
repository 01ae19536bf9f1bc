"""Morris's elementary-effects screening (Morris 1991): the design and its estimators.

The design is R trajectories of d + 1 points each on a p-level grid {0, 1/(p−1), …, 1} of the unit
hypercube, built as SALib's `SALib.sample.morris.sample` builds them (no optimised trajectories): a base
point x* on the lower half of the grid, then each input moved once, in a random order and direction, by
the jump Δ = p / (2(p − 1)). The unit-cube points u become the germs ξ through each germ's quantile: a
bounded germ (uniform) takes the grid itself, its ends being its support's; an unbounded germ (normal)
takes, for level k of the grid, the midpoint (k + ½)/p of the k-th of p equal-probability cells, so that
no point sits at ±∞.

An elementary effect is SALib's: EE = (y_after − y_before) / Δ, signed by the direction the input moved,
Δ the jump in the unit cube. For y = Σ a_i x_i with x_i uniform on [l_i, h_i], EE_i = a_i (h_i − l_i) on
every step. Per input: μ* = mean |EE|, μ = mean EE, σ = their standard deviation (ddof = 1), and a
percentile-bootstrap interval of μ* resampling whole trajectories.
"""
from __future__ import annotations

import numpy as np

from ..analysis.proportions import Points
from ..parameters.germs import GERMS
from .base import DesignKind, count, equal_weights, is_integer
from ..text import FieldError

NOT_DRAWS = ("morris design: its runs are points of trajectories on a grid, not draws of the inputs' law: the "
             "mean, variance, band, quantiles, densities and failure share are the runs' own, not the law's; its "
             "runs give no Sobol' indices themselves; their elementary effects screen the inputs "
             "(outputs.NAME.morris)")


def morris_jump(levels: int) -> float:
    """The grid jump Δ = p / (2(p − 1)) of a p-level grid in the unit cube.

    Parameters
    ----------
    levels : int
        The number of levels p >= 2.

    Returns
    -------
    float
        Δ, a whole number p/2 of grid steps when p is even.
    """
    return levels / (2.0 * (levels - 1))


def morris_unit_points(trajectories: int, d: int, levels: int, seed: int) -> np.ndarray:
    """The R trajectories of a Morris design in the unit cube, stacked: (R (d + 1), d).

    Parameters
    ----------
    trajectories : int
        R >= 1.
    d : int
        The number of inputs.
    levels : int
        The grid's levels p (even, >= 2).
    seed : int
        Seeds numpy's default_rng: the base points, orders and directions.

    Returns
    -------
    numpy.ndarray
        Rows of trajectory r at r (d + 1) … r (d + 1) + d; consecutive rows of a trajectory differ in
        one input by ±Δ, each input moving once.
    """
    rng = np.random.default_rng(seed)
    delta = morris_jump(levels)
    base = np.linspace(0.0, 1.0 - delta, levels // 2)  # the lower half of the grid: x* + Δ stays inside
    lower = np.tril(np.ones((d + 1, d)), -1)  # Morris's B: row k has the first k inputs moved
    runs = []
    for _ in range(trajectories):
        order = rng.permutation(d)
        direction = rng.choice([-1.0, 1.0], d)
        start = rng.choice(base, d)
        moved = lower[:, np.argsort(order)]  # input order[k] moves at step k + 1
        runs.append(start + 0.5 * delta * ((2.0 * moved - 1.0) * direction + 1.0))
    return np.rint(np.vstack(runs) * (levels - 1)) / (levels - 1)  # exactly on the grid (no rounding past 1)


def morris_germs(u: np.ndarray, germs: list[str], levels: int) -> np.ndarray:
    """The germs ξ of unit-cube grid points `u` (N, d): a bounded germ's quantile of u, an unbounded germ's
    quantile of its level's cell midpoint (k + ½)/p (module docstring).

    Parameters
    ----------
    u : numpy.ndarray
        Points of the p-level grid in [0, 1]^d.
    germs : list of str
        Each column's germ (parameters.germs.GERMS).
    levels : int
        p.

    Returns
    -------
    numpy.ndarray
        ξ, shaped as `u`.
    """
    xi = np.empty_like(u, dtype=float)
    for k, name in enumerate(germs):
        germ = GERMS[name]
        bounded = np.isfinite(germ.support).all()
        column = u[:, k] if bounded else (np.rint(u[:, k] * (levels - 1)) + 0.5) / levels
        xi[:, k] = germ.quantile(column)
    return xi


def elementary_effects(xi: np.ndarray, Y: np.ndarray, ok: np.ndarray, levels: int) -> tuple[np.ndarray, int]:
    """The elementary effects of the complete trajectories: ((R_ok, d, T), the trajectories dropped).

    Parameters
    ----------
    xi : numpy.ndarray
        Every run's germs, (R (d + 1), d), in design order.
    Y : numpy.ndarray
        The `ok` runs' values, (n_ok, T).
    ok : numpy.ndarray
        bool (R (d + 1),): the runs that give a value; a trajectory with any other run is dropped.
    levels : int
        p, giving the jump Δ.

    Returns
    -------
    tuple
        EE[r, i, t] = (y after input i moved − y before) / Δ × the direction it moved, and the count of
        trajectories dropped.
    """
    n, d = xi.shape
    r, remainder = divmod(n, d + 1)
    if remainder or r < 1:
        raise ValueError(f"{n} runs do not form trajectories of {d} + 1 points")
    complete = ok.reshape(r, d + 1).all(axis=1)
    rows = (np.cumsum(ok) - 1).reshape(r, d + 1)[complete]  # the complete trajectories' rows among the ok runs
    values = Y[rows]  # (R_ok, d + 1, T)
    step = np.diff(xi.reshape(r, d + 1, d)[complete], axis=1)  # (R_ok, d, d): one input nonzero per step
    moved, direction = np.argmax(step != 0, axis=2), np.sign(step.sum(axis=2))
    effects = np.empty((len(rows), d, Y.shape[1]))
    trajectory = np.arange(len(rows))[:, None]
    effects[trajectory, moved] = np.diff(values, axis=1) * direction[..., None] / morris_jump(levels)
    return effects, int(r - complete.sum())


def morris_measures(effects: np.ndarray, n_boot: int, seed: int, confidence: float = 0.95) -> dict:
    """μ*, μ, σ (ddof = 1) of the elementary effects per input and time, with a percentile-bootstrap
    interval of μ* from `n_boot` resamplings of the trajectories (numpy default_rng(seed)).

    Parameters
    ----------
    effects : numpy.ndarray
        (R, d, T) from `elementary_effects`.
    n_boot : int
        Bootstrap resamples; 0 gives μ* itself as both ends of its interval.
    seed : int
        Seeds the resampling.
    confidence : float
        The interval's level.

    Returns
    -------
    dict
        {"mu_star", "mu", "sigma": (d, T), "mu_star_ci": (2, d, T)}; NaN where undefined (σ with one
        trajectory, everything with none).
    """
    r = len(effects)
    if r == 0:
        nan = np.full(effects.shape[1:], np.nan)
        return {"mu_star": nan, "mu": nan, "sigma": nan, "mu_star_ci": np.stack([nan, nan])}
    size = np.abs(effects)
    mu_star = size.mean(axis=0)
    sigma = effects.std(axis=0, ddof=1) if r > 1 else np.full(mu_star.shape, np.nan)
    if n_boot:
        counts = np.random.default_rng(seed).multinomial(r, np.full(r, 1.0 / r), size=n_boot)
        replicates = (counts @ size.reshape(r, -1) / r).reshape(n_boot, *mu_star.shape)
        ci = np.quantile(replicates, [0.5 * (1 - confidence), 0.5 * (1 + confidence)], axis=0)
    else:
        ci = np.stack([mu_star, mu_star])
    return {"mu_star": mu_star, "mu": effects.mean(axis=0), "sigma": sigma, "mu_star_ci": ci}


def morris_screening(xi: np.ndarray, Y: np.ndarray, ok: np.ndarray, info: dict, n_boot: int, seed: int,
                     names: list[str]) -> tuple[dict, str | None]:
    """The Morris measures of values `Y` of the `ok` runs of a Morris design, and the note of the
    trajectories dropped (None when none is); ValueError naming the fact of `info` that does not fit the runs.

    Parameters
    ----------
    xi : numpy.ndarray
        Every run's germs, in design order.
    Y : numpy.ndarray
        The ok runs' values, (n_ok, T).
    ok : numpy.ndarray
        bool, per run: those that give a value.
    info : dict
        The design's recorded facts (`levels`).
    n_boot : int
        Bootstrap resamples of μ*'s interval.
    seed : int
        Seeds the bootstrap.
    names : list of str
        The inputs' names, in the columns' order.

    Returns
    -------
    tuple
        ({name: {"mu_star", "mu", "sigma" (T,), "mu_star_ci": {"lower", "upper"}}} of `morris_measures`, the
        note or None).
    """
    problem = info_problem(info, len(xi), xi.shape[1])
    if problem:
        raise FieldError(f"design.info.{problem[0]}", f"{problem[1]}, got {info.get(problem[0])!r}")
    levels = info["levels"]
    effects, dropped = elementary_effects(xi, Y, ok, levels)
    note = None
    if dropped:
        kept = len(effects)
        note = (f"the Morris measures are estimated on the {kept} complete trajectories of {kept + dropped} "
                f"(a trajectory with a failed or undefined run has no elementary effect of the inputs after it): "
                f"{dropped} dropped" + ("; σ is undefined with fewer than 2" if kept < 2 else ""))
    found = morris_measures(effects, n_boot, seed)
    return {name: {"mu_star": found["mu_star"][i], "mu": found["mu"][i], "sigma": found["sigma"][i],
                   "mu_star_ci": {"lower": found["mu_star_ci"][0][i], "upper": found["mu_star_ci"][1][i]}}
            for i, name in enumerate(names)}, note


def info_problem(info: dict, runs: int, d: int) -> tuple[str, str] | None:
    """(the key, what it expects) when a Morris design's recorded `info` does not fit its `runs` of `d`
    parameters; None when it fits."""
    levels, trajectories = info.get("levels"), info.get("trajectories")
    if not (is_integer(levels) and levels >= 2 and levels % 2 == 0):
        return "levels", "expected an even integer >= 2"
    if not (is_integer(trajectories) and trajectories * (d + 1) == runs):
        return "trajectories", f"expected the {runs} runs' trajectories of {d} + 1 points"
    return None


class Morris(DesignKind):
    """`morris` {trajectories: R >= 2, levels: p (even, >= 2, default 4)}: N = R (d + 1) runs, trajectory
    after trajectory, equal weights (the runs' own average, not of draws of the law).

    Examples
    --------
    >>> import numpy as np
    >>> from uqflight.designs import build_design
    >>> design = build_design({"kind": "morris", "trajectories": 3}, ["uniform", "uniform"], seed=0)
    >>> len(design.xi), design.info["jump"]  # R (d + 1) = 3 × 3 runs; Δ = p / (2 (p − 1)), p = 4
    (9, 0.6666666666666666)
    >>> steps = np.diff(design.xi.reshape(3, 3, 2), axis=1)  # (trajectory, step, input)
    >>> (steps != 0).sum(axis=2).tolist()  # every step moves one input
    [[1, 1], [1, 1], [1, 1]]
    >>> sorted(set(np.abs(steps).max(axis=2).round(12).ravel().tolist()))  # by 2Δ on ξ = 2u − 1
    [1.333333333333]
    """

    kind = "morris"
    keys = {"trajectories": count(2, description="Required: the trajectories R >= 2, of d + 1 runs each (N = R(d + 1) "
                                                "runs). `trajectories: 20`"),
            "levels": count(2, default=4, description="The levels p of the grid in the unit cube, even, >= 2; the "
                                                       "jump is Δ = p/(2(p − 1)). Default 4. `levels: 6`")}
    example = {"kind": "morris", "trajectories": 4}
    sampling = Points()
    not_draws = NOT_DRAWS
    screening = staticmethod(morris_screening)
    screening_name = "morris"
    info_problem = staticmethod(info_problem)

    def settings(self, spec):
        """Its keys, `levels` even."""
        found = super().settings(spec)
        if found["levels"] % 2:
            raise FieldError("design.levels", f"expected an even number of levels (the jump Δ = p/(2(p−1)) is then "
                             f"p/2 grid steps), got {found['levels']}")
        return found

    def size(self, spec, germs):
        """R (d + 1)."""
        return spec["trajectories"] * (len(germs) + 1)

    def points(self, spec, germs, seed):
        r, levels = spec["trajectories"], spec["levels"]
        u = morris_unit_points(r, len(germs), levels, seed)
        info = {"trajectories": r, "levels": levels, "jump": morris_jump(levels), "samples": len(u), "seed": seed}
        return morris_germs(u, germs, levels), equal_weights(len(u)), info
