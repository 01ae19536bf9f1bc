"""Closed-form models for the wrapped-angle, pick-freeze and failed-run tests (tests/test_sensitivity_trust.py)."""
import hashlib
import math

import numpy as np

TURN_TIME = np.linspace(0.0, 10.0, 41)


def wrapped_turn(p):
    """A heading psi(t) = 179 + b + a t [deg], a ~ U(1, 3) deg/s, b ~ U(-2, 2) deg, reported as a flight
    reports it, wrapped to [-180, 180): runs start on either side of ±180 and cross it.
    Unwrapped: mean 179 + 2 t, variance 4/12 t² + 16/12."""
    psi = 179.0 + p["b"] + p["a"] * TURN_TIME
    return {"time": TURN_TIME, "psi_deg": (psi + 180.0) % 360.0 - 180.0}


def ishigami_failing(p):
    """Ishigami (a = 7, b = 0.1) failing on about 4 % of its points, scattered over the box independently of
    the inputs' values (a hash of the point picks them, as a trim failing here and there would)."""
    x1, x2, x3 = p["x1"], p["x2"], p["x3"]
    if int(hashlib.sha256(repr((x1, x2, x3, 0)).encode()).hexdigest(), 16) % 25 == 0:  # not at the centre
        raise RuntimeError("this point fails")
    return {"y": math.sin(x1) + 7.0 * math.sin(x2) ** 2 + 0.1 * x3**4 * math.sin(x1)}


def turbulent_failing(p):
    """y = x + 0.5 e(seed), e a standard normal draw of numpy's generator seeded by the seed parameter: with
    x ~ N(0, 1) the seed's share of Var y = 1.25 is 0.2 (first order = total: additive). Fails on about 4 %
    of its points, scattered as ishigami_failing's, as trims in turbulence do."""
    if int(hashlib.sha256(repr((p["x"], p["seed"], 0)).encode()).hexdigest(), 16) % 25 == 0:
        raise RuntimeError("this point fails")
    return {"y": p["x"] + 0.5 * float(np.random.default_rng(p["seed"]).standard_normal())}
