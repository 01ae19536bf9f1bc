"""The `script` scenario: a JSBSim run script flown as JSBSim flies it (`load_script`, `run_ic`, `run`).

`simulator.scenario: {kind: script, script: PATH_OR_NAME, end_s: T}`: PATH_OR_NAME is a file relative
to the campaign's folder, or the name of a script shipped with JSBSim (`c172_cruise_8K`). The aircraft
and its initial conditions are the script's `<use aircraft= initialize=>`: the initialisation file
beside the script when there is one, else the aircraft folder's (JSBSim's rule). `end_s` cuts the
script's end time. A sample sets its `ic/...` properties before `run_ic`, the others after it, but for
its `atmosphere/...` ones (turbulence, winds, gusts, the seed) in a script that trims itself (an `<event>`
setting `simulation/do_simple_trim`): those are set at the first step after the script's first trim
completed (JSBSim's `simulation/trim-completed`), so that the trim that sets the flight up is flown in the
air the script itself gives, as a level flight trims in still air. A later trim of the script (a re-trim
at 20 s) flies in the air then set; a failed trim says which air was active and where it came from.

Every sample loads the script afresh (its events and local properties start over). JSBSim reads a
copy of the script without its `<input>` and `<output>` directives (in uqflight's cache; see
directives.py), with its output path at os.devnull: nothing is written beside the script, the
aircraft or the working directory, and no socket is opened. The recorded times are the simulator's
own (`simulation/sim-time-sec`): the script's dt summed as JSBSim sums it, the same for every
sample; at most MAX_STEPS steps, counted from `<run>` before any is held.
"""
from __future__ import annotations

import difflib
import hashlib
import json
import math
import os
import re
from dataclasses import dataclass, replace
from functools import cached_property
from decimal import Decimal, InvalidOperation
from pathlib import Path

import jsbsim
import numpy as np

from ..aircraft import AircraftFiles, cache_dir
from ..directives import checked, parsed, without_io
from ..base import Field, FlightError, ScenarioKind, SimulatorSettingError, TrimError, check_fields
from ..spec import SimulatorSpec
from ..jsbsim import (ATMOSPHERE, DEFAULT_OUTPUTS, OUTPUT_RATE, FlightResult, PropertyAccess, Watch, check_finite,
                      ready_to_load)

DEFAULT_OUTPUT_RATE_HZ = 20.0
RATE_MISMATCH = 1e-4  # the most a recording interval may differ from k steps, relatively (dt = 0.0083333: 4e-6)
MAX_SCRIPT_BYTES = 1 << 20
# the properties JSBSim ties to each of its outputs (FGOutputType::SetIdx): without the outputs, a script's
# event that sets one would stop the flight ("No property ... is defined"), so the flight declares them
OUTPUT_PROPERTY = re.compile(r"simulation/output(?:\[\d+\])?/(?:log_rate_hz|enabled)")
MAX_STEPS = 10**7  # integration steps (80 MB of step times; 23 h at 120 Hz), as many as a results file holds times
TIME = "simulation/sim-time-sec"
TRIM_PROPERTIES = ("simulation/do_simple_trim", "simulation/do_trim")  # an event setting one trims
TRIM_COMPLETED = "simulation/trim-completed"  # JSBSim sets it to 1 after a successful trim
# what a failed trim says was active: the turbulence model (JSBSim's FGWinds::tType) when it makes turbulence
# (Milspec and Tustin: a severity or a wind at 20 ft; standard and Culp: a gain), its settings, the winds
TURBULENCE_TYPES = {0: "none", 1: "standard", 2: "Culp", 3: "Milspec (Dryden)", 4: "Tustin (Milspec)"}
TURBULENCE_SETTINGS = {1: ("atmosphere/turb-gain",), 2: ("atmosphere/turb-gain",),
                       3: ("atmosphere/turbulence/milspec/severity",
                           "atmosphere/turbulence/milspec/windspeed_at_20ft_AGL-fps"),
                       4: ("atmosphere/turbulence/milspec/severity",
                           "atmosphere/turbulence/milspec/windspeed_at_20ft_AGL-fps")}
CALM_FPS = 1e-6  # a wind below this is the trim's rounding (JSBSim's trim leaves ~1e-13 ft/s), not a wind
WINDS = ("atmosphere/wind-north-fps", "atmosphere/wind-east-fps", "atmosphere/wind-down-fps",
         "atmosphere/gust-north-fps", "atmosphere/gust-east-fps", "atmosphere/gust-down-fps")


def jsbsim_scripts() -> Path:
    """The scripts shipped with JSBSim's Python package."""
    return Path(jsbsim.__file__).resolve().parent / "scripts"


def resolve(text: str, folder: Path) -> Path:
    """The script `text` names: a file relative to `folder`, else one of JSBSim's scripts (without .xml)."""
    candidate = Path(text).expanduser()
    candidate = candidate if candidate.is_absolute() else Path(folder) / candidate
    if candidate.is_file():
        return candidate.resolve()
    shipped = jsbsim_scripts()
    if "/" not in text and (shipped / f"{text}.xml").is_file():
        return (shipped / f"{text}.xml").resolve()
    names = sorted(p.stem for p in shipped.glob("*.xml"))
    close = difflib.get_close_matches(text, names, n=3, cutoff=0.6)
    hint = f"; did you mean {' or '.join(close)}?" if close else ""
    raise SimulatorSettingError(f"no script {text!r}: expected a file relative to {folder} or the name of one of the "
                                f"{len(names)} scripts shipped with JSBSim, without .xml (e.g. c172_cruise_8K){hint}")


def _inside(folder: Path, name: str) -> Path:
    """folder/name, refused when the name leads outside the folder."""
    path = (folder / name).resolve()
    if not path.is_relative_to(folder.resolve()):
        raise SimulatorSettingError(f"{name!r} leads outside the script's folder {folder}")
    return path


@dataclass(frozen=True)
class ScriptFile:
    """What uqflight reads of a run script: its aircraft and initialisation, its timing, the files it names."""

    path: Path
    aircraft: str
    initialize: str
    start_s: float
    end_s: float
    dt_s: float
    dt_text: str
    outputs_files: tuple[str, ...]  # `<output file=...>`, relative to the script's folder (hashed; JSBSim never reads them)
    output_properties: tuple[str, ...]  # the properties of JSBSim's outputs it names (OUTPUT_PROPERTY)
    trims: int | None = 0  # the script's trim events (each trims once); None: a persistent one trims again and again

    @classmethod
    def read(cls, path: Path) -> "ScriptFile":
        path = Path(path)
        data = path.read_bytes()
        if len(data) > MAX_SCRIPT_BYTES:
            raise SimulatorSettingError(f"{path} is larger than {MAX_SCRIPT_BYTES >> 10} KiB; a run script is a few "
                                        "pages of XML")
        root = parsed(data, path, SimulatorSettingError)
        if root.tag != "runscript":
            raise SimulatorSettingError(f"{path} is not a JSBSim run script (its root element is <{root.tag}>, "
                                        "not <runscript>)")
        use, run = root.find("use"), root.find("run")
        if use is None or not use.get("aircraft") or not use.get("initialize"):
            raise SimulatorSettingError(f"{path}: expected <use aircraft=... initialize=...>")
        if run is None or run.get("end") is None or run.get("dt") is None:
            raise SimulatorSettingError(f"{path}: expected <run start=... end=... dt=...>")
        try:
            start, end, dt = (float(run.get(key, "0").strip()) for key in ("start", "end", "dt"))
        except ValueError:
            raise SimulatorSettingError(f"{path}: <run> start, end and dt must be numbers") from None
        if not all(map(math.isfinite, (start, end, dt))) or not dt > 0 or not end > start:
            raise SimulatorSettingError(f"{path}: <run> needs finite numbers with dt > 0 and end > start, got "
                                        f"start={start:g}, end={end:g}, dt={dt:g}")
        named = checked(root, path, SimulatorSettingError, "the script's folder")
        files = tuple(name.strip() for tag, name in named if tag == "output")
        for name in files:
            _inside(path.parent, name)
        return cls(path, use.get("aircraft").strip(), use.get("initialize").strip(), start, end, dt,
                   run.get("dt").strip(), files, _output_properties(root), _trim_events(root))

    @property
    def rate_hz(self) -> float:
        return 1.0 / self.dt_s

    @property
    def dt_rounding(self) -> float:
        """Half a unit of the last digit of dt as the script writes it (0.0083333: 5e-8)."""
        try:
            exponent = Decimal(self.dt_text).as_tuple().exponent
        except InvalidOperation:
            return 0.0
        return 0.5 * 10.0 ** exponent if isinstance(exponent, int) else 0.0

    @property
    def default_output_rate_hz(self) -> float:
        """The recording rate when the campaign gives none: DEFAULT_OUTPUT_RATE_HZ where it divides the
        script's rate, else the fastest divisor of that rate at most DEFAULT_OUTPUT_RATE_HZ (dt = 0.0075 s:
        133.3 Hz / 7 = 19.05 Hz; dt = 0.02 s: 50 Hz / 3 = 16.67 Hz; a rate below it: the rate itself)."""
        if self.steps_per_output(DEFAULT_OUTPUT_RATE_HZ) is not None:
            return DEFAULT_OUTPUT_RATE_HZ
        return self.rate_hz / math.ceil(self.rate_hz / DEFAULT_OUTPUT_RATE_HZ)

    def output_rate_hz(self, config: SimulatorSpec) -> float:
        """The recording rate of a campaign's `simulator:` spec `config` flying this script: its
        `output_rate_hz`, else `default_output_rate_hz`."""
        return float(config["output_rate_hz"]) if "output_rate_hz" in config else self.default_output_rate_hz

    def steps_per_output(self, output_rate_hz: float) -> int | None:
        """Integration steps per recorded time; None when `output_rate_hz` does not divide the script's
        rate within the rounding of its dt (k steps of dt must last 1 / output_rate_hz), and at most
        RATE_MISMATCH of it: a dt written with few digits is what JSBSim steps by ("0.02" is 50 Hz, which
        20 Hz does not divide, however "0.02" was rounded), one with many may be a rounded 1/120."""
        k = round(1.0 / (self.dt_s * output_rate_hz))
        if k < 1:
            return None
        tolerance = min(k * self.dt_rounding, RATE_MISMATCH * k * self.dt_s) + 1e-9 * k * self.dt_s
        return k if abs(k * self.dt_s - 1.0 / output_rate_hz) <= tolerance else None

    def initfile(self, aircraft_folder: Path) -> Path | None:
        """The initialisation file beside the script (passed to JSBSim, checked as directives.py checks
        what JSBSim reads), else None: then JSBSim reads the aircraft folder's (checked with the
        aircraft's files); SimulatorSettingError when neither exists."""
        for folder in (self.path.parent, Path(aircraft_folder)):
            for name in (self.initialize, f"{self.initialize}.xml"):
                candidate = _inside(folder, name)
                if candidate.is_file():
                    if folder != self.path.parent:
                        return None
                    checked(parsed(candidate.read_bytes(), candidate, SimulatorSettingError), candidate,
                            SimulatorSettingError, "the script's folder")
                    return candidate
        raise SimulatorSettingError(f"{self.path}: initialize={self.initialize!r} names no file beside the script "
                                    f"nor in the aircraft folder {aircraft_folder}")

    def _end(self, end_s: float | None) -> float:
        """The last time a step may reach: the script's end (or `end_s` when earlier) plus 0.99 dt,
        JSBSim's own margin (FGScript)."""
        return (self.end_s if end_s is None else min(self.end_s, end_s)) + 0.99 * self.dt_s

    def bounded_steps(self, end_s: float | None = None) -> int:
        """The steps before the end by the closed form, without holding any: SimulatorSettingError naming the
        file and what to change when they are more than MAX_STEPS."""
        n = max(0, math.floor((self._end(end_s) - self.start_s) / self.dt_s))
        if n > MAX_STEPS:
            cut = "" if end_s is None else f" cut at {end_s:g} s"
            raise SimulatorSettingError(f"{self.path}: <run start={self.start_s:g} end={self.end_s:g} "
                                        f"dt={self.dt_text}>{cut} is {n:.3g} integration steps, more than {MAX_STEPS}: "
                                        "cut the flight with "
                                        f"simulator.scenario.end_s (at most {self.start_s + MAX_STEPS * self.dt_s:.6g} s) "
                                        "or give the script a larger dt")
        return n

    def steps(self, end_s: float | None = None) -> int:
        """The steps JSBSim runs before the end: the largest n whose summed time start + dt + ... + dt
        is at most the end. The closed form decides unless the sum's rounding (n additions) could
        cross the end, then the sum itself does. SimulatorSettingError beyond MAX_STEPS (`bounded_steps`)."""
        end, dt = self._end(end_s), self.dt_s
        n = self.bounded_steps(end_s)
        slack = (n + 2) * max(abs(end), abs(self.start_s)) * 2.3e-16
        near = min(abs(self.start_s + k * dt - end) for k in (n, n + 1)) <= slack
        if near:
            summed = self._summed(n + 1)
            n = int(np.searchsorted(summed, end, side="right")) - 1
        return n

    def _summed(self, n: int) -> np.ndarray:
        """start, then the time after each of n steps, summed as JSBSim sums it (sim_time += dt; NumPy's
        cumulative sum adds in order, bit for bit the same)."""
        return np.cumsum(np.r_[self.start_s, np.full(n, self.dt_s)])

    def times(self, end_s: float | None = None) -> np.ndarray:
        """The simulator's time at the start and after every step until the end (see `steps`)."""
        return self._summed(self.steps(end_s))

    def flown(self) -> Path:
        """The file JSBSim loads: the script itself, or, when it has `<input>` or `<output>` directives,
        a copy without them in uqflight's cache (keyed by its sha256, written once, all or nothing)."""
        text = without_io(self.path.read_bytes())
        if text is None:
            return self.path
        path = cache_dir("scripts", hashlib.sha256(text).hexdigest()[:24], self.path.name)
        if not path.is_file() or path.read_bytes() != text:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
            tmp.write_bytes(text)
            tmp.replace(path)
        return path


def _output_properties(root) -> tuple[str, ...]:
    """The output properties (OUTPUT_PROPERTY) the script's elements name, in their text or an attribute."""
    found = {match for element in root.iter() for text in (element.text or "", *element.attrib.values())
             for match in OUTPUT_PROPERTY.findall(text)}
    return tuple(sorted(found))


def _trim_events(root) -> int | None:
    """The number of the script's `<event>`s that trim (set simulation/do_simple_trim); None when one of
    them is persistent or continuous (it trims whenever its condition holds again)."""
    count = 0
    for event in root.iter("event"):
        if any((item.get("name") or "").strip() in TRIM_PROPERTIES for item in event.iter("set")):
            if (event.get("persistent") or "").strip() == "true" or (event.get("continuous") or "").strip() == "true":
                return None
            count += 1
    return count


def _script_file(config: SimulatorSpec, base: Path | None) -> ScriptFile:
    path = config.script_path or resolve(config["scenario"]["script"], Path(base or Path.cwd()))
    return ScriptFile.read(Path(path))


@dataclass(frozen=True)
class ScriptSetup:
    """Everything that is the same for every sample of a script campaign."""

    aircraft: str
    root: Path
    script: ScriptFile
    initfile: Path | None  # beside the script, else None (the aircraft folder's, as JSBSim finds it)
    end_s: float | None
    output_rate_hz: float
    outputs: tuple[str, ...]

    @property
    def steps_per_output(self) -> int:
        return self.script.steps_per_output(self.output_rate_hz)

    @cached_property
    def step_times(self) -> np.ndarray:
        """The simulator's time at the start and after every step flown (each seen by the observers)."""
        return self.script.times(self.end_s)

    @property
    def steps(self) -> int:
        return len(self.step_times) - 1

    @property
    def time(self) -> np.ndarray:
        """Recorded times [s]: the simulator's, every steps_per_output steps from the start."""
        return self.step_times[:: self.steps_per_output]

    @property
    def aircraft_file(self) -> Path:
        return Path(self.root) / "aircraft" / self.aircraft / f"{self.aircraft}.xml"


class ScriptFlight(PropertyAccess):
    """Flies the script once per sample, from a fresh load: set ic/..., run_ic, set the rest, run."""

    def __init__(self, setup: ScriptSetup, preflight: bool = True):
        ready_to_load(setup, preflight)
        self.setup = setup
        self._flown_script = str(setup.script.flown())
        self._load()

    def _load(self) -> None:
        s = self.setup
        fdm = jsbsim.FGFDMExec(str(s.root))
        fdm.set_debug_level(0)
        fdm.set_output_path(os.devnull)  # no state file (directives.py)
        if not fdm.load_script(self._flown_script, 0.0, str(s.initfile) if s.initfile else ""):
            raise FlightError(f"JSBSim could not load the script {s.script.path} with aircraft {s.aircraft!r} "
                              f"from {s.root}")
        fdm.disable_output()
        if fdm.get_delta_t() != s.script.dt_s:
            raise FlightError(f"JSBSim reads the script's dt as {fdm.get_delta_t()!r}, uqflight as {s.script.dt_s!r}")
        self._bind(fdm, s.aircraft)
        for name in s.script.output_properties:  # their outputs were removed: the names stay, inert
            if not self.has_property(name):
                self._pm.get_node(name, True)
        self._recorded = [self._output_source(name) for name in s.outputs]

    def prepare_for_validation(self) -> None:
        """The state campaign validation reads nominal values in: the script loaded, before run_ic."""

    def property_value(self, name: str) -> float | None:
        """The value of `name` once the script is loaded (None when there is no such property)."""
        return self.node(name).get_double_value() if self.has_property(name) else None

    def fly(self, settings: dict[str, float] | None = None, observers=()) -> FlightResult:
        """Fly one sample with the given property values, watched by `observers` (t = the simulator's
        time); raises a FlightError subclass."""
        settings = settings or {}
        s = self.setup
        if getattr(self, "_flown", False):
            self._load()
        self._flown = True
        held = {name: value for name, value in settings.items()
                if name.startswith(ATMOSPHERE) and s.script.trims != 0}  # set after the script's trims
        try:
            for name, value in settings.items():
                if name.startswith("ic/"):
                    self.node(name).set_double_value(float(value))
            self.fdm.run_ic()
            for name, value in settings.items():
                if not name.startswith("ic/") and name not in held:
                    self.node(name).set_double_value(float(value))
            data, times = self._run(observers, held)
        except jsbsim.TrimFailureError as exc:
            raise TrimError(f"a trim in the script failed at t = {self.fdm.get_sim_time():.4g} s: "
                            f"{str(exc).strip() or 'no convergence'}; {self._active_air(held)}") from exc
        except jsbsim.BaseError as exc:
            raise FlightError(f"JSBSim stopped the script at t = {self.fdm.get_sim_time():.4g} s: {exc}") from exc
        grid = s.time
        if not np.array_equal(times, grid):
            at = int(np.argmax(times != grid))
            raise FlightError(f"the simulator's time {times[at]:.6g} s is not the script's {grid[at]:.6g} s (recorded "
                              f"time {at}): does the script reset the simulation? cut it before with "
                              "simulator.scenario.end_s")
        check_finite(data)
        return FlightResult(time=grid, outputs=dict(zip(s.outputs, data.T.copy())), trim=None)

    def _active_air(self, held: dict) -> str:
        """What air the failed trim flew in: the turbulence model with its settings and the winds that were
        set (non-zero), each said to come from the script's own events or from the campaign (`held`: the
        campaign's atmosphere settings, set after the script's first trim, or still held for then)."""
        def value(name: str) -> float:
            return self.node(name).get_double_value() if self.has_property(name) else 0.0

        kind = int(value("atmosphere/turb-type"))
        turbulence = ["atmosphere/turb-type", *TURBULENCE_SETTINGS.get(kind, ())] if any(
            value(name) for name in TURBULENCE_SETTINGS.get(kind, ())) else []
        active = [name for name in turbulence if name == "atmosphere/turb-type" or value(name)]
        active += [name for name in WINDS if abs(value(name)) > CALM_FPS]
        applied = held and self._air_applied

        def setting_text(name: str) -> str:
            text = f"{name} = {value(name):.4g}"
            return text + f" ({TURBULENCE_TYPES.get(kind, '?')})" if name == "atmosphere/turb-type" else text

        theirs = [setting_text(name) for name in active if not (applied and name in held)]
        ours = [setting_text(name) for name in active if applied and name in held]
        parts = []
        if theirs:
            parts.append("active at the trim from the script's own events: " + ", ".join(theirs)
                         + " (set them in an event after its trim for a trim in still air)")
        if ours:
            parts.append("active at the trim from the campaign (simulator.properties or parameters, set after the "
                         "script's first trim): " + ", ".join(ours))
        if not parts:
            parts.append("the trim flew in still air (no turbulence, gust or wind set)")
        if held and not applied:
            parts.append("held for after the script's first trim: "
                         + ", ".join(f"{k} = {v:g}" for k, v in held.items()))
        return "; ".join(parts)

    def _run(self, observers, held: dict | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Integrate the setup's steps, recording every steps_per_output steps: (outputs (T, n), times (T,)).
        `held`: settings applied at the first step after the script's first trim completed (see the module doc)."""
        s = self.setup
        completed = self.node(TRIM_COMPLETED) if held and self.has_property(TRIM_COMPLETED) else None
        self._air_applied = completed is None
        if completed is not None:
            completed.set_double_value(0.0)
        else:  # nothing held, or a JSBSim that does not say when a trim completed: set now, as before the first step
            for name, value in (held or {}).items():
                self.node(name).set_double_value(float(value))
        k, steps = s.steps_per_output, s.steps
        clock = self.node(TIME)
        run = self.fdm.run
        data = np.empty((steps // k + 1, len(self._recorded)))
        times = np.empty(steps // k + 1)
        data[0], times[0] = [node.get_double_value() for node, _ in self._recorded], clock.get_double_value()
        watch = Watch(self, observers) if observers else None
        if watch:
            watch(times[0])
        for i in range(1, steps + 1):
            if not run():
                raise FlightError(f"the script ended at t = {clock.get_double_value():.6g} s, before its end "
                                  f"{s.time[-1]:.6g} s: cut it with simulator.scenario.end_s")
            if watch:
                watch(clock.get_double_value())
            if i % k == 0:
                data[i // k] = [node.get_double_value() for node, _ in self._recorded]
                times[i // k] = clock.get_double_value()
            if completed is not None and completed.get_double_value() >= 1.0:  # for the steps after this one
                for name, value in held.items():
                    self.node(name).set_double_value(float(value))
                completed, self._air_applied = None, True
        if completed is not None:
            raise FlightError(f"the script's first trim did not complete before its end {s.time[-1]:.6g} s, so "
                              f"{', '.join(held)} (set after it) never took effect: end the flight later "
                              "(simulator.scenario.end_s), or set them in the script's own events")
        data *= np.array([scale for _, scale in self._recorded])
        return data, times


class Script(ScenarioKind):
    """Fly a JSBSim run script as JSBSim does, its events included (keys `scenario.script`, `scenario.end_s`,
    `output_rate_hz`).

    Examples
    --------
    >>> Script().flight_summary(SimulatorSpec("jsbsim", {"scenario": {"kind": "script", "script": "c172_cruise_8K",
    ...                                                                "end_s": 20}}))
    {'flight': 'script c172_cruise_8K, cut at 20 s', 'excitation': "the script's events"}
    """

    kind = "script"
    fields = {"output_rate_hz": OUTPUT_RATE}
    scenario_fields = {
        "script": Field("Required for `script`: a JSBSim run script, a file relative to the campaign file or the "
                        "name of one shipped with JSBSim (without `.xml`). `script: c172_cruise_8K`"),
        "end_s": Field("Ends the run before the script's `<run end=>` [s]. `end_s: 20`")}
    example = {"kind": "jsbsim", "scenario": {"kind": "script", "script": "c172_cruise_8K", "end_s": 2.0},
               "output_rate_hz": 10.0}

    def check(self, check, sim: SimulatorSpec, folder: Path) -> SimulatorSpec:
        """Resolve and read the script, check end_s, the output rate against the script's dt and the
        campaign's aircraft against the script's (`check` is the campaign's Checker)."""
        from ..aircraft import AircraftNotFound, locate

        scenario = sim["scenario"]
        if "script" not in scenario:
            check.fail("simulator.scenario.script", "is required: a run script relative to the campaign file, or the "
                                                    "name of one shipped with JSBSim (e.g. c172_cruise_8K)")
        text = check.string(scenario["script"], "simulator.scenario.script")
        try:
            script = ScriptFile.read(resolve(text, folder))
        except (SimulatorSettingError, OSError) as exc:
            check.fail("simulator.scenario.script", str(exc))
        end = None
        if "end_s" in scenario:
            end = check.number(scenario["end_s"], "simulator.scenario.end_s")
            if not script.start_s < end <= script.end_s:
                check.fail("simulator.scenario.end_s", f"expected a time after the script's start {script.start_s:g} "
                                                       f"s and at most its end {script.end_s:g} s, got {end:g}")
        try:
            script.bounded_steps(end)
        except SimulatorSettingError as exc:
            check.fail("simulator.scenario.end_s" if end is not None else "simulator.scenario.script", str(exc))
        check_fields(check, sim.as_mapping(), "simulator", self.fields)
        rate = script.output_rate_hz(sim)
        if script.steps_per_output(rate) is None:
            divisors = ", ".join(f"{script.rate_hz / k:.4g}" for k in range(1, 7))
            check.fail("simulator.output_rate_hz", f"expected a divisor of the script's {script.rate_hz:.7g} Hz rate "
                                                   f"(dt = {script.dt_text} s: {divisors}, ...), got {rate:g}")
        named = sim.get("aircraft", script.aircraft)
        check.string(named, "simulator.aircraft")
        try:
            location = locate(named, folder)
        except AircraftNotFound as exc:
            check.fail("simulator.aircraft", str(exc))
        if location.name != script.aircraft:
            check.fail("simulator.aircraft", f"{named!r} is not the script's aircraft {script.aircraft!r} (<use "
                                             f"aircraft=> in {script.path.name}); leave simulator.aircraft out, or "
                                             "name that aircraft")
        try:
            script.initfile(location.folder)
        except SimulatorSettingError as exc:
            check.fail("simulator.scenario.script", str(exc))
        return replace(sim.with_settings(aircraft=named), script_path=str(script.path))

    def span(self, config: SimulatorSpec) -> float | None:
        """end_s when given, else the script's own end once it is resolved (`script_path`), else None: no
        file is read before the campaign is resolved."""
        end = config.get("scenario", {}).get("end_s")
        if isinstance(end, (int, float)) and not isinstance(end, bool):
            return float(end)
        return ScriptFile.read(Path(config.script_path)).end_s if config.script_path else None

    def times(self, config: SimulatorSpec) -> int:
        """The number of recorded times, from the script's timing and the output rate alone."""
        script = _script_file(config, None)
        end_s = config.get("scenario", {}).get("end_s")
        steps = script.steps(None if end_s is None else float(end_s))
        return steps // script.steps_per_output(script.output_rate_hz(config)) + 1

    def setup(self, config: SimulatorSpec, root: Path | None = None, base: Path | None = None,
              properties=()) -> ScriptSetup:
        """A ScriptSetup from a campaign's `simulator:` spec: the script's
        aircraft located and patched as for level flight (see `LevelFlight.setup`)."""
        from ..patch import PreparedAircraft

        script = _script_file(config, base)
        name = config.get("aircraft", script.aircraft)
        root = config.root or root
        if root is None:
            prepared = PreparedAircraft(config.aircraft_path or name, base, properties)
            name, root = prepared.name, prepared.root
        root = Path(root)
        scenario = config.get("scenario", {})
        return ScriptSetup(
            aircraft=name, root=root, script=script,
            initfile=script.initfile(root / "aircraft" / name) if (root / "aircraft" / name).is_dir() else None,
            end_s=float(scenario["end_s"]) if "end_s" in scenario else None,
            output_rate_hz=script.output_rate_hz(config),
            outputs=tuple(config.get("outputs", DEFAULT_OUTPUTS)),
        )

    def flight(self, setup: ScriptSetup, preflight: bool = True) -> ScriptFlight:
        return ScriptFlight(setup, preflight=preflight)

    def files(self, config: SimulatorSpec) -> dict[str, bytes]:
        """The script, its initialisation file when beside it, and the output files it names (keys relative
        to the script's folder): what a worker needs beyond the aircraft's files."""
        script = ScriptFile.read(Path(config.script_path))
        folder = script.path.parent
        names = [script.path.name, *script.outputs_files]
        for name in (script.initialize, f"{script.initialize}.xml"):
            if _inside(folder, name).is_file():
                names.append(name)
                break
        return {name: _inside(folder, name).read_bytes() for name in dict.fromkeys(names)}

    def localize(self, config: SimulatorSpec, folder: Path) -> SimulatorSpec:
        """The spec reading the script (and the files beside it) from `folder`, where `files` were written."""
        return replace(config, script_path=str(Path(folder) / Path(config.script_path).name))

    def relocated(self, config: dict, folder: Path) -> dict:
        """A script given as a file relative to `folder` made absolute (a JSBSim script keeps its name)."""
        scenario = dict(config["scenario"])
        candidate = Path(folder) / str(scenario["script"])
        if not Path(str(scenario["script"])).is_absolute() and candidate.is_file():
            scenario["script"] = str(candidate.resolve())
        return {**config, "scenario": scenario}

    def provenance(self, config: SimulatorSpec) -> dict:
        """The scenario and the sha256 of the script's files, for the results file."""
        return {"scenario": json.dumps({"kind": "script", "script": Path(config.script_path).name,
                                        "sha256": AircraftFiles("", self.files(config)).hash()})}

    def flight_summary(self, config: SimulatorSpec) -> dict[str, str]:
        """The script flown, as the campaign names it (the report's campaign table)."""
        scenario = config.get("scenario") or {}
        end = f", cut at {scenario['end_s']:g} s" if isinstance(scenario.get("end_s"), (int, float)) else ""
        return {"flight": f"script {scenario.get('script', '?')}{end}", "excitation": "the script's events"}

    def resolution(self, setup: ScriptSetup, settings, ours=None) -> None:
        """A script has no second way of flying it: no resolution of its own."""
        return None
