"""The `uqflight` command line: simulate, plan, run, report, check, info, demo."""
from __future__ import annotations

import csv
import os
from collections import Counter
from pathlib import Path
from typing import List, Optional

import numpy as np
import typer

from .simulators.jsbsim import DEFAULT_OUTPUTS, Excitation, FlightError, FlightSetup, JSBSimFlight

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
    from .campaign import CampaignError, jsbsim_probe, load_campaign

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
    force: bool = typer.Option(False, help="Overwrite a results file made from another campaign."),
):
    """Run a campaign into its HDF5 results file; rerunning resumes where it stopped."""
    from .execution import Progress, run_campaign

    spec = _load(campaign)
    if executor not in (None, "local", "dask"):
        typer.echo(f"error: --executor: expected local or dask, got {executor!r}", err=True)
        raise typer.Exit(2)
    if workers is not None and workers < 1:
        typer.echo(f"error: --workers: expected an integer >= 1, got {workers}", err=True)
        raise typer.Exit(2)
    total = len(spec.design().xi)
    try:
        summary = run_campaign(spec, out=out, workers=workers, executor=executor, scheduler=scheduler,
                               force=force, progress=Progress(total))
    except (FileExistsError, ValueError) as exc:
        typer.echo(f"error: {campaign}: {exc}", err=True)
        raise typer.Exit(2)
    typer.echo(summary.describe())


@app.command()
def info(results: Path = typer.Argument(..., help="Results file (.h5).")):
    """Show a results file's campaign, design, done and failed runs, storage and versions."""
    from .store import ResultStore, Status

    try:
        store = ResultStore.open(results)
    except (OSError, ValueError) as exc:
        typer.echo(f"error: {results}: {exc}", err=True)
        raise typer.Exit(2)
    with store:
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
        typer.echo(f"storage: {store.storage_description}")
        typer.echo(f"versions: {attrs.get('versions', '?')}")
        if "aircraft_hash" in attrs:
            typer.echo(f"aircraft sha256: {attrs['aircraft_hash']}")
