"""The report of one or more results files (the paper's section 5): JSON, CSV tables, PNG plots and
one page, as self-contained HTML and as Markdown.

Layout of the report directory:
    summary.json               the first file's statistics (the fixed schema of DESIGN.md)
    summaries/<stem>.json      every file's, when several are given
    tables/*.csv               statistics over time per file and output, statistics and Sobol' indices
                               at selected times, errors against the reference, PCE vs Monte Carlo
    plots/*.png                the figures
    report.html                all of it on one page, plots embedded: it can be mailed
    report.md                  the same, linking plots/
"""
from __future__ import annotations

from pathlib import Path

from ..check import write_baseline
from .files import _write_text, write_csv, write_statistics_tables, write_summaries
from .loading import Entry, load_entries, method_label  # noqa: F401
from .render import render_html, render_markdown
from .sections import Table, build_sections, files_section

DEFAULT_TIMES = (10.0, 25.0, float("inf"))  # the tables' times: 10 s, 25 s and the final time


def write_report(paths: list[Path], out_dir: Path, reference: Path | None = None,
                 times=DEFAULT_TIMES, baseline: Path | None = None, method: dict | None = None) -> list[Path]:
    """Write the whole report of `paths` into `out_dir`; returns the files written."""
    out_dir = Path(out_dir)
    for sub in ("plots", "tables"):
        (out_dir / sub).mkdir(parents=True, exist_ok=True)
    entries, ref = load_entries(paths, reference, method)
    written = write_summaries(entries, out_dir)
    written += write_statistics_tables(entries, out_dir)
    sections = build_sections(entries, ref, times, out_dir)
    for table in (block for section in sections for block in section.blocks if isinstance(block, Table)):
        written.append(write_csv(out_dir / table.file, table.header, table.rows))
    sections.append(files_section(written, out_dir))
    title = f"uqflight report: {entries[0].label}" + (f" and {len(entries) - 1} more" if len(entries) > 1 else "")
    written.append(_write_text(out_dir / "report.html", render_html(title, sections, out_dir)))
    written.append(_write_text(out_dir / "report.md", render_markdown(title, sections)))
    if baseline:
        written.append(write_baseline(entries[0].stats, entries[0].campaign_hash, baseline))
    return written

