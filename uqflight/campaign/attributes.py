"""The campaign facts a results file keeps as root attributes of JSON text (`method`, `germs`, `analysis`,
`seeds`, `dependence`: see execution.py), checked when the file is read by the checks its campaign file
passed (schema), so that a damaged or hand-edited attribute is one line naming the file, the attribute
and the field inside it, never a number computed from it.
"""
from __future__ import annotations

import json
from dataclasses import dataclass

from ..parameters.germs import GERMS
from . import schema
from .schema import CampaignError, Checker, shown


@dataclass(frozen=True)
class StoredFacts:
    """What a results file was made with: its method, germs, analysis options, the parameters that are
    seeds, and the copula of dependent inputs (GaussianCopula.summary; None: independent)."""

    method: dict
    germs: list[str]
    analysis: dict
    seeds: list[str]
    dependence: dict | None


class AttributeChecker(Checker):
    """A Checker whose field paths start with a root attribute: `method.order` is the field order of
    the attribute method."""

    def fail(self, path: str, message: str):
        attribute, _, inside = path.partition(".")
        raise CampaignError(f"{self.source}: attribute {attribute}", inside, message)


def stored_facts(attrs: dict, source: str, parameters: list[str], quantities: list[str]) -> StoredFacts:
    """The checked facts of a results file's root attributes (`source` names it, `parameters` and
    `quantities` are its names); CampaignError naming the file, the attribute and the field."""
    check = AttributeChecker(source)
    method = schema.method(check, _json(check, attrs, "method"))
    analysis = schema.analysis(check, _json(check, attrs, "analysis", "{}"), quantities)
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
    return StoredFacts(method, germs, analysis, seeds, None if copula is None else copula.summary())


def _json(check: Checker, attrs: dict, name: str, default: str | None = None):
    """The value of the JSON text in attribute `name` (`default` when absent; None: required)."""
    text = attrs.get(name, default)
    if text is None:
        check.fail(name, "is missing")
    if not isinstance(text, str):
        check.fail(name, f"expected JSON text, got {shown(text)}")
    try:
        return json.loads(text)
    except (ValueError, RecursionError) as exc:
        check.fail(name, f"is not JSON ({exc})")


def _listed(value) -> str:
    """A value as a message quotes it, a list by its first items."""
    if not isinstance(value, list):
        return shown(value)
    return "[" + ", ".join(shown(item) for item in value[:4]) + (", ...]" if len(value) > 4 else "]")
