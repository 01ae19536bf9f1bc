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

The report is written into a temporary folder beside OUT and moved into place when complete: a
report that fails or is interrupted leaves OUT as it was (no half-written directory).
"""
from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

from ..check import write_baseline
from .files import _write_text, write_csv, write_statistics_tables, write_summaries
from .loading import Entry, load_entries, parse_methods
from .render import render_html, render_markdown
from .sections import Table, build_sections, files_section

__all__ = ["default_out_dir", "parse_methods", "write_report"]

DEFAULT_TIMES = (10.0, 25.0, float("inf"))  # the tables' times: 10 s, 25 s and the final time


def default_out_dir(results: Path) -> Path:
    """The report folder next to the (first) results file: RESULTS-report/."""
    results = Path(results)
    return results.with_name(f"{results.stem}-report")


def write_report(paths: list[Path], out_dir: Path | None = None, reference: Path | None = None,
                 times=DEFAULT_TIMES, baseline: Path | None = None, method: dict | list[dict] | None = None,
                 progress=None, partial: bool = False, allow_aliasing: bool = False) -> list[Path]:
    """Write the whole report of `paths` into `out_dir` (default: next to the first file,
    RESULTS-report/); returns the files written (the baseline last, when asked for).

    `method`: one override {"kind", "order"}, a list of them (each file analysed with each, overlaid
    in the plots), or None (each campaign's own). `progress(text)` is told each stage. `partial`,
    `allow_aliasing`: see statistics.analyse. Everything is written into a temporary folder first and
    moved into place at the end; nothing is written when a file is refused (statistics.BadInput)."""
    out_dir = Path(os.path.abspath(out_dir if out_dir is not None else default_out_dir(paths[0])))
    check_replaceable(out_dir)
    tell = progress or (lambda text: None)
    entries, ref = load_entries(paths, reference, method, progress=tell, partial=partial,
                                allow_aliasing=allow_aliasing)
    out_dir.parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{out_dir.name}.", suffix=".partial", dir=out_dir.parent))
    staging.chmod(0o755)  # mkdtemp makes it private; a report is for reading
    try:
        _write_into(staging, entries, ref, times, tell)
        tell(f"moving the report into {out_dir}")
        _replace_dir(staging, out_dir)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    written = sorted(p for p in out_dir.rglob("*") if p.is_file())
    if baseline:
        written.append(write_baseline(entries[0].stats, entries[0].campaign_hash, baseline))
    return written


def _write_into(out_dir: Path, entries: list[Entry], ref: Entry | None, times, tell) -> None:
    for sub in ("plots", "tables"):
        (out_dir / sub).mkdir(parents=True, exist_ok=True)
    tell("writing summaries and tables")
    written = write_summaries(entries, out_dir)
    written += write_statistics_tables(entries, out_dir)
    tell("drawing the plots")
    sections = build_sections(entries, ref, times, out_dir, progress=tell)
    for table in (block for section in sections for block in section.blocks if isinstance(block, Table)):
        written.append(write_csv(out_dir / table.file, table.header, table.rows))
    written += [out_dir / "report.html", out_dir / "report.md"]
    sections.append(files_section(written, out_dir))
    tell("writing the page")
    title = f"uqflight report: {entries[0].label}" + (f" and {len(entries) - 1} more" if len(entries) > 1 else "")
    _write_text(out_dir / "report.html", render_html(title, sections, out_dir))
    _write_text(out_dir / "report.md", render_markdown(title, sections))


REPORT_FILES = {"report.html": None, "report.md": None, "summary.json": None,  # what a report writes, and
                "plots": ".png", "tables": ".csv", "summaries": ".json"}      # its folders' file types


def check_replaceable(out_dir: Path) -> None:
    """Refuse (FileExistsError) to replace anything at `out_dir` but nothing, an empty folder or an
    earlier report: a folder holding only what a report writes (a user's file there is never deleted)."""
    if not out_dir.exists() and not out_dir.is_symlink():
        return
    if out_dir.is_dir() and not out_dir.is_symlink():
        entries = list(out_dir.iterdir())
        if not entries or (out_dir / "report.html").is_file() and all(_written_by_a_report(e) for e in entries):
            return
    raise FileExistsError(f"{out_dir} exists and is not a uqflight report (it holds other files, or is not a "
                          "folder); a report replaces only an earlier report: choose another --out, or move it away")


def _written_by_a_report(entry: Path) -> bool:
    if entry.name not in REPORT_FILES or entry.is_symlink():
        return False
    suffix = REPORT_FILES[entry.name]
    if suffix is None:
        return entry.is_file()
    return entry.is_dir() and all(f.is_file() and not f.is_symlink() and f.suffix == suffix for f in entry.iterdir())


def _replace_dir(staging: Path, out_dir: Path) -> None:
    """Move the finished `staging` folder to `out_dir`, replacing an older report there."""
    old = None
    if out_dir.exists():
        old = out_dir.with_name(f".{out_dir.name}.old-{staging.name}")
        out_dir.rename(old)
    try:
        staging.rename(out_dir)
    except BaseException:
        if old is not None:
            old.rename(out_dir)
        raise
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)
