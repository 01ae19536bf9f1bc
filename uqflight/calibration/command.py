"""The `uqflight calibrate` command; `register(app)` adds it to a typer app (cli/commands.py wires it in)."""
from __future__ import annotations

import os
import signal
import sys
from pathlib import Path
from typing import List, Optional

import typer

from ..cli.arguments import RefusingGroup, check_campaign_file, check_output, check_results_file
from ..text import Refusal
from ..text.console import echo, one_line, quoted_name
from ..running.progress import Progress

EXIT_NOT_CONVERGED = 3
EXIT_INTERRUPTED = 130


def foreign_outputs(out: Path) -> list[str]:
    """The files in `out` that a calibration would replace (or remove) when `out` is not an earlier
    calibration's folder (one holding a posterior.h5 that a calibration wrote): a user's summary.json or
    report.html there is never overwritten."""
    from .outputs import OUTPUT_FILES, is_posterior_file

    if not out.is_dir() or is_posterior_file(out / "posterior.h5"):
        return []
    return [name for name in (*OUTPUT_FILES, "report.html") if (out / name).exists() or (out / name).is_symlink()]


def calibrate_command(
    results: Path = typer.Argument(..., metavar="RESULTS", help="Results file (.h5) of the campaign to calibrate: its runs give the "
                                             "surrogate, its campaign the prior and the simulator."),
    data: Path = typer.Option(..., help="Flight data CSV as `uqflight simulate --out` writes it: time_s and "
                                        "output columns (an empty cell is a missing value)."),
    out: Path = typer.Option(..., help="Output directory (created if missing)."),
    output: List[str] = typer.Option([], "--output", help="Output to calibrate on (repeatable; default: every "
                                                          "data column that is an output of the campaign)."),
    noise: List[str] = typer.Option([], "--noise", help="OUTPUT=SIGMA: known noise std in the output's unit "
                                                        "(repeatable); other outputs' noise is inferred."),
    seed: int = typer.Option(0, help="Seeds the optimiser starts, the walkers and the predictive draws."),
    walkers: Optional[int] = typer.Option(None, help="Ensemble walkers (even, >= 2 x dimensions; default "
                                                     "max(32, 2 x dimensions + 2))."),
    steps: Optional[int] = typer.Option(None, help="Steps per walker, exactly; the first half is burn-in. Default: "
                                                   "until the chain has converged (checked every 250 steps from "
                                                   "1000 on; two checks in a row), at most 6000."),
    method: Optional[str] = typer.Option(None, metavar="KIND[:ORDER]", help="Surrogate method (default: the "
                                         "results file's), as report and surrogate export take it: "
                                         "pseudo_galerkin, least_squares:3, regression, ..."),
    order: Optional[int] = typer.Option(None, help="Total degree of the surrogate PCE (default: the file's)."),
    campaign: Optional[Path] = typer.Option(None, help="The campaign file, when the one stored in the results "
                                                       "file cannot be rebuilt (a python model file elsewhere)."),
    predictive_draws: int = typer.Option(50, help="Posterior draws flown with the real simulator for the "
                                                  "posterior predictive band."),
    truth: List[str] = typer.Option([], "--truth", metavar="NAME=VALUE", help="A parameter's known true value "
                                    "(physical units; repeatable): marked in the plots and the page, and "
                                    "summary.json says whether the 95 % interval holds it."),
):
    """Bayesian calibration of the campaign's parameters on flight data (PCE surrogate + emcee).

    Writes OUT/posterior.h5 (draws in standard and physical variables), OUT/summary.json (prior and posterior mean, std, 95 % interval per parameter, correlations, diagnostics; strict JSON), OUT/calibrated.yaml (the campaign with the posterior marginals), OUT/plots/ (corner, marginals, posterior predictive from real simulator runs) and OUT/report.html (all of it on one self-contained page).

    Exit 0: done; 2: bad input (data, options, results file, data times outside the surrogate's); 3: the chain did not converge (nothing written; the message says what to change); 130: interrupted (Ctrl-C).
    """  # noqa: E501
    from .likelihood import parse_noise

    check_results_file(results)
    if campaign is not None:
        check_campaign_file(campaign)
    check_output(out, "--out", folder=True, create=True)
    overwritten = foreign_outputs(out)
    if overwritten:
        raise Refusal(f"--out {out}: holds {', '.join(overwritten)}, which a calibration would replace and which "
                      "an earlier calibration did not write (no posterior.h5 of one there); choose another --out, or "
                      "move them away")
    method, order = _method(method, order)
    if predictive_draws < 1:
        raise Refusal(f"--predictive-draws: expected an integer >= 1, got {predictive_draws}")
    # the options parsed before the sampler's and the surrogate's modules are imported: a refusal is immediate
    sigmas = parse_noise(list(noise))
    known = _truth(truth)
    from ..running.runner import WorkerError
    from .run import NotConverged, calibrate

    streams, previous = (sys.stdout, sys.stderr), signal.signal(signal.SIGINT, _interrupted)
    try:
        with Progress(0, label="calibrate") as progress:
            result = calibrate(results, data, out, outputs=list(output) or None, noise=sigmas, seed=seed,
                               walkers=walkers, steps=steps, method=method, order=order, campaign=campaign,
                               predictive_draws=predictive_draws, truth=known, progress=progress)
    except KeyboardInterrupt:
        sys.stdout, sys.stderr = streams
        echo(f"\ninterrupted: no calibration written to {out}", err=True)
        raise typer.Exit(EXIT_INTERRUPTED)
    except WorkerError as exc:  # no simulator for the predictive runs (the model cannot be built or hangs)
        raise Refusal(f"{results}: the posterior predictive runs cannot be flown: {exc}") from exc
    except NotConverged as exc:
        echo("not converged: no posterior is reported.", err=True)
        for problem in exc.diagnostics["problems"]:
            echo(f"  - {problem}", err=True)
        if _page[0] is not None and (out / "report.html").is_file():
            (out / "report.html").unlink()  # the page of an earlier run would look like this run's
            exc.removed.append("report.html")
        if exc.removed:
            echo(f"  (removed the outputs of an earlier run from {out}: {', '.join(exc.removed)})", err=True)
        raise typer.Exit(EXIT_NOT_CONVERGED)
    finally:
        signal.signal(signal.SIGINT, previous)
    summary = result.summary
    diag = summary["diagnostics"]
    echo(f"surrogate: {summary['surrogate']['kind']} order {summary['surrogate']['order']} from "
         f"{summary['surrogate']['runs']} runs; {diag['walkers']} walkers x {diag['steps']} steps, "
         f"acceptance {diag['acceptance_fraction']['mean']:.2f}, {diag['steps_per_tau']:.0f} tau kept, "
         f"max split-R-hat {max(diag['split_rhat'].values()):.3f}")
    echo(f"{'parameter':<10} {'prior mean':>12} {'prior std':>11} {'post mean':>12} {'post std':>11} "
         f"{'narrowing':>9}  95 % interval")
    for name, p in summary["parameters"].items():
        narrowing = p["narrowing"]
        echo(f"{quoted_name(name):<10} {p['prior']['mean']:12.6g} {p['prior']['std']:11.4g} {p['posterior']['mean']:12.6g} "
             f"{p['posterior']['std']:11.4g} {narrowing if narrowing is not None else float('nan'):9.2f}  "
             f"[{p['posterior']['ci95'][0]:.6g}, {p['posterior']['ci95'][1]:.6g}]")
    for name, n in summary["noise"].items():
        if n["inferred"]:
            echo(f"noise {quoted_name(name)}: sigma {n['inferred']['mean']:.4g} (inferred)")
    pred = summary["predictive"]
    cover = ", ".join(f"{quoted_name(k)} {v:.0%}" if v is not None else f"{quoted_name(k)} -" for k, v in pred["coverage95"].items())
    echo(f"posterior predictive ({pred['draws']} simulator runs, {pred['failed']} failed): data inside the "
         f"95 % band: {cover}")
    written = list(result.written)
    if _page[0] is not None:
        written.append(_page[0](out).name)
    echo(f"wrote {', '.join(written)} to {out} ({summary['seconds']['total']:.1f} s)")
    refused = summary.get("calibrated_campaign", {}).get("refused")
    if refused:
        echo(f"warning: calibrated.yaml not written: {one_line(refused)}; the calibration is kept (posterior.h5, "
             "summary.json, the plots): write the campaign from summary.json's posterior", err=True)


def _truth(items: list[str]) -> dict[str, float] | None:
    """--truth NAME=VALUE items as {name: value}; a Refusal for a malformed or repeated item (`calibrate` refuses
    a name that is no parameter of the results file)."""
    from .likelihood import parse_pairs

    return parse_pairs(items, "--truth", "NAME=VALUE with a finite VALUE") if items else None


def _method(text: str | None, order: int | None) -> tuple[str | None, int | None]:
    """--method KIND[:ORDER] (the report's parser) and --order into (kind, order); a Refusal naming the option."""
    from ..methods.parsing import checked_order, parse_methods

    try:
        if text is None:
            return None, None if order is None else checked_order(order)
        parsed = parse_methods([text], order)[0]
    except ValueError as exc:
        raise Refusal(f"{'--method' if text else '--order'}: {exc}") from exc
    if order is not None and parsed.order != order:
        raise Refusal(f"--method {text} and --order {order} give two orders: give one")
    return parsed.kind, parsed.order


def _interrupted(signum, frame):
    """Ctrl-C: stop with one line. emcee prints every exception raised in the log-probability (a
    KeyboardInterrupt too) with its arguments and a traceback before re-raising it: what is printed
    from here on goes to /dev/null, until the command restores the streams to say it stopped."""
    sys.stdout = sys.stderr = open(os.devnull, "w")
    raise KeyboardInterrupt


_page = [None]  # writes OUT/report.html after a calibration (`register`'s page)


def register(app: typer.Typer, page=None) -> None:
    """Add the `calibrate` command to `app`, whose group becomes a `RefusingGroup` (the command's refusals
    exit 2); `page(out) -> Path`, when given, writes the calibration's page into OUT
    (report.calibration_page, a layer above this one); without it, an earlier one stays."""
    if page is not None:
        _page[0] = page
    app.info.cls = RefusingGroup
    app.command("calibrate")(calibrate_command)
