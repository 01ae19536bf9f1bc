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

import base64
import csv
import html
import json
import re
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path

import numpy as np
import yaml

from . import plots
from .check import write_baseline
from .statistics import Statistics, add_reference_errors, read_statistics, summary_json

METHOD_NAMES = {"integration": "Int", "pseudo_galerkin": "PG", "interpolation": "interpolation",
                "regression": "regression", "least_squares": "least squares", "monte_carlo": "MC"}
DEFAULT_TIMES = (10.0, 25.0, float("inf"))  # the tables' times: 10 s, 25 s and the final time


@dataclass
class Entry:
    """One analysed results file and how the report names it."""

    stats: Statistics
    stem: str
    label: str
    campaign_hash: str
    inputs: str

    @property
    def outputs(self) -> dict:
        return self.stats.outputs

    @property
    def monte_carlo(self) -> bool:
        return self.stats.method["kind"] == "monte_carlo"

    @property
    def pick_freeze(self) -> bool:
        return self.stats.design_kind == "pick_freeze"

    @property
    def has_sobol(self) -> bool:
        return any(out.sobol_first for out in self.outputs.values())

    @property
    def has_errors(self) -> bool:
        return any(out.errors for out in self.outputs.values())


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


@dataclass
class Section:
    title: str
    anchor: str
    text: str
    blocks: list = field(default_factory=list)


def method_label(method: dict) -> str:
    """A method as in the paper's legends, e.g. "PG order 2", "MC"."""
    kind = method["kind"]
    name = METHOD_NAMES.get(kind, kind)
    if kind == "monte_carlo":
        return name
    return f"{name} order {method['order']}" + (" split" if method.get("split") else "")


def input_distributions(campaign_text: str) -> str:
    """The campaign's input distribution(s), e.g. "normal" or "normal, uniform"."""
    parameters = (yaml.safe_load(campaign_text) or {}).get("parameters") or {}
    return ", ".join(dict.fromkeys(str(spec.get("distribution", "?")) for spec in parameters.values()))


def load_entries(paths: list[Path], reference: Path | None, method: dict | None = None,
                 partial: bool = False, allow_aliasing: bool = False) -> tuple[list[Entry], Entry | None]:
    """Every file analysed (with `method` overriding the campaigns' methods, the reference
    excepted), with errors against the reference unless it is the reference itself, and the reference."""
    stems: set[str] = set()
    ref = _entry(reference, *read_statistics(reference), set()) if reference else None
    entries = []
    for path in paths:
        stats, attrs = read_statistics(path, method, partial=partial, allow_aliasing=allow_aliasing)
        if ref is not None and not _same_file(path, reference):
            add_reference_errors(stats, ref.stats)
        entries.append(_entry(path, stats, attrs, stems))
    return entries, ref


def _entry(path: Path, stats: Statistics, attrs: dict, stems: set[str]) -> Entry:
    stem = _unique(file_name(Path(path).stem), stems)
    runs = f"partial: {stats.completed} of {stats.runs} runs" if stats.partial else f"{stats.runs} runs"
    label = f"{stats.campaign_name or stem}: {method_label(stats.method)}, {runs}"
    return Entry(stats, stem, label, str(attrs.get("campaign_hash", "")),
                 input_distributions(str(attrs.get("campaign", ""))))


def file_name(name: str) -> str:
    """An output or file name made safe for a file name: "velocities/vc-kts" → "velocities_vc-kts"."""
    return re.sub(r"[^A-Za-z0-9_.-]", "_", name)


def _same_file(a, b) -> bool:
    return Path(a).resolve() == Path(b).resolve()


def _unique(stem: str, taken: set[str]) -> str:
    name, n = stem, 1
    while name in taken:
        n += 1
        name = f"{stem}-{n}"
    taken.add(name)
    return name


def write_report(paths: list[Path], out_dir: Path, reference: Path | None = None,
                 times=DEFAULT_TIMES, baseline: Path | None = None, method: dict | None = None,
                 partial: bool = False, allow_aliasing: bool = False) -> list[Path]:
    """Write the whole report of `paths` into `out_dir`; returns the files written. Nothing is written
    when a file is refused (statistics.BadInput)."""
    out_dir = Path(out_dir)
    entries, ref = load_entries(paths, reference, method, partial, allow_aliasing)
    for sub in ("plots", "tables"):
        (out_dir / sub).mkdir(parents=True, exist_ok=True)
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


def write_summaries(entries: list[Entry], out_dir: Path) -> list[Path]:
    """summary.json for the first file; summaries/<stem>.json for each when there are several."""
    written = [_write_json(out_dir / "summary.json", summary_json(entries[0].stats))]
    if len(entries) > 1:
        (out_dir / "summaries").mkdir(exist_ok=True)
        written += [_write_json(out_dir / "summaries" / f"{e.stem}.json", summary_json(e.stats)) for e in entries]
    return written


def write_statistics_tables(entries: list[Entry], out_dir: Path) -> list[Path]:
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
            path = out_dir / "tables" / f"statistics_{entry.stem}_{file_name(name)}.csv"
            written.append(write_csv(path, header, np.column_stack(columns).tolist()))
    return written


def build_sections(entries: list[Entry], ref: Entry | None, times: list[float], out_dir: Path) -> list[Section]:
    """The report's sections, drawing their plots into out_dir/plots."""
    sections = [inputs_section(entries, ref), statistics_section(entries, ref, times, out_dir)]
    if any(e.has_errors for e in entries):
        sections.append(accuracy_section(entries, out_dir))
    if any(e.has_sobol for e in entries):
        sections.append(sensitivity_section(entries, times, out_dir))
    extra = [ref] if ref is not None and not any(_same_file(ref.stats.path, e.stats.path) for e in entries) else []
    monte_carlo = [e for e in entries + extra if e.monte_carlo]
    if len(monte_carlo) >= 2:
        sections.append(monte_carlo_section(monte_carlo, out_dir))
    return sections


def inputs_section(entries: list[Entry], ref: Entry | None) -> Section:
    rows = [[e.label, e.stats.path, e.stats.design_kind, method_label(e.stats.method), e.inputs, e.stats.runs,
             e.stats.failed, e.campaign_hash[:12]] for e in entries]
    text = (f"Errors and KLD are against the reference {ref.label} ({ref.stats.path})." if ref
            else "No reference file: no errors or KLD (give a Monte Carlo file with --reference).")
    if ref:
        lacking = [f"{e.label}: {name}" for e in entries if not _same_file(e.stats.path, ref.stats.path)
                   for name, out in e.outputs.items() if not out.errors]
        if lacking:
            text += (" No errors for " + "; ".join(lacking) + " (the reference lacks the output or has "
                     "another time grid).")
    return Section("Results files", "files", text, [Table(
        "The results files (the first is the one summary.json and the single-file plots describe)",
        ["label", "file", "design", "method", "inputs", "runs", "failed", "campaign sha256"], rows,
        "tables/files.csv")])


def statistics_section(entries: list[Entry], ref: Entry | None, times: list[float], out_dir: Path) -> Section:
    """Figs. 6-8 for the first file, and every file's statistics at the selected times."""
    first = entries[0]
    plot_dir = out_dir / "plots"
    overlay = ref.outputs if ref is not None and not _same_file(ref.stats.path, first.stats.path) else None
    blocks = [Figure(_rel(plots.plot_mean_band(first.outputs, plot_dir / "mean_band.png",
                                               f"Mean and 99 % band: {first.label}", overlay), out_dir),
                     "Mean and 99 % band of each output over time (paper Figs. 6-7)"
                     + ("; the reference dashed." if overlay else "."))]
    blocks.append(Figure(_rel(plots.plot_cov(first.outputs, plot_dir / "cov.png",
                                             f"Modified coefficient of variation: {first.label}"), out_dir),
                         "Modified coefficient of variation std(t) / max|mean| of every output (paper Fig. 8)."))
    for name, out in first.outputs.items():
        path = plots.plot_pdf_over_time(out, plot_dir / f"pdf_{file_name(name)}.png",
                                        f"PDF of {plots.short_label(name)}: {first.label}", times)
        blocks.append(Figure(_rel(path, out_dir), f"PDF of {plots.label(name, out.units)} over time "
                                                  "(paper Figs. 6-7, right) and at the selected times."))
    rows = []
    for entry in entries:
        for name, out in entry.outputs.items():
            for i in plots.time_indices(out.time, times):
                rows.append([entry.label, name, out.units, out.time[i], out.mean[i], out.std[i], out.band99[0][i],
                             out.band99[1][i], out.cov[i]])
    blocks.append(Table("Statistics at the selected times",
                        ["file", "output", "unit", "time [s]", "mean", "std", "band99 lower", "band99 upper",
                         "cov [-]"], rows, "tables/statistics_at_times.csv"))
    return Section("Statistics over time", "statistics", f"Plots of {first.label}; the full statistics over "
                   "time of every file and output are in tables/statistics_<file>_<output>.csv.", blocks)


def accuracy_section(entries: list[Entry], out_dir: Path) -> Section:
    """Eq. 49 errors over time (Figs. 10-19), their table, and the KLD against the runs (Fig. 20)."""
    compared = [e for e in entries if e.has_errors]
    curves = [(e.label, e.outputs) for e in compared]
    blocks = []
    for key, what in (("eps_m", "mean"), ("eps_v", "variance")):
        path = plots.plot_errors(curves, key, out_dir / "plots" / f"{key}.png",
                                 f"Relative error of the {what} against the reference (Eq. 49)")
        blocks.append(Figure(_rel(path, out_dir), f"ε of the {what} over time, one line per file "
                                                  "(paper Figs. 10-19)."))
    if len(compared) >= 2:
        points = [(f"{method_label(e.stats.method)} ({e.stats.design_kind})", e.stats.runs,
                   {name: out.errors["kld_final"] for name, out in e.outputs.items() if out.errors}) for e in compared]
        path = plots.plot_kld_vs_runs(points, out_dir / "plots" / "kld_vs_runs.png",
                                      "Kullback-Leibler divergence from the reference at the final time (Eq. 50)")
        blocks.append(Figure(_rel(path, out_dir), "KLD of each output's final-time PDF from the reference's "
                                                  "against the number of runs, one line per method and design "
                                                  "(paper Fig. 20)."))
    rows = [[e.label, name, out.errors["eps_m_summary"]["max"], out.errors["eps_m_summary"]["mean"],
             out.errors["eps_v_summary"]["max"], out.errors["eps_v_summary"]["mean"], out.errors["kld_final"],
             e.stats.runs] for e in compared for name, out in e.outputs.items() if out.errors]
    blocks.append(Table("Errors against the reference: max and mean over time of ε_m and ε_v, KLD at the final time",
                        ["file", "output", "eps_m max", "eps_m mean", "eps_v max", "eps_v mean", "KLD final",
                         "runs"], rows, "tables/errors.csv"))
    return Section("Accuracy against the reference", "accuracy",
                   "ε_m = |E − E_ref| / max|E_ref|, ε_v the same for the variance (Eq. 49); "
                   "KLD = ∫ ρ ln(ρ / ρ_ref) (Eq. 50).", blocks)


def sensitivity_section(entries: list[Entry], times: list[float], out_dir: Path) -> Section:
    """Sobol' indices over time (Fig. 21), at the selected times (Table 3), and PCE vs MC (Table 4)."""
    with_sobol = [e for e in entries if e.has_sobol]
    blocks = []
    for entry in with_sobol:
        path = plots.plot_sobol(entry.outputs, out_dir / "plots" / f"sobol_{entry.stem}.png",
                                f"First-order Sobol' indices: {entry.label}")
        blocks.append(Figure(_rel(path, out_dir), f"First-order Sobol' indices over time of {entry.label} "
                                                  "(paper Fig. 21)" + (", bootstrap 95 % intervals shaded."
                                                                       if entry.pick_freeze else ".")))
    parameters = list(dict.fromkeys(p for e in with_sobol for p in e.stats.parameter_names))
    for kind, what in (("sobol_first", "First-order"), ("sobol_total", "Total")):
        rows = [[e.label, name, out.time[i], *(_at(getattr(out, kind), p, i) for p in parameters)]
                for e in with_sobol for name, out in e.outputs.items() for i in plots.time_indices(out.time, times)]
        caption = f"{what} Sobol' indices at the selected times" + (" (paper Table 3)" if kind == "sobol_first" else "")
        blocks.append(Table(caption, ["file", "output", "time [s]", *parameters], rows, f"tables/{kind}.csv"))
    if any(e.pick_freeze for e in with_sobol) and any(not e.pick_freeze for e in with_sobol):
        blocks.append(pce_vs_mc_table(with_sobol, parameters))
    return Section("Sensitivity: Sobol' indices", "sensitivity",
                   "From the PCE (Eq. 53) for the PCE methods; from pick-freeze estimators for a pick_freeze design.",
                   blocks)


def pce_vs_mc_table(entries: list[Entry], parameters: list[str]) -> Table:
    """First-order indices at the final time per output and parameter, one column per file (Table 4)."""
    header = ["output", "time [s]", "parameter"]
    for e in entries:
        header += [e.label] + ([f"{e.label} 95 % CI lower", f"{e.label} 95 % CI upper"] if e.pick_freeze else [])
    rows = []
    for name, out in entries[0].outputs.items():
        for parameter in parameters:
            row = [name, out.time[-1], parameter]
            for e in entries:
                other = e.outputs.get(name)
                row.append(_at(other.sobol_first, parameter, -1) if other else "")
                if e.pick_freeze:
                    ci = other.sobol_first_ci.get(parameter) if other else None
                    row += [ci[0][-1], ci[1][-1]] if ci is not None else ["", ""]
            rows.append(row)
    return Table("First-order Sobol' indices at the final time: PCE against Monte Carlo pick-freeze (paper Table 4)",
                 header, rows, "tables/sobol_pce_vs_mc.csv")


def _at(indices: dict, parameter: str, i: int):
    return indices[parameter][i] if parameter in indices else ""


def monte_carlo_section(entries: list[Entry], out_dir: Path) -> Section:
    """Several Monte Carlo files (the reference too) overlaid, e.g. normal against uniform inputs (Figs. 4-5)."""
    labelled = [(f"{e.label} (inputs {e.inputs})", e.outputs) for e in entries]
    bands = plots.plot_band_comparison(labelled, out_dir / "plots" / "mc_bands.png",
                                       "Monte Carlo files: mean (solid) and 99 % band (dashed)")
    pdfs = plots.plot_final_pdfs(labelled, out_dir / "plots" / "mc_pdf_final.png",
                                 "Monte Carlo files: PDF at the final time")
    return Section("Monte Carlo files compared", "monte-carlo",
                   "The Monte Carlo files side by side, e.g. normal against uniform inputs (paper Figs. 4-5).",
                   [Figure(_rel(bands, out_dir), "Mean and 99 % band of each Monte Carlo file."),
                    Figure(_rel(pdfs, out_dir), "PDF of each output at the final time for each Monte Carlo file.")])


def files_section(written: list[Path], out_dir: Path) -> Section:
    listing = "\n".join(f"- {_rel(p, out_dir)}" for p in written)
    return Section("Data files", "data", "Written beside this page (plots in plots/):\n" + listing)


# -- rendering ---------------------------------------------------------------------------------
STYLE = """body{font-family:sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;color:#222}
table{border-collapse:collapse;margin:.5em 0 1.5em;font-size:.85em;display:block;overflow-x:auto}
th,td{border:1px solid #ccc;padding:.2em .5em;text-align:right}th{background:#eee}
td:first-child,td:nth-child(2){text-align:left}img{max-width:100%}figure{margin:1em 0 2em}
figcaption{font-size:.9em;color:#444}pre{background:#f6f6f6;padding:.5em}"""


def render_html(title: str, sections: list[Section], out_dir: Path) -> str:
    """One self-contained page: the plots as base64 PNG data URIs, a table of contents, the tables."""
    toc, body = [], []
    for s in sections:
        toc.append(f'<li><a href="#{s.anchor}">{html.escape(s.title)}</a>' + _html_toc(s) + "</li>")
        body.append(f'<h2 id="{s.anchor}">{html.escape(s.title)}</h2>')
        body.append(f"<pre>{html.escape(s.text)}</pre>" if "\n" in s.text else f"<p>{html.escape(s.text)}</p>")
        body += [_html_block(s.anchor, n, block, out_dir) for n, block in enumerate(s.blocks)]
    stamp = datetime.now(timezone.utc).isoformat(timespec="seconds")
    return (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>{html.escape(title)}</title>'
            f"<style>{STYLE}</style></head><body>\n<h1>{html.escape(title)}</h1>\n<p>Written {stamp} by uqflight.</p>\n"
            f"<h2>Contents</h2><ul>{''.join(toc)}</ul>\n" + "\n".join(body) + "\n</body></html>\n")


def _html_toc(section: Section) -> str:
    items = [f'<li><a href="#{section.anchor}-{n}">{html.escape(_block_title(b))}</a></li>'
             for n, b in enumerate(section.blocks)]
    return f"<ul>{''.join(items)}</ul>" if items else ""


def _block_title(block) -> str:
    return f"{block.file}: {block.caption}" if isinstance(block, Figure) else f"Table: {block.caption}"


def _html_block(anchor: str, n: int, block, out_dir: Path) -> str:
    if isinstance(block, Figure):
        data = base64.b64encode((out_dir / block.file).read_bytes()).decode("ascii")
        return (f'<figure id="{anchor}-{n}"><img src="data:image/png;base64,{data}" alt="{html.escape(block.file)}">'
                f"<figcaption>{html.escape(block.caption)} ({html.escape(block.file)})</figcaption></figure>")
    head = "".join(f"<th>{html.escape(h)}</th>" for h in block.header)
    rows = "".join("<tr>" + "".join(f"<td>{html.escape(_cell(v))}</td>" for v in row) + "</tr>" for row in block.rows)
    return (f'<h3 id="{anchor}-{n}">{html.escape(block.caption)}</h3><p>({html.escape(block.file)})</p>'
            f"<table><tr>{head}</tr>{rows}</table>")


def render_markdown(title: str, sections: list[Section]) -> str:
    """The same page in Markdown, linking the PNGs in plots/."""
    lines = [f"# {title}", "", "## Contents", ""]
    lines += [f"- [{s.title}](#{s.anchor})" for s in sections]
    for s in sections:
        lines += ["", f'<a id="{s.anchor}"></a>', f"## {s.title}", "", s.text]
        for block in s.blocks:
            if isinstance(block, Figure):
                lines += ["", f"![{block.caption}]({block.file})", "", f"*{block.caption}* ({block.file})"]
            else:
                lines += ["", f"### {block.caption}", "", f"({block.file})", "",
                          "| " + " | ".join(block.header) + " |", "|" + "---|" * len(block.header)]
                lines += ["| " + " | ".join(_cell(v).replace("|", "\\|") for v in row) + " |" for row in block.rows]
    return "\n".join(lines) + "\n"


def _cell(value) -> str:
    """A table cell for reading: 4 significant digits, one decimal from 1000 on (an altitude of
    14966.1 ft, not 1.497e+04); the CSVs keep full precision."""
    if isinstance(value, (float, np.floating)):
        return f"{value:.1f}" if 1e3 <= abs(value) < 1e7 else f"{value:.4g}"
    return str(value)


# -- files -------------------------------------------------------------------------------------
def write_csv(path: Path, header: list[str], rows: list[list]) -> Path:
    with open(path, "w", newline="", encoding="utf-8") as fh:
        writer = csv.writer(fh)
        writer.writerow(header)
        writer.writerows([[float(v) if isinstance(v, np.floating) else v for v in row] for row in rows])
    return path


def _write_json(path: Path, data: dict) -> Path:
    path.write_text(json.dumps(data, indent=1, allow_nan=False) + "\n", encoding="utf-8")
    return path


def _write_text(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


def _rel(path: Path, out_dir: Path) -> str:
    return Path(path).relative_to(out_dir).as_posix()
