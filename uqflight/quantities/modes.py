"""The phugoid and short-period modes of the linearised model at the trim point (the paper's Eq. 8-9),
from JSBSim's FGLinearization: the eigenvalues of its system matrix, each complex pair classified
by the states of its eigenvector, not by its frequency (bacm's short period and Dutch roll have
nearly the same frequency):
* longitudinal when its longitudinal states (Vt/V, alpha, theta, q) outweigh its lateral ones
  (beta, phi, p, psi, r), in the norm of those dimensionless components;
* of those, the phugoid trades speed for height (|ΔVt/V| > |Δalpha|), the short period is an
  angle-of-attack oscillation (|Δalpha| ≥ |ΔVt/V|); the slowest phugoid and the fastest short
  period are kept when several pairs qualify.
A mode with no such pair (e.g. an overdamped short period) is undefined: NaN.
"""
from __future__ import annotations

import math

import numpy as np

LONGITUDINAL = ("Vt", "Alpha", "Theta", "Q")
LATERAL = ("Beta", "Phi", "P", "Psi", "R")
NAN = float("nan")


def eigen_modes(fdm) -> dict[str, float]:
    """{take: value} of the four mode quantities at the state `fdm` is trimmed in."""
    import jsbsim

    lin = jsbsim.FGLinearization(fdm)
    names = list(lin.x_names)
    values, vectors = np.linalg.eig(np.asarray(lin.system_matrix, dtype=float))
    speed = float(np.asarray(lin.x0, dtype=float)[names.index("Vt")]) or 1.0
    scale = np.array([1.0 / speed if name == "Vt" else 1.0 for name in names])
    column = {name: names.index(name) for name in LONGITUDINAL + LATERAL if name in names}
    phugoid, short = [], []
    for value, vector in zip(values, vectors.T):
        if not value.imag > 0:
            continue
        size = np.abs(vector) * scale
        longitudinal = math.hypot(*(size[column[n]] for n in LONGITUDINAL if n in column))
        lateral = math.hypot(*(size[column[n]] for n in LATERAL if n in column))
        if longitudinal <= lateral:
            continue
        (phugoid if size[column["Vt"]] > size[column["Alpha"]] else short).append(complex(value))
    result = dict.fromkeys(("phugoid_period_s", "phugoid_damping", "short_period_frequency_rad_s",
                            "short_period_damping"), NAN)
    if phugoid:
        slowest = min(phugoid, key=abs)
        result["phugoid_period_s"] = 2 * math.pi / slowest.imag
        result["phugoid_damping"] = -slowest.real / abs(slowest)
    if short:
        fastest = max(short, key=abs)
        result["short_period_frequency_rad_s"] = abs(fastest)
        result["short_period_damping"] = -fastest.real / abs(fastest)
    return result
