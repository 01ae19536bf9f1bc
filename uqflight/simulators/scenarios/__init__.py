"""Scenario kinds: how a JSBSim run is flown (`simulator.scenario.kind`), one module and one entry each.

- level_flight (the default): trim in unaccelerated level flight, elevator excitation, record
  (keys flight, excitation, duration_s, output_rate_hz, trim).
- script: a JSBSim run script (`scenario: {kind: script, script, end_s}`, key output_rate_hz).

An entry owns its keys and their checks (the campaign schema asks it), builds the setup and the
flight of a campaign's `simulator:` mapping, counts its recorded times from the campaign alone, names
the files beyond the aircraft's that travel to workers, and states its provenance and resolution.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from . import level_flight, script


@dataclass(frozen=True)
class ScenarioKind:
    """A registered scenario.

    keys: the `simulator:` keys it owns (beside kind, aircraft, scenario and outputs); scenario_keys: the
    keys of `simulator.scenario` beside kind. check(checker, simulator, folder) -> simulator: refuses
    with checker.fail(field, message), resolves files against the campaign's folder. setup(config, root,
    base, properties) -> setup (aircraft, root, aircraft_file, time, outputs). flight(setup, preflight)
    -> flight: fly(settings, observers=()) -> FlightResult. times(config): the number of recorded times.
    files(config) -> {name: bytes}: files beyond the aircraft's that a worker needs; localize(config,
    folder) -> config reading them from `folder`; relocated(config, folder) -> config with the files it names
    relative to the campaign's `folder` made absolute. provenance(config) -> results-file attributes. span(config)
    -> the flight's last time [s] from the campaign alone (once a script is resolved, its own end), or None.
    resolution(setup, settings, outputs) -> {output: (T,)} or None: the simulator's own resolution.
    facts(config) -> {"flight": text, "excitation": text}: what is flown, defaults resolved (the report).
    """

    keys: tuple[str, ...]
    scenario_keys: tuple[str, ...]
    check: Callable
    setup: Callable
    flight: Callable
    times: Callable
    files: Callable
    localize: Callable
    relocated: Callable
    provenance: Callable
    resolution: Callable
    span: Callable
    example: dict  # a small `simulator:` mapping of this kind (tests)
    facts: Callable


REGISTRY: dict[str, ScenarioKind] = {
    "level_flight": ScenarioKind(
        level_flight.KEYS, (), level_flight.check, level_flight.setup, level_flight.flight, level_flight.times,
        level_flight.files, level_flight.localize, level_flight.relocated,
        level_flight.provenance, level_flight.resolution, level_flight.span,
        {"kind": "jsbsim", "duration_s": 2.0, "output_rate_hz": 10.0}, facts=level_flight.facts),
    "script": ScenarioKind(
        script.KEYS, script.SCENARIO_KEYS, script.check, script.setup, script.flight, script.times,
        script.files, script.localize, script.relocated, script.provenance,
        script.resolution, script.span,
        {"kind": "jsbsim", "scenario": {"kind": "script", "script": "c172_cruise_8K", "end_s": 2.0},
         "output_rate_hz": 10.0}, facts=script.facts),
}
SCENARIO_KINDS = tuple(REGISTRY)
DEFAULT = "level_flight"


def scenario_kind(config: dict) -> str:
    """The scenario kind of a `simulator:` mapping (level_flight when it names none)."""
    scenario = config.get("scenario")
    return scenario.get("kind", DEFAULT) if isinstance(scenario, dict) else DEFAULT


def scenario_entry(config: dict) -> ScenarioKind:
    return REGISTRY[scenario_kind(config)]
