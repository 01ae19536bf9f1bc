"""The report of one or more results files (the paper's section 5): JSON, CSV tables, PNG plots and
one page, as self-contained HTML and as Markdown.

Layout of the report directory:
    summary.json               the first file's statistics (the fixed schema of docs/summary-json.md)
    summaries/<stem>.json      every file's, when several are given
    tables/*.csv               statistics over time per file and output, statistics and Sobol' indices
                               at selected times, errors against the reference, PCE vs Monte Carlo
    plots/*.png                the figures (*.svg with --format svg; *.pdf beside the PNGs with pdf)
    report.html                all of it on one page, plots embedded: it can be mailed
    report.md                  the same, linking plots/

The report is written into a staging folder beside OUT and swapped into place when complete
(`replace`): a report that fails or is interrupted leaves OUT as it was (no half-written directory),
and OUT is never absent. The figures are drawn by a drawer forked before the files are read
(forking.PreparedChild), which imports matplotlib while they are analysed; this process writes the data
files and the page and never imports it.
"""
from __future__ import annotations

import os
import shutil
from pathlib import Path

from ..analysis.check import write_baseline
from ..running.forking import FORKS, ChildFailed, PreparedChild
from ..running.progress import Progress
from ..analysis.statistics import BadInput
from .files import _write_text, write_csv, write_statistics_tables, write_summaries
from .loading import AnalysedFile, file_name_within, load_entries
from .formats import FORMATS, export_format, exporting
from .replace import OUT_NAME_BYTES, check_replaceable, make_staging, replace_dir

__all__ = ["DrawingFailed", "check_replaceable", "default_out_dir", "write_report"]

DEFAULT_TIMES = (10.0, 25.0, float("inf"))  # the tables' times: 10 s, 25 s and the final time


class DrawingFailed(RuntimeError):
    """A figure of the report could not be drawn: the message names its section and what it raised (the
    traceback is printed where it was drawn). Nothing is written."""


def default_out_dir(results: Path) -> Path:
    """The report folder next to the (first) results file: RESULTS-report/ (a long RESULTS cut, see file_name_within)."""
    results = Path(results)
    return results.with_name(file_name_within(results.stem, OUT_NAME_BYTES - len("-report")) + "-report")


def write_report(paths: list[Path], out_dir: Path | None = None, reference: Path | None = None,
                 times=DEFAULT_TIMES, baseline: Path | None = None, method: dict | list[dict] | None = None,
                 progress=None, partial: bool = False, allow_aliasing: bool = False, fmt: str = "png",
                 exceedance: dict | None = None) -> list[Path]:
    """Write the whole report of `paths` into `out_dir` (default: next to the first file,
    RESULTS-report/); returns the files written (the baseline last, when asked for).

    `method`: one override {"kind", "order"}, a list of them (each file analysed with each, overlaid
    in the plots), or None (each campaign's own). `progress` (a Progress) is told each stage. `partial`,
    `allow_aliasing`, `exceedance` ({quantity: [{above: X} | {below: X}]}, replacing the campaign's
    thresholds of the quantities it names): see statistics.analyse. `fmt`: the figures' format (formats.FORMATS; see
    formats.exporting). Everything is written into a temporary folder first and
    moved into place at the end; nothing is written when a file is refused (statistics.BadInput)."""
    out_dir = Path(os.path.abspath(out_dir if out_dir is not None else default_out_dir(paths[0])))
    if fmt not in FORMATS:
        raise ValueError(f"figure format: expected one of {', '.join(FORMATS)}, got {fmt!r}")
    check_replaceable(out_dir)
    progress = progress or Progress(0, quiet=True)
    drawer = PreparedChild(_ready_to_draw, _draw) if FORKS else None  # gets ready while the files are analysed
    try:
        entries, ref = load_entries(paths, reference, method, progress=progress, partial=partial,
                                    allow_aliasing=allow_aliasing, exceedance=exceedance, scatter_time=times[-1])
        if baseline and entries[0].stats.rare_runs:
            raise BadInput(f"{entries[0].stats.path}: --write-baseline: a {entries[0].stats.design_kind} file has no "
                           "statistics of the input law to keep (its event's probability is in summary.json); "
                           "write the report without it")
        out_dir.parent.mkdir(parents=True, exist_ok=True)
        staging = make_staging(out_dir)
        try:
            with exporting(fmt):
                _write_into(staging, entries, ref, times, progress, drawer)
            written = sorted(out_dir / p.relative_to(staging) for p in staging.rglob("*") if p.is_file())
            progress.stage(f"moving the report into {out_dir}")
            replace_dir(staging, out_dir)
        except BaseException:
            shutil.rmtree(staging, ignore_errors=True)
            raise
    finally:
        if drawer is not None:
            drawer.close()
    if baseline:
        written.append(write_baseline(entries[0].stats, entries[0].campaign_hash, baseline))
    return written


def _write_into(out_dir: Path, entries: list[AnalysedFile], ref: AnalysedFile | None, times, progress: Progress,
                drawer: PreparedChild | None) -> None:
    """The report's files in `out_dir`: the data files written here while `drawer` (a PreparedChild of _draw;
    None: this process) draws the sections, then the page."""
    for sub in ("plots", "tables"):
        (out_dir / sub).mkdir(parents=True, exist_ok=True)
    on_message = _drawing_progress(progress)
    if drawer is not None:
        drawer.start((entries, ref, times, out_dir, export_format()))
    progress.stage("writing summaries and tables")
    written = _data_files(entries, out_dir)
    try:
        if drawer is None:
            from .sections import build_sections

            sections = build_sections(entries, ref, times, out_dir, on_message)
        else:
            sections = drawer.wait(on_message)
    except ChildFailed as exc:  # a section that raised, named, or a drawing process that died
        raise DrawingFailed(f"cannot draw the report's plots: {exc}") from exc
    on_message(("drawn", None))
    from .blocks import Table, files_section
    from .render import render_html, render_markdown

    for table in (block for section in sections for block in section.blocks if isinstance(block, Table)):
        written.append(write_csv(out_dir / table.file, table.header, table.rows))
    written += [out_dir / "report.html", out_dir / "report.md"]
    sections.append(files_section(written, out_dir))
    progress.stage("writing the page")
    title = f"uqflight report: {entries[0].label}" + (f" and {len(entries) - 1} more" if len(entries) > 1 else "")
    _write_text(out_dir / "report.html", render_html(title, sections, out_dir))
    _write_text(out_dir / "report.md", render_markdown(title, sections, out_dir))


def _ready_to_draw() -> None:
    """What the drawer does before its work: import the drawing (matplotlib) and load the fonts."""
    from . import sections  # noqa: F401
    from .plots import warm_text_caches

    warm_text_caches()


def _draw(payload, tell) -> list:
    """The drawer's work: the sections of (entries, ref, times, out_dir, figure format), shared with a
    child of its own per further CPU; `tell` gets what `build_sections` tells."""
    entries, ref, times, out_dir, fmt = payload
    from .sections import build_sections

    with exporting(fmt):
        return build_sections(entries, ref, times, out_dir, tell)


def _drawing_progress(progress: Progress):
    """What turns build_sections' messages into `progress`: the stage and its count of sections, the
    section this process (or the drawer) is drawing, named as it starts and counted as done as the next
    starts; ("drawn", None) ends it."""
    stages, started = [], []

    def on_message(message) -> None:
        kind, value = message
        if kind == "jobs":
            stages[:] = value
            progress.stage("drawing the plots", len(stages), "sections")
        elif kind == "starting":
            progress.advance(1 if started else 0, stages[value])
            started.append(value)
        else:
            progress.advance(len(stages), "drawn")

    return on_message


def _data_files(entries: list[AnalysedFile], out_dir: Path) -> list[Path]:
    """summary.json (and summaries/) and the statistics tables over time, written into `out_dir`."""
    return write_summaries(entries, out_dir) + write_statistics_tables(entries, out_dir)
