"""Analysed results files → report entries: statistics, labels, the campaign's parameters and the file's facts."""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import yaml

from ..check import read_statistics
from ..statistics import Statistics, add_reference_errors

METHOD_NAMES = {"integration": "Int", "pseudo_galerkin": "PG", "interpolation": "interpolation",
                "regression": "regression", "least_squares": "least squares", "monte_carlo": "MC"}

@dataclass
class Entry:
    """One analysed results file and how the report names it."""

    stats: Statistics
    stem: str
    label: str
    campaign_hash: str
    inputs: str

    @property
    def outputs(self) -> dict:
        return self.stats.outputs

    @property
    def monte_carlo(self) -> bool:
        return self.stats.method["kind"] == "monte_carlo"

    @property
    def pick_freeze(self) -> bool:
        return self.stats.design_kind == "pick_freeze"

    @property
    def has_sobol(self) -> bool:
        return any(out.sobol_first for out in self.outputs.values())

    @property
    def has_errors(self) -> bool:
        return any(out.errors for out in self.outputs.values())



def method_label(method: dict) -> str:
    """A method as in the paper's legends, e.g. "PG order 2", "MC"."""
    kind = method["kind"]
    name = METHOD_NAMES.get(kind, kind)
    if kind == "monte_carlo":
        return name
    return f"{name} order {method['order']}" + (" split" if method.get("split") else "")


def input_distributions(campaign_text: str) -> str:
    """The campaign's input distribution(s), e.g. "normal" or "normal, uniform"."""
    parameters = (yaml.safe_load(campaign_text) or {}).get("parameters") or {}
    return ", ".join(dict.fromkeys(str(spec.get("distribution", "?")) for spec in parameters.values()))


def load_entries(paths: list[Path], reference: Path | None,
                 method: dict | None = None) -> tuple[list[Entry], Entry | None]:
    """Every file analysed (with `method` overriding the campaigns' methods, the reference
    excepted), with errors against the reference unless it is the reference itself, and the reference."""
    stems: set[str] = set()
    ref = _entry(reference, *read_statistics(reference), set()) if reference else None
    entries = []
    for path in paths:
        stats, attrs = read_statistics(path, method)
        if ref is not None and not _same_file(path, reference):
            add_reference_errors(stats, ref.stats)
        entries.append(_entry(path, stats, attrs, stems))
    return entries, ref


def _entry(path: Path, stats: Statistics, attrs: dict, stems: set[str]) -> Entry:
    stem = _unique(file_name(Path(path).stem), stems)
    label = f"{stats.campaign_name or stem}: {method_label(stats.method)}, {stats.runs} runs"
    return Entry(stats, stem, label, str(attrs.get("campaign_hash", "")),
                 input_distributions(str(attrs.get("campaign", ""))))


def file_name(name: str) -> str:
    """An output or file name made safe for a file name: "velocities/vc-kts" → "velocities_vc-kts"."""
    return re.sub(r"[^A-Za-z0-9_.-]", "_", name)


def _same_file(a, b) -> bool:
    return Path(a).resolve() == Path(b).resolve()


def _unique(stem: str, taken: set[str]) -> str:
    name, n = stem, 1
    while name in taken:
        n += 1
        name = f"{stem}-{n}"
    taken.add(name)
    return name

