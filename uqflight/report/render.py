"""The report page as self-contained HTML (plots embedded) and as Markdown (linking plots/)."""
from __future__ import annotations

import base64
import html
import re
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from .blocks import Figure, Section

STYLE = """body{font-family:sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;color:#222}
table{border-collapse:collapse;margin:.5em 0 1.5em;font-size:.85em;display:block;overflow-x:auto}
th,td{border:1px solid #ccc;padding:.2em .5em;text-align:right}th{background:#eee}
td:first-child,td:nth-child(2){text-align:left}img{max-width:100%}figure{margin:1em 0 2em}
figcaption{font-size:.9em;color:#444}pre{background:#f6f6f6;padding:.5em;overflow-x:auto}
.notes{border:2px solid #c60;background:#fff4e5;padding:.5em 1em;margin:1em 0}
.notes h2{margin:.2em 0;color:#a40}"""


def render_html(title: str, sections: list[Section], out_dir: Path) -> str:
    """One self-contained page: the plots as base64 PNG data URIs, a table of contents, the tables."""
    toc, body, lead = [], [], []
    for s in sections:
        if s.lead:  # before the contents, not in them
            lead += [f'<h2 id="{s.anchor}">{html.escape(s.title)}</h2>', f"<p>{html.escape(s.text)}</p>"]
            lead += [_html_block(s.anchor, n, block, out_dir) for n, block in enumerate(s.blocks)]
            continue
        toc.append(f'<li><a href="#{s.anchor}">{html.escape(s.title)}</a>' + _html_toc(s) + "</li>")
        if s.notes:
            items = "".join(f"<li>{html.escape(line.removeprefix('- '))}</li>" for line in s.text.splitlines())
            body.append(f'<div class="notes"><h2 id="{s.anchor}">{html.escape(s.title)}</h2><ul>{items}</ul></div>')
            continue
        body.append(f'<h2 id="{s.anchor}">{html.escape(s.title)}</h2>')
        if s.preformatted:  # the campaign text, folded below the tables and figures
            body += [_html_block(s.anchor, n, block, out_dir) for n, block in enumerate(s.blocks)]
            body.append(f"<details><summary>Campaign text</summary><pre>{html.escape(s.text)}</pre></details>")
            continue
        body.append(f"<pre>{html.escape(s.text)}</pre>" if "\n" in s.text else f"<p>{html.escape(s.text)}</p>")
        body += [_html_block(s.anchor, n, block, out_dir) for n, block in enumerate(s.blocks)]
    stamp = datetime.now(timezone.utc).isoformat(timespec="seconds")
    return (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>{html.escape(title)}</title>'
            f"<style>{STYLE}</style></head><body>\n<h1>{html.escape(title)}</h1>\n<p>Written {stamp} by uqflight.</p>\n"
            + "\n".join(lead) + f"\n<h2>Contents</h2><ul>{''.join(toc)}</ul>\n" + "\n".join(body)
            + "\n</body></html>\n")


def _html_toc(section: Section) -> str:
    items = [f'<li><a href="#{section.anchor}-{n}">{html.escape(_block_title(b))}</a></li>'
             for n, b in enumerate(section.blocks)]
    return f"<ul>{''.join(items)}</ul>" if items else ""


def _block_title(block) -> str:
    return f"{block.file}: {block.caption}" if isinstance(block, Figure) else f"Table: {block.caption}"


def _html_block(anchor: str, n: int, block, out_dir: Path) -> str:
    if isinstance(block, Figure):
        return figure_html(f"{anchor}-{n}", block, out_dir)
    header, groups = page_view(block)
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    rows = "".join((f'<tr><th colspan="{len(header)}" style="text-align:left">{html.escape(group)}</th></tr>'
                    if group is not None else "")
                   + "".join("<tr>" + "".join(f"<td>{html.escape(_cell(v))}</td>" for v in row) + "</tr>"
                             for row in rows) for group, rows in groups)
    return (f'<h3 id="{anchor}-{n}">{html.escape(block.caption)}</h3><p>({html.escape(block.file)})</p>'
            f"<table><tr>{head}</tr>{rows}</table>")


MIME = {".png": "image/png", ".svg": "image/svg+xml"}


def figure_html(anchor: str, block: Figure, out_dir: Path) -> str:
    """A figure embedded as a data URI (PNG or SVG), its caption, and a link to its PDF when one was
    written beside it (`report --format pdf`)."""
    path = out_dir / block.file
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    pdf = Path(block.file).with_suffix(".pdf")
    link = f' <a href="{html.escape(pdf.as_posix())}">PDF</a>' if (out_dir / pdf).is_file() else ""
    return (f'<figure id="{anchor}"><img src="data:{MIME[path.suffix]};base64,{data}" alt="{html.escape(block.file)}">'
            f"<figcaption>{html.escape(block.caption)} ({html.escape(block.file)}){link}</figcaption></figure>")


def render_markdown(title: str, sections: list[Section], out_dir: Path | None = None) -> str:
    """The same page in Markdown, linking the figures in plots/ (and their PDFs in out_dir, if any). Every name, reason and caption is
    escaped (`md`); the campaign text sits in a fence longer than any run of backticks in it."""
    lines = [f"# {md(title)}"]
    lead = [s for s in sections if s.lead]
    for s in lead + [None] + [s for s in sections if not s.lead]:
        if s is None:
            lines += ["", "## Contents", ""] + [f"- [{md(s.title)}](#{s.anchor})" for s in sections if not s.lead]
            continue
        text = "\n".join(md(line) for line in s.text.splitlines())
        if s.preformatted:
            fence = "`" * max(3, 1 + max((len(run) for run in re.findall("`+", s.text)), default=0))
            text = f"{fence}yaml\n{s.text}\n{fence}"
        if s.notes:
            text = "\n".join(f"> **{md(line)}**" for line in s.text.splitlines())
        lines += ["", f'<a id="{s.anchor}"></a>', f"## {md(s.title)}", "", text]
        for block in s.blocks:
            if isinstance(block, Figure):
                lines += ["", f"![{md(block.caption)}]({block.file})", "", f"*{md(block.caption)}* ({md(block.file)})"]
                pdf = Path(block.file).with_suffix(".pdf")
                if out_dir is not None and (out_dir / pdf).is_file():
                    lines[-1] += f" [PDF]({pdf.as_posix()})"
            else:
                header, groups = page_view(block)
                lines += ["", f"### {md(block.caption)}", "", f"({md(block.file)})", "",
                          "| " + " | ".join(md(h) for h in header) + " |", "|" + "---|" * len(header)]
                for group, rows in groups:
                    if group is not None:
                        lines.append(f"| **{md(group)}** |" + " |" * (len(header) - 1))
                    lines += ["| " + " | ".join(md(_cell(v)) for v in row) + " |" for row in rows]
    return "\n".join(lines) + "\n"


def page_view(table) -> tuple[list[str], list[tuple[str | None, list[list]]]]:
    """The header and rows a table shows on the page (its `page` view, else its CSV's), in groups: for a
    grouped table one group per value of its first column, that column then left out; else one group."""
    header, rows = table.page or (table.header, table.rows)
    if not table.grouped:
        return list(header), [(None, rows)]
    groups: dict[str, list[list]] = {}
    for row in rows:
        groups.setdefault(str(row[0]), []).append(row[1:])
    return list(header[1:]), list(groups.items())


MARKDOWN_SPECIAL = re.compile(r"([\\`*_{}\[\]<>|#!~])")


def md(text: str) -> str:
    """`text` as literal Markdown on one line: its punctuation backslash-escaped, so that a name or a
    failure reason holding | * _ ` [ ] < > # cannot end a table cell, make a link, emphasis, a
    heading or HTML."""
    return MARKDOWN_SPECIAL.sub(r"\\\1", " ".join(str(text).splitlines()))


def _cell(value) -> str:
    """A table cell for reading: 4 significant digits, one decimal from 1000 on (an altitude of
    14966.1 ft, not 1.497e+04); the CSVs keep full precision. No value (None) is "—"."""
    if value is None:
        return "—"
    if isinstance(value, (float, np.floating)):
        return f"{value:.1f}" if 1e3 <= abs(value) < 1e7 else f"{value:.4g}"
    return str(value)


