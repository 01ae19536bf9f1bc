"""Any Python callable as the simulator: closed-form models for tests, other models for users.

The callable gets a dict {parameter name: value} (a float; an int for a `distribution: seed`) and returns a dict {output name: array or
scalar}; an optional "time" entry gives the time of the array outputs (otherwise the steps are
numbered 0, 1, 2, ...). A scalar output has one time point.
"""
from __future__ import annotations

import hashlib
import importlib
import importlib.util
import sys
from pathlib import Path
from typing import Callable

import numpy as np

from .base import DivergenceError, FlightError, SimulatorSettingError, nominal_failed
from .spec import SimulatorSpec


def split_spec(spec) -> tuple[str, str]:
    """(module or file, attribute) of `module:attribute` or `path/to/file.py:attribute`, nothing imported."""
    if not isinstance(spec, str) or spec.count(":") != 1:
        shown = repr(spec) if isinstance(spec, str) and len(repr(spec)) <= 60 else type(spec).__name__
        raise SimulatorSettingError(f"expected 'package.module:callable' or 'file.py:callable', got {shown}")
    module_name, attribute = spec.split(":")
    return module_name, attribute


def load_function(spec: str, base: Path) -> Callable:
    """The callable named `module:attribute` or `path/to/file.py:attribute` (relative to base): the
    module is imported, which runs its code."""
    module_name, attribute = split_spec(spec)
    try:
        if module_name.endswith(".py"):
            file = (base / module_name) if not Path(module_name).is_absolute() else Path(module_name)
            if not file.is_file():
                raise SimulatorSettingError(f"expected an existing Python file, got {str(file)!r} "
                                            "(a relative path is read from the campaign's folder)")
            unique = "uqflight_user_" + hashlib.sha256(str(file.resolve()).encode()).hexdigest()[:12]
            module = sys.modules.get(unique)
            if module is None:
                module_spec = importlib.util.spec_from_file_location(unique, file)
                module = importlib.util.module_from_spec(module_spec)
                module_spec.loader.exec_module(module)
                sys.modules[unique] = module
        else:
            module = importlib.import_module(module_name)
    except SimulatorSettingError:
        raise
    except Exception as exc:  # the user's module failed to import: say which and why
        raise SimulatorSettingError(f"cannot import {module_name!r}: {type(exc).__name__}: {exc}") from exc
    function = getattr(module, attribute, None)
    if not callable(function):
        raise SimulatorSettingError(f"{module_name!r} has no callable {attribute!r}")
    return function


class PythonSimulator:
    """Calls `function` once per sample and checks what it returns."""

    def __init__(self, config: SimulatorSpec, parameter_names: list[str], base: Path):
        self.function = load_function(config["function"], base)
        self.names = list(parameter_names)
        self.seeds = set(config.seed_parameters)  # given to the function as Python ints
        self.outputs = config.get("outputs")
        self.units: dict[str, str] = {}
        self.time: np.ndarray | None = None  # the nominal run's times (`layout`), which every run must return

    def layout(self, kappa: np.ndarray) -> tuple[np.ndarray, list[str]]:
        """Time and output names, from one call at `kappa` (the nominal point); NominalFailed when the
        function fails there."""
        try:
            raw = self._call(kappa)
        except Exception as exc:  # the user's function: any error
            raise nominal_failed(self.names, kappa, exc) from exc
        names = self.outputs or [k for k in raw if k != "time"]
        missing = [n for n in names if n not in raw]
        if missing:
            raise ValueError(f"simulator.outputs: the function returned no {', '.join(map(repr, missing))} "
                             f"(it returned {', '.join(map(repr, raw))})")
        lengths = {n: np.size(raw[n]) for n in names}
        if len(set(lengths.values())) != 1:
            raise ValueError(f"simulator.outputs: outputs of different lengths {lengths}; run one campaign per time grid")
        length = next(iter(lengths.values()))
        time = self._time(raw, length)
        if time.shape != (length,):
            raise ValueError(f"simulator.function: 'time' has {time.size} entries, the outputs {length}")
        if not np.isfinite(time).all() or np.any(np.diff(time) <= 0):
            raise ValueError("simulator.function: 'time' must be finite and strictly increasing")
        self.outputs = list(names)
        self.time = time
        return time, self.outputs

    def expect_time(self, time: np.ndarray) -> None:
        """Check every run's times against `time`, the nominal run's (`layout`'s in another process)."""
        self.time = np.asarray(time, dtype=float)

    @staticmethod
    def _time(raw: dict, length: int) -> np.ndarray:
        """The times the function gave (its "time" entry), else its steps numbered 0, 1, 2, ..."""
        return np.asarray(raw["time"], dtype=float) if "time" in raw else np.arange(length, dtype=float)

    def evaluate(self, kappa: np.ndarray, observers=()) -> dict[str, np.ndarray]:
        """The outputs at `kappa`; each observer gets `step(t, values)` at every time point of the
        model's own grid, `values` being those of the outputs it names in `properties`."""
        raw = self._call(kappa)
        result = {}
        for name in self.outputs or [k for k in raw if k != "time"]:
            if name not in raw:
                raise FlightError(f"the function returned no output {name!r}")
            result[name] = np.atleast_1d(np.asarray(raw[name], dtype=float))
            if not np.all(np.isfinite(result[name])):
                raise DivergenceError(f"NaN or infinite value in output {name!r}")
        self._check_time(raw, result)
        for observer in observers:
            self._feed(observer, raw, result)
        return result

    def _check_time(self, raw: dict, result: dict) -> None:
        """FlightError when the run's times are not the nominal run's (`layout`'s), which every run's values
        are stored against: a run on another grid of the same length would be stored against the wrong
        times."""
        grid = self.time
        if grid is None or not result:
            return
        time = self._time(raw, len(next(iter(result.values()))))
        if time.shape != grid.shape and "time" not in raw:
            return  # outputs of another length: the worker's check of the outputs' lengths says so
        if time.shape != grid.shape or not np.array_equal(time, grid):
            if time.shape != grid.shape:
                found = f"{time.size} times"
            else:
                first = int(np.flatnonzero(time != grid)[0])
                found = f"time {time[first]:g} where the nominal run has {grid[first]:g}"
            raise FlightError(f"the function's 'time' differs from the nominal run's ({found}; {grid.size} times "
                              f"from {grid[0]:g} to {grid[-1]:g}): every run must return the nominal's times")

    @staticmethod
    def _feed(observer, raw: dict, result: dict) -> None:
        missing = [name for name in observer.properties if name not in result]
        if missing:
            raise FlightError(f"a quantity reads {', '.join(map(repr, missing))}, which is not among the "
                              f"model's outputs ({', '.join(result)})")
        columns = [result[name] for name in observer.properties]
        length = len(columns[0]) if columns else 0
        time = np.asarray(raw["time"], dtype=float) if "time" in raw else np.arange(length, dtype=float)
        for j in range(length):
            observer.step(float(time[j]), [float(column[j]) for column in columns])

    @staticmethod
    def source(name: str) -> tuple[str, float]:
        """A quantity's `of:` names one of the model's outputs, read as it is."""
        return name, 1.0

    def restart(self) -> None:
        """Nothing to reload: a Python function keeps no state between samples."""

    def _call(self, kappa: np.ndarray) -> dict:
        raw = self.function({name: int(value) if name in self.seeds else float(value)
                             for name, value in zip(self.names, kappa)})
        if not isinstance(raw, dict):
            raise FlightError(f"the function returned {type(raw).__name__}, expected a dict of outputs")
        return raw
