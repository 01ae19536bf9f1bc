"""`simulator: {kind: jsbsim, aircraft, scenario, outputs, properties, ...}`: a JSBSim aircraft flown as its
scenario kind says (level flight when it names none; simulators/scenarios owns the scenario's keys)."""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from ...text.labels import name_unit
from ..aircraft import AircraftNotFound, locate
from ..base import Field, SimulatorKind
from ..bundle import aircraft_bundle
from ..jsbsim import DEFAULT_OUTPUTS, NAMED_OUTPUTS, UNITS, aircraft_hash
from ..scenarios import DEFAULT as DEFAULT_SCENARIO
from ..scenarios import REGISTRY as SCENARIOS
from ..scenarios import SCENARIO_KINDS, scenario_entry
from ..spec import SimulatorSpec
from .outputs import KIND, OUTPUTS, check_outputs


class JSBSimSimulator:
    """The campaign's aircraft and flight, flown as its scenario kind says (scenarios/); parameters
    map to JSBSim properties."""

    def __init__(self, config: SimulatorSpec, properties: list[str], base: Path | None = None):
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
        flight: the drift between its two valid trims; see `LevelFlight.resolution`), or None."""
        return self.scenario.resolution(self.setup, self.settings(kappa), ours)

    def restart(self) -> None:
        """Reload the aircraft (about 2 ms), so that a chunk's results do not depend on what
        the worker flew before: JSBSim's turboprop keeps engine state across resets, which
        moves trims in the 13th digit. Chunks are fixed by design order, so results are
        bit-identical whatever the number of workers or the executor."""
        if self._flown:
            self.flight = self.scenario.flight(self.setup, preflight=False)  # checked by __init__
            self._flown = False



class JSBSim(SimulatorKind):
    """A JSBSim flight (scenario below).

    Examples
    --------
    >>> JSBSim().span(SimulatorSpec("jsbsim", {"duration_s": 3.0}))
    3.0
    """

    kind = "jsbsim"
    aircraft = True
    fields = {
        "kind": KIND,
        "aircraft": Field("A project or JSBSim aircraft name, or a folder (relative to the campaign file). Default "
                          "`bacm` (level flight); a script names its own. `aircraft: c172p`"),
        "scenario": Field("How a JSBSim run is flown: `{kind: level_flight}` (the default) or `{kind: script, "
                          "script: NAME_OR_PATH}`."),
        "outputs": OUTPUTS,
        "properties": Field("`{PROPERTY: VALUE}` set for every run (`ic/...` before the reset, the others after it; "
                            "level flight applies `atmosphere/...` after the trim). "
                            "`properties: {atmosphere/turb-type: 3}`"),
    }
    example = ({"kind": "jsbsim", "duration_s": 1.0, "output_rate_hz": 10.0},
               {"CL0": {"property": "aero/uq/CL0", "distribution": "normal", "interval_pct": 20}})

    def check(self, check, value: dict) -> dict:
        """The keys as written (the scenario's by its kind); the aircraft is not located yet (`resolve`)."""
        scenario = SCENARIOS[DEFAULT_SCENARIO]
        if "scenario" in value:
            written = value["scenario"]
            if not isinstance(written, dict):
                check.fail("simulator.scenario", f"expected a mapping with a kind key, got {check.quoted(written)}")
            if "kind" not in written:
                check.fail("simulator.scenario.kind", f"is required; expected one of {', '.join(SCENARIO_KINDS)}")
            scenario = SCENARIOS[check.string(written["kind"], "simulator.scenario.kind", SCENARIO_KINDS)]
            check.mapping(written, "simulator.scenario", ("kind", *scenario.scenario_keys))
        sim = dict(check.mapping(value, "simulator", (*self.keys, *scenario.keys)))
        if scenario.default_aircraft is not None:  # a script names its aircraft itself (resolved with the script)
            sim.setdefault("aircraft", scenario.default_aircraft)
        if "aircraft" in sim:
            check.string(sim["aircraft"], "simulator.aircraft")
        if "properties" in sim:
            check_fixed_properties(check, sim["properties"])
        if "outputs" in sim:
            check_outputs(check, sim["outputs"])
        return sim

    def resolve(self, check, sim: SimulatorSpec, source: str) -> SimulatorSpec:
        """The scenario's files resolved and the aircraft located (`aircraft_path`, the folder that travels
        with the simulator), relative to the campaign file `source`."""
        sim = scenario_entry(sim).check(check, sim, Path(source).resolve().parent)
        aircraft = check.string(sim.get("aircraft", SCENARIOS[DEFAULT_SCENARIO].default_aircraft), "simulator.aircraft")
        return replace(sim.with_settings(aircraft=aircraft), aircraft_path=located_aircraft(check, aircraft, source))

    def make(self, config: SimulatorSpec, parameter_names: list[str], properties: list[str],
             base: Path) -> JSBSimSimulator:
        return JSBSimSimulator(config, properties, base)

    def bundle(self, config: SimulatorSpec, properties, base) -> dict | None:
        """The aircraft (the patched copy when `properties` perturb its functions) and its scenario's files."""
        return aircraft_bundle(config, properties, base, scenario_entry(config).files)

    def provenance(self, config: SimulatorSpec, base: Path | None = None, properties=()) -> dict:
        """The aircraft's hash (the patched copy's when `properties` scale or offset its functions), and what
        its scenario kind adds (nothing for level flight)."""
        scenario = scenario_entry(config)
        return {"aircraft_hash": aircraft_hash(scenario.setup(config, base=base, properties=properties)),
                **scenario.provenance(config)}

    def relocated(self, config: dict, folder: Path) -> dict:
        """An aircraft given as a folder relative to `folder` made absolute (a project or JSBSim aircraft
        keeps its name), and the scenario's files as its kind says."""
        sim = dict(config)
        if "aircraft" in sim:
            try:
                location = locate(sim["aircraft"], Path(folder))
            except AircraftNotFound:  # not there (any more): as written, for the campaign's checks to name it
                location = None
            if location is not None and location.origin == "path":
                sim["aircraft"] = str(location.folder)
        return scenario_entry(sim).relocated(sim, Path(folder))

    def recorded(self, config: SimulatorSpec) -> tuple[int, int]:
        return scenario_entry(config).times(config), len(config.get("outputs", DEFAULT_OUTPUTS))

    def span(self, config: SimulatorSpec) -> float | None:
        return scenario_entry(config).span(config)

    def trims_level(self, config: SimulatorSpec) -> bool:
        return scenario_entry(config).level_trim

    def flight_summary(self, config: SimulatorSpec) -> dict[str, str]:
        return scenario_entry(config).flight_summary(config)

    def check_source(self, check, name, path: str, config: SimulatorSpec, aircraft) -> None:
        """A named output or, when the aircraft is known, one of its properties."""
        check.string(name, path)
        if aircraft is not None and name not in NAMED_OUTPUTS and aircraft.value(name) is None:
            check.fail(path, f"expected one of {', '.join(NAMED_OUTPUTS)} or a JSBSim property of aircraft "
                             f"{aircraft.aircraft!r}, got {name!r}{aircraft.hint(name)}")


def check_fixed_properties(check, value) -> dict:
    """`simulator.properties`: {PROPERTY: VALUE} set for every run (a turbulence model, a steady wind)."""
    if not isinstance(value, dict) or not value:
        check.fail("simulator.properties", "expected a mapping of JSBSim properties to numbers, got "
                                           f"{check.quoted(value)}")
    for name, number in value.items():
        check.string(name, "simulator.properties")
        check.number(number, f"simulator.properties.{name}")
    return value


def located_aircraft(check, aircraft: str, source: str) -> str:
    """The folder of the aircraft `aircraft`, relative to the campaign file `source` (or the project's,
    JSBSim's; see `aircraft.locate`). Reads folders only."""
    try:
        return str(locate(aircraft, Path(source).resolve().parent).folder)
    except AircraftNotFound as exc:
        check.fail("simulator.aircraft", str(exc))


