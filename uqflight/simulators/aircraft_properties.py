"""The aircraft as campaign validation sees it: property names, values and writability, with hints."""
from __future__ import annotations


import jsbsim

from .directives import LINEARIZATION
from .scenarios import flight_setup_from
from .spec import SimulatorSpec


class AircraftProperties:
    """The campaign's aircraft as a sample finds it before the flight, as its scenario prepares it
    (level flight: loaded, with the flight condition's initial conditions set, so `ic/vt-kts` reads the
    campaign's airspeed and `ic/vc-kts` the matching calibrated airspeed; a script: loaded with it).
    Validation reads nominal values here: the class is the `read_aircraft` of `campaign.load_campaign`."""

    def __init__(self, simulator: SimulatorSpec):
        from .aircraft import aero_functions
        from .aero_factors import aero_factors
        from .scenarios import scenario_entry

        setup = flight_setup_from(simulator.with_settings(outputs=[]))  # raises AircraftNotFound (a FileNotFoundError)
        self.aircraft = setup.aircraft
        xml = setup.aircraft_file.read_bytes()
        self.functions = [f.name for f in aero_functions(xml)]
        self.aero_factors = aero_factors(xml)  # each function's unit and reference factor
        self._flight = scenario_entry(simulator).flight(setup)
        self._flight.prepare_for_validation()

    def value(self, name: str) -> float | None:
        """The property's value (None when the aircraft has no such property)."""
        return self._flight.property_value(name)

    def writable(self, name: str) -> bool:
        """False for a read-only property, and for simulation/do_linearization: setting it makes JSBSim
        write a file in the working directory (directives.py)."""
        return LINEARIZATION not in name and self._flight.node(name).get_attribute(jsbsim.Attribute.WRITE)

    def hint(self, name: str) -> str:
        """'; did you mean ...?' with the aircraft's properties closest to `name`, or ''."""
        return self._flight.property_hint(name)

