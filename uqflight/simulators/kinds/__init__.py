"""Simulator kinds (`simulator.kind`): what runs a sample, one module and one entry each.

- jsbsim: a JSBSim aircraft flown as its scenario kind says (simulators/scenarios); parameters set
  properties of the aircraft or perturb its aerodynamic functions.
- python: any Python callable (closed forms for tests, other models); parameters are its arguments.

An entry owns its keys and their checks (the campaign schema asks it), finds what it runs, builds the
simulator a worker uses, names the files that travel to workers and the provenance the results file
keeps, and counts what a run records from the campaign alone (for `limits`).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from . import jsbsim, python


@dataclass(frozen=True)
class SimulatorKind:
    """A registered simulator kind.

    keys: its `simulator:` keys (a JSBSim scenario adds its own: `check` asks it). check(checker, value)
    -> the mapping checked as written, nothing imported or located. resolve(checker, sim, source):
    find what it runs relative to the campaign file `source` (a python module is imported; an aircraft
    located); only for campaigns about to be planned or run. make(config, parameter_names, properties,
    base) -> simulator. bundle(config, properties, base) -> the files a worker needs, or None.
    provenance(config, base, properties) -> results-file attributes. relocated(config, folder) -> the
    mapping as written with the files it names relative to `folder` made absolute (a campaign written
    elsewhere, e.g. calibrate's calibrated.yaml, reads the same files). recorded(config) -> (times, outputs)
    a run records, from the campaign alone (1 where known only once a sample has run). span(config) ->
    the flight's last time [s], or None. check_source(checker, name, path, config, aircraft): a name a
    quantity reads. aircraft: parameters set properties of an aircraft (`property` or `function`
    required, checked against the probed aircraft). integer_seeds: a seed parameter reaches the model
    as an int (JSBSim properties are doubles). facts(config) -> {"flight": text, "excitation": text}: what
    is flown, defaults resolved (the report; {} for a model). example: a small `simulator:` mapping of this kind and the
    `parameters:` of a campaign on it (tests).
    """

    keys: tuple[str, ...]
    check: Callable
    resolve: Callable
    make: Callable
    bundle: Callable
    provenance: Callable
    relocated: Callable
    recorded: Callable
    span: Callable
    check_source: Callable
    aircraft: bool
    integer_seeds: bool
    facts: Callable
    example: tuple[dict, dict]


REGISTRY: dict[str, SimulatorKind] = {
    "jsbsim": SimulatorKind(jsbsim.KEYS, jsbsim.check, jsbsim.resolve, jsbsim.make, jsbsim.bundle,
                            jsbsim.provenance, jsbsim.relocated, jsbsim.recorded, jsbsim.span, jsbsim.check_source,
                            aircraft=True, integer_seeds=False, facts=jsbsim.facts,
                            example=({"kind": "jsbsim", "duration_s": 1.0, "output_rate_hz": 10.0},
                                     {"CL0": {"property": "aero/uq/CL0", "distribution": "normal",
                                              "interval_pct": 20}})),
    "python": SimulatorKind(python.KEYS, python.check, python.resolve, python.make, python.bundle,
                            python.provenance, python.relocated, python.recorded, python.span, python.check_source,
                            aircraft=False, integer_seeds=True, facts=python.facts,
                            example=({"kind": "python", "function": "uqflight.simulators.models:exp_decay"},
                                     {"a": {"distribution": "normal", "nominal": 1.0, "lower": 0.9, "upper": 1.1}})),
}
SIMULATOR_KINDS = tuple(REGISTRY)


def simulator_entry(config: dict) -> SimulatorKind:
    """The entry of a checked `simulator:` mapping."""
    return REGISTRY[config["kind"]]

