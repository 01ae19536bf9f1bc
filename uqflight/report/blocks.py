"""The blocks of the report's page (sections of text, figures and tables), without matplotlib: the page
is written by a process that never imports it (the figures may be drawn by others)."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path


@dataclass
class Figure:
    file: str  # relative to the report directory
    caption: str


@dataclass
class Table:
    caption: str
    header: list[str]
    rows: list[list]
    file: str  # the CSV, relative to the report directory
    page: tuple[list[str], list[list]] | None = None  # (header, rows) the page shows instead, e.g. rounded
    grouped: bool = False  # the page shows the first column once, as a heading row over its rows


@dataclass
class Section:
    title: str
    anchor: str
    text: str
    blocks: list = field(default_factory=list)
    preformatted: bool = False  # the text as written (the campaign YAML)
    notes: bool = False  # a box at the top the reader must see
    lead: bool = False  # shown before the table of contents (the headline)


def files_section(written: list[Path], out_dir: Path) -> Section:
    """The section listing the files written, relative to `out_dir`."""
    listing = "\n".join(f"- {_rel(p, out_dir)}" for p in written)
    return Section("Data files", "data", "Written beside this page (plots in plots/):\n" + listing)


def _rel(path: Path, out_dir: Path) -> str:
    """`path` relative to `out_dir`, with forward slashes (as the page links it)."""
    return Path(path).relative_to(out_dir).as_posix()
