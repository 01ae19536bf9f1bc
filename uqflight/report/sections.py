"""What the report page says: its sections, each with text, figures (drawn into plots/) and tables."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from . import plots
from .loading import Entry, _same_file, file_name, method_label

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



def _rel(path: Path, out_dir: Path) -> str:
    return Path(path).relative_to(out_dir).as_posix()
