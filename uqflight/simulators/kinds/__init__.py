"""Simulator kinds (`simulator.kind`): what runs a sample, one module and one class each (`SimulatorKind`
in ../base.py; a subclass registers itself).

- jsbsim: a JSBSim aircraft flown as its scenario kind says (simulators/scenarios); parameters set
  properties of the aircraft or perturb its aerodynamic functions.
- python: any Python callable (closed forms for tests, other models); parameters are its arguments.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from ..base import SimulatorKind
from ..bundle import unpacked
from ..scenarios import scenario_entry
from ..spec import SimulatorSpec
from . import jsbsim, python  # noqa: F401  (defining their classes registers them)

REGISTRY = SimulatorKind.registry
SIMULATOR_KINDS = tuple(REGISTRY)


def make_bundle(simulator: SimulatorSpec, properties, base: str | Path) -> dict | None:
    """{"kind", "name", "hash", "zip"} for the simulator's files, or None when there is nothing to send."""
    return simulator.entry.bundle(simulator, properties, base)


def localized(spec):
    """The WorkerSpec with its simulator reading the bundle's files from this worker's cache (see
    `bundle.unpacked`, which refuses unsafe or mismatched files), its scenario's as its kind says."""
    if not getattr(spec, "bundle", None):
        return spec
    simulator, folder = unpacked(spec.bundle, spec.simulator)
    if folder is not None:
        simulator = scenario_entry(simulator).localize(simulator, folder)
    return replace(spec, simulator=simulator, bundle=None)
