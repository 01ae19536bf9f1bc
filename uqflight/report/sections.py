"""What the report page says: its sections, each with text, figures (drawn into plots/) and tables."""
from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np

from . import plots
from .blocks import Figure, Section, Table, _rel
from ..text.labels import shown_time
from .formats import shown_path
from ..analysis.sobol import unresolved
from ..running.forking import ChildFailed, share_work
from ..text.console import one_line
from .sensitivity import N_TOO_SMALL, NEGLIGIBLE, index_text, plot_sensitivity
from .loading import AnalysedFile, _same_file, file_name_within, one_per_file

BELOW_FLOOR = "below reference resolution"
UNRESOLVED = "unresolved"

def build_sections(entries: list[AnalysedFile], ref: AnalysedFile | None, times: list[float], out_dir: Path,
                   on_message: Callable[[tuple], None] | None = None) -> list[Section]:
    """The report's sections, drawing their plots into out_dir/plots. The sections are built by this
    process and a forked child per further core (forking.share_work), the costliest first: each
    process draws its sections' figures itself, with the fonts it has loaded. `on_message`, when given, is
    told ("jobs", the sections' stage texts) first, then ("starting", k) as this process starts the k-th."""
    jobs = section_jobs(entries, ref, times, out_dir)
    order = sorted(range(len(jobs)), key=lambda k: -jobs[k][0])
    if on_message is not None:
        on_message(("jobs", [stage for _, stage, _ in jobs]))
    plots.warm_text_caches()  # before the fork: every process inherits the loaded fonts
    with plots.collecting_at_the_end():
        sections = share_work([_named(stage, build) for _, stage, build in jobs], order,
                              starting=None if on_message is None else lambda k: on_message(("starting", k)))
    return [section for section in sections if section is not None]


def _named(stage: str, build: Callable[[], Section | None]) -> Callable[[], Section | None]:
    """`build`, whose error (a file error aside: the report's "cannot write") is a ChildFailed naming the
    section by its `stage` and saying what it raised."""
    def run():
        try:
            return build()
        except OSError:
            raise
        except Exception as exc:
            raise ChildFailed(f"{stage} raised {type(exc).__name__}: {one_line(str(exc))}") from exc
    return run


def section_jobs(entries: list[AnalysedFile], ref: AnalysedFile | None, times: list[float],
                 out_dir: Path) -> list[tuple[int, str, Callable[[], Section | None]]]:
    """The report's sections in page order as (cost, stage, build): `cost` the panels it draws, roughly
    (what sets how long it takes), `stage` what the progress says while it is drawn, `build` what
    returns the section (None: nothing to show). The PDF figures are a job of their own, which the
    statistics section shows."""
    from .headline import headline_section
    from .trajectories import trajectories_section

    k = len(entries)
    outputs = max(len(e.outputs) for e in entries)
    inputs = max(len(e.stats.parameter_names) for e in entries)
    jobs = [(0, "writing the headline", lambda: headline_section(entries[0], times)),
            (0, "writing the notes", lambda: notes_section(entries)),
            (k, "drawing the design", lambda: run_section(entries, out_dir)),
            (0, "writing the inputs", lambda: inputs_section(entries, ref)),
            (0, "writing the failures", lambda: failures_section(entries))]
    if outputs:  # none: a rare-event design's runs are not draws of the input law (rare_statistics)
        jobs += [((outputs + 1) * k + (outputs if k >= 2 else 0), "drawing the statistics over time",
                  lambda: statistics_section(entries, ref, times, out_dir)),
                 (2 * outputs * k, "drawing the PDFs", lambda: draw_pdfs(entries, times, out_dir))]
    jobs.append(((outputs + inputs) * k, "drawing the runs", lambda: trajectories_section(entries, times, out_dir)))
    if any(e.has_errors for e in entries):
        jobs.append((2 * outputs + 2, "drawing the errors against the reference",
                     lambda: accuracy_section(entries, out_dir)))
    if any(e.stats.quantities for e in entries):
        from .quantities import quantities_section

        quantities = max(len(e.stats.quantities) for e in entries)
        jobs.append((2 * quantities * k, "drawing the quantities of interest",
                     lambda: quantities_section(entries, out_dir)))
    if any(getattr(e.stats, "index_set", None) for e in entries):
        from .index_set import index_set_section

        jobs.append((k, "drawing the adaptive grid's index set", lambda: index_set_section(entries, out_dir)))
    if any(getattr(e.stats, "rare_runs", None) for e in entries):
        from .rare_event import rare_event_section

        jobs.append((2 * k, "drawing the rare event's estimate", lambda: rare_event_section(entries, out_dir)))
    if any(e.stats.seeds for e in entries):
        from .variance_split import variance_split_section

        jobs.append((0, "writing the variance split", lambda: variance_split_section(entries, times)))
    screened = dict.fromkeys(out.screening.name for e in entries for out in e.outputs.values() if out.screening)
    for name in screened:  # a screening design's measures: its own page (report.screenings)
        from .screenings import SCREENINGS

        page = SCREENINGS[name]
        jobs.append((outputs * k, page.stage, lambda page=page: page.section(entries, times, out_dir)))
    if any(e.has_sobol for e in entries):
        jobs.append((3 * outputs * k, "drawing the Sobol' indices",
                     lambda: sensitivity_section(entries, times, out_dir)))
    decay = [e for e in entries if any(getattr(o, "coefficient_decay", None) for o in e.outputs.values())]
    if decay:
        jobs.append((outputs * len(decay), "drawing the coefficient decay", lambda: decay_section(decay, out_dir)))
    extra = [ref] if ref is not None and not any(_same_file(ref.stats.path, e.stats.path) for e in entries) else []
    monte_carlo = [e for e in entries + extra if e.monte_carlo]
    if len(monte_carlo) >= 2:
        jobs.append((2 * outputs, "drawing the Monte Carlo files compared",
                     lambda: monte_carlo_section(monte_carlo, out_dir)))
    return jobs


def notes_section(entries: list[AnalysedFile]) -> Section | None:
    """What the reader must see before any number (Statistics.notes), per file; None without notes."""
    lines = [f"{e.label}: {note}" for e in entries for note in (getattr(e.stats, "notes", None) or [])]
    if not lines:
        return None
    return Section("Notes", "notes", "\n".join(f"- {line}" for line in dict.fromkeys(lines)), notes=True)


def run_section(entries: list[AnalysedFile], out_dir: Path) -> Section:
    """What was run: per results file its parameters, flight condition, excitation, design, method,
    seed, versions, aircraft hash and date; its campaign text; the design scatter (Fig. 9)."""
    blocks = []
    facts, parameter_rows = [], []
    for e in one_per_file(entries):
        settings, simulator = e.settings, e.simulator
        methods = ", ".join(dict.fromkeys(x.stats.estimator_label for x in entries
                                          if (x.path or x.stats.path) == (e.path or e.stats.path)))
        versions = ", ".join(f"{k} {v}" for k, v in e.stats.record.versions.items())
        failed = getattr(e.stats, "failed", 0)
        counts = f"{e.stats.runs} runs, {failed} failed"
        if getattr(e.stats, "pending", 0):
            counts += f", {e.stats.pending} not run"
        flown = e.stats.record.flight
        info = ", ".join(f"{k} {v}" for k, v in e.stats.design_info.items())
        facts.append([e.stem, ("flight", flown.get("flight", "-")), ("excitation", flown.get("excitation", "-")),
                      ("simulator", ", ".join(f"{k} {simulator[k]}" for k in ("kind", "aircraft", "function",
                                                                              "duration_s", "output_rate_hz")
                                              if k in simulator)),
                      ("design", f"{e.stats.design_kind} {info}".strip()),
                      ("method", methods), ("seed", e.stats.record.campaign.seed), ("runs", counts),
                      ("created", e.attrs.get("created", "?")), ("aircraft sha256", e.attrs.get("aircraft_hash", "-")),
                      ("campaign sha256", e.campaign_hash), ("versions", versions)])
        for p in e.parameters:
            spec = settings["parameters"][p["name"]]
            interval = (f"±{spec['interval_pct']:g} % of nominal" if "interval_pct" in spec else "lower, upper")
            parameter_rows.append([e.stem, p["name"], p["property"], p["distribution"], p["lower"], p["upper"],
                                   p["nominal"], interval])
    header = ["fact"] + [row[0] for row in facts]
    rows = [[fact] + [row[k][1] for row in facts] for k, (fact, _) in enumerate(facts[0][1:], start=1)]
    blocks.append(Table("The campaign: flight condition, excitation, design, method, seed, provenance",
                        header, rows, "tables/campaign.csv"))
    blocks.append(Table("Uncertain parameters: distribution, interval and nominal value",
                        ["file", "parameter", "property", "distribution", "lower", "upper", "nominal", "interval"],
                        parameter_rows, "tables/parameters.csv"))
    for e in one_per_file(entries):
        path = plots.plot_design_pairs(e.stats.drawn,
                                       out_dir / "plots" / file_name_within(f"design_{e.file_stem}.png"),
                                       f"Design: {e.stats.design_kind}, "
                                       f"{e.stats.runs} points ({e.file_stem})")
        if path is not None:
            blocks.append(Figure(_rel(path, out_dir), f"The design points of {e.file_stem} projected on each pair "
                                 "of inputs in physical values (paper Fig. 9); a symmetric grid once, in ξ, with "
                                 "the inputs' values at its levels; negative weights orange, failed runs red crosses."))
    texts = "\n\n".join(f"# {e.path or e.stats.path}\n{str(e.attrs.get('campaign', '')).strip()}"
                          for e in one_per_file(entries))
    return Section("What was run", "run", texts, blocks, preformatted=True)


def failures_section(entries: list[AnalysedFile]) -> Section | None:
    """Each failed run's parameters and reason (Statistics.failures), when any."""
    rows, parameters = [], []
    for e in one_per_file(entries):
        for failure in getattr(e.stats, "failures", None) or []:
            values = failure.get("parameters") or {}
            parameters += [p for p in values if p not in parameters]
            rows.append((e.stem, failure, values))
    if not rows:
        return None
    table = [[stem, f.get("run", ""), f.get("status", ""), f.get("reason", ""), *(v.get(p, "") for p in parameters)]
             for stem, f, v in rows]
    text = "; ".join(f"{e.stem}: failure probability {_probability(e.stats.failure_probability)}"
                     for e in one_per_file(entries) if getattr(e.stats, "failure_probability", None))
    return Section("Failed runs", "failures", text or "The runs that failed, with their parameters.",
                   [Table("Failed runs: parameters and reason", ["file", "run", "status", "reason", *parameters],
                          table, "tables/failures.csv")])


def _probability(p: dict) -> str:
    """The failure probability as the page says it: the estimate and its interval where they exist
    (a grid has no interval, and no estimate with signed weights), and how they were computed."""
    estimate, lower, upper = (_finite(p.get(key)) for key in ("estimate", "lower", "upper"))
    if estimate is None:
        return f"not estimated ({p.get('method', '')})"
    if lower is None or upper is None:
        return f"{estimate:.3g}, no interval ({p.get('method', '')})"
    return f"{estimate:.3g} (95 % interval {lower:.3g} to {upper:.3g}, {p.get('method', '')})"


def _finite(value) -> float | None:
    return None if value is None or not np.isfinite(value) else float(value)


def inputs_section(entries: list[AnalysedFile], ref: AnalysedFile | None) -> Section:
    rows = [[e.label, e.stats.path, e.stats.design_kind, e.stats.method_label, e.inputs, e.stats.runs,
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


def statistics_section(entries: list[AnalysedFile], ref: AnalysedFile | None, times: list[float], out_dir: Path) -> Section:
    """Figs. 6-8 for every file (and method), the methods' bands overlaid, and the statistics at the
    selected times."""
    plot_dir = out_dir / "plots"
    blocks = []
    for entry in entries:
        overlay = ref.outputs if ref is not None and not _same_file(ref.stats.path, entry.stats.path) else None
        blocks.append(Figure(_rel(plots.plot_mean_band(entry.outputs, plot_dir / file_name_within(f"mean_band_{entry.stem}.png"),
                                                       f"Mean and 99 % band: {entry.label}", overlay), out_dir),
                             f"Mean and 99 % band of each output over time of {entry.label} (paper Figs. 6-7)"
                             + ("; the reference dashed." if overlay else ".")))
        blocks.append(Figure(_rel(plots.plot_cov(entry.outputs, plot_dir / file_name_within(f"cov_{entry.stem}.png"),
                                                 f"Spread over time: {entry.label}"), out_dir),
                             f"Modified coefficient of variation std(t) / max|mean| of the outputs of {entry.label} "
                             "(paper Fig. 8); outputs on an offset datum (min|mean| more than "
                             f"{plots.OFFSET_DATUM:g} × the mean's excursion, e.g. an altitude) as std in their unit."))
        for name, (out, path, _) in pdf_figures(entry, out_dir).items():
            blocks.append(Figure(_rel(shown_path(path), out_dir), f"PDF of {plots.label(name, out.units)} over "
                                 f"time of {entry.label} (paper Figs. 6-7, right) and at the selected times."))
    if len(entries) >= 2:
        labelled = [(e.label, e.outputs) for e in entries] + ([(f"reference {ref.label}", ref.outputs)]
                                                             if ref is not None else [])
        path = plots.plot_band_comparison(labelled, plot_dir / "bands_compared.png",
                                          "Every file and method against the first: mean and 99 % band edges")
        blocks.append(Figure(_rel(path, out_dir), "Mean and 99 % band edges of every file and method minus the "
                             "first's, over time" + (", the reference last." if ref is not None else ".")))
    extra = _extra_statistics(entries)
    rows = []
    for entry in entries:
        for name, out in entry.outputs.items():
            for i in plots.time_indices(out.time, times):
                rows.append([entry.label, name, out.units, out.time[i], out.mean[i], out.std[i], out.band99[0][i],
                             out.band99[1][i], out.cov[i], *(_extra_value(out, key, i) for key, _ in extra)])
    blocks.append(Table("Statistics at the selected times",
                        ["file", "output", "unit", "time [s]", "mean", "std", "band99 lower", "band99 upper",
                         "cov [-]", *(title for _, title in extra)], rows, "tables/statistics_at_times.csv"))
    return Section("Statistics over time", "statistics", "Plots of every file and method; the full statistics over "
                   "time of every file and output are in tables/statistics_<file>_<output>.csv.", blocks)


def pdf_figures(entry: AnalysedFile, out_dir: Path) -> dict[str, tuple]:
    """(output, path, title) of the PDF figure of each output of `entry`, by output name."""
    return {name: (out, out_dir / "plots" / file_name_within(f"pdf_{entry.stem}_{entry.output_files[name]}.png"),
                   f"PDF of {plots.short_label(name)}: {entry.label}") for name, out in entry.outputs.items()}


def draw_pdfs(entries: list[AnalysedFile], times: list[float], out_dir: Path) -> None:
    """The PDF figures of every file (shown by statistics_section): those over time on one figure per file."""
    for entry in entries:
        figures = pdf_figures(entry, out_dir).values()
        plots.plot_pdfs_over_time([f for f in figures if f[0].time.size > 1], times)
        for out, path, title in figures:
            if out.time.size == 1:
                plots.plot_pdf_over_time(out, path, title, times)


def _extra_statistics(entries: list[AnalysedFile]) -> list[tuple[str, str]]:
    """(attribute or quantile key, column title) of the optional statistics some file has: skewness,
    kurtosis, leave-one-out error, quantiles."""
    found = []
    for key, title in (("skewness", "skewness [-]"), ("kurtosis", "kurtosis [-]"), ("loo_error", "LOO error [-]")):
        if any(getattr(o, key, None) is not None for e in entries for o in e.outputs.values()):
            found.append((key, title))
    levels = dict.fromkeys(q for e in entries for o in e.outputs.values()
                           for q in (getattr(o, "quantiles", None) or {}))
    found += [(f"quantile:{q}", f"quantile {q}") for q in levels]
    return found


def _extra_value(out, key: str, i: int):
    if key.startswith("quantile:"):
        values = (getattr(out, "quantiles", None) or {}).get(_quantile_key(out, key.partition(":")[2]))
    else:
        values = getattr(out, key, None)
    if values is None:
        return ""
    values = np.atleast_1d(np.asarray(values, dtype=float))
    return values[i] if values.size > i else values[-1]


def _quantile_key(out, text: str):
    for q in getattr(out, "quantiles", None) or {}:
        if str(q) == text:
            return q
    return text


def _floor_max(out, key: str) -> float | None:
    floor = (out.errors or {}).get(f"{key}_floor")
    if floor is None:
        return None
    floor = np.asarray(floor, dtype=float)
    return float(np.nanmax(floor)) if floor.size and np.isfinite(floor).any() else None


def _below_floor(values: dict[str, tuple[float, float | None]]) -> str:
    """"below reference resolution: eps_m, KLD" naming the errors under the reference's own noise, or ""."""
    below = [name for name, (value, floor) in values.items()
             if floor is not None and np.isfinite(value) and value < floor]
    return f"{BELOW_FLOOR}: {', '.join(below)}" if below else ""


def accuracy_section(entries: list[AnalysedFile], out_dir: Path) -> Section:
    """Eq. 49 errors over time (Figs. 10-19) with the reference's floor, their table, the
    convergence against runs, and the KLD against the runs (Fig. 20)."""
    compared = [e for e in entries if e.has_errors]
    curves = [(e.label, e.outputs) for e in compared]
    blocks = []
    for key, what in (("eps_m", "mean"), ("eps_v", "variance")):
        path = plots.plot_errors(curves, key, out_dir / "plots" / f"{key}.png",
                                 f"Relative error of the {what} against the reference (Eq. 49)")
        blocks.append(Figure(_rel(path, out_dir), f"ε of the {what} over time, one line per file and method "
                                                  "(paper Figs. 10-19); the reference's own floor dashed when "
                                                  "known: errors below it are not resolved by the reference."))
    if len(compared) >= 2:
        points = [(f"{e.stats.method_label} ({e.stats.design_kind})", e.stats.runs,
                   {name: (out.errors["eps_m_summary"]["max"], out.errors["eps_v_summary"]["max"],
                           _floor_max(out, "eps_m"), _floor_max(out, "eps_v"))
                    for name, out in e.outputs.items() if out.errors}) for e in compared]
        path = plots.plot_convergence(points, out_dir / "plots" / "convergence.png",
                                      "Largest error over time against the number of runs")
        blocks.append(Figure(_rel(path, out_dir), "max over time of ε_m and ε_v against the number of runs, one line "
                             "per method and design, log-log; the reference's floor dashed when known."))
        points = [(f"{e.stats.method_label} ({e.stats.design_kind})", e.stats.runs,
                   {name: (out.errors["kld_final"], out.errors.get("kld_floor")) for name, out in e.outputs.items()
                    if out.errors}) for e in compared]
        path = plots.plot_kld_vs_runs(points, out_dir / "plots" / "kld_vs_runs.png",
                                      "Kullback-Leibler divergence from the reference at the final time (Eq. 50)")
        blocks.append(Figure(_rel(path, out_dir), "KLD of each output's final-time PDF from the reference's "
                                                  "against the number of runs, one line per method and design "
                                                  "(paper Fig. 20); the reference's KLD floor dashed: a KLD "
                                                  "below it is the reference's sampling noise."))
    rows = []
    for e in compared:
        for name, out in e.outputs.items():
            if not out.errors:
                continue
            fm, fv = _floor_max(out, "eps_m"), _floor_max(out, "eps_v")
            kld, kld_floor = out.errors["kld_final"], out.errors.get("kld_floor")
            eps_m, eps_v = out.errors["eps_m_summary"]["max"], out.errors["eps_v_summary"]["max"]
            rows.append([e.label, name, eps_m, fm, out.errors["eps_m_summary"]["mean"], eps_v, fv,
                         out.errors["eps_v_summary"]["mean"], kld, kld_floor, e.stats.runs,
                         _below_floor({"eps_m": (eps_m, fm), "eps_v": (eps_v, fv), "KLD": (kld, kld_floor)})])
    notes = dict.fromkeys(str(out.errors["floor_note"]) for e in compared for out in e.outputs.values()
                          if out.errors and out.errors.get("floor_note"))
    blocks.append(Table("Errors against the reference: max and mean over time of ε_m and ε_v, KLD at the final time",
                        ["file", "output", "eps_m max", "eps_m floor", "eps_m mean", "eps_v max", "eps_v floor",
                         "eps_v mean", "KLD final", "KLD floor", "runs", "resolution"], rows, "tables/errors.csv"))
    return Section("Accuracy against the reference", "accuracy",
                   "ε_m = |E − E_ref| / max|E_ref|, ε_v the same for the variance (Eq. 49); "
                   "KLD = ∫ ρ ln(ρ / ρ_ref) (Eq. 50)." + "".join(f" {n}" for n in notes), blocks)


def sensitivity_section(entries: list[AnalysedFile], times: list[float], out_dir: Path) -> Section:
    """Sobol' indices over time (Fig. 21), at the selected times (Table 3), and PCE vs MC (Table 4)."""
    with_sobol = [e for e in entries if e.has_sobol]
    blocks = []
    for entry in with_sobol:
        path = plots.plot_sobol(entry.outputs, out_dir / "plots" / file_name_within(f"sobol_{entry.stem}.png"),
                                f"First-order Sobol' indices: {entry.label}")
        blocks.append(Figure(_rel(path, out_dir), f"First-order Sobol' indices over time of {entry.label} "
                                                  "(paper Fig. 21)" + (", bootstrap 95 % intervals shaded."
                                                                       if entry.pick_freeze else ".")))
        path = plot_sensitivity(entry.outputs, out_dir / "plots" / file_name_within(f"sensitivity_{entry.stem}.png"),
                                f"Partial variances and Sobol' indices: {entry.label}")
        if path is not None:
            blocks.append(Figure(_rel(path, out_dir), f"Per output of {entry.label}: the partial variances "
                                 "S_i(t)·Var(t) stacked, in the output's unit squared, the interactions "
                                 "Var − Σ S_i·Var on top, so the stack's height is the variance; beside them the "
                                 "first-order S_i and total S_Ti indices, greyed where the variance is below "
                                 f"{NEGLIGIBLE:g} of its largest over time (std under 1 % of its largest) or "
                                 "unresolved: there an index is the share of almost nothing."))
    if len(with_sobol) >= 2:
        path = plots.plot_sobol_compared([(e.label, e.outputs) for e in with_sobol],
                                         out_dir / "plots" / "sobol_compared.png",
                                         "First-order Sobol' indices: every file and method")
        blocks.append(Figure(_rel(path, out_dir), "First-order Sobol' indices of every file and method overlaid: "
                             "one colour per parameter, one line style per file and method."))
    parameters = list(dict.fromkeys(p for e in with_sobol for p in e.stats.parameter_names))
    for kind, what in (("sobol_first", "First-order"), ("sobol_total", "Total")):
        rows = [[e.label, name, out.time[i], *(_at(getattr(out, kind), p, i) for p in parameters)]
                for e in with_sobol for name, out in e.outputs.items() for i in plots.time_indices(out.time, times)]
        caption = f"{what} Sobol' indices at the selected times" + (" (paper Table 3)" if kind == "sobol_first" else "")
        page = [[e.label, name, f"{shown_time(out.time, i):g}", *(_shown(out, kind, p, i) for p in parameters)]
                for e in with_sobol for name, out in e.outputs.items() for i in plots.time_indices(out.time, times)]
        blocks.append(Table(caption, ["file", "output", "time [s]", *parameters], rows, f"tables/{kind}.csv",
                            page=(["file", "output", "time [s]", *parameters], page), grouped=True))
    if any(e.pick_freeze for e in with_sobol) and any(not e.pick_freeze for e in with_sobol):
        blocks.append(pce_vs_mc_table(with_sobol, parameters))
    return Section("Sensitivity: Sobol' indices", "sensitivity",
                   "From the PCE (Eq. 53) for the PCE methods; from pick-freeze estimators for a pick_freeze design.",
                   blocks)


def pce_vs_mc_table(entries: list[AnalysedFile], parameters: list[str]) -> Table:
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
    page = [[name, f"{time:g}", parameter, *map(index_text, values)] for name, time, parameter, *values in rows]
    return Table("First-order Sobol' indices at the final time: PCE against Monte Carlo pick-freeze (paper Table 4)",
                 header, rows, "tables/sobol_pce_vs_mc.csv", page=(header, page))


def _shown(out, kind: str, parameter: str, i: int) -> str:
    """An index as the page shows it (index_text), "… (n too small)" where its pick-freeze interval resolves no
    share (analysis.sobol.unresolved)."""
    text = index_text(_at(getattr(out, kind), parameter, i))
    ci = getattr(out, f"{kind}_ci").get(parameter)
    if ci is not None and unresolved(getattr(out, kind)[parameter][i], ci[:, i]):
        text += f" ({N_TOO_SMALL})"
    return text


def _at(indices: dict, parameter: str, i: int):
    """An index for the tables: "unresolved" where the output's variance is not resolved (NaN)."""
    if parameter not in indices:
        return ""
    value = indices[parameter][i]
    return UNRESOLVED if value is None or not np.isfinite(value) else value


def decay_section(entries: list[AnalysedFile], out_dir: Path) -> Section:
    """The PCE coefficients' root-sum-square per total degree over time (convergence of the expansion)."""
    blocks = []
    for e in entries:
        start = e.simulator.get("excitation", {}).get("start_s")
        path = plots.plot_coefficient_decay(e.outputs, out_dir / "plots" / file_name_within(f"coefficient_decay_{e.stem}.png"),
                                            f"PCE coefficients by total degree: {e.label}", start_s=start)
        blocks.append(Figure(_rel(path, out_dir), f"Root-sum-square of the PCE coefficients of each total degree "
                             f"from 1 on over time, {e.label}, from the excitation's start on: a fast decay "
                             "says the order suffices."))
    return Section("Convergence of the expansion", "decay", "Coefficients of degree p small against those of "
                   "degree p-1 mean the expansion has converged at that time.", blocks)


def monte_carlo_section(entries: list[AnalysedFile], out_dir: Path) -> Section:
    """Several Monte Carlo files (the reference too) overlaid, e.g. normal against uniform inputs (Figs. 4-5)."""
    labelled = [(f"{e.label} (inputs {e.inputs})", e.outputs) for e in entries]
    bands = plots.plot_band_comparison(labelled, out_dir / "plots" / "mc_bands.png",
                                       "Monte Carlo files against the first: mean and 99 % band edges")
    pdfs = plots.plot_final_pdfs(labelled, out_dir / "plots" / "mc_pdf_final.png",
                                 "Monte Carlo files: PDF at the final time")
    return Section("Monte Carlo files compared", "monte-carlo",
                   "The Monte Carlo files side by side, e.g. normal against uniform inputs (paper Figs. 4-5).",
                   [Figure(_rel(bands, out_dir), "Mean and 99 % band edges of each Monte Carlo file minus the first's."),
                    Figure(_rel(pdfs, out_dir), "PDF of each output at the final time for each Monte Carlo file.")])
