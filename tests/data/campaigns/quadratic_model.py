"""A model file next to its campaign (good_python_file.yaml): y(t) = x t^2 + y0 on 5 steps."""
import numpy as np


def quadratic(p):
    t = np.linspace(0.0, 1.0, 5)
    return {"time": t, "y": p["x"] * t**2 + p["y0"]}
