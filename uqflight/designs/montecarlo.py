"""Sampling designs: Monte Carlo and quasi-Monte Carlo points mapped to the germs, equal weights.

Uniform points u in (0, 1)^d become ξ through each germ's inverse CDF (Φ⁻¹ for normal, 2u − 1 for
uniform), so low-discrepancy structure carries over to ξ.
"""
from __future__ import annotations

import numpy as np

from ..parameters.germs import draw_germs, germ_quantiles
from .spec import check_keys, given_count, integer, optional_boolean


def equal_weights(n: int) -> np.ndarray:
    return np.full(n, 1.0 / n)


def sobol_points(n: int, d: int, scramble: bool, seed: int) -> np.ndarray:
    """The first n points of a Sobol' sequence in [0, 1)^d.

    Drawn as the next power of 2 and cut, so scipy does not warn about balance. The unscrambled
    sequence starts at the origin, which has no normal quantile, so it is skipped.
    """
    from scipy.stats import qmc

    skip = 0 if scramble else 1
    engine = qmc.Sobol(d, scramble=scramble, rng=seed)
    return engine.random_base2((n + skip - 1).bit_length())[skip : n + skip]


def samples_size(spec: dict, germs: list[str]) -> int | None:
    """Runs of `monte_carlo`, `halton` and `latin_hypercube`: `samples`."""
    return given_count(spec, "samples")


def sobol_size(spec: dict, germs: list[str]) -> int | None:
    """Runs of `sobol`: samples × replicates."""
    n = given_count(spec, "samples")
    replicates = given_count(spec, "replicates") if "replicates" in spec else 1
    return None if n is None or replicates is None else n * replicates


def monte_carlo_design(spec: dict, germs: list[str], seed: int):
    """`monte_carlo` {samples}: independent draws from numpy's default_rng(seed)."""
    check_keys(spec, "monte_carlo", ("samples",))
    n = integer(spec, "samples", "monte_carlo", minimum=1)
    return draw_germs(germs, n, seed), equal_weights(n), {"samples": n, "generator": "numpy default_rng", "seed": seed}


def sobol_design(spec: dict, germs: list[str], seed: int):
    """`sobol` {samples, scramble (default true), replicates (default 1)}: Sobol' points, Owen-scrambled
    with the seed. With R replicates (randomised QMC), R independent scrambles of `samples` points each
    (seeds spawned from the campaign's), stacked replicate after replicate: R × samples runs whose
    replicate-to-replicate spread gives the standard error of every statistic."""
    check_keys(spec, "sobol", ("samples", "scramble", "replicates"))
    n = integer(spec, "samples", "sobol", minimum=1)
    scramble = optional_boolean(spec, "scramble", default=True)
    replicates = integer(spec, "replicates", "sobol", minimum=1) if "replicates" in spec else 1
    if replicates == 1:
        xi = germ_quantiles(sobol_points(n, len(germs), scramble, seed), germs)
        return xi, equal_weights(n), {"samples": n, "scramble": scramble, "seed": seed}
    if not scramble:
        raise ValueError("design.replicates: replicates need scramble: true (unscrambled copies are identical)")
    children = np.random.SeedSequence(seed).spawn(replicates)
    u = np.vstack([sobol_points(n, len(germs), True, np.random.default_rng(child)) for child in children])
    return (germ_quantiles(u, germs), equal_weights(n * replicates),
            {"samples": n, "replicates": replicates, "scramble": True, "seed": seed})


def halton_design(spec: dict, germs: list[str], seed: int):
    """`halton` {samples, scramble (default true)}: Halton points; unscrambled, the origin is skipped."""
    check_keys(spec, "halton", ("samples", "scramble"))
    n = integer(spec, "samples", "halton", minimum=1)
    from scipy.stats import qmc

    scramble = optional_boolean(spec, "scramble", default=True)
    engine = qmc.Halton(len(germs), scramble=scramble, rng=seed)
    if not scramble:
        engine.fast_forward(1)
    xi = germ_quantiles(engine.random(n), germs)
    return xi, equal_weights(n), {"samples": n, "scramble": scramble, "seed": seed}


def latin_hypercube_design(spec: dict, germs: list[str], seed: int):
    """`latin_hypercube` {samples}: one point in each of n equal-probability slices per dimension."""
    check_keys(spec, "latin_hypercube", ("samples",))
    from scipy.stats import qmc

    n = integer(spec, "samples", "latin_hypercube", minimum=1)
    xi = germ_quantiles(qmc.LatinHypercube(len(germs), rng=seed).random(n), germs)
    return xi, equal_weights(n), {"samples": n, "seed": seed}
