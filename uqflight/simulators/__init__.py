"""Simulators: one object per worker that turns a row of physical values κ into outputs.

Both kinds offer `probe(kappa) -> (time, output names)`, `evaluate(kappa) -> {name: (T,)}`
(raising a FlightError subclass for a failed sample) and `restart()`.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from .base import FlightError
from .jsbsim import NAMED_OUTPUTS, UNITS, FlightSetup, JSBSimFlight, flight_setup_from
from .python import PythonSimulator


class JSBSimSimulator:
    """The campaign's aircraft and flight; parameters map to JSBSim properties."""

    def __init__(self, config: dict, properties: list[str], base: Path | None = None):
        # the aircraft is located (a path relative to the campaign's folder) and, when parameters
        # set aero/uq/scale/... or aero/uq/offset/... properties, patched (see patch.py)
        self.setup: FlightSetup = flight_setup_from(config, base=base, properties=properties)
        self.properties = list(properties)
        self.flight = JSBSimFlight(self.setup)
        self._flown = False
        self.units = {name: UNITS.get(name, "") for name in self.setup.outputs}

    def probe(self, kappa: np.ndarray) -> tuple[np.ndarray, list[str]]:
        return self.setup.time, list(self.setup.outputs)

    def evaluate(self, kappa: np.ndarray, observers=()) -> dict[str, np.ndarray]:
        """`observers` see every integration step (JSBSimFlight.run_trimmed)."""
        self._flown = True
        return self.flight.fly(dict(zip(self.properties, map(float, kappa))), observers).outputs

    @staticmethod
    def source(name: str) -> tuple[str, float]:
        """The property a quantity's `of:` reads and its scale: a named output's, else the property."""
        return NAMED_OUTPUTS.get(name, (name, 1.0))

    def trim_repeatability(self, kappa: np.ndarray, ours: dict[str, np.ndarray] | None = None
                           ) -> dict[str, np.ndarray] | None:
        """{output: (T,)}: how far the flight of `kappa` with the campaign's trim (`ours`, the outputs
        `evaluate(kappa)` gave, flown here when None) and with the other trim (Newton's, JSBSim's) have
        drifted apart so far, max over t' ≤ t of |y₁(t') − y₂(t')|. Both trims pass the same acceptance
        checks, so a spread of the outputs below this is the trims' residual dynamics, not the inputs':
        the simulator does not resolve it. None when either trim fails."""
        other = replace(self.setup, trim="jsbsim" if self.setup.trim == "newton" else "newton")
        settings = dict(zip(self.properties, map(float, kappa)))
        try:
            ours = ours if ours is not None else JSBSimFlight(self.setup, preflight=False).fly(settings).outputs
            theirs = JSBSimFlight(other, preflight=False).fly(settings).outputs  # same files as __init__ checked
        except FlightError:
            return None
        return {name: np.maximum.accumulate(np.abs(ours[name] - theirs[name])) for name in ours}

    def restart(self) -> None:
        """Reload the aircraft (about 2 ms), so that a chunk's results do not depend on what
        the worker flew before: JSBSim's turboprop keeps engine state across resets, which
        moves trims in the 13th digit. Chunks are fixed by design order, so results are
        bit-identical whatever the number of workers or the executor."""
        if self._flown:
            self.flight = JSBSimFlight(self.setup, preflight=False)  # checked by __init__
            self._flown = False


def make_simulator(config: dict, parameter_names: list[str], properties: list[str], base: Path):
    """The simulator a campaign's `simulator:` mapping describes."""
    if config["kind"] == "python":
        return PythonSimulator(config, parameter_names, base)
    return JSBSimSimulator(config, properties, base)


__all__ = ["FlightError", "JSBSimSimulator", "PythonSimulator", "make_simulator"]
