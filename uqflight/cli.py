"""The `uqflight` command line: simulate, plan, run, report, check, info, demo."""
from __future__ import annotations

import csv
from pathlib import Path
from typing import List, Optional

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
