"""Any Python callable as the simulator: closed-form models for tests, other models for users.

The callable gets a dict {parameter name: value} and returns a dict {output name: array or
scalar}; an optional "time" entry gives the time of the array outputs (otherwise the steps are
numbered 0, 1, 2, ...). A scalar output has one time point.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .jsbsim import DivergenceError, FlightError


class PythonSimulator:
    """Calls `function` once per sample and checks what it returns."""

    def __init__(self, config: dict, parameter_names: list[str], base: Path):
        from ..campaign import load_function

        self.function = load_function(config["function"], base)
        self.names = list(parameter_names)
        self.outputs = config.get("outputs")
        self.units: dict[str, str] = {}

    def probe(self, kappa: np.ndarray) -> tuple[np.ndarray, list[str]]:
        """Time and output names, from one call at `kappa` (the nominal point)."""
        raw = self._call(kappa)
        names = self.outputs or [k for k in raw if k != "time"]
        missing = [n for n in names if n not in raw]
        if missing:
            raise ValueError(f"simulator.outputs: the function returned no {', '.join(map(repr, missing))} "
                             f"(it returned {', '.join(map(repr, raw))})")
        lengths = {n: np.size(raw[n]) for n in names}
        if len(set(lengths.values())) != 1:
            raise ValueError(f"simulator.outputs: outputs of different lengths {lengths}; run one campaign per time grid")
        length = next(iter(lengths.values()))
        time = np.asarray(raw["time"], dtype=float) if "time" in raw else np.arange(length, dtype=float)
        if time.shape != (length,):
            raise ValueError(f"simulator.function: 'time' has {time.size} entries, the outputs {length}")
        self.outputs = list(names)
        return time, self.outputs

    def evaluate(self, kappa: np.ndarray) -> dict[str, np.ndarray]:
        raw = self._call(kappa)
        result = {}
        for name in self.outputs or [k for k in raw if k != "time"]:
            if name not in raw:
                raise FlightError(f"the function returned no output {name!r}")
            result[name] = np.atleast_1d(np.asarray(raw[name], dtype=float))
            if not np.all(np.isfinite(result[name])):
                raise DivergenceError(f"NaN or infinite value in output {name!r}")
        return result

    def restart(self) -> None:
        """Nothing to reload: a Python function keeps no state between samples."""

    def _call(self, kappa: np.ndarray) -> dict:
        raw = self.function(dict(zip(self.names, map(float, kappa))))
        if not isinstance(raw, dict):
            raise FlightError(f"the function returned {type(raw).__name__}, expected a dict of outputs")
        return raw
