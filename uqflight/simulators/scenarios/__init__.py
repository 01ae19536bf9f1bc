"""Scenario kinds: how a JSBSim run is flown (`simulator.scenario.kind`), one module and one class each
(`ScenarioKind` in ../base.py; a subclass registers itself).

- level_flight (the default): trim in unaccelerated level flight, elevator excitation, record.
- script: a JSBSim run script (`scenario: {kind: script, script, end_s}`).
"""
from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

from ..base import ScenarioKind
from ..spec import SimulatorSpec
from . import level_flight, script  # noqa: F401  (defining their classes registers them)

REGISTRY = ScenarioKind.registry
SCENARIO_KINDS = tuple(REGISTRY)
DEFAULT = level_flight.LevelFlight.kind


def scenario_entry(config: SimulatorSpec | Mapping) -> ScenarioKind:
    """The scenario kind of a `simulator:` spec or mapping (level_flight when it names none)."""
    scenario = config.get("scenario")
    return REGISTRY[scenario.get("kind", DEFAULT) if isinstance(scenario, Mapping) else DEFAULT]


def flight_setup_from(config: SimulatorSpec, root: Path | None = None, base: Path | None = None, properties=()):
    """The setup of a campaign's `simulator:` spec, built by its scenario kind: the aircraft located (a
    path relative to `base`, the project's, JSBSim's; see `aircraft.locate`) and patched when `properties`
    scale or offset its functions, unless `root` or config.root is given."""
    return scenario_entry(config).setup(config, root, base, properties)
