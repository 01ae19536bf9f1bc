"""The `uqflight` command line: simulate, plan, run, report, check, info, demo."""
from __future__ import annotations

import os
import signal
import threading


def _interrupted_while_starting(signum, frame):
    """Ctrl-C while the command line is still importing (NumPy, typer, ...): one line and exit 130, as an
    interrupted command says, not a KeyboardInterrupt traceback from inside an import. Nothing has
    been done yet, so nothing is left to clean up."""
    os.write(2, b"\ninterrupted: uqflight was starting, nothing was done\n")
    os._exit(130)


# only where Python's own Ctrl-C handler is in place (an ignored SIGINT stays ignored, a program's own
# handler stays its own), until the module is imported; the commands handle Ctrl-C from then on
_STARTING = (threading.current_thread() is threading.main_thread()
             and signal.getsignal(signal.SIGINT) is signal.default_int_handler)
if _STARTING:
    signal.signal(signal.SIGINT, _interrupted_while_starting)

import csv  # noqa: E402 (the imports below are what Ctrl-C may interrupt)
import io
import json
from collections import Counter
from pathlib import Path
from typing import List, Optional

import numpy as np
import typer

from .arguments import RefusingGroup, check_campaign_file, check_output, check_results_file
from ..calibration.command import register as register_calibrate
from ..text import Refusal
from ..text.console import EXIT_BAD_INPUT, echo, listed, one_line, quoted_name
from ..running import stopping
from .fast_exit import exit_fast
from ..running.progress import Progress

from ..methods import METHOD_KINDS, MethodSpec
from ..simulators.base import FlightError
from ..simulators.aircraft import default_condition
from ..simulators.jsbsim import DEFAULT_OUTPUTS
from ..simulators.scenarios.level_flight import Excitation, FlightSetup, JSBSimFlight

CONTEXT = {"help_option_names": ["-h", "--help"]}
# simulate's CSV and plot, beside the campaigns' results (results/ is in .gitignore)
DEFAULT_CSV, DEFAULT_PLOT = Path("results/flight.csv"), Path("results/flight.png")
# rich_markup_mode=None: help text is shown as written, so units such as [ft], [kt], [deg], [s] are
# not swallowed as rich markup
app = typer.Typer(help="Uncertainty quantification campaigns on a JSBSim flight-dynamics model.", cls=RefusingGroup,
                  no_args_is_help=True, add_completion=False, context_settings=CONTEXT, rich_markup_mode=None)
surrogate_app = typer.Typer(help="The PCE surrogate of a results file: export it as JSON.", no_args_is_help=True,
                            context_settings=CONTEXT, rich_markup_mode=None)
app.add_typer(surrogate_app, name="surrogate")


def main() -> None:
    """The `uqflight` console script: `app`, then an exit without the interpreter's teardown (uqflight.cli.fast_exit)."""
    try:
        app()
    except SystemExit as done:
        if done.code == 130 and isinstance(getattr(done.__context__, "__cause__", None), KeyboardInterrupt):
            echo("\ninterrupted", err=True)  # a Ctrl-C no command caught (typer exits 130 silently): say so
        exit_fast(done.code)
    exit_fast(0)


def _calibration_page(out: Path) -> Path:
    from ..report.calibration_page import write_calibration_page

    return write_calibration_page(out)


register_calibrate(app, page=_calibration_page)


def _version(value: bool):
    if value:
        from .. import __version__

        echo(f"uqflight {__version__}")
        raise typer.Exit(0)


@app.callback()
def cli(version: bool = typer.Option(False, "--version", callback=_version, is_eager=True,
                                     help="Print the version and exit.")):
    """Uncertainty quantification campaigns on a JSBSim flight-dynamics model."""


def parse_settings(pairs: list[str], option: str = "--set") -> dict[str, float]:
    """`PROPERTY=VALUE` pairs into a dict; a malformed pair is a usage error naming it and `option`."""
    settings = {}
    for pair in pairs:
        name, sep, value = pair.partition("=")
        try:
            if not sep or not name:
                raise ValueError
            settings[name.strip()] = float(value)
        except ValueError:
            raise typer.BadParameter(f"expected NAME=NUMBER, got {pair!r}", param_hint=option)
    return settings


@app.command()
def simulate(
    set_: List[str] = typer.Option([], "--set", metavar="PROPERTY=VALUE", help="PROPERTY=VALUE set before the trim, e.g. aero/uq/CL0=0.25 (repeatable)."),
    scale: List[str] = typer.Option([], "--scale", metavar="FUNCTION=FACTOR", help="FUNCTION=FACTOR: multiply an aerodynamic function of the "
                                                        "aircraft, e.g. aero/coefficient/CLwbh=1.1 (repeatable)."),
    offset: List[str] = typer.Option([], "--offset", metavar="FUNCTION=DELTA", help="FUNCTION=DELTA: add a coefficient increment to an aerodynamic "
                                                          "function (DELTA times its reference factor qbar·S, qbar·S·c̄ or qbar·S·b; repeatable)."),
    offset_value: List[str] = typer.Option([], "--offset-value", metavar="FUNCTION=VALUE", help="FUNCTION=VALUE: add VALUE in the "
                                                          "function's own unit (lbf, lbf·ft, a helper's own; repeatable)."),
    altitude_ft: Optional[float] = typer.Option(None, help="Trim altitude [ft] (default: the aircraft's, 15000 for bacm)."),
    airspeed_ktas: Optional[float] = typer.Option(None, help="Trim true airspeed [kt] (default: the aircraft's, 200 for bacm)."),
    excitation: str = typer.Option("pulse", help="Elevator excitation: pulse, step, doublet or none."),
    amplitude_deg: float = typer.Option(1.0, help="Excitation amplitude [deg], positive trailing edge down."),
    start_s: float = typer.Option(1.0, help="Excitation start [s]."),
    pulse_duration_s: float = typer.Option(1.0, help="Excitation duration [s] (pulse, doublet)."),
    duration_s: float = typer.Option(50.0, help="Flight time after the trim [s]."),
    output_rate_hz: float = typer.Option(20.0, help="Recording rate [Hz]; divides the 120 Hz integration rate."),
    output: List[str] = typer.Option([], "--output", metavar="PROPERTY", help="Extra JSBSim property to record (repeatable)."),
    aircraft: str = typer.Option("bacm", help="Aircraft: a name in the project's aircraft/ or JSBSim's, or a "
                                              "path to an aircraft folder (`uqflight aircraft --list`)."),
    noise: List[str] = typer.Option([], "--noise", metavar="OUTPUT=SIGMA", help="OUTPUT=SIGMA: add Gaussian "
                                    "noise of std SIGMA (in the output's unit) to the written data, e.g. "
                                    "alpha_deg=0.05 (repeatable; seeded by --seed)."),
    seed: int = typer.Option(0, help="Seeds the --noise draws: the same seed gives the same data."),
    out: Path = typer.Option(DEFAULT_CSV, help="Write the time histories to this CSV file (the default's folder "
                                               "is made when missing)."),
    plot: Path = typer.Option(DEFAULT_PLOT, help="Write a PNG plot of the outputs (the default's folder is made "
                                                 "when missing)."),
    no_files: bool = typer.Option(False, "--no-files", help="Write neither the CSV nor the plot: print only."),
):
    """Trim one flight in level flight, excite the elevator and record the outputs (by default into
    results/flight.csv and results/flight.png, from the working directory)."""
    from ..simulators.noise import add_noise, check_noise

    settings = parse_settings(set_)
    sigmas = parse_settings(noise, "--noise")
    recorded = tuple(DEFAULT_OUTPUTS) + tuple(output)
    check_noise(recorded, sigmas, seed)
    files = [] if no_files else [(out, "--out"), (plot, "--plot")]
    for path, option in files:
        check_output(path, option, create=path in (DEFAULT_CSV, DEFAULT_PLOT))
    try:
        located = _prepared(aircraft, scale, offset, offset_value)
        settings.update(located.settings)
        condition = default_condition(located.name)
        altitude_ft = condition["altitude_ft"] if altitude_ft is None else altitude_ft
        airspeed_ktas = condition["airspeed_ktas"] if airspeed_ktas is None else airspeed_ktas
        setup = FlightSetup(
            aircraft=located.name, root=located.root, altitude_ft=altitude_ft, airspeed_ktas=airspeed_ktas,
            excitation=Excitation(kind=excitation, amplitude_deg=amplitude_deg, start_s=start_s,
                                  duration_s=pulse_duration_s),
            duration_s=duration_s, output_rate_hz=output_rate_hz,
            outputs=recorded)
        flight = JSBSimFlight(setup)
        result = flight.fly(settings)
        outputs = add_noise(result.outputs, sigmas, seed)
    except FlightError as exc:
        echo(f"flight failed: {exc}", err=True)
        raise typer.Exit(1)
    except (ValueError, KeyError, FileNotFoundError, RuntimeError) as exc:  # bad input; an aircraft JSBSim refuses
        raise Refusal(exc.args[0]) from exc
    echo(result.trim.describe())
    if flight.surface_warning:
        echo(f"warning: {flight.surface_warning}", err=True)
    for line in _offset_lines(located, flight):
        echo(line)
    if sigmas:
        echo(f"noise added (seed {seed}): " + ", ".join(f"{name} sigma {sigma:g}" for name, sigma in sigmas.items()))
    for name, values in outputs.items():
        echo(f"{name:>12}: start {values[0]:12.4f}  min {values.min():12.4f}  max {values.max():12.4f}")
    for path, _ in files:
        path.parent.mkdir(parents=True, exist_ok=True)  # results/ for the defaults; a given folder exists
    if files:
        with open(out, "w", newline="") as fh:
            writer = csv.writer(fh)
            writer.writerow(["time_s", *outputs])
            for i, t in enumerate(result.time):
                writer.writerow([f"{t:g}", *(repr(float(v[i])) for v in outputs.values())])
        echo(f"wrote {out}")
        from ..report.plots import plot_flight

        plot_flight(result.time, outputs, plot,
                    title=f"{setup.aircraft}: {excitation} {amplitude_deg:g} deg at {altitude_ft:g} ft, {airspeed_ktas:g} KTAS"
                    + (" (noise added)" if sigmas else ""))
        echo(f"wrote {plot}")


def _offset_lines(located, flight) -> list[str]:
    """What each --offset added at the trimmed state: ΔC, the reference factor and their product."""
    from ..simulators.aero_factors import aero_factors

    refs = aero_factors(located.files.main)
    lines = []
    for function, kind, prop, value in located.pairs:
        if kind == "offset":
            ref = refs[function]
            factor = float(np.prod([flight.property_value(p) for p in ref.factor]))
            lines.append(f"offset {function}: {value:g} x {ref.symbol} = {value:g} x {factor:.6g} = "
                         f"{value * factor:.6g} {ref.unit} at the trim")
    return lines


def _prepared(aircraft: str, scale: list[str], offset: list[str], offset_value: list[str] = ()):
    """The aircraft of `simulate`/`aircraft`, patched for --scale/--offset/--offset-value; `.settings`
    holds the patch properties' values, `.pairs` (function, kind, property, value). Raises a Refusal (a
    bad function, an aircraft not found, an aircraft file that is not XML)."""
    from ..simulators.base import SimulatorSettingError
    from ..simulators.patch import PreparedAircraft, patch_property, resolve_function

    plain = PreparedAircraft(aircraft, Path.cwd())
    pairs = []
    for kind, items in (("scale", scale), ("offset", offset), ("offset_value", offset_value)):
        option = "--" + kind.replace("_", "-")
        for name, value in parse_settings(items, option).items():
            try:
                function = resolve_function(name, plain.functions)
                pairs.append((function, kind, patch_property(function, kind, plain.functions), value))
            except SimulatorSettingError as exc:
                raise Refusal(f"{option} {name}: {exc} (aircraft {plain.name!r})") from exc
    prepared = PreparedAircraft(aircraft, Path.cwd(), patches=[(f, k) for f, k, _, _ in pairs]) if pairs else plain
    prepared.settings = {prop: value for _, _, prop, value in pairs}
    prepared.pairs = pairs
    return prepared


def _load(path: Path):
    """The validated campaign; a CampaignError naming the file and the field."""
    from ..campaign import load_campaign
    from ..simulators.aircraft_properties import AircraftProperties

    check_campaign_file(path)
    return load_campaign(path, read_aircraft=AircraftProperties)


@app.command()
def plan(campaign_file: Path = typer.Argument(..., metavar="CAMPAIGN", help="Campaign YAML file.")):
    """Validate a campaign and print its design, the number of runs and an estimated time."""
    from ..designs import REGISTRY as DESIGNS
    from ..designs import describe
    from ..running.runner import WorkerError, timed_nominal
    from ..methods import METHODS

    campaign = _load(campaign_file)
    design = campaign.design()
    echo(f"campaign: {quoted_name(str(campaign.name))} ({campaign_file})")
    echo("parameters:")
    for p in campaign.parameters:
        echo(f"  {quoted_name(p.name):<10} {quoted_name(p.property):<18} {p.distribution:<16} nominal {p.nominal:<10.6g} "
             f"interval [{p.lower:.6g}, {p.upper:.6g}]")
    if campaign.dependence is not None:
        echo(f"dependence: {campaign.dependence.kind} over {listed(campaign.dependence.names)} (standard-normal germs, "
             "Cholesky in this order)")
    echo(describe(design))
    kind = campaign.method.kind
    if DESIGNS[design.kind].rare:  # its own estimator: the runs are not draws of the input law
        echo(f"method: none (the {design.kind} estimates the probability of its event only)")
    else:
        entry = METHODS[kind]
        order = campaign.method.order
        echo(f"method: {kind}" + (f" ({entry.order_key.replace('_', ' ')} {order})"
                                  if entry.builds_pce(DESIGNS[design.kind].sampled) else ""))
    runs = campaign.runs or len(design.xi)  # an adaptive grid's budget: its rounds are made from the results
    echo(f"runs: {runs}" + (" at most (design.budget)" if DESIGNS[design.kind].adaptive else ""))
    echo(f"results: {Path(campaign.storage.path).resolve()} (storage.path, from the working directory; "
         "--out to choose)")
    try:
        timed = timed_nominal(campaign)
    except WorkerError as exc:  # its message says it all (a hang, a crash, a build or nominal failure), as `run`'s
        raise Refusal(f"{campaign_file}: {exc}") from exc
    for warning in timed.warnings:  # e.g. the excitation left the elevator unmoved
        echo(f"warning: the nominal flight: {one_line(warning)}", err=True)
    seconds = timed.seconds
    workers = min(campaign.execution.workers, CORES)
    echo(f"estimated time: {runs * seconds / workers:.0f} s with {workers} worker(s) "
         f"({seconds * 1e3:.0f} ms per run, one nominal run timed now on this machine)")


CORES = os.cpu_count() or 1


@app.command()
def run(
    campaign_file: Path = typer.Argument(..., metavar="CAMPAIGN", help="Campaign YAML file."),
    workers: Optional[int] = typer.Option(None, help="Worker processes (default: execution.workers)."),
    out: Optional[Path] = typer.Option(None, help="Results file (default: storage.path)."),
    executor: Optional[str] = typer.Option(None, help="local or dask (default: execution.executor)."),
    scheduler: Optional[str] = typer.Option(None, help="Dask scheduler address, e.g. tcp://host:8786; "
                                                       "without it, a LocalCluster."),
    force: bool = typer.Option(False, help="Overwrite a results file made from another campaign (never a file "
                                           "another run holds, nor one that is not a uqflight results file)."),
    restart: bool = typer.Option(False, help="Start a results file of this same campaign over instead of resuming "
                                             "it (never a file another run holds)."),
):
    """Run a campaign into its HDF5 results file; rerunning resumes where it stopped.

    Exit 0: done; 1: a run-time failure; 2: refused (bad campaign, a file another run holds, a file
    that is not this campaign's, a full disk: the message says what to do); 130 (SIGINT) or 143
    (SIGTERM): stopped cleanly, the finished runs are kept, rerun to resume."""
    from ..running.runner import DiskFull, IncompleteFile, WorkerError, run_campaign
    from ..store import CorruptFile
    from ..store.results import REFLY

    campaign = _load(campaign_file)
    check_output(out or Path(campaign.storage.path), "--out" if out else "storage.path", create=True,
                 inputs=[campaign_file])
    if executor not in (None, "local", "dask"):
        raise Refusal(f"--executor: expected local or dask, got {executor!r}")
    if workers is not None and workers < 1:
        raise Refusal(f"--workers: expected an integer >= 1, got {workers}")
    resume = f"uqflight run {campaign_file}" + (f" --out {out}" if out else "")
    previous = stopping.install()  # SIGINT and SIGTERM stop cleanly, even if a handler's exception is lost
    try:
        summary = run_campaign(campaign, out=out, workers=workers, executor=executor, scheduler=scheduler,
                               force=force, progress=True, restart=restart)
    except DiskFull as exc:
        echo(f"\nerror: {exc.strerror}", err=True)
        _exit_now(2)
    except CorruptFile as exc:  # the fix named with this run's own command
        raise Refusal(f"{str(exc).removesuffix(': ' + REFLY)}; `{resume} --restart` starts it over") from exc
    except IncompleteFile as exc:
        echo(f"error: {exc}", err=True)
        _exit_now(1)
    except (FileExistsError, ValueError, WorkerError) as exc:
        raise Refusal(f"{campaign_file}: {exc}") from exc
    except KeyboardInterrupt as exc:
        code = 143 if isinstance(exc, stopping.Terminated) else 130
        echo(f"\n{'terminated' if code == 143 else 'interrupted'}: the finished runs are stored; "
             f"rerun `{resume}` to resume", err=True)
        raise typer.Exit(code)
    finally:
        stopping.restore(previous)
    echo(summary.describe())


def _exit_now(code: int):
    """Exit without the interpreter's teardown: after HDF5 met a full disk, its library may crash
    (exit 139) while freeing the failed file's objects at exit. The file is closed and the lock
    released by then; only the exit code and the message matter."""
    import sys

    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


@app.command()
def info(results: Path = typer.Argument(..., metavar="RESULTS", help="Results file (.h5).")):
    """Show a results file's campaign, design, done and failed runs, storage and versions."""
    from ..store import LockHeld, ResultStore, Status, read_error
    from ..store.lock import describe_holder, live_holder

    check_results_file(results)
    writer = live_holder(results)
    if writer:
        echo(f"being written by {describe_holder(writer)}")
    try:
        try:
            store = ResultStore.open(results, while_written=writer is not None)
        except LockHeld:  # HDF5's lock held by a writer without a lock file of ours
            echo("locked by another process (a run writing it?): read as it is now")
            writer = {"locked": True}
            store = ResultStore.open(results, while_written=True)
    except Refusal:  # CorruptFile: its message names the file
        raise
    except (OSError, ValueError) as exc:
        retry = "; it is being written: try again in a moment" if writer else ""
        raise Refusal(f"{results}: {read_error(exc)}{retry}") from exc
    with store:
        try:
            _describe_results(results, store, Status)
        except OSError as exc:  # h5py's, on a part read on the way (CorruptFile names the file)
            raise Refusal(f"{results}: {read_error(exc)}") from exc


def _describe_results(results, store, Status) -> None:
    from ..analysis.statistics import file_record

    status = store.status
    attrs = store.attrs
    recorded = file_record(store, results)  # checked as every reader checks it: the design's facts too
    echo(f"file: {results}")
    echo(f"campaign: {quoted_name(recorded.campaign.name)} (sha256 {one_line(str(store.campaign_hash[:12]))})")
    echo(f"design: {recorded.design_kind} {one_line(json.dumps(recorded.design_info))}")
    state = store.index_set()  # an adaptive grid's refinement (/design)
    if state is not None:
        echo(f"index set: {len(state.indices)} multi-indices, {state.rounds} rounds, "
             f"{'stopped by ' + state.stopped if state.stopped else 'refining (resume to go on)'}")
    record = store.rare_event()  # a rare-event design's estimate (/rare_event), once its rounds finished
    if record is not None:
        echo(f"rare event: P({quoted_name(record['of'])} {'>' if record['side'] == 'above' else '<'} {record['threshold']:g})"
             f" = {record['probability']:.4g} (95 %: {record['lower']:.4g} to {record['upper']:.4g}), cov "
             f"{record['cov']:.3g}".replace("cov nan", "cov undefined")
             + f", {record['runs']} runs, stopped by {quoted_name(record['stopped'])}")
    echo(f"parameters: {listed(store.parameter_names)}")
    echo(f"outputs: {listed(store.output_names)} ({store.time.size} times, "
         f"{store.time[0]:g} to {store.time[-1]:g} s)")
    counts = {s.name.lower(): int(np.sum(status == s)) for s in Status}
    echo("runs: " + ", ".join(f"{v} {k}" for k, v in counts.items()) + f" (of {status.size})")
    done = status.size - counts["pending"]
    echo(f"progress: {done} of {status.size} runs done ({100 * done / max(status.size, 1):.1f} %)")
    reasons = Counter(r for r, s in zip(store.reasons, status) if s > 0)
    for reason, n in reasons.most_common(5):
        echo(f"  failed ({n}): {one_line(reason)}")
    problems = store.verify()  # reads every checksummed chunk: a flipped byte is reported
    for problem in problems:
        echo(f"  problem: {one_line(str(problem))}")
    echo(f"storage: {store.storage_description}")
    echo(f"versions: {', '.join(f'{one_line(k)} {one_line(v)}' for k, v in recorded.versions.items())}")
    if "aircraft_hash" in attrs:
        echo(f"aircraft sha256: {one_line(str(attrs['aircraft_hash']))}")
    if problems:
        raise typer.Exit(EXIT_BAD_INPUT)


@app.command()
def report(
    results: List[Path] = typer.Argument(..., metavar="RESULTS", help="Results files (.h5). The first is the one summary.json, "
                                                   "the baseline and the default folder describe."),
    out: Optional[Path] = typer.Option(None, help="Report directory (default: RESULTS-report/ next to the first "
                                                  "results file). Replaced only when the new report is complete."),
    reference: Optional[Path] = typer.Option(None, help="Monte Carlo results file: the errors ε_m, ε_v (Eq. 49) "
                                                        "and KLD (Eq. 50) of every file are taken against it."),
    times: Optional[str] = typer.Option(None, help="Comma-separated times in seconds for the tables at selected "
                                                   "times (the nearest recorded times; 'end' is the final time; a time "
                                                   "outside the flight is refused). Default: 10,25,end, where 10 and 25 "
                                                   "beyond a shorter flight are its end."),
    write_baseline: Optional[Path] = typer.Option(None, help="Also write the first file's statistics to this "
                                                             "JSON file, the baseline of `uqflight check`."),
    method: List[str] = typer.Option([], metavar="KIND[:ORDER]", help="KIND[:ORDER], repeatable: analyse every file with each method "
                                              "instead of its campaign's, overlaid in the plots, e.g. --method "
                                              "pseudo_galerkin:2 --method least_squares:3 --method sparse:4:selection=omp,q=0.75 "
                                              "(KIND:ORDER:KEY=VALUE,... for a kind's own settings). KIND: "
                                              + ", ".join(METHOD_KINDS) + " (the runs of one grid serve every "
                                              "method)."),
    order: Optional[int] = typer.Option(None, help="Polynomial order for a --method given without :ORDER "
                                                   "(default: the campaign's)."),
    partial: bool = typer.Option(False, help="Analyse a file with pending runs on its completed runs, where that "
                                             "is valid (Monte Carlo, QMC, least squares, regression); labelled partial."),
    allow_aliasing: bool = typer.Option(False, help="Let a projection's order exceed what the grid integrates "
                                                    "exactly (refused otherwise); the report says so."),
    figure_format: str = typer.Option("png", "--format", metavar="png|svg|pdf",
                                      help="Format of plots/: png; svg (the page embeds the SVGs); pdf (beside "
                                           "PNGs of the same names, which the page embeds and links to the PDFs)."),
    exceedance: List[str] = typer.Option([], "--exceedance", metavar="NAME>X|NAME<X",
                                         help="P(NAME > X) or P(NAME < X) of a quantity of interest, repeatable: "
                                              "replaces the campaign's analysis.exceedance thresholds of NAME, "
                                              "computed from the stored runs (nothing is flown again); quote it "
                                              "in the shell, e.g. --exceedance 'peak_nz>3.5'."),
):
    """Statistics, tables, plots and a report page of one or more results files.

    Several files (and methods) are compared side by side (labelled campaign: method, runs). OUT gets:
    summary.json (the first file; schema in docs/summary-json.md), summaries/<stem>.json (every file, when
    several), tables/*.csv (campaign, parameters, statistics over time per file and output,
    statistics and Sobol' indices at the selected times, errors against the reference),
    plots/*.png, report.html (self-contained, plots embedded) and report.md (linking plots/).
    The report is written to a temporary folder and moved into place when complete.
    """
    from ..methods.parsing import parse_methods
    from ..report import DEFAULT_TIMES, DrawingFailed, default_out_dir, write_report

    try:
        selected = (list(DEFAULT_TIMES) if times is None else
                    [float("inf") if t.strip() == "end" else float(t) for t in times.split(",")])
    except ValueError:
        raise typer.BadParameter(f"expected comma-separated seconds or 'end', got {times!r}", param_hint="--times")
    if figure_format not in ("png", "svg", "pdf"):
        raise typer.BadParameter(f"expected png, svg or pdf, got {figure_format!r}", param_hint="--format")
    if order is not None and not method:
        raise typer.BadParameter("--order needs --method KIND", param_hint="--order")
    try:
        overrides = parse_methods(method, order)
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="--method")
    from ..quantities.spec import parse_exceedance_option

    try:
        thresholds = parse_exceedance_option(exceedance)
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="--exceedance")
    for path in [*results, *([reference] if reference else [])]:
        check_results_file(path)
    if thresholds:
        _check_quantities(thresholds, results)
    out = out if out is not None else default_out_dir(results[0])
    if not out.exists() and not out.is_symlink():  # an existing DIR is the report's to judge (check_replaceable)
        check_output(out, "--out", folder=True, create=True)
    if write_baseline:
        check_output(write_baseline, "--write-baseline", inputs=[*results, *([reference] if reference else [])])
    if times is not None:
        _check_times(times, selected, results)
    try:
        with Progress(0, label="report") as progress:
            written = write_report(results, out, reference=reference, times=selected, baseline=write_baseline,
                                   method=overrides or None, progress=progress, partial=partial,
                                   allow_aliasing=allow_aliasing, fmt=figure_format, exceedance=thresholds or None)
    except OSError as exc:
        raise Refusal(f"cannot write the report: {exc}") from exc
    except DrawingFailed as exc:  # uqflight's own failure, not the input's: its traceback is above
        echo(f"error: {exc}; no report written ({out} unchanged)", err=True)
        raise typer.Exit(1)
    except KeyboardInterrupt:
        echo(f"\ninterrupted: no report written ({out} unchanged)", err=True)
        raise typer.Exit(130)
    in_report = [p for p in written if Path(os.path.abspath(out)) in p.parents]  # written paths are absolute
    echo(f"wrote {len(in_report)} files to {out}: open {out / 'report.html'}")
    if write_baseline:
        echo(f"wrote baseline {write_baseline}")


def _check_quantities(thresholds: dict, results: list[Path]) -> None:
    """A Refusal naming --exceedance when a threshold names a quantity some results file does not have (an
    unreadable file is the report's to refuse)."""
    from ..store import ResultStore

    for path in results:
        try:
            with ResultStore.open(path) as store:
                names = list(store.quantity_names)
        except (OSError, KeyError, ValueError):
            continue
        unknown = [name for name in thresholds if name not in names]
        if unknown:
            raise Refusal(f"--exceedance: {path} has no quantity {unknown[0]!r}; its quantities: "
                          f"{', '.join(names) or 'none (the campaign has no quantities: mapping)'}")


def _check_times(text: str, selected: list[float], results: list[Path]) -> None:
    """A Refusal naming --times and the flight's time range when a time lies outside a file's recorded
    times (more than half a recording step); 'end' is always inside. An unreadable file is the
    report's to refuse."""
    from ..text.labels import shown_time
    from ..store import ResultStore

    for path in results:
        try:
            with ResultStore.open(path) as store:
                time = store.time
        except (OSError, KeyError, ValueError):
            continue
        half = (time[-1] - time[0]) / max(len(time) - 1, 1) / 2
        outside = [t for t in selected if np.isfinite(t) and not time[0] - half <= t <= time[-1] + half]
        if outside:
            raise Refusal(f"--times {text}: {', '.join(f'{t:g}' for t in outside)} s outside the flight of {path}, "
                          f"which records {shown_time(time, 0):g} to {shown_time(time, -1):g} s; choose times in that "
                          "range or 'end'")


@app.command()
def design(
    campaign_file: Path = typer.Argument(..., metavar="CAMPAIGN", help="Campaign YAML file."),
    csv_path: Optional[Path] = typer.Option(None, "--csv", help="Write the design to this CSV file instead of "
                                            "standard output ('-': standard output): one row per run, columns "
                                            "run, xi_<name> (standard variables), <name> (physical values "
                                            "kappa) and weight."),
):
    """Print a campaign's design (the points and weights the runs would use) as CSV, without running it."""
    to_stdout = csv_path is None or str(csv_path) == "-"
    if not to_stdout:
        check_output(csv_path, "--csv", inputs=[campaign_file])
    campaign = _load(campaign_file)
    points = campaign.design()
    kappa = campaign.to_physical(points.xi)
    names = [p.name for p in campaign.parameters]
    rows = [["run", *(f"xi_{n}" for n in names), *names, "weight"]]
    rows += [[j, *map(repr, map(float, x)), *map(repr, map(float, k)), repr(float(w))]
             for j, (x, k, w) in enumerate(zip(points.xi, kappa, points.weights))]
    if to_stdout:  # through echo: a closed pipe (`| head`) ends quietly
        text = io.StringIO()
        csv.writer(text, lineterminator="\n").writerows(rows)
        echo(text.getvalue(), nl=False)
    else:
        try:
            with open(csv_path, "w", newline="") as fh:
                csv.writer(fh).writerows(rows)
        except OSError as exc:
            raise Refusal(f"cannot write {csv_path}: {exc.strerror}") from exc
    echo(f"wrote {'the design' if to_stdout else csv_path}: {len(points.xi)} points of a {points.kind} design in "
         f"{len(names)} parameters ({listed(names)})", err=to_stdout)


@surrogate_app.command("export")
def surrogate_export(
    results: Path = typer.Argument(..., metavar="RESULTS", help="Results file (.h5)."),
    out: Path = typer.Option(..., help="JSON file to write (strict JSON)."),
    method: Optional[str] = typer.Option(None, help="KIND[:ORDER[:KEY=VALUE,...]] instead of the campaign's "
                                                    "method, e.g. least_squares:3 or sparse:4; a method without a "
                                                    "PCE of its own (monte_carlo) exports as least squares on a "
                                                    "sampled design, pseudo-Galerkin on a grid, as calibrate does."),
):
    """Export the PCE of every output over time as JSON: germs, multi-indices, coefficients per output
    and time, the parameters' distributions (name, distribution, lower, upper, nominal), the time
    grid, method and order. Load it in Python with uqflight.analysis.surrogate.load(path).evaluate(kappa)."""
    from ..analysis.surrogate import export

    try:
        override = parse_method_option(method)
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="--method")
    check_results_file(results)
    check_output(out, "--out", inputs=[results])
    try:
        with Progress(0, label="surrogate export") as progress:
            export(results, out, override, progress)
    except Refusal:  # BadInput: its message names the file
        raise
    except (OSError, KeyError, ValueError) as exc:
        raise Refusal(f"{results}: cannot export the surrogate ({' '.join(str(exc).split())})") from exc
    echo(f"wrote {out}")


def parse_method_option(method: str | None) -> MethodSpec | None:
    from ..methods.parsing import parse_methods

    return parse_methods([method])[0] if method else None


@app.command()
def check(
    results: Path = typer.Argument(..., metavar="RESULTS", help="Results file (.h5) to recompute the statistics of."),
    baseline: Path = typer.Option(..., help="Baseline JSON from `uqflight report ... --write-baseline`."),
    rtol: float = typer.Option(1e-6, help="Relative tolerance."),
    atol: float = typer.Option(1e-9, help="Absolute tolerance, in each statistic's own unit."),
    partial: bool = typer.Option(False, help="Check a file with pending runs on its completed runs (see report)."),
):
    """Recompute a results file's statistics and compare them with a baseline.

    Compares mean, variance, 99 % band and Sobol' indices per output and time: a value drifts when
    |value - baseline| > atol + rtol * |baseline|. The defaults (rtol 1e-6, atol 1e-9) allow for
    floating-point noise only: the statistics are deterministic (seeded). Exit 0: no drift; 1: drift
    (the worst values per statistic are listed); 2: bad input (missing or malformed baseline, other
    outputs or time grid, unreadable results file).
    """
    from ..analysis.check import compare, drift_table, load_baseline
    from ..analysis.statistics import read_statistics

    if rtol < 0 or atol < 0:
        raise Refusal("--rtol and --atol must be >= 0")
    check_results_file(results)
    expected = load_baseline(baseline)
    stats, attrs = read_statistics(results, partial=partial)
    comparison = compare(stats, expected, rtol, atol)
    if expected.get("campaign_hash") and expected["campaign_hash"] != attrs.get("campaign_hash"):
        recorded_hash = one_line(str(attrs.get('campaign_hash'))[:12])
        raise Refusal(f"{results} comes from another campaign (sha256 {recorded_hash}) "
                      f"than the baseline {baseline} ({str(expected['campaign_hash'])[:12]}): compare a results file "
                      "with the baseline of its own campaign")
    if comparison.drifts:
        echo(f"drift: {len(comparison.drifts)} of {comparison.compared} values outside "
             f"rtol={rtol:g}, atol={atol:g}")
        echo(drift_table(comparison))
        raise typer.Exit(1)
    echo(f"no drift: {comparison.compared} values within rtol={rtol:g}/atol={atol:g}")


@app.command("aircraft")
def aircraft_command(
    aircraft: Optional[str] = typer.Argument(None, metavar="AIRCRAFT", help="Aircraft: a name in the project's aircraft/ or JSBSim's, "
                                                        "or a path to an aircraft folder."),
    altitude_ft: Optional[float] = typer.Option(None, help="Trim altitude [ft] (default: the aircraft's)."),
    airspeed_ktas: Optional[float] = typer.Option(None, help="Trim true airspeed [kt] (default: the aircraft's)."),
    list_: bool = typer.Option(False, "--list", help="List the project's and JSBSim's aircraft."),
    trim: bool = typer.Option(False, "--trim", help="Also trim the aircraft in level flight at the altitude and "
                                                    "airspeed (exit 1 when it cannot, saying why and what to do)."),
):
    """An aircraft's aerodynamic functions (axis, name, description), engines and elevator travel, without
    flying it; with --trim its nominal trim too."""
    from ..simulators.aircraft import AircraftFiles, aero_functions, known_aircraft
    from ..simulators.engines import engine_kinds
    from ..simulators.aero_factors import aero_factors, factor_values

    if list_ or aircraft is None:
        for origin, names in known_aircraft().items():
            echo(f"{origin}: {' '.join(map(quoted_name, names))}")  # folder names: quoted when odd
        return
    located = _prepared(aircraft, [], [])
    files = AircraftFiles.read(located.location)
    echo(f"aircraft: {located.name} ({located.location.origin}: {located.location.folder})")
    echo(f"files: {len(files.files)} XML, sha256 {files.hash()}")
    functions = aero_functions(files.main)
    refs = aero_factors(files.main)
    echo(f"aerodynamic functions ({len(functions)}; perturb with function: NAME, perturbation: "
         "scale|offset|offset_value; unit, and the factor an offset ΔC is multiplied by):")
    for f in functions:
        ref = refs[f.name]
        factor = f"ΔC x {ref.symbol}" if not ref.refusal else "offset_value only"
        echo(f"  {quoted_name(f.axis) if f.axis else '-':<6} {quoted_name(f.name):<40} {ref.unit or 'own':<6} {factor:<17} "
             f"{one_line(f.description[:60])}")
    condition = default_condition(located.name)
    condition.update({k: v for k, v in (("altitude_ft", altitude_ft), ("airspeed_ktas", airspeed_ktas)) if v is not None})
    setup = FlightSetup(aircraft=located.name, root=located.root, excitation=Excitation(kind="none"), **condition)
    try:
        flight = JSBSimFlight(setup)
    except (RuntimeError, FileNotFoundError) as exc:  # an aircraft JSBSim cannot load
        raise Refusal(str(exc)) from exc
    echo("engines:")
    for i, (name, kind, thruster) in enumerate(engine_kinds(flight.fdm)):
        echo(f"  {i}: {quoted_name(name):<24} {quoted_name(kind):<10} thruster: {quoted_name(thruster)}")
    echo(f"elevator travel: {flight.elevator_travel_deg[0]:.1f} deg down, {flight.elevator_travel_deg[1]:.1f} deg up"
         + ("" if not flight.has_property("fcs/elevator-excitation-deg") else " (fcs/elevator-excitation-deg used)"))
    if trim:
        echo(f"nominal trim at {setup.altitude_ft:g} ft, {setup.airspeed_ktas:g} KTAS:")
        try:
            echo(flight.trim({}).describe())
        except FlightError as exc:
            echo(f"trim failed: {exc}", err=True)
            raise typer.Exit(1)
        where = "at the trim"
    else:  # qbar = ρ V² / 2 at the condition's altitude and airspeed: the trim's, without trimming
        flight.prepare_for_validation()
        flight.fdm.run_ic()
        where = f"at {setup.altitude_ft:g} ft, {setup.airspeed_ktas:g} KTAS"
        echo(f"not trimmed: `uqflight aircraft {aircraft} --trim` trims it at {setup.altitude_ft:g} ft, "
             f"{setup.airspeed_ktas:g} KTAS (--altitude-ft, --airspeed-ktas)")
    echo(f"reference factors {where} (an offset ΔC adds ΔC times its function's): " + ", ".join(
        f"{symbol} = {number:.6g} {unit}" for symbol, number, unit in factor_values(flight.property_value)))


if _STARTING:  # imported: Ctrl-C is a KeyboardInterrupt again, which each command handles
    signal.signal(signal.SIGINT, signal.default_int_handler)
