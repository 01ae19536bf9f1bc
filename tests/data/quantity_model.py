"""A closed-form model for the quantities of interest: y(t) = a + b t, z(t) = a t² and w(t) = a − b t on
t = 0, 0.25, ..., 4 (17 time points), for parameters a and b."""
import numpy as np

TIME = np.linspace(0.0, 4.0, 17)


def ramp(p: dict) -> dict:
    a, b = p["a"], p["b"]
    return {"time": TIME, "y": a + b * TIME, "z": a * TIME**2, "w": a - b * TIME}
