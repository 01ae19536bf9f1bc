"""The JSBSim engine every scenario flies on (scenarios/): the named outputs, a loaded model's cached
property nodes (`PropertyAccess`), the observers that watch every integration step (`Watch`), what a
flight returns (`FlightResult`), the check before loading an aircraft and its provenance hash.

Every scenario's flight loop accepts observers (`Observer`): the quantities of interest are
computed by one, at every integration step.
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

import jsbsim
import numpy as np

from .base import DivergenceError, Field
from .preflight import check_loads

REPO_ROOT = Path(__file__).resolve().parents[2]  # the source tree (aircraft/bacm)


def default_root() -> Path:
    """The root holding the project's aircraft: the source tree, else the installed package data."""
    from .aircraft import project_roots

    roots = project_roots()
    return roots[0] if roots else REPO_ROOT
DEFAULT_OUTPUTS = ("alpha_deg", "theta_deg", "h_ft", "q_degps", "vtas_kt")

# Named outputs: (JSBSim property, scale to the output's unit).
NAMED_OUTPUTS = {
    "alpha_deg": ("aero/alpha-deg", 1.0),
    "theta_deg": ("attitude/theta-deg", 1.0),
    "h_ft": ("position/h-sl-ft", 1.0),
    "q_degps": ("velocities/q-rad_sec", 180.0 / math.pi),
    "vtas_kt": ("velocities/vtrue-kts", 1.0),
}
# every scenario's recording rate
OUTPUT_RATE = Field("Recording rate [Hz]; must divide the integration rate (120 Hz for level flight, the script's "
                    "own). Default 20, or for a script whose rate 20 does not divide the fastest divisor of its rate "
                    "below 20 (dt = 0.02 s: 16.67). `output_rate_hz: 10`", number=True, minimum=0.0, strict=True)
UNITS = {"alpha_deg": "deg", "theta_deg": "deg", "h_ft": "ft", "q_degps": "deg/s", "vtas_kt": "kt"}

ATMOSPHERE = "atmosphere/"  # settings applied after the trim (still air), at t = 0 of the recorded flight


@dataclass
class FlightResult:
    time: np.ndarray
    outputs: dict[str, np.ndarray]
    trim: object  # a level flight's TrimResult; None: the scenario has no trim of its own (a script trims itself)
    warnings: list[str] = field(default_factory=list)  # what the reader must know, e.g. an unmoved surface


class Observer(Protocol):
    """Watches one flight: `step(t, values)` is called once at t = 0 (after the trim, or after a script's
    run_ic) and after every integration step, with the current values of `properties` in order. A
    level flight also calls `at_trim(fdm)`, when the observer has it, right after a successful trim and
    before the excitation."""

    properties: tuple[str, ...]

    def step(self, t: float, values: Sequence[float]) -> None:
        """One integration step's values of `properties` at the simulator's time t [s]."""


class Watch:
    """A flight's observers bound to their property nodes: `watch(t)` calls every observer's step."""

    def __init__(self, flight, observers: Sequence[Observer]):
        self._bound = [(observer.step, [flight.node(name) for name in observer.properties])
                       for observer in observers]

    def __call__(self, t: float) -> None:
        for step, nodes in self._bound:
            step(t, [node.get_double_value() for node in nodes])


def aircraft_hash(setup) -> str:
    """sha256 over the aircraft's XML files (airframe, engines, systems), for provenance."""
    from .aircraft import AircraftFiles, AircraftLocation

    location = AircraftLocation(setup.aircraft, setup.aircraft_file.parent, Path(setup.root), "root")
    return AircraftFiles.read(location).hash()


def quiet_jsbsim() -> None:
    """Silence JSBSim's console messages (trim reports print even at debug level 0)."""
    jsbsim.set_logger(jsbsim.DefaultLogger(jsbsim.LogLevel.FATAL))


def ready_to_load(setup, preflight: bool = True) -> None:
    """Before a flight loads `setup`'s aircraft: FileNotFoundError when its file is missing; with
    `preflight`, the check that JSBSim loads it without aborting the process (preflight.py); JSBSim quiet."""
    if not setup.aircraft_file.is_file():
        raise FileNotFoundError(f"aircraft {setup.aircraft!r}: no file {setup.aircraft_file}")
    if preflight:  # JSBSim may abort the process that loads a broken aircraft
        check_loads(setup.root, setup.aircraft)
    quiet_jsbsim()


class PropertyAccess:
    """Cached property nodes of a loaded `self.fdm`, with errors naming the aircraft's closest properties."""

    fdm: jsbsim.FGFDMExec
    aircraft: str

    def _bind(self, fdm: jsbsim.FGFDMExec, aircraft: str) -> None:
        self.fdm, self.aircraft = fdm, aircraft
        self._pm = fdm.get_property_manager()
        self._nodes: dict[str, object] = {}

    def has_property(self, name: str) -> bool:
        return bool(self._pm.hasNode(name))

    def node(self, name: str):
        """The cached property node of `name` (KeyError naming it if the aircraft lacks it)."""
        node = self._nodes.get(name)
        if node is None:
            if not self.has_property(name):
                raise KeyError(f"property {name!r} does not exist in aircraft {self.aircraft!r}"
                               f"{self.property_hint(name)}")
            node = self._nodes[name] = self._pm.get_node(name)
        return node

    def property_hint(self, name: str) -> str:
        """'; did you mean ...?' with the aircraft's properties closest to `name` (any case), or ''."""
        import difflib

        names = [line.rsplit(" (", 1)[0] for line in self.fdm.query_property_catalog("").splitlines()]
        by_lower = {n.lower(): n for n in names}
        close = difflib.get_close_matches(name.lower(), by_lower, n=3, cutoff=0.8)
        return f"; did you mean {' or '.join(by_lower[c] for c in close)}?" if close else ""

    def _output_source(self, name: str):
        prop, scale = NAMED_OUTPUTS.get(name, (name, 1.0))
        return self.node(prop), scale


def check_finite(data: np.ndarray) -> None:
    """DivergenceError when the recorded outputs hold a NaN or an infinity."""
    if not np.all(np.isfinite(data)):
        raise DivergenceError("NaN or infinite value in the recorded outputs")

