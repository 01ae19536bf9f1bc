"""Closed-form models for the checks of an expansion on its own runs (methods.validation): smooth ones that
an order-2 expansion carries, and ones with a kink that it cannot."""
import numpy as np

TIME = np.linspace(0.0, 2.0, 9)


def smooth(p):
    """y(t) = 1 + t (x1 + 0.5 x1 x2 + 0.3 x2²) + 0.1 t² x3: a polynomial of degree 2 in the inputs at every time,
    which an order-2 expansion represents exactly (no error beyond rounding)."""
    x1, x2, x3 = p["x1"], p["x2"], p["x3"]
    return {"time": TIME, "y": 1.0 + TIME * (x1 + 0.5 * x1 * x2 + 0.3 * x2**2) + 0.1 * TIME**2 * x3}


def peak_bank(p):
    """phi(t) = 30 max(0, x1 + 0.5 x2 + 0.2 x3) sin t + 2 t: a bank angle whose response is cut at 0 (a max() of
    smooth inputs, as a roll that one sign of the disturbance starts and the other never does): it and its peak
    over time have a kink across x1 + 0.5 x2 + 0.2 x3 = 0 that no polynomial carries."""
    x1, x2, x3 = p["x1"], p["x2"], p["x3"]
    kick = np.maximum(0.0, x1 + 0.5 * x2 + 0.2 * x3)
    return {"time": TIME, "phi": 30.0 * kick * np.sin(TIME) + 2.0 * TIME}


def step(p):
    """y = 1 where x1 > 0.3, else 0: a discontinuity."""
    return {"y": float(p["x1"] > 0.3) + 0.01 * p["x2"]}
