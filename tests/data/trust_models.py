"""Closed-form models for the trust tests: known variances, zero means and failures at known inputs."""
import numpy as np

TIME = np.linspace(0.0, 1.0, 5)


def sum_of_squares(p):
    """y(t) = 15000 + t (x1² + x2²): no spread at t = 0 but 15000 carried in every run (its variance
    there is rounding noise at most); S1 = S2 = 1/2 for t > 0 with x1, x2 iid."""
    return {"time": TIME, "y": 15000.0 + TIME * (p["x1"] ** 2 + p["x2"] ** 2)}


def identity(p):
    """y = x: mean 0 on a symmetric design, so its CoV is undefined."""
    return {"y": p["x"]}


def fails_above(p):
    """y = x, failing where x > 0.6: with x ~ U(-1, 1) the failure probability is 0.2."""
    if p["x"] > 0.6:
        raise ValueError("x above 0.6")
    return {"y": p["x"]}


def quadratic_failing_corner(p):
    """y = 1 + x1 + x1 x2 + x2² (mean 2, variance 4 for iid N(0, 1)), failing where x1 > 2 and x2 > 2
    (one corner of a 4 × 4 Gauss–Hermite grid)."""
    x1, x2 = p["x1"], p["x2"]
    if x1 > 2.0 and x2 > 2.0:
        raise ValueError("the corner")
    return {"y": 1.0 + x1 + x1 * x2 + x2**2}
