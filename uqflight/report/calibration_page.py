"""The page of a calibration: OUT/report.html from OUT/summary.json and OUT/plots/, self-contained
like the report's (report.render), written by `uqflight calibrate` after its outputs."""
from __future__ import annotations

import json
from pathlib import Path

from ..text.labels import parameter_unit
from .render import render_html
from .blocks import Figure, Section, Table

PAGE = "report.html"
FIGURES = (("plots/corner.png", "Posterior pairs and marginals in physical values; posterior mean dashed and +, "
                                "the truth red when given (--truth)."),
           ("plots/marginals.png", "Prior (grey) against posterior (blue) of each parameter; posterior mean dashed, "
                                   "the truth red when given."),
           ("plots/predictive.png", "The data, the real simulator flown at posterior draws and the 95 % predictive "
                                    "band (runs + noise); right: the same about the runs' median."))


def write_calibration_page(out: Path) -> Path:
    """Write OUT/report.html for the calibration in OUT; returns its path."""
    out = Path(out)
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    sections = [parameters_section(summary), noise_section(summary), diagnostics_section(summary),
                Section("Plots", "plots", "Written to plots/ beside this page.",
                        [Figure(file, caption) for file, caption in FIGURES if (out / file).is_file()])]
    page = out / PAGE
    title = f"uqflight calibration: {summary.get('campaign', '')} on {Path(str(summary.get('data', ''))).name}"
    page.write_text(render_html(title, sections, out), encoding="utf-8")
    return page


def parameters_section(summary: dict) -> Section:
    truth = any("truth" in p for p in summary["parameters"].values())
    header = ["parameter", "property", "unit", "prior mean", "prior std", "posterior mean", "posterior std",
              "95 % lower", "95 % upper", "narrowing"] + (["truth", "truth in 95 %"] if truth else [])
    rows = []
    for name, p in summary["parameters"].items():
        post = p["posterior"]
        row = [name, p["property"], parameter_unit(p["property"]) or "?", p["prior"]["mean"], p["prior"]["std"],
               post["mean"], post["std"], post["ci95"][0], post["ci95"][1], _value(p.get("narrowing"))]
        if truth:
            row += [_value(p.get("truth")), {True: "yes", False: "NO"}.get(p.get("truth_in_ci95"), "")]
        rows.append(row)
    surrogate = summary.get("surrogate", {})
    text = (f"Surrogate: {surrogate.get('kind', '?')} order {surrogate.get('order', '?')} from "
            f"{surrogate.get('runs', '?')} runs of {summary.get('results', '')}; data {summary.get('data', '')}; "
            f"seed {summary.get('seed', '')}. Narrowing = prior std / posterior std.")
    return Section("Parameters: prior and posterior", "parameters", text,
                   [Table("Prior and posterior of each parameter (physical values)", header, rows, "summary.json")])


def noise_section(summary: dict) -> Section:
    coverage = (summary.get("predictive") or {}).get("coverage95") or {}
    rows = []
    for name, n in summary["noise"].items():
        inferred = n.get("inferred") or {}
        rows.append([name, _value(n.get("given")), _value(inferred.get("mean")), _value(n.get("surrogate_error_rms")),
                     n.get("data_points", ""), _value(coverage.get(name))])
    return Section("Noise and posterior predictive", "noise",
                   "Noise std per output in its unit, given (--noise) or inferred; the share of the data inside "
                   "the 95 % posterior predictive band.",
                   [Table("Noise, surrogate error and predictive coverage per output",
                          ["output", "noise given", "noise inferred (mean)", "surrogate error RMS", "data points",
                           "data inside 95 % band"], rows, "summary.json")])


def diagnostics_section(summary: dict) -> Section:
    d = summary["diagnostics"]
    tau = d.get("autocorrelation_time") or {}
    rhat = d.get("split_rhat") or {}
    rows = [[name, _value(tau.get(name)), _value(rhat.get(name))] for name in dict.fromkeys([*tau, *rhat])]
    acceptance = (d.get("acceptance_fraction") or {}).get("mean")
    text = (f"{d.get('walkers', '?')} walkers × {d.get('steps', '?')} steps (first half burn-in); mean acceptance "
            f"{_format(acceptance)}; kept chain {_format(d.get('steps_per_tau'))} autocorrelation times long.")
    return Section("Sampler diagnostics", "diagnostics", text,
                   [Table("Integrated autocorrelation time τ and split-R̂ per sampled variable",
                          ["variable", "τ [steps]", "split-R̂"], rows, "summary.json")])


def _value(value):
    return "" if value is None else value


def _format(value) -> str:
    return "?" if value is None else f"{value:.3g}"
