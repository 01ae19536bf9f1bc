"""Analysed results files → report entries: statistics, labels, the campaign's parameters and the file's facts."""
from __future__ import annotations

import hashlib
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

from ..analysis.statistics import BadInput, Statistics, add_reference_errors, read_statistics


@dataclass
class AnalysedFile:
    """One analysed results file and how the report names it."""

    stats: Statistics
    stem: str
    label: str
    campaign_hash: str
    attrs: dict = field(default_factory=dict)  # the results file's root attributes
    path: str = ""  # the results file (several entries share one with several --method)
    output_files: dict = field(default_factory=dict)  # output name → its part of file names, unique in the entry
    file_stem: str = ""  # the results file's part of the names of its own figures (design, runs), unique in the report

    @property
    def settings(self) -> dict:
        """The recorded campaign's mapping as written (campaign.record: checked when the file was read)."""
        return self.stats.record.campaign.mapping

    @property
    def simulator(self) -> dict:
        """The recorded campaign's `simulator:` mapping as written."""
        return self.settings["simulator"]

    @property
    def parameters(self) -> list[dict]:
        """The recorded campaign's parameters (campaign.record.STORED_KEYS), with the nominal values its run read."""
        return self.stats.record.parameter_rows

    @property
    def inputs(self) -> str:
        """The campaign's input distribution(s), e.g. "normal" or "normal, uniform"."""
        return ", ".join(dict.fromkeys(p.distribution for p in self.stats.record.campaign.parameters))

    @property
    def outputs(self) -> dict:
        return self.stats.outputs

    @property
    def monte_carlo(self) -> bool:
        return not self.stats.expands

    @property
    def pick_freeze(self) -> bool:
        return self.stats.sobol_from_runs

    @property
    def has_sobol(self) -> bool:
        return any(out.sobol_first for out in self.outputs.values())

    @property
    def has_errors(self) -> bool:
        return any(out.errors for out in self.outputs.values())


def load_entries(paths: list[Path], reference: Path | None, method: dict | list[dict] | None = None,
                 progress=None, partial: bool = False, allow_aliasing: bool = False,
                 exceedance: dict | None = None, scatter_time: float = float("inf")) -> tuple[list[AnalysedFile], AnalysedFile | None]:
    """Every file analysed once per method (`method`: one override, several, or None for the
    campaigns' own; the reference keeps its own), with errors against the reference unless it is
    the reference itself, and the reference. `progress` (a Progress) counts each file's outputs.
    `exceedance`: thresholds replacing the campaigns' (statistics.analyse). Each file's first entry
    carries the runs the report draws (Statistics.drawn), its scatter at `scatter_time`."""
    methods = method if isinstance(method, list) else [method]
    methods = methods or [None]
    stems: set[str] = set()
    file_stems = _file_stems(paths)
    ref = None
    if reference:
        ref = _entry(reference, *read_statistics(reference, progress=progress), set(), _file_stems([reference]))
    entries = []
    for path in paths:
        for k, override in enumerate(methods):
            stats, attrs = read_statistics(path, override, partial=partial, allow_aliasing=allow_aliasing,
                                           progress=progress, exceedance=exceedance,
                                           scatter_time=scatter_time if k == 0 else None)
            if ref is not None and not _same_file(path, reference):
                add_reference_errors(stats, ref.stats)
            entries.append(_entry(path, stats, attrs, stems, file_stems, with_method=len(methods) > 1))
    _rare_alone(entries, ref)
    return entries, ref


def _rare_alone(entries: list[AnalysedFile], ref: AnalysedFile | None) -> None:
    """A rare-event design's file is reported alone (BadInput otherwise): its runs are not draws of the input
    law, so it has no statistics over time to overlay on another file's or to compare with a reference."""
    rare = [e for e in entries + ([ref] if ref else []) if e.stats.rare_runs]
    if rare and (len(entries) > 1 or ref is not None):
        raise BadInput(f"{rare[0].stats.path}: a {rare[0].stats.design_kind} file is reported alone (no other "
                       "results file, --method or --reference): its runs are not draws of the input law, it has "
                       "only its event's probability; report it by itself")


def _file_stems(paths: list[Path]) -> dict[Path, str]:
    """Each results file (resolved) → its stem made safe for file names, given -2, -3 when an earlier file
    has it (a/r.h5 and b/r.h5: "r" and "r-2"); a file given twice keeps its first."""
    taken: set[str] = set()
    stems: dict[Path, str] = {}
    for path in paths:
        key = Path(path).resolve()
        if key not in stems:
            stems[key] = _unique(file_name(Path(path).stem), taken)
    return stems


def _entry(path: Path, stats: Statistics, attrs: dict, stems: set[str], file_stems: dict[Path, str],
           with_method: bool = False) -> AnalysedFile:
    name = Path(path).stem + (f"_{stats.method.kind}{stats.method.order}" if with_method else "")
    stem = _unique(file_name(name), stems)
    runs = f"partial: {stats.completed} of {stats.runs} runs" if stats.partial else f"{stats.runs} runs"
    label = f"{stats.campaign_name or stem}: {stats.estimator_label}, {runs}"
    taken: set[str] = set()
    output_files = {name: _unique(file_name(name), taken) for name in stats.outputs}
    return AnalysedFile(stats, stem, label, str(attrs.get("campaign_hash", "")), dict(attrs), str(path), output_files,
                 file_stems[Path(path).resolve()])


def file_name(name: str) -> str:
    """An output or file name made safe for a file name: "velocities/vc-kts" → "velocities_vc-kts"."""
    return re.sub(r"[^A-Za-z0-9_.-]", "_", name)


NAME_BYTES = 255  # the longest name of one file or folder (ext4, XFS, Btrfs: bytes; APFS, NTFS: 255 characters)


def file_name_within(name: str, limit: int = NAME_BYTES) -> str:
    """`name` (a file name, its extension kept) as it is when its UTF-8 takes at most `limit` bytes; else cut
    and given "-" and 16 hex digits of the whole name's SHA-256 before its extension, so that names sharing
    a long start stay apart."""
    data = name.encode()
    if len(data) <= limit:
        return name
    stem, ext = os.path.splitext(name)
    if len(ext) > 8:  # a dot in the name, not an extension
        stem, ext = name, ""
    tag = "-" + hashlib.sha256(data).hexdigest()[:16]
    keep = stem.encode()[:limit - len(tag) - len(ext.encode())].decode(errors="ignore")
    return keep + tag + ext


def one_per_file(entries: list[AnalysedFile]) -> list[AnalysedFile]:
    """One entry per results file (several --method give several entries of one file)."""
    seen, unique = set(), []
    for e in entries:
        key = str(Path(e.path or e.stats.path).resolve())
        if key not in seen:
            seen.add(key)
            unique.append(e)
    return unique


def _same_file(a, b) -> bool:
    return Path(a).resolve() == Path(b).resolve()


def _unique(stem: str, taken: set[str]) -> str:
    name, n = stem, 1
    while name in taken:
        n += 1
        name = f"{stem}-{n}"
    taken.add(name)
    return name

