"""The campaign setup a results file keeps as root attributes (see running/runner.py): of JSON text (`method`,
`germs`, `analysis`, `seeds`, `dependence`, `design_info`, `versions`) or plain text (`design_kind`, the
provenance in TEXT), checked when the file is read, by the checks its campaign file passed (schema) where
there are some, so that a damaged or hand-edited attribute is one line naming the file, the attribute and
the field inside it, never a traceback or a number computed from it.
"""
from __future__ import annotations

import functools
import json
from dataclasses import dataclass

from ..designs import DESIGN_KINDS
from ..designs import REGISTRY as DESIGNS
from ..designs.base import is_integer
from ..parameters.germs import GERMS
from ..store.resume import campaign_mapping
from . import schema
from ..text.console import quoted_value
from .schema import CampaignError, Checker

# provenance shown by the report and compared by check (campaign_hash, aircraft_hash, scenario): text when present
TEXT = ("campaign_name", "campaign_hash", "campaign_path", "created", "aircraft_hash", "scenario")


@dataclass(frozen=True)
class RecordedSetup:
    """What a results file was made with: its method, germs, analysis options, the parameters that are
    seeds, the copula of dependent inputs (GaussianCopula.summary; None: independent), and its design's kind
    and recorded facts (designs.Design.info), and the campaign's `seed`, which seeds the analysis's draws."""

    method: dict
    germs: list[str]
    analysis: dict
    seeds: list[str]
    dependence: dict | None
    design_kind: str
    design_info: dict
    seed: int = 0


class AttributeChecker(Checker):
    """A Checker whose field paths start with a root attribute: `method.order` is the field order of
    the attribute method."""

    def fail(self, path: str, message: str):
        attribute, _, inside = path.partition(".")
        raise CampaignError(f"{self.source}: attribute {attribute}", inside, message)


def recorded_setup(attrs: dict, source: str, parameters: list[str], quantities: list[str], runs: int) -> RecordedSetup:
    """The checked setup of a results file's root attributes (`source` names it, `parameters` and
    `quantities` are its names, `runs` its design's size); CampaignError naming the file, the attribute
    and the field."""
    check = AttributeChecker(source)
    for name in TEXT:
        if name in attrs and not isinstance(attrs[name], str):
            check.fail(name, f"expected text, got {quoted_value(attrs[name])}")
    versions = _json(check, attrs, "versions")
    if not isinstance(versions, dict):
        check.fail("versions", f"expected a mapping of package versions, got {quoted_value(versions)}")
    kind = attrs.get("design_kind")
    if not isinstance(kind, str) or kind not in DESIGN_KINDS:
        check.fail("design_kind", f"expected one of {', '.join(DESIGN_KINDS)}, got {quoted_value(kind)}")
    info = _design_info(check, _json(check, attrs, "design_info"), kind, runs, len(parameters))
    method = schema.method(check, _json(check, attrs, "method"))
    analysis = schema.analysis(check, _json(check, attrs, "analysis"), quantities)
    germs = _json(check, attrs, "germs")
    if (not isinstance(germs, list) or len(germs) != len(parameters)
            or not all(isinstance(germ, str) and germ in GERMS for germ in germs)):
        check.fail("germs", f"expected a list of {len(parameters)} germs ({' / '.join(GERMS)}), one per parameter "
                            f"({', '.join(parameters)}), got {_listed(germs)}")
    seeds = _json(check, attrs, "seeds", "[]")
    if (not isinstance(seeds, list) or not all(isinstance(name, str) and name in parameters for name in seeds)
            or len(set(seeds)) != len(seeds)):
        check.fail("seeds", f"expected a list of distinct parameter names ({', '.join(parameters)}), "
                            f"got {_listed(seeds)}")
    dependence = _json(check, attrs, "dependence", "null")
    if isinstance(dependence, dict):  # what the indices are of is said again from the names
        dependence = {key: value for key, value in dependence.items() if key != "sobol_of"}
    copula = schema.dependence(check, dependence, parameters, seeds)
    seed = _checked_seed(check, attrs.get("campaign", ""))
    return RecordedSetup(method, germs, analysis, seeds, None if copula is None else copula.summary(), kind, info, seed)


@functools.lru_cache(maxsize=8)
def stored_settings(campaign_text: str) -> dict:
    """The stored campaign text's mapping as written (YAML), {} when unreadable or not a mapping: what the
    report shows and reads the seed and the excitation from (shared, not to be changed: the text read once)."""
    return campaign_mapping(campaign_text)


def _checked_seed(check: Checker, text: str) -> int:
    """The seed of the stored campaign text, read as the report reads it (it draws the report's runs and
    the analysis's band, bootstrap and exceedance draws): an integer >= 0 when given, 0 when not (a text
    that is no mapping is the report's to show as unreadable)."""
    settings = stored_settings(text)
    if "seed" not in settings:
        return 0
    check.integer(settings["seed"], "campaign.seed", 0)
    return int(settings["seed"])


def _design_info(check: Checker, info, kind: str, runs: int, d: int) -> dict:
    """The design's recorded facts, those the statistics read checked against the file's `runs` and `d`
    parameters: replicates (blocks of runs), n_base (a pick-freeze design's base rows), scramble."""
    if not isinstance(info, dict):
        check.fail("design_info", f"expected a mapping of the design's facts, got {quoted_value(info)}")
    replicates = info.get("replicates", 1)
    if not is_integer(replicates) or not 1 <= replicates <= max(runs, 1) or runs % replicates:
        check.fail("design_info.replicates", f"expected an integer >= 1 dividing the {runs} runs, "
                                             f"got {quoted_value(replicates)}")
    problem = DESIGNS[kind].info_problem(info, runs, d)
    if problem:
        check.fail(f"design_info.{problem[0]}", f"{problem[1]}, got {quoted_value(info.get(problem[0]))}")
    if not isinstance(info.get("scramble", True), bool):
        check.fail("design_info.scramble", f"expected true or false, got {quoted_value(info['scramble'])}")
    return info


def _json(check: Checker, attrs: dict, name: str, default: str | None = None):
    """The value of the JSON text in attribute `name` (`default` when absent, for the attributes a run writes
    only when the campaign has them; None: required)."""
    text = attrs.get(name, default)
    if text is None:
        check.fail(name, "is missing: the file is damaged or was not written by uqflight: fly its campaign again "
                         "(`uqflight run CAMPAIGN --out FILE --restart`)")
    if not isinstance(text, str):
        check.fail(name, f"expected JSON text, got {quoted_value(text)}")
    try:
        return json.loads(text)
    except (ValueError, RecursionError) as exc:
        check.fail(name, f"is not JSON ({exc})")


def _listed(value) -> str:
    """A value as a message quotes it, a list by its first items."""
    if not isinstance(value, list):
        return quoted_value(value)
    return "[" + ", ".join(quoted_value(item) for item in value[:4]) + (", ...]" if len(value) > 4 else "]")
