"""A closed-form model that fails on purpose, for failure-isolation tests."""
import numpy as np


def flaky(p):
    x = p["x"]
    if x > 1.5:
        raise RuntimeError("model blew up")
    if x < -1.5:
        return {"y": np.array([np.nan, 1.0])}
    return {"y": np.array([x, x * x])}
