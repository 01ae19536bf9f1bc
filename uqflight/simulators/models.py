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


PHUGOID_TIME = np.linspace(0.0, 50.0, 1001)


def phugoid(p: dict) -> dict:
    """Five aircraft-like histories (1001 times over 50 s): a damped phugoid and short-period
    response whose trim, amplitude, period and damping move with inputs a, b, c (each ~ N(0, 1)).
    Cheap stand-in for the aircraft where only the data volume matters (runner and memory tests)."""
    t = PHUGOID_TIME
    a, b, c = p.get("a", 0.0), p.get("b", 0.0), p.get("c", 0.0)
    omega = 2 * np.pi / (46.0 * (1 + 0.02 * b))
    phugoid_wave = np.exp(-0.015 * (1 + 0.1 * c) * t) * np.sin(omega * t)
    short = np.exp(-1.2 * t) * np.sin(1.6 * t)
    return {
        "alpha_deg": 6.3 + 0.2 * a - 1.0 * short,
        "theta_deg": 6.3 + 0.2 * a + 0.7 * (1 + 0.05 * c) * phugoid_wave - 1.5 * short,
        "h_ft": 15000.0 - 35.0 * (1 + 0.05 * a) * phugoid_wave,
        "q_degps": -1.6 * np.exp(-1.2 * t) * np.cos(1.6 * t) + 0.05 * b * np.cos(omega * t),
        "vtas_kt": 200.0 + 1.7 * (1 + 0.03 * b) * phugoid_wave,
    }


ANISOTROPIC_A, ANISOTROPIC_B, ANISOTROPIC_C = 1.2, 0.02, 0.01


def anisotropic(p: dict) -> dict:
    """y = exp(A x1) + B Σ_{k≥2} sin(x_k) + C x1 x2 over the parameters in order, each ~ N(0, 1): one
    dominant input among the others (A = 1.2, B = 0.02, C = 0.01). E[y] = exp(A²/2);
    Var[y] = exp(2A²) − exp(A²) + (d − 1) B² (1 − e⁻²)/2 + C²."""
    x = np.array(list(p.values()), dtype=float)
    return {"y": np.exp(ANISOTROPIC_A * x[0]) + ANISOTROPIC_B * np.sin(x[1:]).sum() + ANISOTROPIC_C * x[0] * x[1]}


def normal_sum(p: dict) -> dict:
    """y = Σ_k x_k / √d over the parameters in order, each ~ N(0, 1): y ~ N(0, 1), so P(y > t) = Φ(−t)
    (a linear limit state of reliability index t, for the rare-event designs)."""
    x = np.array(list(p.values()), dtype=float)
    return {"y": x.sum() / np.sqrt(x.size)}


def seeded_sum(p: dict) -> dict:
    """y = (x + z)/√2 with x ~ N(0, 1) the parameter `x` and z ~ N(0, 1) drawn from the random stream of the
    integer seed `seed` (numpy's default generator): y ~ N(0, 1) over x and the seed, P(y > t) = Φ(−t),
    and y is not smooth in the seed (a rare event with a seed parameter)."""
    z = np.random.default_rng(int(p["seed"])).standard_normal()
    return {"y": (float(p["x"]) + z) / np.sqrt(2.0)}
