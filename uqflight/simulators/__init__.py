"""Simulators: one object per worker that turns a row of physical values κ into outputs.

Both kinds offer `layout(kappa) -> (time, output names)`, `evaluate(kappa) -> {name: (T,)}`
(raising a FlightError subclass for a failed sample) and `restart()`.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .base import FlightError
from .jsbsim import NAMED_OUTPUTS, UNITS, aircraft_hash
from .python import PythonSimulator
from .scenarios import scenario_entry


class JSBSimSimulator:
    """The campaign's aircraft and flight, flown as its scenario kind says (scenarios/); parameters
    map to JSBSim properties."""

    def __init__(self, config: dict, properties: list[str], base: Path | None = None):
        # the aircraft is located (a path relative to the campaign's folder) and, when parameters
        # set aero/uq/scale/... or aero/uq/offset/... properties, patched (see patch.py)
        self.scenario = scenario_entry(config)
        self.setup = self.scenario.setup(config, base=base, properties=properties)
        self.properties = list(properties)
        self.fixed = {str(k): float(v) for k, v in config.get("properties", {}).items()}  # every run's settings
        self.flight = self.scenario.flight(self.setup)
        self._flown = False
        self.units = {name: UNITS.get(name, "") for name in self.setup.outputs}

    def layout(self, kappa: np.ndarray) -> tuple[np.ndarray, list[str]]:
        return self.setup.time, list(self.setup.outputs)

    def evaluate(self, kappa: np.ndarray, observers=()) -> dict[str, np.ndarray]:
        """`observers` see every integration step (JSBSimFlight.run_trimmed)."""
        self._flown = True
        return self.flight.fly(self.settings(kappa), observers).outputs

    def settings(self, kappa: np.ndarray) -> dict[str, float]:
        """The property values of the run at `kappa`: the campaign's fixed `simulator.properties`, then
        the parameters' values."""
        return {**self.fixed, **dict(zip(self.properties, map(float, kappa)))}

    @staticmethod
    def source(name: str) -> tuple[str, float]:
        """The property a quantity's `of:` reads and its scale: a named output's, else the property."""
        return NAMED_OUTPUTS.get(name, (name, 1.0))

    def resolution(self, kappa: np.ndarray, ours: dict[str, np.ndarray] | None = None
                           ) -> dict[str, np.ndarray] | None:
        """{output: (T,)}: the simulator's own resolution at `kappa` as its scenario states it (level
        flight: the drift between its two valid trims; see `level_flight.resolution`), or None."""
        return self.scenario.resolution(self.setup, self.settings(kappa), ours)

    def restart(self) -> None:
        """Reload the aircraft (about 2 ms), so that a chunk's results do not depend on what
        the worker flew before: JSBSim's turboprop keeps engine state across resets, which
        moves trims in the 13th digit. Chunks are fixed by design order, so results are
        bit-identical whatever the number of workers or the executor."""
        if self._flown:
            self.flight = self.scenario.flight(self.setup, preflight=False)  # checked by __init__
            self._flown = False


def simulator_provenance(config: dict, base: Path | None = None, properties=()) -> dict:
    """Results-file attributes naming what a JSBSim campaign flew: the aircraft's hash (the patched copy's
    when `properties` scale or offset its functions), and what its scenario kind adds (nothing for level
    flight)."""
    entry = scenario_entry(config)
    return {"aircraft_hash": aircraft_hash(entry.setup(config, base=base, properties=properties)),
            **entry.provenance(config)}


def make_simulator(config: dict, parameter_names: list[str], properties: list[str], base: Path):
    """The simulator a campaign's `simulator:` mapping describes."""
    if config["kind"] == "python":
        return PythonSimulator(config, parameter_names, base)
    return JSBSimSimulator(config, properties, base)


__all__ = ["FlightError", "JSBSimSimulator", "PythonSimulator", "make_simulator", "simulator_provenance"]
