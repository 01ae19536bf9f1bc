"""The report's section on a random stream's share: for files whose design is pick-freeze over a seed
parameter, each quantity's and each output's variance split between the seed (the turbulence realisation,
aleatory) and the other inputs (epistemic), first-order and total, with the pick-freeze intervals
(`statistics.variance_split`)."""
from __future__ import annotations

import numpy as np

from ..analysis.sobol import unresolved
from ..analysis.statistics import variance_split
from .sensitivity import N_TOO_SMALL, index_text
from .loading import AnalysedFile
from .blocks import Section, Table


def _row(label: str, name: str, out, seed: str, at: int) -> tuple[list, list]:
    """(CSV row, page row): the page marks a share its interval does not resolve "(n too small)"."""
    split = variance_split(out, seed)
    row, page = [label, name], [label, name]
    for group in ("seeds", "other_parameters"):
        shares = split[group]
        for order in ("first", "total"):
            value, lower, upper = (float(v[at]) for v in (shares[order], shares[f"{order}_ci"]["lower"],
                                                           shares[f"{order}_ci"]["upper"]))
            row += [value, lower, upper]
            loose = bool(unresolved(value, (lower, upper)))
            page += [index_text(value) + (f" ({N_TOO_SMALL})" if loose else ""), index_text(lower), index_text(upper)]
    return [value if not (isinstance(value, float) and np.isnan(value)) else "unresolved" for value in row], page


def variance_split_section(entries: list[AnalysedFile], times: list[float]) -> Section | None:
    """None when no file has a seed parameter with pick-freeze indices."""
    rows, page = [], []
    for entry in entries:
        seeds = entry.stats.seeds
        if not seeds:
            continue
        for name, quantity in entry.stats.quantities.items():
            if quantity.output is not None and quantity.output.sobol_first_ci:
                row, shown = _row(entry.label, name, quantity.output, seeds[0], 0)
                rows.append(row)
                page.append(shown)
        for name, out in entry.outputs.items():
            if not out.sobol_first_ci:
                continue
            for t in times:
                at = int(np.argmin(np.abs(out.time - t)))
                row, shown = _row(entry.label, f"{name} at {out.time[at]:g} s", out, seeds[0], at)
                rows.append(row)
                page.append(shown)
    if not rows:
        return None
    header = ["file", "quantity or output"] + [f"{group} {order}{part}" for group in ("seed", "others")
                                               for order in ("first", "total") for part in ("", " lower", " upper")]
    return Section("Variance split: the random stream against the other inputs", "variance-split",
                   "The share of each variance due to the seed parameter's random stream (e.g. the turbulence "
                   "realisation: aleatory) and to the other inputs (epistemic), from the pick-freeze Sobol' "
                   "indices with their bootstrap intervals: the seed's first-order and total indices, and the "
                   "others' as the complement's closed indices (first 1 − S_T(seed), total 1 − S(seed)). "
                   "Estimates outside [0, 1] are sampling noise: read the intervals; a share whose interval is "
                   "wider than 0.5 or lies outside [0, 1] is marked 'n too small'. With failed runs the shares are "
                   "those of the complete base rows (the notes count the rows dropped).",
                   [Table("Shares of the variance", header, rows, "tables/variance_split.csv", page=(header, page))])
