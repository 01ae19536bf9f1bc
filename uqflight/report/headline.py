"""The page's first block: the key numbers of the first file (the one summary.json describes), per output at
the report's times and per quantity of interest: mean ± std, the 99 % band, the top Sobol' contributors."""
from __future__ import annotations

import math

import numpy as np

from . import plots
from .loading import Entry
from .sensitivity import top_contributors
from .blocks import Section, Table

NO_INDICES = "no Sobol' indices"


def _decimals(std: float) -> int:
    """Decimals that show two significant digits of the std (at most 10; 4 significant digits without a spread)."""
    if not np.isfinite(std) or std <= 0:
        return -1
    return min(10, max(0, 1 - math.floor(math.log10(std))))


def _number(value: float, decimals: int) -> str:
    if value is None or not np.isfinite(value):
        return "null"
    return f"{value:.{decimals}f}" if decimals >= 0 else f"{value:.4g}"


def mean_std_text(mean: float, std: float, unit: str) -> str:
    """"14966 ± 12 ft": the mean to the std's second significant digit."""
    decimals = _decimals(std)
    return f"{_number(mean, decimals)} ± {_number(std, decimals)}" + (f" {unit}" if unit else "")


def band_text(lower: float, upper: float, std: float) -> str:
    decimals = _decimals(std)
    return f"{_number(lower, decimals)} to {_number(upper, decimals)}"


def _row(name: str, out, i: int, time) -> tuple[list, list]:
    """(CSV row, page row) of one output at time index i (or a quantity: time None)."""
    mean, std, lower, upper = (float(v[i]) for v in (out.mean, out.std, *out.band99))
    top = top_contributors(out.sobol_first, i, out.sobol_first_ci or None) if out.sobol_first else NO_INDICES
    csv = [name, out.units, "" if time is None else float(time), mean, std, lower, upper, top]
    page = [name, "" if time is None else f"{time:g}", mean_std_text(mean, std, out.units),
            band_text(lower, upper, std), top]
    return csv, page


def headline_section(entry: Entry, times: list[float]) -> Section:
    """The headline table of `entry` (tables/headline.csv at full precision, the page rounded to the std)."""
    rows, page = [], []
    for name, out in entry.outputs.items():
        for i in plots.time_indices(out.time, times):
            csv_row, page_row = _row(name, out, i, out.time[i])
            rows.append([entry.label, *csv_row])
            page.append(page_row)
    for name, quantity in entry.stats.quantities.items():
        if quantity.output is None:
            rows.append([entry.label, name, "", "", None, None, None, None, "undefined (see the notes)"])
            page.append([name, "", "undefined (see the notes)", "", ""])
            continue
        csv_row, page_row = _row(name, quantity.output, 0, None)
        rows.append([entry.label, *csv_row])
        page.append(page_row)
    contributors = "top contributors (first-order Sobol')"
    header = ["file", "output or quantity", "unit", "time [s]", "mean", "std", "band99 lower", "band99 upper",
              contributors]
    table = Table(f"Key numbers of {entry.label}", header, rows, "tables/headline.csv",
                  page=(["output or quantity", "time [s]", "mean ± std", "99 % band", contributors], page))
    text = ("Mean ± std, the 99 % band (0.5 % to 99.5 % quantiles) and the largest first-order Sobol' shares of "
            "the variance (up to three, each ≥ 1 %; 'interactions' = 1 − Σ S_i when ≥ 5 %; 'unresolved': a variance "
            "at the simulator's noise; with a pick-freeze design each share carries its 95 % bootstrap interval, "
            "and an index whose interval is wider than 0.5 or lies outside [0, 1] reads 'unresolved (its interval, "
            "n too small)'), "
            "per output at the selected times (--times) and per quantity of interest. "
            "Rounded to two digits of the std; in full in tables/headline.csv, as in summary.json.")
    if entry.stats.notes:
        text += " Read the notes below before these numbers."
    return Section("Headline", "headline", text, [table], lead=True)
