"""The figures' export format (png, svg or pdf), without matplotlib: the report chooses it before its
plotting modules are imported."""
from __future__ import annotations

from contextlib import contextmanager
from pathlib import Path

FORMATS = ("png", "svg", "pdf")
_format = ["png"]  # the export format of the figures (`exporting`)


@contextmanager
def exporting(fmt: str):
    """Write the figures drawn inside as `fmt`: png; svg (vector; the page embeds it); pdf (vector,
    beside a PNG of the same name that the page shows)."""
    if fmt not in FORMATS:
        raise ValueError(f"unknown figure format {fmt!r}: expected one of {', '.join(FORMATS)}")
    previous, _format[0] = _format[0], fmt
    try:
        yield
    finally:
        _format[0] = previous


def export_format() -> str:
    """The format figures are written in now."""
    return _format[0]


def shown_path(path: Path) -> Path:
    """The file of `path`'s figure that the page shows, in the export format."""
    return Path(path).with_suffix(".svg" if export_format() == "svg" else ".png")
