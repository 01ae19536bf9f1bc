"""Closed-form models with a random stream: the output's spread splits between an input x and a seed."""
import numpy as np

NOISE_STD = 0.5
TIME = np.array([0.0, 1.0, 2.0])


def noise(seed: int) -> float:
    """e(seed): a fixed pseudo-random function of the seed, N(0, 1) over seeds (numpy's generator)."""
    return float(np.random.default_rng(seed).standard_normal())


def x_plus_noise(p):
    """y(t) = t·x + NOISE_STD·e(seed) for t > 0 and y(0) = x: with x ~ N(0, 1), Var y(t) = t² + 0.25, the
    seed's share 0.25 / (t² + 0.25) (first-order = total: additive), and none at t = 0. Refuses a seed that
    is not a Python int, as a random generator would."""
    seed = p["seed"]
    if not isinstance(seed, int):
        raise TypeError(f"the seed arrived as {type(seed).__name__}, not int")
    e = NOISE_STD * noise(seed)
    return {"time": TIME, "y": np.array([p["x"], p["x"] + e, 2.0 * p["x"] + e])}
