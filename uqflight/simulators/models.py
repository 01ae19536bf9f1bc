"""Closed-form models for the `python` simulator kind: known answers to test the methods against.

Each takes {parameter name: value} and returns {output name: value or array}.
"""
from __future__ import annotations

import numpy as np

DECAY_TIME = np.linspace(0.0, 5.0, 51)


def ishigami(p: dict) -> dict:
    """Ishigami function, a = 7, b = 0.1; inputs x1, x2, x3 uniform on [-pi, pi].
    Sobol' S1 = 0.3139, 0.4424, 0; ST = 0.5576, 0.4424, 0.2437."""
    x1, x2, x3 = p["x1"], p["x2"], p["x3"]
    return {"y": np.sin(x1) + 7.0 * np.sin(x2) ** 2 + 0.1 * x3**4 * np.sin(x1)}


def linear(p: dict) -> dict:
    """y = sum_i (i+1) * x_i over the parameters in order: S_i = (i+1)^2 var_i / sum_j (j+1)^2 var_j."""
    return {"y": sum((i + 1) * value for i, value in enumerate(p.values()))}


def exp_decay(p: dict) -> dict:
    """x(t) = exp(-a t) on t in [0, 5] s; with a ~ N(mu, s^2): E = exp(-mu t + s^2 t^2 / 2),
    Var = exp(-2 mu t + 2 s^2 t^2) - E^2."""
    return {"time": DECAY_TIME, "x": np.exp(-p["a"] * DECAY_TIME)}
