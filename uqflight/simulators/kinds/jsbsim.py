"""`simulator: {kind: jsbsim, aircraft, scenario, outputs, properties, ...}`: a JSBSim aircraft flown as its
scenario kind says (level flight when it names none; simulators/scenarios owns the scenario's keys)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ...labels import name_unit
from ..jsbsim import DEFAULT_OUTPUTS, NAMED_OUTPUTS, UNITS, aircraft_hash
from ..scenarios import DEFAULT as DEFAULT_SCENARIO
from ..scenarios import REGISTRY as SCENARIOS
from ..scenarios import SCENARIO_KINDS, scenario_entry, scenario_kind
from .outputs import check_outputs

KEYS = ("kind", "aircraft", "scenario", "outputs", "properties")
DEFAULT_AIRCRAFT = "bacm"


def check(check, value: dict) -> dict:
    """The keys as written (the scenario's by its entry); the aircraft is not located yet (`resolve`)."""
    kind = DEFAULT_SCENARIO
    if "scenario" in value:
        scenario = value["scenario"]
        if not isinstance(scenario, dict):
            check.fail("simulator.scenario", f"expected a mapping with a kind key, got {check.shown(scenario)}")
        if "kind" not in scenario:
            check.fail("simulator.scenario.kind", f"is required; expected one of {', '.join(SCENARIO_KINDS)}")
        kind = check.string(scenario["kind"], "simulator.scenario.kind", SCENARIO_KINDS)
        check.mapping(scenario, "simulator.scenario", ("kind", *SCENARIOS[kind].scenario_keys))
    sim = dict(check.mapping(value, "simulator", (*KEYS, *SCENARIOS[kind].keys)))
    if kind == DEFAULT_SCENARIO:  # a script names its aircraft itself (resolved with the script)
        sim.setdefault("aircraft", DEFAULT_AIRCRAFT)
    if "aircraft" in sim:
        check.string(sim["aircraft"], "simulator.aircraft")
    if "properties" in sim:
        check_fixed_properties(check, sim["properties"])
    if "outputs" in sim:
        check_outputs(check, sim["outputs"])
    return sim


def check_fixed_properties(check, value) -> dict:
    """`simulator.properties`: {PROPERTY: VALUE} set for every run (a turbulence model, a steady wind)."""
    if not isinstance(value, dict) or not value:
        check.fail("simulator.properties", "expected a mapping of JSBSim properties to numbers, got "
                                           f"{check.shown(value)}")
    for name, number in value.items():
        check.string(name, "simulator.properties")
        check.number(number, f"simulator.properties.{name}")
    return value


def resolve(check, sim: dict, source: str) -> None:
    """The scenario's files resolved and the aircraft located (`sim["aircraft_path"]`, the folder that
    travels with the simulator), relative to the campaign file `source`."""
    folder = Path(source).resolve().parent
    sim.update(SCENARIOS[scenario_kind(sim)].check(check, sim, folder))
    check.string(sim.setdefault("aircraft", DEFAULT_AIRCRAFT), "simulator.aircraft")
    locate_aircraft(check, sim, source)


def locate_aircraft(check, sim: dict, source: str) -> None:
    """sim["aircraft_path"]: the folder of the aircraft, relative to the campaign file `source` (or the
    project's, JSBSim's; see `aircraft.locate`). Reads folders only."""
    from ..aircraft import AircraftNotFound, locate

    try:
        sim["aircraft_path"] = str(locate(sim["aircraft"], Path(source).resolve().parent).folder)
    except AircraftNotFound as exc:
        check.fail("simulator.aircraft", str(exc))


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
        self.units = {name: UNITS.get(name) or name_unit(name) for name in self.setup.outputs}

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

    def resolution(self, kappa: np.ndarray, ours: dict[str, np.ndarray] | None = None) -> dict[str, np.ndarray] | None:
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


def make(config: dict, parameter_names: list[str], properties: list[str], base: Path) -> JSBSimSimulator:
    return JSBSimSimulator(config, properties, base)


def bundle(config: dict, properties, base) -> dict | None:
    from ..bundle import aircraft_bundle

    return aircraft_bundle(config, properties, base)


def provenance(config: dict, base: Path | None = None, properties=()) -> dict:
    """The aircraft's hash (the patched copy's when `properties` scale or offset its functions), and what
    its scenario kind adds (nothing for level flight)."""
    entry = scenario_entry(config)
    return {"aircraft_hash": aircraft_hash(entry.setup(config, base=base, properties=properties)),
            **entry.provenance(config)}


def relocated(config: dict, folder: Path) -> dict:
    """An aircraft given as a folder relative to `folder` made absolute (a project or JSBSim aircraft
    keeps its name), and the scenario's files as its kind says."""
    from ..aircraft import AircraftNotFound, locate

    sim = dict(config)
    if "aircraft" in sim:
        try:
            location = locate(sim["aircraft"], Path(folder))
        except AircraftNotFound:  # not there (any more): as written, for the campaign's checks to name it
            location = None
        if location is not None and location.origin == "path":
            sim["aircraft"] = str(location.folder)
    return SCENARIOS[scenario_kind(sim)].relocated(sim, Path(folder))


def recorded(config: dict) -> tuple[int, int]:
    return scenario_entry(config).times(config), len(config.get("outputs", DEFAULT_OUTPUTS))


def span(config: dict) -> float | None:
    return scenario_entry(config).span(config)


def facts(config: dict) -> dict[str, str]:
    return scenario_entry(config).facts(config)


def check_source(check, name, path: str, config: dict, aircraft) -> None:
    """A named output or, when the aircraft is known, one of its properties."""
    check.string(name, path)
    if aircraft is not None and name not in NAMED_OUTPUTS and aircraft.value(name) is None:
        check.fail(path, f"expected one of {', '.join(NAMED_OUTPUTS)} or a JSBSim property of aircraft "
                         f"{aircraft.aircraft!r}, got {name!r}{aircraft.hint(name)}")
