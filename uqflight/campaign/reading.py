"""The campaign a results file records, for the commands that read results (`info`, `report`, `check`,
`surrogate export`, and `calibrate` up to its posterior-predictive runs).

Reading never runs campaign code: the stored campaign text is checked as written and its simulator
is never resolved (`schema.resolve_simulator` is not called here): no python module is imported,
whatever files lie in the working directory, beside the results file or at the campaign's recorded
path. The parameters (with the nominal values a run read from its aircraft) come from the results
file's `parameters` attribute; a file without it is refused, naming the attribute and `run --restart`.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

from ..parameters import Parameter
from ..simulators.kinds import simulator_entry
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
    if attrs.get("parameters") is None:
        check.fail("parameters", "the results file records no parameters attribute (the parameters' laws with the "
                                 f"nominal values its run read): {REFLY}")
    parameters = _stored(check, data, attrs["parameters"])
    return build_campaign(check, data, simulator, parameters, str(attrs.get("campaign", "")))


def stored_parameters(attrs: dict) -> list[dict] | None:
    """The parameters of a results file (root attributes) as dicts (STORED_KEYS); None when they cannot be
    rebuilt (a damaged file, or one without the `parameters` attribute)."""
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
