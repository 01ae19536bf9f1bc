"""The campaign a results file records, stored once: the root attribute `record`, versioned JSON, beside the
campaign's YAML text (the attribute `campaign`), which is for people and never read as a campaign.

The record holds the campaign's mapping as written and what `plan` resolved from it: the parameters' laws
with the nominal values read from the aircraft, the method with the order its design allows, the design's
kind and facts (`designs.Design.info`), and the package versions. Every command that reads results
(`info`, `report`, `check`, `surrogate export`, `calibrate`) reads it through `read_record`, which checks it
with the campaign's own checks, once, into a `CampaignRecord`: a damaged or hand-edited record is one line
naming the file and the field, never a traceback or a number computed from it.

Reading never runs campaign code: the simulator is never resolved (`schema.resolve_simulator` is not
called), so no python module is imported, whatever files lie beside the results file.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass, replace

from ..designs import DESIGN_KINDS
from ..designs import REGISTRY as DESIGNS
from ..designs.base import is_integer
from ..parameters import Parameter, seed_names
from ..text.console import quoted_value
from . import Campaign, build_campaign, check_settings, schema
from .schema import CampaignError, Checker

ATTRIBUTE = "record"
VERSION = 1
STORED_KEYS = ("name", "property", "distribution", "nominal", "lower", "upper")
RECORD_KEYS = ("version", "campaign", "parameters", "method", "design", "versions")
PROVENANCE = ("campaign_hash", "campaign_path", "created", "aircraft_hash", "scenario")  # text attributes beside it
REFLY = "fly the campaign again (`uqflight run CAMPAIGN --out FILE --restart` starts this file over)"


@dataclass(frozen=True)
class CampaignRecord:
    """A results file's campaign (`campaign`: with its parameters' nominal values and its method's order as
    its run resolved them), its design's kind and recorded facts, and the versions it was made with."""

    campaign: Campaign
    design_kind: str
    design_info: dict
    versions: dict

    @property
    def seeds(self) -> list[str]:
        """The parameters that are random streams' seeds."""
        return seed_names(self.campaign.parameters)

    @property
    def dependence(self) -> dict | None:
        """The inputs' copula as summary.json states it (GaussianCopula.summary); None: independent."""
        return None if self.campaign.dependence is None else self.campaign.dependence.summary()

    @property
    def flight(self) -> dict[str, str]:
        """What the simulator flies ({"flight": ..., "excitation": ...}), defaults resolved by its kind (and
        scenario kind); {} for a python model."""
        return self.campaign.simulator.entry.flight_summary(self.campaign.simulator)

    @property
    def parameter_rows(self) -> list[dict]:
        """The parameters as plain data (STORED_KEYS)."""
        return parameter_rows(self.campaign.parameters)


def parameter_rows(parameters: list[Parameter]) -> list[dict]:
    """Parameters as plain data, one dict of STORED_KEYS each."""
    return [{key: getattr(p, key) for key in STORED_KEYS} for p in parameters]


def record_text(campaign: Campaign, design_kind: str, design_info: dict, versions: dict) -> str:
    """The `record` attribute of a results file of `campaign` (validated for its aircraft and design)."""
    return json.dumps({"version": VERSION, "campaign": campaign.mapping,
                       "parameters": parameter_rows(campaign.parameters), "method": campaign.method.as_mapping(),
                       "design": {"kind": design_kind, "info": design_info}, "versions": versions}, default=str)


class RecordChecker(Checker):
    """A Checker whose messages name the file's attribute `record` and the field inside it; a campaign's
    own field (`method.order`, as its checks name it) is inside the record's `campaign`."""

    def __init__(self, source: str, inside: str = ""):
        super().__init__(source)
        self.inside = inside

    def fail(self, path: str, message: str):
        field_path = ".".join(part for part in (self.inside, path) if part)
        raise CampaignError(f"{self.source}: attribute {ATTRIBUTE}", field_path, message)


def read_record(attrs, source: str) -> CampaignRecord:
    """The campaign a results file records (its root attributes `attrs`; `source` names it in messages and is
    where a later simulator run resolves relative files from): CampaignError naming the file, the attribute
    and the field when it is missing, of another version, or does not pass the campaign's checks."""
    for name in PROVENANCE:
        if name in attrs and not isinstance(attrs[name], str):
            raise CampaignError(f"{source}: attribute {name}", "", f"expected text, got {quoted_value(attrs[name])}")
    check = RecordChecker(source)
    text = attrs.get(ATTRIBUTE)
    if text is None:
        raise CampaignError(source, "", f"the results file has no {ATTRIBUTE} attribute (the campaign it was made "
                                        f"with): a file of an older layout, or not written by uqflight: {REFLY}")
    if not isinstance(text, str):
        check.fail("", f"expected JSON text, got {quoted_value(text)}")
    try:
        record = json.loads(text)
    except (ValueError, RecursionError) as exc:
        check.fail("", f"is not JSON ({exc})")
    record = check.mapping(record, "", RECORD_KEYS, required=RECORD_KEYS)
    if record["version"] != VERSION or isinstance(record["version"], bool):
        check.fail("version", f"this uqflight reads version {VERSION}, the file holds version "
                              f"{quoted_value(record['version'])}: {REFLY}")
    versions = record["versions"]
    if not isinstance(versions, dict) or not all(isinstance(v, str) for v in versions.values()):
        check.fail("versions", f"expected a mapping of package versions, got {quoted_value(versions)}")
    inside = RecordChecker(source, "campaign")
    try:
        _, data, simulator = check_settings(inside, record["campaign"])
    except RecursionError:
        check.fail("campaign", "is nested deeper than a campaign")
    parameters = _parameters(check, data, record["parameters"])
    campaign = replace(build_campaign(inside, data, simulator, parameters, str(attrs.get("campaign", "")),
                                      mapping=record["campaign"]),
                       method=schema.method(RecordChecker(source), record["method"]))
    design = check.mapping(record["design"], "design", ("kind", "info"), required=("kind", "info"))
    kind = design["kind"]
    if not isinstance(kind, str) or kind not in DESIGN_KINDS:
        check.fail("design.kind", f"expected one of {', '.join(DESIGN_KINDS)}, got {quoted_value(kind)}")
    return CampaignRecord(campaign, kind, design["info"], versions)


def check_design_info(record: CampaignRecord, source: str, runs: int) -> None:
    """The design's recorded facts that the statistics read, checked against the file's `runs`: replicates
    (blocks of runs), n_base (a pick-freeze design's base rows), scramble, and its kind's own."""
    check, info = RecordChecker(source, "design.info"), record.design_info
    if not isinstance(info, dict):
        RecordChecker(source).fail("design.info", f"expected a mapping of the design's facts, got {quoted_value(info)}")
    replicates = info.get("replicates", 1)
    if not is_integer(replicates) or not 1 <= replicates <= max(runs, 1) or runs % replicates:
        check.fail("replicates", f"expected an integer >= 1 dividing the {runs} runs, got {quoted_value(replicates)}")
    problem = DESIGNS[record.design_kind].info_problem(info, runs, len(record.campaign.parameters))
    if problem:
        check.fail(problem[0], f"{problem[1]}, got {quoted_value(info.get(problem[0]))}")
    if not isinstance(info.get("scramble", True), bool):
        check.fail("scramble", f"expected true or false, got {quoted_value(info['scramble'])}")


def _parameters(check: Checker, data: dict, rows) -> list[Parameter]:
    """The record's parameters (their laws with the nominal values the run read), checked against the
    campaign's parameters."""
    names = [str(name) for name in data["parameters"]] if isinstance(data["parameters"], dict) else None
    if (not isinstance(rows, list) or not all(isinstance(r, dict) and set(r) == set(STORED_KEYS) for r in rows)
            or [r["name"] for r in rows] != names):
        check.fail("parameters", f"expected one entry ({', '.join(STORED_KEYS)}) per parameter of the campaign "
                                 f"({', '.join(names or [])}): the file is damaged or was not written by uqflight")
    parameters = []
    for row in rows:
        numbers = [row[key] for key in ("nominal", "lower", "upper")]
        if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in numbers):
            check.fail(f"parameters.{row['name']}", "holds a value that is not a finite number: the file is damaged")
        try:
            parameters.append(Parameter(str(row["name"]), str(row["property"]), str(row["distribution"]),
                                        *map(float, numbers)))
        except ValueError as exc:
            check.fail(f"parameters.{row['name']}", str(exc))
    return parameters
