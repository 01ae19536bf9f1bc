"""Sampling designs: Monte Carlo and quasi-Monte Carlo points mapped to the germs, equal weights.

Uniform points u in (0, 1)^d become ξ through each germ's inverse CDF (Φ⁻¹ for normal, 2u − 1 for
uniform), so low-discrepancy structure carries over to ξ.
"""
from __future__ import annotations

import numpy as np

from ..analysis.proportions import Net, Stratified
from ..parameters.germs import draw_germs, germ_quantiles
from .base import DesignKind, count, equal_weights, flag
from ..text import FieldError


def sobol_points(n: int, d: int, scramble: bool, seed: int) -> np.ndarray:
    """The first n points of a Sobol' sequence in [0, 1)^d.

    Drawn as the next power of 2 and cut, so scipy does not warn about balance. The unscrambled
    sequence starts at the origin, which has no normal quantile, so it is skipped.
    """
    from scipy.stats import qmc

    skip = 0 if scramble else 1
    engine = qmc.Sobol(d, scramble=scramble, rng=seed)
    return engine.random_base2((n + skip - 1).bit_length())[skip : n + skip]


SAMPLES = "Number of points, >= 1. `samples: 1024`"
SCRAMBLE = "Scramble the QMC points with the seed. Default true. `scramble: false`"

class MonteCarlo(DesignKind):
    """`monte_carlo` {samples}: independent draws from numpy's default_rng(seed).

    Examples
    --------
    >>> import numpy as np
    >>> from uqflight.designs import build_design
    >>> design = build_design({"kind": "monte_carlo", "samples": 8}, ["uniform", "normal"], seed=3)
    >>> design.xi.shape, design.weights.tolist() == [1 / 8] * 8
    ((8, 2), True)
    >>> u = np.random.default_rng(3).random((8, 2))  # the seed's uniforms, through each germ's quantile
    >>> bool((design.xi[:, 0] == 2 * u[:, 0] - 1).all())  # the uniform germ's: ξ = 2u − 1
    True
    """

    kind = "monte_carlo"
    keys = {"samples": count(1, description=SAMPLES)}
    example = {"kind": "monte_carlo", "samples": 64}

    def points(self, spec, germs, seed):
        n = spec["samples"]
        return draw_germs(germs, n, seed), equal_weights(n), {"samples": n, "generator": "numpy default_rng", "seed": seed}


class Sobol(DesignKind):
    """`sobol` {samples, scramble (default true), replicates (default 1)}: Sobol' points, Owen-scrambled
    with the seed. With R replicates (randomised QMC), R independent scrambles of `samples` points each
    (seeds spawned from the campaign's), stacked replicate after replicate: R × samples runs whose
    replicate-to-replicate spread gives the standard error of every statistic.

    Examples
    --------
    >>> from uqflight.designs import build_design, design_size
    >>> spec = {"kind": "sobol", "samples": 8, "replicates": 3}
    >>> design_size(spec, ["uniform"])  # replicates × samples
    24
    >>> design = build_design(spec, ["uniform"], seed=0)
    >>> eighths = ((design.xi[:, 0] + 1) / 2 * 8).astype(int).reshape(3, 8)  # u = (ξ + 1)/2, by eighths
    >>> [sorted(replicate) for replicate in eighths.tolist()]  # each scramble: one point in every eighth
    [[0, 1, 2, 3, 4, 5, 6, 7], [0, 1, 2, 3, 4, 5, 6, 7], [0, 1, 2, 3, 4, 5, 6, 7]]
    """

    kind = "sobol"
    keys = {"samples": count(1, description=SAMPLES), "scramble": flag(True, SCRAMBLE),
            "replicates": count(1, default=1, description="R independent scrambles of `samples` points (randomised "
                                "QMC), giving every statistic's standard error. Default 1. `replicates: 16`")}
    example = {"kind": "sobol", "samples": 64}
    sampling = Net()

    def settings(self, spec):
        """Its keys, `replicates` > 1 only scrambled."""
        found = super().settings(spec)
        if found["replicates"] > 1 and not found["scramble"]:
            raise FieldError("design.replicates", "replicates need scramble: true (unscrambled copies are identical)")
        return found

    def size(self, spec, germs):
        return spec["samples"] * spec["replicates"]

    def points(self, spec, germs, seed):
        n, scramble, replicates = spec["samples"], spec["scramble"], spec["replicates"]
        if replicates == 1:
            xi = germ_quantiles(sobol_points(n, len(germs), scramble, seed), germs)
            return xi, equal_weights(n), {"samples": n, "scramble": scramble, "seed": seed}
        children = np.random.SeedSequence(seed).spawn(replicates)
        u = np.vstack([sobol_points(n, len(germs), True, np.random.default_rng(child)) for child in children])
        return (germ_quantiles(u, germs), equal_weights(n * replicates),
                {"samples": n, "replicates": replicates, "scramble": True, "seed": seed})


class Halton(DesignKind):
    """`halton` {samples, scramble (default true)}: Halton points; unscrambled, the origin is skipped.

    Examples
    --------
    >>> from uqflight.designs import build_design
    >>> spec = {"kind": "halton", "samples": 4, "scramble": False}
    >>> u = (build_design(spec, ["uniform", "uniform"], seed=0).xi + 1) / 2  # back to the unit square
    >>> u[:, 0].tolist()  # van der Corput in base 2, from 1/2: the origin is skipped
    [0.5, 0.25, 0.75, 0.125]
    >>> (9 * u[:, 1]).round(12).tolist()  # base 3: 1/3, 2/3, 1/9, 4/9
    [3.0, 6.0, 1.0, 4.0]
    """

    kind = "halton"
    keys = {"samples": count(1, description=SAMPLES), "scramble": flag(True, SCRAMBLE)}
    example = {"kind": "halton", "samples": 64}
    sampling = Net()

    def points(self, spec, germs, seed):
        from scipy.stats import qmc

        n, scramble = spec["samples"], spec["scramble"]
        engine = qmc.Halton(len(germs), scramble=scramble, rng=seed)
        if not scramble:
            engine.fast_forward(1)
        xi = germ_quantiles(engine.random(n), germs)
        return xi, equal_weights(n), {"samples": n, "scramble": scramble, "seed": seed}


class LatinHypercube(DesignKind):
    """`latin_hypercube` {samples}: one point in each of n equal-probability slices per dimension.

    Examples
    --------
    >>> import numpy as np
    >>> from scipy.stats import norm
    >>> from uqflight.designs import build_design
    >>> design = build_design({"kind": "latin_hypercube", "samples": 5}, ["uniform", "normal"], seed=2)
    >>> u = np.column_stack([(design.xi[:, 0] + 1) / 2, norm.cdf(design.xi[:, 1])])  # each germ's CDF
    >>> [sorted(column) for column in (5 * u).astype(int).T.tolist()]  # the fifth each point falls in
    [[0, 1, 2, 3, 4], [0, 1, 2, 3, 4]]
    """

    kind = "latin_hypercube"
    keys = {"samples": count(1, description=SAMPLES)}
    example = {"kind": "latin_hypercube", "samples": 64}
    sampling = Stratified()

    def points(self, spec, germs, seed):
        from scipy.stats import qmc

        n = spec["samples"]
        xi = germ_quantiles(qmc.LatinHypercube(len(germs), rng=seed).random(n), germs)
        return xi, equal_weights(n), {"samples": n, "seed": seed}
