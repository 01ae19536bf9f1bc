"""The `level_flight` scenario: trim in unaccelerated level flight, elevator excitation, record
(`JSBSimFlight` in ../jsbsim.py). Keys: flight {altitude_ft, airspeed_ktas}, excitation {kind,
amplitude_deg, start_s, duration_s}, duration_s, output_rate_hz, trim."""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from ..base import FlightError
from ..jsbsim import Excitation, FlightSetup, JSBSimFlight

KEYS = ("flight", "excitation", "duration_s", "output_rate_hz", "trim")
EXCITATION_KEYS = ("kind", "amplitude_deg", "start_s", "duration_s")
FLIGHT_KEYS = ("altitude_ft", "airspeed_ktas")


def check(check, sim: dict, folder: Path) -> dict:
    """The scenario's keys checked (`check` is the campaign's Checker); the timing by FlightSetup itself."""
    if "trim" in sim:
        check.string(sim["trim"], "simulator.trim", FlightSetup.TRIMS)
    flight = check.mapping(sim.get("flight", {}), "simulator.flight", FLIGHT_KEYS)
    if "altitude_ft" in flight:
        check.number(flight["altitude_ft"], "simulator.flight.altitude_ft", 0.0)
    if "airspeed_ktas" in flight:
        check.number(flight["airspeed_ktas"], "simulator.flight.airspeed_ktas", 0.0, strict=True)
    excitation = check.mapping(sim.get("excitation", {}), "simulator.excitation", EXCITATION_KEYS)
    if "kind" in excitation:
        check.string(excitation["kind"], "simulator.excitation.kind", Excitation.KINDS)
    if "amplitude_deg" in excitation:
        check.number(excitation["amplitude_deg"], "simulator.excitation.amplitude_deg")
    for key in ("start_s", "duration_s"):
        if key in excitation:
            check.number(excitation[key], f"simulator.excitation.{key}", 0.0)
    if "duration_s" in sim:
        check.number(sim["duration_s"], "simulator.duration_s", 0.0, strict=True)
    if "output_rate_hz" in sim:
        check.number(sim["output_rate_hz"], "simulator.output_rate_hz", 0.0, strict=True)
    try:
        _timing(sim)
    except ValueError as exc:  # FlightSetup's own message: "output_rate_hz: expected ..."
        key, _, message = str(exc).partition(": ")
        check.fail(f"simulator.{key}", message)
    return sim


def _timing(config: dict) -> FlightSetup:
    """The timing alone, FlightSetup's defaults where the campaign gives none (its own checks apply)."""
    return FlightSetup(**{key: float(config[key]) for key in ("duration_s", "rate_hz", "output_rate_hz") if key in config})


def span(config: dict) -> float:
    """The flight's last time [s]: duration_s."""
    return _timing(config).duration_s


def times(config: dict) -> int:
    """The number of recorded times (the trimmed state, then duration_s at output_rate_hz)."""
    return _timing(config).n_times


def setup(config: dict, root: Path | None = None, base: Path | None = None, properties=()) -> FlightSetup:
    """A FlightSetup from a campaign's `simulator:` mapping (keys already validated). The aircraft
    is located (a path relative to `base`, the project's, JSBSim's; see `aircraft.locate`) and
    patched when `properties` scale or offset its functions, unless `root` or config["root"] is given."""
    from ..aircraft import default_condition
    from ..jsbsim import DEFAULT_OUTPUTS
    from ..patch import PreparedAircraft

    name = config.get("aircraft", "bacm")
    root = config.get("root", root)
    if root is None:
        prepared = PreparedAircraft(config.get("aircraft_path", name), base, properties)
        name, root = prepared.name, prepared.root
    flight = {**default_condition(name), **config.get("flight", {})}
    return FlightSetup(
        aircraft=name,
        root=Path(root),
        altitude_ft=float(flight["altitude_ft"]),
        airspeed_ktas=float(flight["airspeed_ktas"]),
        excitation=Excitation(**config.get("excitation", {})),
        duration_s=float(config.get("duration_s", 50.0)),
        rate_hz=float(config.get("rate_hz", 120.0)),
        output_rate_hz=float(config.get("output_rate_hz", 20.0)),
        outputs=tuple(config.get("outputs", DEFAULT_OUTPUTS)),
        trim=config.get("trim", "newton"),
    )


def facts(config: dict) -> dict[str, str]:
    """The flight condition and excitation a campaign's `simulator:` mapping flies, defaults resolved
    (the report's campaign table), without locating the aircraft."""
    from ..aircraft import default_condition

    condition = {**default_condition(str(config.get("aircraft", "bacm"))), **(config.get("flight") or {})}
    excitation = Excitation(**(config.get("excitation") or {}))
    shape = (f"{excitation.kind}" if excitation.kind == "none" else
             f"{excitation.kind} {excitation.amplitude_deg:g} deg at {excitation.start_s:g} s"
             + (f" for {excitation.duration_s:g} s" if excitation.kind != "step" else ""))
    return {"flight": f"level, {condition['altitude_ft']:g} ft, {condition['airspeed_ktas']:g} KTAS, "
                      f"trim {config.get('trim', 'newton')}",
            "excitation": f"elevator {shape}"}


def flight(setup: FlightSetup, preflight: bool = True) -> JSBSimFlight:
    return JSBSimFlight(setup, preflight=preflight)


def files(config: dict) -> dict[str, bytes]:
    """Nothing beyond the aircraft's files."""
    return {}


def localize(config: dict, folder: Path) -> dict:
    return config


def relocated(config: dict, folder: Path) -> dict:
    """Level flight names no files."""
    return config


def provenance(config: dict) -> dict:
    """Nothing beyond the aircraft's hash (results files stay as they were before scenarios)."""
    return {}


def resolution(setup: FlightSetup, settings: dict[str, float], ours: dict[str, np.ndarray] | None = None
               ) -> dict[str, np.ndarray] | None:
    """{output: (T,)}: how far the flight of `settings` with the campaign's trim (`ours`, the outputs it
    gave, flown here when None) and with the other trim (Newton's, JSBSim's) have drifted apart so far,
    max over t' ≤ t of |y₁(t') − y₂(t')|. Both trims pass the same acceptance checks, so a spread of the
    outputs below this is the trims' residual dynamics, not the inputs': the simulator does not resolve
    it. None when either trim fails."""
    other = replace(setup, trim="jsbsim" if setup.trim == "newton" else "newton")
    try:
        ours = ours if ours is not None else JSBSimFlight(setup, preflight=False).fly(settings).outputs
        theirs = JSBSimFlight(other, preflight=False).fly(settings).outputs  # same files as the simulator checked
    except FlightError:
        return None
    return {name: np.maximum.accumulate(np.abs(ours[name] - theirs[name])) for name in ours}
