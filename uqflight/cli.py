"""The `uqflight` command line: simulate, plan, run, report, check, info, demo."""
from __future__ import annotations

import csv
import os
import signal
from collections import Counter
from pathlib import Path
from typing import List, Optional

import numpy as np
import typer

from .methods import METHOD_KINDS
from .simulators.base import FlightError
from .simulators.jsbsim import DEFAULT_OUTPUTS, Excitation, FlightSetup, JSBSimFlight

app = typer.Typer(help="Uncertainty quantification campaigns on a JSBSim flight-dynamics model.",
                  no_args_is_help=True, add_completion=False)


@app.callback()
def cli():
    """Uncertainty quantification campaigns on a JSBSim flight-dynamics model."""


def parse_settings(pairs: list[str]) -> dict[str, float]:
    """`PROPERTY=VALUE` pairs into a dict; a malformed pair is a usage error naming it."""
    settings = {}
    for pair in pairs:
        name, sep, value = pair.partition("=")
        try:
            if not sep or not name:
                raise ValueError
            settings[name.strip()] = float(value)
        except ValueError:
            raise typer.BadParameter(f"expected PROPERTY=NUMBER, got {pair!r}", param_hint="--set")
    return settings


@app.command()
def simulate(
    set_: List[str] = typer.Option([], "--set", help="PROPERTY=VALUE set before the trim, e.g. aero/uq/CL0=0.25 (repeatable)."),
    altitude_ft: float = typer.Option(15000.0, help="Trim altitude [ft]."),
    airspeed_ktas: float = typer.Option(200.0, help="Trim true airspeed [kt]."),
    excitation: str = typer.Option("pulse", help="Elevator excitation: pulse, step, doublet or none."),
    amplitude_deg: float = typer.Option(1.0, help="Excitation amplitude [deg], positive trailing edge down."),
    start_s: float = typer.Option(1.0, help="Excitation start [s]."),
    pulse_duration_s: float = typer.Option(1.0, help="Excitation duration [s] (pulse, doublet)."),
    duration_s: float = typer.Option(50.0, help="Flight time after the trim [s]."),
    output_rate_hz: float = typer.Option(20.0, help="Recording rate [Hz]; divides the 120 Hz integration rate."),
    output: List[str] = typer.Option([], "--output", help="Extra JSBSim property to record (repeatable)."),
    aircraft: str = typer.Option("bacm", help="Aircraft folder under aircraft/."),
    out: Optional[Path] = typer.Option(None, help="Write the time histories to this CSV file."),
    plot: Optional[Path] = typer.Option(None, help="Write a PNG plot of the outputs."),
):
    """Trim one flight in level flight, excite the elevator and record the outputs."""
    settings = parse_settings(set_)
    try:
        setup = FlightSetup(
            aircraft=aircraft, altitude_ft=altitude_ft, airspeed_ktas=airspeed_ktas,
            excitation=Excitation(kind=excitation, amplitude_deg=amplitude_deg, start_s=start_s,
                                  duration_s=pulse_duration_s),
            duration_s=duration_s, output_rate_hz=output_rate_hz,
            outputs=tuple(DEFAULT_OUTPUTS) + tuple(output))
        flight = JSBSimFlight(setup)
        result = flight.fly(settings)
    except (ValueError, KeyError, FileNotFoundError) as exc:
        typer.echo(f"error: {exc.args[0]}", err=True)
        raise typer.Exit(2)
    except FlightError as exc:
        typer.echo(f"flight failed: {exc}", err=True)
        raise typer.Exit(1)
    typer.echo(result.trim.describe())
    for name, values in result.outputs.items():
        typer.echo(f"{name:>12}: start {values[0]:12.4f}  min {values.min():12.4f}  max {values.max():12.4f}")
    if out:
        with open(out, "w", newline="") as fh:
            writer = csv.writer(fh)
            writer.writerow(["time_s", *result.outputs])
            for i, t in enumerate(result.time):
                writer.writerow([f"{t:g}", *(repr(float(v[i])) for v in result.outputs.values())])
        typer.echo(f"wrote {out}")
    if plot:
        from .plots import plot_flight

        plot_flight(result.time, result.outputs, plot,
                    title=f"{aircraft}: {excitation} {amplitude_deg:g} deg at {altitude_ft:g} ft, {airspeed_ktas:g} KTAS")
        typer.echo(f"wrote {plot}")


def _load(path: Path):
    """The validated campaign, or exit 2 with the validation message (no traceback)."""
    from .campaign import CampaignError, load_campaign
    from .simulators.jsbsim_probe import jsbsim_probe

    try:
        return load_campaign(path, probe=jsbsim_probe)
    except CampaignError as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(2)


@app.command()
def plan(campaign: Path = typer.Argument(..., help="Campaign YAML file.")):
    """Validate a campaign and print its design, the number of runs and an estimated time."""
    from .designs import describe

    spec = _load(campaign)
    design = spec.design()
    typer.echo(f"campaign: {spec.name} ({campaign})")
    typer.echo("parameters:")
    for p in spec.parameters:
        typer.echo(f"  {p.name:<10} {p.property:<18} {p.distribution:<16} nominal {p.nominal:<10.6g} "
                   f"interval [{p.lower:.6g}, {p.upper:.6g}]")
    typer.echo(describe(design))
    typer.echo(f"method: {spec.method['kind']} (order {spec.method['order']})")
    runs = len(design.xi)
    typer.echo(f"runs: {runs}")
    if spec.simulator["kind"] == "jsbsim":
        workers = spec.execution["workers"]
        seconds = runs * SECONDS_PER_FLIGHT * spec.simulator.get("duration_s", 50.0) / 50.0 / min(workers, CORES)
        typer.echo(f"estimated time: {seconds:.0f} s with {workers} worker(s) "
                   f"(~{SECONDS_PER_FLIGHT * 1e3:.0f} ms per 50-s flight on this machine)")


SECONDS_PER_FLIGHT = 0.05  # measured by benchmarks/flight_cost.py (trim + 50 s at 120 Hz)
CORES = os.cpu_count() or 1


@app.command()
def run(
    campaign: Path = typer.Argument(..., help="Campaign YAML file."),
    workers: Optional[int] = typer.Option(None, help="Worker processes (default: execution.workers)."),
    out: Optional[Path] = typer.Option(None, help="Results file (default: storage.path)."),
    executor: Optional[str] = typer.Option(None, help="local or dask (default: execution.executor)."),
    scheduler: Optional[str] = typer.Option(None, help="Dask scheduler address, e.g. tcp://host:8786; "
                                                       "without it, a LocalCluster."),
    force: bool = typer.Option(False, help="Overwrite a results file made from another campaign (never a file "
                                           "another run holds, nor one that is not a uqflight results file)."),
):
    """Run a campaign into its HDF5 results file; rerunning resumes where it stopped.

    Exit 0: done; 1: a run-time failure; 2: refused (bad campaign, a file another run holds, a file
    that is not this campaign's, a full disk: the message says what to do); 130 (SIGINT) or 143
    (SIGTERM): stopped cleanly, the finished runs are kept, rerun to resume."""
    from .execution import DiskFull, IncompleteFile, WorkerError, run_campaign
    from .store import CorruptFile

    spec = _load(campaign)
    if executor not in (None, "local", "dask"):
        typer.echo(f"error: --executor: expected local or dask, got {executor!r}", err=True)
        raise typer.Exit(2)
    if workers is not None and workers < 1:
        typer.echo(f"error: --workers: expected an integer >= 1, got {workers}", err=True)
        raise typer.Exit(2)
    resume = f"uqflight run {campaign}" + (f" --out {out}" if out else "")
    previous = _stop_on_sigterm()
    try:
        summary = run_campaign(spec, out=out, workers=workers, executor=executor, scheduler=scheduler,
                               force=force, progress=True)
    except DiskFull as exc:
        typer.echo(f"\nerror: {exc.strerror}", err=True)
        _exit_now(2)
    except CorruptFile as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(2)
    except IncompleteFile as exc:
        typer.echo(f"error: {exc}", err=True)
        _exit_now(1)
    except (FileExistsError, ValueError, WorkerError) as exc:
        typer.echo(f"error: {campaign}: {exc}", err=True)
        raise typer.Exit(2)
    except KeyboardInterrupt as exc:
        code = 143 if isinstance(exc, Terminated) else 130
        typer.echo(f"\n{'terminated' if code == 143 else 'interrupted'}: the finished runs are stored; "
                   f"rerun `{resume}` to resume", err=True)
        raise typer.Exit(code)
    finally:
        signal.signal(signal.SIGTERM, previous)
    typer.echo(summary.describe())


def _exit_now(code: int):
    """Exit without the interpreter's teardown: after HDF5 met a full disk, its library may crash
    (exit 139) while freeing the failed file's objects at exit. The file is closed and the lock
    released by then; only the exit code and the message matter."""
    import sys

    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


class Terminated(KeyboardInterrupt):
    """SIGTERM, handled like SIGINT: a clean stop."""


def _stop_on_sigterm():
    def stop(signum, frame):
        raise Terminated()

    return signal.signal(signal.SIGTERM, stop)


@app.command()
def info(results: Path = typer.Argument(..., help="Results file (.h5).")):
    """Show a results file's campaign, design, done and failed runs, storage and versions."""
    from .store import CorruptFile, ResultStore, Status, read_error

    try:
        store = ResultStore.open(results)
    except CorruptFile as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(2)
    except (OSError, ValueError) as exc:
        typer.echo(f"error: {results}: {read_error(exc)}", err=True)
        raise typer.Exit(2)
    with store:
        try:
            _describe_results(results, store, Status)
        except OSError as exc:
            typer.echo(f"error: {results}: {read_error(exc)}", err=True)
            raise typer.Exit(2)


def _describe_results(results, store, Status) -> None:
    status = store.status
    attrs = store.attrs
    typer.echo(f"file: {results}")
    typer.echo(f"campaign: {attrs.get('campaign_name', '?')} (sha256 {store.campaign_hash[:12]})")
    typer.echo(f"design: {attrs.get('design_kind', '?')} {attrs.get('design_info', '')}")
    typer.echo(f"parameters: {', '.join(store.parameter_names)}")
    typer.echo(f"outputs: {', '.join(store.output_names)} ({store.time.size} times, "
               f"{store.time[0]:g} to {store.time[-1]:g} s)")
    counts = {s.name.lower(): int(np.sum(status == s)) for s in Status}
    typer.echo("runs: " + ", ".join(f"{v} {k}" for k, v in counts.items()) + f" (of {status.size})")
    reasons = Counter(r for r, s in zip(store.reasons, status) if s > 0)
    for reason, n in reasons.most_common(5):
        typer.echo(f"  failed ({n}): {reason}")
    problems = store.verify()  # reads every checksummed chunk: a flipped byte is reported
    for problem in problems:
        typer.echo(f"  problem: {problem}")
    typer.echo(f"storage: {store.storage_description}")
    typer.echo(f"versions: {attrs.get('versions', '?')}")
    if "aircraft_hash" in attrs:
        typer.echo(f"aircraft sha256: {attrs['aircraft_hash']}")
    if problems:
        raise typer.Exit(2)


@app.command()
def report(
    results: List[Path] = typer.Argument(..., help="Results files (.h5). The first is the one summary.json, "
                                                   "the baseline and the single-file plots describe."),
    out: Path = typer.Option(..., help="Report directory (created if missing)."),
    reference: Optional[Path] = typer.Option(None, help="Monte Carlo results file: the errors ε_m, ε_v (Eq. 49) "
                                                        "and KLD (Eq. 50) of every file are taken against it."),
    times: str = typer.Option("10,25,end", help="Comma-separated times in seconds for the tables at selected times "
                                                "(the nearest recorded times; 'end' is the final time)."),
    write_baseline: Optional[Path] = typer.Option(None, help="Also write the first file's statistics to this "
                                                             "JSON file, the baseline of `uqflight check`."),
    method: Optional[str] = typer.Option(None, help="Method for every file instead of its campaign's: integration, "
                                                    "pseudo_galerkin, interpolation, regression, least_squares, "
                                                    "monte_carlo (the runs of one grid serve every method)."),
    order: Optional[int] = typer.Option(None, help="Polynomial order with --method (default: the campaign's)."),
):
    """Statistics, tables, plots and a report page of one or more results files.

    Several files are compared side by side (labelled campaign: method, runs). OUT gets:
    summary.json (the first file; schema in DESIGN.md), summaries/<stem>.json (every file, when
    several), tables/*.csv (statistics over time per file and output, statistics and Sobol' indices
    at the selected times, errors against the reference, PCE vs Monte Carlo Sobol' indices when a
    pick_freeze file is given), plots/*.png, report.html (self-contained, plots embedded) and
    report.md (linking plots/).
    """
    from .check import BadInput
    from .report import write_report

    try:
        selected = [float("inf") if t.strip() == "end" else float(t) for t in times.split(",")]
    except ValueError:
        raise typer.BadParameter(f"expected comma-separated seconds or 'end', got {times!r}", param_hint="--times")
    override = {key: value for key, value in (("kind", method), ("order", order)) if value is not None}
    if method is not None and method not in METHOD_KINDS:
        raise typer.BadParameter(f"expected one of {', '.join(METHOD_KINDS)}, got {method!r}", param_hint="--method")
    if order is not None and order < 0:
        raise typer.BadParameter(f"expected an integer >= 0, got {order}", param_hint="--order")
    try:
        written = write_report(results, out, reference=reference, times=selected, baseline=write_baseline,
                               method=override or None)
    except BadInput as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(2)
    except OSError as exc:
        typer.echo(f"error: cannot write the report: {exc}", err=True)
        raise typer.Exit(2)
    typer.echo(f"wrote {len(written)} files to {out}: open {out / 'report.html'}")
    if write_baseline:
        typer.echo(f"wrote baseline {write_baseline}")


@app.command()
def check(
    results: Path = typer.Argument(..., help="Results file (.h5) to recompute the statistics of."),
    baseline: Path = typer.Option(..., help="Baseline JSON from `uqflight report ... --write-baseline`."),
    rtol: float = typer.Option(1e-6, help="Relative tolerance."),
    atol: float = typer.Option(1e-9, help="Absolute tolerance, in each statistic's own unit."),
):
    """Recompute a results file's statistics and compare them with a baseline.

    Compares mean, variance, 99 % band and Sobol' indices per output and time: a value drifts when
    |value - baseline| > atol + rtol * |baseline|. The defaults (rtol 1e-6, atol 1e-9) allow for
    floating-point noise only: the statistics are deterministic (seeded). Exit 0: no drift; 1: drift
    (the worst values per statistic are listed); 2: bad input (missing or malformed baseline, other
    outputs or time grid, unreadable results file).
    """
    from .check import BadInput, compare, drift_table, load_baseline, read_statistics

    if rtol < 0 or atol < 0:
        typer.echo("error: --rtol and --atol must be >= 0", err=True)
        raise typer.Exit(2)
    try:
        expected = load_baseline(baseline)
        stats, attrs = read_statistics(results)
        comparison = compare(stats, expected, rtol, atol)
    except BadInput as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(2)
    if expected.get("campaign_hash") and expected["campaign_hash"] != attrs.get("campaign_hash"):
        typer.echo(f"note: {results} comes from another campaign (sha256 {str(attrs.get('campaign_hash'))[:12]}) "
                   f"than the baseline ({str(expected['campaign_hash'])[:12]})")
    if comparison.drifts:
        typer.echo(f"drift: {len(comparison.drifts)} of {comparison.compared} values outside "
                   f"rtol={rtol:g}, atol={atol:g}")
        typer.echo(drift_table(comparison))
        raise typer.Exit(1)
    typer.echo(f"no drift: {comparison.compared} values within rtol={rtol:g}/atol={atol:g}")
