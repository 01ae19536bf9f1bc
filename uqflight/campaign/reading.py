"""The campaign a results file records, for the commands that read results (`info`, `report`, `check`,
`surrogate export`, and `calibrate` up to its posterior-predictive runs).

Reading never runs campaign code: the stored campaign text is checked as written and its simulator
is never resolved (`schema.resolve_simulator` is not called here): no python module is imported,
whatever files lie in the working directory, beside the results file or at the campaign's recorded
path. The parameters (with the nominal values a run read from its aircraft) come from the results
file's `parameters` attribute. Files written before that attribute: the nominal values the
campaign left to its aircraft are read from the aircraft (JSBSim loading its XML, located from the
recorded campaign folder); a python simulator's parameters never need its code.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

from ..parameters import Parameter
from ..simulators.kinds import simulator_entry
from ..simulators.kinds.jsbsim import locate_aircraft
from . import Campaign, build_campaign, read_settings, schema
from .schema import CampaignError, Checker

STORED_KEYS = ("name", "property", "distribution", "nominal", "lower", "upper")
REFLY = "fly the campaign again (`uqflight run CAMPAIGN --out FILE --restart` starts this file over)"


def parameter_rows(parameters: list[Parameter]) -> list[dict]:
    """Parameters as plain data, one dict of STORED_KEYS each."""
    return [{key: getattr(p, key) for key in STORED_KEYS} for p in parameters]


def parameters_attribute(campaign: Campaign) -> str:
    """The `parameters` attribute a run stores: its parameters' laws (with the nominal values it read
    from its aircraft) as JSON, a list of STORED_KEYS."""
    return json.dumps(parameter_rows(campaign.parameters))


def results_campaign(attrs: dict, source: str) -> Campaign:
    """The campaign of a results file's root attributes (`campaign` text, `parameters`), without running
    any of its code; `source` names it in messages and is the folder a later simulator run resolves from.
    CampaignError when it cannot be rebuilt."""
    check, data, simulator = read_settings(str(attrs.get("campaign", "")), source)
    if attrs.get("parameters") is not None:
        parameters = _stored(check, data, attrs["parameters"])
    else:
        try:
            parameters = schema.parameters(check, data["parameters"], simulator["kind"], None)
        except CampaignError:
            if not simulator_entry(simulator).aircraft:
                raise
            parameters = _from_aircraft(check, data, simulator, attrs)
    return build_campaign(check, data, simulator, parameters, str(attrs.get("campaign", "")))


def stored_parameters(attrs: dict) -> list[dict] | None:
    """The parameters of a results file (root attributes) as dicts (STORED_KEYS); None when they cannot be
    rebuilt (e.g. an older file whose aircraft is not on this machine)."""
    try:
        campaign = results_campaign(attrs, "<results file>")
    except (CampaignError, OSError):
        return None
    return parameter_rows(campaign.parameters)


def _stored(check: Checker, data: dict, value) -> list[Parameter]:
    """The `parameters` attribute checked against the campaign text's parameters."""
    try:
        rows = json.loads(value)
    except (TypeError, ValueError, RecursionError):
        rows = None
    names = [str(name) for name in data["parameters"]] if isinstance(data["parameters"], dict) else None
    if (not isinstance(rows, list) or not all(isinstance(r, dict) and set(r) == set(STORED_KEYS) for r in rows)
            or [r["name"] for r in rows] != names):
        check.fail("parameters", "the results file's parameters attribute does not match its campaign: the file "
                                 "is damaged or was not written by uqflight")
    parameters = []
    for row in rows:
        numbers = [row[key] for key in ("nominal", "lower", "upper")]
        if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in numbers):
            check.fail(f"parameters.{row['name']}", "the results file's parameters attribute holds a value that is "
                                                    "not a finite number: the file is damaged")
        try:
            parameters.append(Parameter(str(row["name"]), str(row["property"]), str(row["distribution"]),
                                        *map(float, numbers)))
        except ValueError as exc:
            check.fail(f"parameters.{row['name']}", str(exc))
    return parameters


def _from_aircraft(check: Checker, data: dict, simulator: dict, attrs: dict) -> list[Parameter]:
    """An older file's parameters with nominal values from its JSBSim aircraft, located from the folder
    of the campaign file the run recorded (`campaign_path`)."""
    from ..simulators.validation_view import validation_view

    recorded = str(attrs.get("campaign_path", "")) or "<results file>"  # no path: the working directory
    if not isinstance(simulator.get("aircraft"), str):  # e.g. a script's: only its run resolved it
        check.fail("simulator.aircraft", "the campaign stored in the file names no aircraft (its script does), and "
                                         f"the file records no parameters attribute to take the nominal values "
                                         f"from: {REFLY}")
    simulator = dict(simulator)
    locate_aircraft(check, simulator, str(Path(recorded)))
    try:
        aircraft = validation_view(simulator)
    except (FileNotFoundError, RuntimeError) as exc:
        check.fail("simulator.aircraft", str(exc))
    return schema.parameters(check, data["parameters"], "jsbsim", aircraft)


def campaign_mapping(campaign: Campaign) -> dict:
    """The campaign file as a YAML mapping (read as `uqflight` reads it)."""
    import yaml

    return yaml.load(campaign.text, Loader=schema.CampaignLoader)


def portable_mapping(campaign: Campaign) -> dict:
    """`campaign_mapping` with the files its simulator names relative to the campaign's folder (a model
    file, an aircraft folder, a script) made absolute: the same campaign when written elsewhere."""
    mapping = campaign_mapping(campaign)
    mapping["simulator"] = simulator_entry(mapping["simulator"]).relocated(mapping["simulator"],
                                                                          campaign_folder(campaign))
    return mapping


def campaign_folder(campaign: Campaign) -> Path:
    """The folder of the campaign file (where its python model and relative paths are looked up)."""
    return Path(campaign.source).resolve().parent


def check_campaign_text(text: str, source: str) -> None:
    """Validate campaign text as `uqflight plan` does (CampaignError when it would be refused)."""
    from ..simulators.validation_view import validation_view
    from . import parse_campaign

    parse_campaign(text, source, view=validation_view)
