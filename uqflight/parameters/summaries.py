"""Parameters as plain data for people and JSON: their prior summaries and their specs."""
from __future__ import annotations

import numpy as np

from .germs import GERMS


def prior_summaries(parameters) -> dict[str, dict]:
    """Prior mean, std and central 95 % interval of every parameter, in physical units."""
    out = {}
    for p in parameters:
        lower, upper = (float(v) for v in p.to_physical(GERMS[p.germ].quantile(np.array([0.025, 0.975]))))
        out[p.name] = {"mean": float(p.mean), "std": float(p.std), "ci95": [lower, upper]}
    return out


def parameter_specs(parameters) -> dict[str, dict]:
    """Each parameter as plain data: property, distribution, germ, nominal, lower, upper."""
    return {p.name: {"property": p.property, "distribution": p.distribution, "germ": p.germ,
                     "nominal": float(p.nominal), "lower": float(p.lower), "upper": float(p.upper)}
            for p in parameters}
