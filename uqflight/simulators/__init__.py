"""Simulators: one object per worker that turns a row of physical values κ into outputs.

Every kind (simulators/kinds) offers `layout(kappa) -> (time, output names)`, `evaluate(kappa) -> {name:
(T,)}` (raising a FlightError subclass for a failed sample) and `restart()`.
"""
from __future__ import annotations

from pathlib import Path

from .base import FlightError
from .kinds.jsbsim import JSBSimSimulator
from .python import PythonSimulator
from .spec import SimulatorSpec


def simulator_provenance(config: SimulatorSpec, base: Path | None = None, properties=()) -> dict:
    """Results-file attributes naming what the campaign's simulator runs (a JSBSim aircraft's hash, its
    scenario's files; nothing for a python model)."""
    return config.entry.provenance(config, base, properties)


def make_simulator(config: SimulatorSpec, parameter_names: list[str], properties: list[str], base: Path):
    """The simulator a campaign's `simulator:` spec describes."""
    return config.entry.make(config, parameter_names, properties, base)


__all__ = ["FlightError", "JSBSimSimulator", "PythonSimulator", "SimulatorSpec", "make_simulator",
           "simulator_provenance"]
