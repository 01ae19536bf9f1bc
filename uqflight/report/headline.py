"""The page's first block: the first file's (the one summary.json describes) exceedance probabilities with
their intervals, the number an engineer came for, then its key numbers per output at the report's times and
per quantity of interest: mean ± std, the 99 % band, the top Sobol' contributors; a flagged row marked ⚠
with its flags."""
from __future__ import annotations

import math

import numpy as np

from ..text.labels import shown_time
from . import plots
from .loading import AnalysedFile
from .screenings import SCREENINGS
from .sensitivity import top_contributors
from .blocks import Section, Table

NO_INDICES = "no Sobol' indices"
NO_INTERVAL = "—"
FLAGGED = "⚠ "


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


def flagged(name: str, flags) -> str:
    """The page's name of an output or quantity: marked ⚠ when its statistics are flagged."""
    return FLAGGED + name if flags else name


def _row(name: str, out, i: int, time, flags: list[str]) -> tuple[list, list]:
    """(CSV row, page row) of one output at time index i, shown as `time` (or a quantity: time None), with
    its `flags`; the CSV keeps the recorded time."""
    mean, std, lower, upper = (float(v[i]) for v in (out.mean, out.std, *out.band99))
    top = (SCREENINGS[out.screening.name].ranked_text(out.screening.measures, i) if out.screening else
           top_contributors(out.sobol_first, i, out.sobol_first_ci or None) if out.sobol_first else NO_INDICES)
    csv = [name, out.units, "" if time is None else float(out.time[i]), mean, std, lower, upper, top, "; ".join(flags)]
    page = [flagged(name, flags), "" if time is None else f"{time:g}", mean_std_text(mean, std, out.units),
            band_text(lower, upper, std), top, "; ".join(flags)]
    return csv, page


def event_text(name: str, item: dict) -> str:
    """"P(peak_nz > 4.5)": the event of one exceedance item ({above: X} or {below: X})."""
    bound = "above" if "above" in item else "below"
    return f"P({name} {'>' if bound == 'above' else '<'} {item[bound]:g})"


def probability_text(value) -> str:
    """The probability to 3 digits, "—" where it is undefined (its note says why)."""
    return NO_INTERVAL if value is None or not np.isfinite(value) else f"{value:.3g}"


def interval_text(lower, upper) -> str:
    """"0.012 to 0.034", or "—" where the estimate has no interval (a PCE's, an unscrambled QMC's)."""
    if lower is None or upper is None or not (np.isfinite(lower) and np.isfinite(upper)):
        return NO_INTERVAL
    return f"{lower:.3g} to {upper:.3g}"


def exceedance_table(entry: AnalysedFile) -> Table | None:
    """The exceedance probabilities of `entry`'s quantities (analysis.exceedance, or report --exceedance)
    with their 95 % intervals, "—" for none; None when none was asked for."""
    rows, page = [], []
    for name, quantity in entry.stats.quantities.items():
        for item in quantity.exceedance:
            event, flags = event_text(name, item), item["flags"]
            rows.append([entry.label, name, event, item["probability"], item["lower"], item["upper"],
                         item["method"], "; ".join(flags), item["note"]])
            note = item["note"]
            for flag in flags:  # on the page, a flag is said once, in its column (the CSV keeps the whole note)
                note = note.replace(f"; {flag}", "")
            page.append([flagged(event, flags), probability_text(item["probability"]),
                         interval_text(item["lower"], item["upper"]), item["method"] or "", "; ".join(flags), note])
    if not rows:
        return None
    return Table(f"Exceedance probabilities of {entry.label}",
                 ["file", "quantity", "event", "probability", "lower", "upper", "method", "flags", "note"], rows,
                 "tables/headline_exceedance.csv",
                 page=_without_empty_flags(["event", "probability", "95 % interval", "method", "flags", "note"], page))


def _without_empty_flags(header: list[str], page: list[list]) -> tuple[list[str], list[list]]:
    """The page's (header, rows) without the flags column when no row is flagged (the CSV keeps it)."""
    k = header.index("flags")
    if any(row[k] for row in page):
        return header, page
    return header[:k] + header[k + 1:], [row[:k] + row[k + 1:] for row in page]


def headline_section(entry: AnalysedFile, times: list[float]) -> Section:
    """The headline of `entry`: its exceedance probabilities (tables/headline_exceedance.csv) first, then its
    key numbers (tables/headline.csv at full precision, the page rounded to the std)."""
    rows, page = [], []
    for name, out in entry.outputs.items():
        for i in plots.time_indices(out.time, times):
            csv_row, page_row = _row(name, out, i, shown_time(out.time, i), out.flags)
            rows.append([entry.label, *csv_row])
            page.append(page_row)
    for name, quantity in entry.stats.quantities.items():
        if quantity.output is None:
            rows.append([entry.label, name, "", "", None, None, None, None, "undefined (see the notes)", ""])
            page.append([name, "", "undefined (see the notes)", "", "", ""])
            continue
        csv_row, page_row = _row(name, quantity.output, 0, None, quantity.flags)
        rows.append([entry.label, *csv_row])
        page.append(page_row)
    screening = next((SCREENINGS[out.screening.name] for out in entry.outputs.values() if out.screening), None)
    contributors = screening.column if screening else "top contributors (first-order Sobol')"
    header = ["file", "output or quantity", "unit", "time [s]", "mean", "std", "band99 lower", "band99 upper",
              contributors, "flags"]
    table = Table(f"Key numbers of {entry.label}", header, rows, "tables/headline.csv",
                  page=_without_empty_flags(["output or quantity", "time [s]", "mean ± std", "99 % band", contributors,
                                             "flags"], page))
    exceedance = exceedance_table(entry)
    text = ("Mean ± std, the 99 % band (0.5 % to 99.5 % quantiles) and the largest first-order Sobol' shares of "
            "the variance (up to three, each ≥ 1 %; 'interactions' = 1 − Σ S_i when ≥ 5 %; 'unresolved': a variance "
            "at the simulator's noise; with a pick-freeze design each share carries its 95 % bootstrap interval, "
            "and an index whose interval is wider than 0.5 or lies outside [0, 1] reads 'unresolved (its interval, "
            "n too small)'), "
            "per output at the selected times (--times) and per quantity of interest"
            + (screening.sentence if screening else "") + ". "
            "Rounded to two digits of the std; in full in tables/headline.csv, as in summary.json. "
            f"A row marked {FLAGGED.strip()} is flagged: its flags say what is wrong and what helps.")
    if exceedance is not None:
        text = ("First the exceedance probabilities asked for (analysis.exceedance, or report --exceedance), each "
                f"with its 95 % interval ({NO_INTERVAL}: the estimate has none, see its note); then " + text[0].lower()
                + text[1:])
    if entry.stats.notes:
        text += " Read the notes below before these numbers."
    from .rare_event import headline_table

    rare = headline_table(entry)
    if rare is not None:  # a rare-event design: its estimate (c.o.v., runs, β) in place of the exceedance table;
        exceedance = rare  # its runs have no mean or band of the law
        text = ("The probability of the design's event with its 95 % interval, c.o.v., runs and reliability index "
                "β = −Φ⁻¹(p) (in full in tables/rare_event.csv, as in summary.json); below, the quantities' other "
                "statistics, undefined: the runs were chosen to reach the event, they are not draws of the input "
                "law. Read the notes below before these numbers.")
    return Section("Headline", "headline", text, [b for b in (exceedance, table) if b is not None], lead=True)
