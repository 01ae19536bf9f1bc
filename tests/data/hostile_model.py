"""Models that misbehave on purpose, for the runner's reliability tests (tests/test_run_faults.py)."""
import os
import signal
import time

import numpy as np


def crashing(p):
    """x > 1.6 exits its process (exit code 3), x < -1.6 segfaults; otherwise [x, x^2]."""
    x = p["x"]
    if x > 1.6:
        os._exit(3)
    if x < -1.6:
        os.kill(os.getpid(), signal.SIGSEGV)
        time.sleep(5)
    return {"y": np.array([x, x * x])}


def hanging(p):
    """x > 1.7 never returns; otherwise [x, x^2]."""
    x = p["x"]
    if x > 1.7:
        while True:
            time.sleep(0.05)
    return {"y": np.array([x, x * x])}


def slow(p):
    """0.1 s per sample."""
    time.sleep(0.1)
    x = p["x"]
    return {"y": np.array([x, x * x])}


def long_histories(p):
    """5000 values per run (40 kB): fills a small disk quickly."""
    x = p["x"]
    t = np.linspace(0.0, 1.0, 5000)
    return {"time": t, "y": np.sin(x * t) + x}
