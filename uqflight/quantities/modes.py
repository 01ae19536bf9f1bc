"""The phugoid and short-period modes of the linearised model at the trim point (the paper's Eq. 8-9),
from JSBSim's FGLinearization: the eigenvalues of its system matrix, each complex pair classified
by the states of its eigenvector, not by its frequency (bacm's short period and Dutch roll have
nearly the same frequency):
* longitudinal when its longitudinal states (Vt/V, alpha, theta, q) outweigh its lateral ones
  (beta, phi, p, psi, r), in the norm of those dimensionless components;
* of those, the phugoid trades speed for height (|ΔVt/V| > |Δalpha|), the short period is an
  angle-of-attack oscillation (|Δalpha| ≥ |ΔVt/V|); the slowest phugoid and the fastest short
  period are kept when several pairs qualify.
A mode with no such pair (e.g. an overdamped short period) is undefined: NaN. The period is the
damped one, 2π/Im λ; the frequency the natural one, |λ|; the damping ratio −Re λ/|λ|.
"""
from __future__ import annotations

import math

import numpy as np

LONGITUDINAL = ("Vt", "Alpha", "Theta", "Q")
LATERAL = ("Beta", "Phi", "P", "Psi", "R")
NAN = float("nan")
MODES = ("phugoid_period_s", "phugoid_damping", "short_period_frequency_rad_s", "short_period_damping")
WIND = ("atmosphere/wind-north-fps", "atmosphere/wind-east-fps", "atmosphere/wind-down-fps")


def eigen_modes(fdm) -> dict[str, float]:
    """{take: value} of the four mode quantities at the state `fdm` is trimmed in."""
    import jsbsim

    dt, wind = fdm.get_delta_t(), {name: fdm[name] for name in WIND}
    lin = jsbsim.FGLinearization(fdm)
    # The linearisation leaves the integration suspended (dt = 0), the engines' outputs of its last
    # perturbed evaluation and a wind of ~1e-9 fps: restored, so that the flight goes on as trimmed
    fdm.set_dt(dt)
    for name, value in wind.items():
        fdm[name] = value
    fdm.get_propulsion().get_steady_state()
    return classified_modes(list(lin.x_names), np.asarray(lin.system_matrix, dtype=float),
                            np.asarray(lin.x0, dtype=float))


def classified_modes(names: list[str], system: np.ndarray, x0: np.ndarray) -> dict[str, float]:
    """The four mode quantities of the system matrix `system` over the states `names` (FGLinearization's:
    Vt, Alpha, Theta, Q, ..., Beta, Phi, P, Psi, R, ...) at the trimmed state `x0`."""
    values, vectors = np.linalg.eig(system)
    speed = float(x0[names.index("Vt")]) or 1.0
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
    result = dict.fromkeys(MODES, NAN)
    if phugoid:
        slowest = min(phugoid, key=abs)
        result["phugoid_period_s"] = 2 * math.pi / slowest.imag
        result["phugoid_damping"] = -slowest.real / abs(slowest)
    if short:
        fastest = max(short, key=abs)
        result["short_period_frequency_rad_s"] = abs(fastest)
        result["short_period_damping"] = -fastest.real / abs(fastest)
    return result
