"""The report's data files: summary JSON and CSV tables."""
from __future__ import annotations

import csv
import re
from pathlib import Path

import numpy as np

from ..text.json_text import json_text
from ..analysis.statistics import summary_json
from .loading import AnalysedFile, file_name_within


def write_summaries(entries: list[AnalysedFile], out_dir: Path) -> list[Path]:
    """summary.json for the first file; summaries/<stem>.json for each when there are several."""
    written = [_write_json(out_dir / "summary.json", summary_json(entries[0].stats))]
    if len(entries) > 1:
        (out_dir / "summaries").mkdir(exist_ok=True)
        written += [_write_json(out_dir / "summaries" / file_name_within(f"{e.stem}.json"), summary_json(e.stats))
                    for e in entries]
    return written


def write_statistics_tables(entries: list[AnalysedFile], out_dir: Path) -> list[Path]:
    """tables/statistics_<stem>_<output>.csv: every statistic of one output over time."""
    written = []
    for entry in entries:
        for name, out in entry.outputs.items():
            unit = f" [{out.units}]" if out.units else ""
            square = f" [{out.units}^2]" if out.units else ""
            header = ["time [s]", f"mean{unit}", f"std{unit}", f"variance{square}", f"band99 lower{unit}",
                      f"band99 upper{unit}", "cov [-]"]
            columns = [out.time, out.mean, out.std, out.variance, *out.band99, out.cov]
            if out.errors:
                header += ["eps_m [-]", "eps_v [-]"]
                columns += [out.errors["eps_m"], out.errors["eps_v"]]
            path = out_dir / "tables" / file_name_within(f"statistics_{entry.stem}_{entry.output_files[name]}.csv")
            written.append(write_csv(path, header, np.column_stack(columns).tolist()))
    return written

# -- files -------------------------------------------------------------------------------------
def write_csv(path: Path, header: list[str], rows: list[list]) -> Path:
    with open(path, "w", newline="", encoding="utf-8") as fh:
        writer = csv.writer(fh)
        writer.writerow([csv_safe(h) for h in header])
        writer.writerows([[float(v) if isinstance(v, np.floating) else csv_safe(v) for v in row] for row in rows])
    return path


FORMULA_START = ("=", "+", "-", "@", "\t", "\r")
NUMBER = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?")


def csv_safe(value):
    """A text cell a spreadsheet would evaluate as a formula (starting with = + - @, a tab or a carriage
    return) behind a single quote, which spreadsheets show as text; numbers, and text that is a
    plain number such as "-0.5", stay as they are."""
    if isinstance(value, str) and value.startswith(FORMULA_START) and not NUMBER.fullmatch(value):
        return "'" + value
    return value


def _write_json(path: Path, data: dict) -> Path:
    path.write_text(json_text(data), encoding="utf-8")
    return path


def _write_text(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path

