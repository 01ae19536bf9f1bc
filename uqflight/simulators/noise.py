"""Measurement noise for simulated flight data (`uqflight simulate --noise NAME=SIGMA --seed N`)."""
from __future__ import annotations

import zlib

import numpy as np

from ..text import Refusal


def check_noise(names, sigmas: dict[str, float], seed: int) -> None:
    """A Refusal naming an output not in `names`, a sigma that is negative or not finite, or a negative seed."""
    unknown = [name for name in sigmas if name not in names]
    if unknown:
        raise Refusal(f"--noise: no output {', '.join(map(repr, unknown))} (outputs: {', '.join(names)})")
    bad = [f"{name}={sigma!r}" for name, sigma in sigmas.items() if not (np.isfinite(sigma) and sigma >= 0)]
    if bad:
        raise Refusal(f"--noise: expected SIGMA >= 0 (a standard deviation in the output's unit), got {', '.join(bad)}")
    if seed < 0:
        raise Refusal(f"--seed: expected an integer >= 0, got {seed}")


def add_noise(outputs: dict[str, np.ndarray], sigmas: dict[str, float], seed: int) -> dict[str, np.ndarray]:
    """`outputs` with independent N(0, sigma²) noise added to each output named in `sigmas` (checked
    by `check_noise`).

    Each output draws from its own stream, seeded by (seed, crc32 of its name): the same seed gives
    the same bits, and an output's noise does not depend on which other outputs are noisy."""
    check_noise(list(outputs), sigmas, seed)
    noisy = dict(outputs)
    for name, sigma in sigmas.items():
        stream = np.random.default_rng([seed, zlib.crc32(name.encode())])
        noisy[name] = outputs[name] + stream.normal(0.0, sigma, np.shape(outputs[name]))
    return noisy
