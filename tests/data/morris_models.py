"""Closed-form models for the Morris screening tests, on t = 0, 0.5, 1 (3 time points)."""
import numpy as np

TIME = np.linspace(0.0, 1.0, 3)
A = (2.0, -3.0, 0.5)


def linear(p: dict) -> dict:
    """y(t) = (1 + t) Σ a_i x_i, a = A: every elementary effect of x_i is (1 + t) a_i (h_i − l_i)."""
    return {"time": TIME, "y": (1.0 + TIME) * sum(a * p[f"x{i + 1}"] for i, a in enumerate(A))}


def interaction(p: dict) -> dict:
    """y(t) = x1 + (1 + t) x2 x3: x1's effects are constant (σ = 0), x2's and x3's depend on the other."""
    return {"time": TIME, "y": p["x1"] + (1.0 + TIME) * p["x2"] * p["x3"]}


def nonlinear(p: dict) -> dict:
    """Ishigami-like, with a normal input: y(t) = sin x1 + 7 sin² x2 + t x3⁴ sin x1."""
    return {"time": TIME, "y": np.sin(p["x1"]) + 7.0 * np.sin(p["x2"]) ** 2 + TIME * p["x3"] ** 4 * np.sin(p["x1"])}


def failing(p: dict) -> dict:
    """`nonlinear`, failing where x1 > 2.5 (its upper quarter on [-π, π])."""
    if p["x1"] > 2.5:
        raise ValueError("x1 above 2.5")
    return nonlinear(p)
