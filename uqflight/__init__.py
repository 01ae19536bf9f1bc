"""uqflight: uncertainty quantification campaigns on a JSBSim flight-dynamics model.

The Python API, one function per command; each imports what it needs when called, so `import uqflight`
stays cheap. A campaign from file to statistics, on a closed-form python model (docs/python.md):

>>> import pathlib, tempfile, uqflight
>>> scratch = tempfile.TemporaryDirectory()
>>> folder = pathlib.Path(scratch.name)
>>> _ = (folder / "decay.yaml").write_text('''
... name: decay
... simulator: {kind: python, function: "uqflight.simulators.models:exp_decay"}
... parameters: {a: {distribution: normal, nominal: 1.0, interval_pct: 30}}
... design: {kind: sparse_grid, level: 4}
... method: {kind: pseudo_galerkin, order: 4}
... ''')
>>> campaign = uqflight.load_campaign(folder / "decay.yaml")
>>> campaign.runs
5
>>> summary = uqflight.run(campaign, out=folder / "decay.h5")
>>> summary.ran, sum(summary.failures.values())
(5, 0)
>>> stats = uqflight.analyse(summary.path)
>>> x = stats.outputs["x"]    # x(t) = exp(-a t), a ~ N(1, 0.1²): E[x(1)] = exp(-1 + 0.01/2)
>>> round(float(x.mean[10]), 4), round(float(x.time[10]), 1)
(0.3697, 1.0)
>>> _ = uqflight.export_surrogate(summary.path, folder / "pce.json")
>>> pce = uqflight.load_surrogate(folder / "pce.json")
>>> round(float(pce.evaluate([[1.0]])["x"][0, 10]), 4)    # at a = 1: exp(-1) = 0.3679
0.3679
>>> scratch.cleanup()
"""
from __future__ import annotations

__version__ = "0.1.0"
__all__ = ["analyse", "calibrate", "export_surrogate", "load_campaign", "load_surrogate", "run", "simulate",
           "write_report"]


def load_campaign(path, check_aircraft: bool = True):
    """The validated campaign of a campaign file, checked as `uqflight plan` checks it.

    Parameters
    ----------
    path : str or Path
        The campaign file (YAML).
    check_aircraft : bool
        Check a JSBSim campaign's property and output names against its aircraft and read the nominal values
        from it (JSBSim loads the aircraft); False skips that, and nominal values must then be given.

    Returns
    -------
    uqflight.campaign.Campaign
        The campaign, frozen: its parameters, design, method and settings (`execution`, `storage`, `analysis`,
        `limits`), and `runs`, the design's size.

    Raises
    ------
    uqflight.campaign.CampaignError
        Naming the file, the field and what was expected. A python simulator's module is imported: its code runs.
    """
    from .campaign import load_campaign as load
    from .simulators.aircraft_properties import AircraftProperties

    return load(path, read_aircraft=AircraftProperties if check_aircraft else None)


def run(campaign, out=None, workers: int | None = None, executor: str | None = None,
        scheduler: str | None = None, force: bool = False, restart: bool = False, progress: bool = False):
    """Run a campaign into its results file, resuming a file of this campaign begun before, as `uqflight run` does.

    Parameters
    ----------
    campaign : Campaign, str or Path
        A campaign (`load_campaign`), or a campaign file, which is loaded first.
    out : str or Path, optional
        The results file; default the campaign's `storage.path`.
    workers, executor, scheduler : optional
        `run`'s options: worker processes, `local` or `dask`, a Dask scheduler's address. With `executor="dask"`
        and no scheduler, call it under `if __name__ == "__main__":` (a LocalCluster starts processes).
    force : bool
        Replace a results file of another campaign.
    restart : bool
        Start a results file of this same campaign over.
    progress : bool
        Print the progress line.

    Returns
    -------
    uqflight.running.runner.RunSummary
        `.path`, `.ran`, `.skipped`, `.failures` (reason: count).

    Raises
    ------
    CampaignError, LockHeld, FileExistsError, DiskFull, WorkerError
        See `uqflight.running.runner.run_campaign`.
    """
    from .running.runner import run_campaign

    if not hasattr(campaign, "design_spec"):
        campaign = load_campaign(campaign)
    return run_campaign(campaign, out=out, workers=workers, executor=executor, scheduler=scheduler, force=force,
                        progress=progress, restart=restart)


def _methods(method) -> list | None:
    """`KIND[:ORDER]` strings or {"kind", "order"} mappings (one or a list) into method overrides (MethodSpec);
    ValueError naming a bad one."""
    from .methods.parsing import parse_methods

    if method is None:
        return None
    items = method if isinstance(method, (list, tuple)) else [method]
    return [parse_methods([m.get("kind", "")], m.get("order"))[0] if isinstance(m, dict) else parse_methods([m])[0]
            for m in items]


def _thresholds(exceedance) -> dict | None:
    """`exceedance` as analyse takes it: "NAME>X" strings (one or a list) parsed, a mapping as it is."""
    if exceedance is None or isinstance(exceedance, dict):
        return exceedance
    from .quantities.spec import parse_exceedance_option

    return parse_exceedance_option([exceedance] if isinstance(exceedance, str) else list(exceedance))


def analyse(results, method=None, reference=None, partial: bool = False, allow_aliasing: bool = False,
            exceedance=None):
    """The statistics of a results file, as `uqflight report` computes them. Never runs campaign code.

    Parameters
    ----------
    results : str or Path
        The results file.
    method : str or dict, optional
        "KIND[:ORDER]" or {"kind", "order"} instead of the campaign's method.
    reference : str or Path, optional
        A results file to take the errors ε_m, ε_v and the KLD against.
    partial, allow_aliasing : bool
        As `report --partial` and `--allow-aliasing`.
    exceedance : str, list of str or dict, optional
        "NAME>X" / "NAME<X" strings, or {NAME: [{above: X}]}, replacing the campaign's thresholds of NAME, as
        `report --exceedance`.

    Returns
    -------
    uqflight.analysis.statistics.Statistics
        `.outputs[NAME]` (mean, variance, std, band99, quantiles, sobol_first, sobol_total, ... over time),
        `.quantities[NAME]`, `.notes`, `.failure_probability`, `.record` (the campaign the file records).

    Raises
    ------
    uqflight.analysis.statistics.BadInput
        One line naming the file and what to do, when the file cannot give right numbers.
    """
    from .analysis.statistics import BadInput
    from .analysis.statistics import analyse as statistics

    methods = _methods(method)
    if methods and len(methods) > 1:
        raise ValueError("analyse takes one method; report compares several")
    try:
        return statistics(results, reference=reference, method=methods[0] if methods else None, partial=partial,
                          allow_aliasing=allow_aliasing, exceedance=_thresholds(exceedance))
    except BadInput:
        raise
    except (OSError, KeyError) as exc:
        raise BadInput(f"{results}: cannot analyse the results file ({' '.join(str(exc).split())})") from exc


def write_report(results, out=None, reference=None, method=None, times=(10.0, 25.0, float("inf")),
           baseline=None, partial: bool = False, allow_aliasing: bool = False, exceedance=None) -> list:
    """Write the report of one results file or several, as `uqflight report` does (an example: docs/python.md).

    Parameters
    ----------
    results : str, Path or list of them
        The results files; the first is the one summary.json and the baseline describe.
    out : str or Path, optional
        The report's folder; default RESULTS-report/ beside the first file.
    reference : str or Path, optional
        A Monte Carlo results file the errors are taken against.
    method : str, dict or list of them, optional
        "KIND[:ORDER]" or mappings, compared on the same runs.
    times : tuple of float
        The tables' times in seconds (inf: the final one).
    baseline : str or Path, optional
        Also write the baseline of `uqflight check` there.
    partial, allow_aliasing : bool
        As `report --partial` and `--allow-aliasing`.
    exceedance : str, list of str or dict, optional
        Thresholds replacing the campaign's, as in `analyse`.

    Returns
    -------
    list of Path
        The files written.

    Raises
    ------
    BadInput
        As `analyse`; ValueError for a malformed threshold.
    """
    from pathlib import Path

    from .report import write_report as write

    paths = [Path(p) for p in (results if isinstance(results, (list, tuple)) else [results])]
    return write(paths, out, reference=reference, times=times, baseline=baseline, method=_methods(method),
                 partial=partial, allow_aliasing=allow_aliasing, exceedance=_thresholds(exceedance))


def export_surrogate(results, out, method=None):
    """Write the PCE of every output of a results file as JSON, as `uqflight surrogate export` does.

    Parameters
    ----------
    results : str or Path
        The results file.
    out : str or Path
        The JSON file to write.
    method : str or dict, optional
        "KIND[:ORDER]" or a mapping instead of the campaign's method.

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    uqflight.text.Refusal
        Naming the file and why no surrogate can be made.
    """
    from .analysis.surrogate import export

    methods = _methods(method)
    return export(results, out, methods[0] if methods else None)


def load_surrogate(path):
    """The PCE surrogate of an exported JSON file, checked before anything is evaluated.

    Parameters
    ----------
    path : str or Path
        A file written by `export_surrogate`.

    Returns
    -------
    uqflight.analysis.surrogate.Surrogate
        `.evaluate(kappa)` or `.evaluate(xi=...)` gives {output: (M, T)} at M points; `.mean()`, `.variance()`
        give {output: (T,)}.

    Raises
    ------
    uqflight.text.Refusal
        Naming the file and the key that is wrong.
    """
    from .analysis.surrogate import load

    return load(path)


def simulate(settings: dict | None = None, *, aircraft: str = "bacm", altitude_ft: float | None = None,
             airspeed_ktas: float | None = None, excitation: str = "pulse", amplitude_deg: float = 1.0,
             start_s: float = 1.0, pulse_duration_s: float = 1.0, duration_s: float = 50.0,
             output_rate_hz: float = 20.0, outputs=(), trim: str = "newton"):
    """Fly one flight as `uqflight simulate` does: trim in level flight, excite the elevator, record the outputs.

    Parameters
    ----------
    settings : dict, optional
        {property: value} set before the trim, e.g. {"aero/uq/CL0": 0.22}.
    aircraft : str
        The aircraft: a name (the project's or JSBSim's) or its folder.
    altitude_ft, airspeed_ktas : float, optional
        The trim condition; default the aircraft's.
    excitation, amplitude_deg, start_s, pulse_duration_s : optional
        The elevator's excitation (pulse, step or doublet), its amplitude, start and length.
    duration_s, output_rate_hz : float
        How long the flight is recorded, and how often.
    outputs : sequence of str
        JSBSim properties recorded beside alpha_deg, theta_deg, h_ft, q_degps and vtas_kt.
    trim : str
        "newton" or "jsbsim".

    Returns
    -------
    FlightResult
        `.time`, `.outputs[NAME]`, `.trim`, `.warnings`.

    Raises
    ------
    uqflight.simulators.base.FlightError
        When the trim or the flight fails.

    Examples
    --------
    >>> flight = simulate({"aero/uq/CL0": 0.22}, duration_s=2.0)
    >>> float(flight.time[-1]), sorted(flight.outputs)[:2]
    (2.0, ['alpha_deg', 'h_ft'])
    """
    from pathlib import Path

    from .simulators.aircraft import default_condition
    from .simulators.jsbsim import DEFAULT_OUTPUTS
    from .simulators.scenarios.level_flight import Excitation, FlightSetup, JSBSimFlight
    from .simulators.patch import PreparedAircraft

    located = PreparedAircraft(aircraft, Path.cwd())
    condition = default_condition(located.name)
    setup = FlightSetup(
        aircraft=located.name, root=located.root,
        altitude_ft=condition["altitude_ft"] if altitude_ft is None else altitude_ft,
        airspeed_ktas=condition["airspeed_ktas"] if airspeed_ktas is None else airspeed_ktas,
        excitation=Excitation(kind=excitation, amplitude_deg=amplitude_deg, start_s=start_s,
                              duration_s=pulse_duration_s),
        duration_s=duration_s, output_rate_hz=output_rate_hz, outputs=tuple(DEFAULT_OUTPUTS) + tuple(outputs),
        trim=trim)
    return JSBSimFlight(setup).fly(dict(settings or {}))


def calibrate(results, data, out, noise: dict | None = None, outputs: list[str] | None = None, seed: int = 0,
              walkers: int | None = None, steps: int | None = None, method: str | None = None, order: int | None = None,
              campaign=None, predictive_draws: int = 50):
    """Calibrate the parameters of the campaign of a results file on flight data, as `uqflight calibrate` does
    (docs/calibration.md; an example: docs/python.md).

    Parameters
    ----------
    results : str or Path
        The results file whose runs give the surrogate.
    data : str or Path
        The flight data: a CSV as `uqflight simulate --out` writes it.
    out : str or Path
        The folder for posterior.h5, summary.json, calibrated.yaml and plots/.
    noise : dict, optional
        {output: known noise std}; the others' noise is inferred.
    outputs : list of str, optional
        The outputs calibrated on; default every output the data and the surrogate share.
    seed, walkers, steps : optional
        The sampler's seed, walkers and steps.
    method, order : optional
        The surrogate's method and order instead of the campaign's.
    campaign : str or Path, optional
        The campaign file, when its python model is not beside the results file.
    predictive_draws : int
        Posterior draws flown for the predictive band.

    Returns
    -------
    Calibration
        `.summary` (the summary.json mapping) and `.written` (the files).

    Raises
    ------
    uqflight.text.Refusal
        Bad input or settings, naming what is wrong.
    NotConverged
        `.diagnostics["problems"]` says what to change (`uqflight.calibration.run`).
    """
    from .calibration.run import calibrate as calibration

    return calibration(results, data, out, outputs=outputs, noise=noise, seed=seed, walkers=walkers, steps=steps,
                       method=method, order=order, campaign=campaign, predictive_draws=predictive_draws)
