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


def hanging_at_centre(p):
    """Never returns at the centre x = 0 of U(-2, 2) (the nominal every command flies first); else [x, x^2]."""
    x = p["x"]
    while x == 0.0:
        time.sleep(0.05)
    return {"y": np.array([x, x * x])}


def segfault_at_centre(p):
    """Segfaults at the centre x = 0 (the nominal); else [x, x^2]."""
    x = p["x"]
    if x == 0.0:
        os.kill(os.getpid(), signal.SIGSEGV)
        time.sleep(5)
    return {"y": np.array([x, x * x])}


def multi_line_failure(p):
    """Fails where x > 1 with a reason on two lines, the second one looking like a line of uqflight's."""
    x = p["x"]
    if x > 1.0:
        raise ValueError("first line\nerror: a forged second line")
    return {"y": np.array([x, x * x])}


def shifted_time(p):
    """[x, x^2] at times 0 and 1, but at times 5 and 6 where x > 1: the same length, another grid."""
    x = p["x"]
    return {"time": np.array([0.0, 1.0]) + (5.0 if x > 1.0 else 0.0), "y": np.array([x, x * x])}


def forged_names(p):
    """An output whose name holds a newline and a forged line of uqflight's (of the one parameter, whatever
    its name)."""
    (x,) = p.values()
    return {"y\nerror: forged": np.array([x, x * x]), "z": np.array([1.0 + x, 2.0])}
