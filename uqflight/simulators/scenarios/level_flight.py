"""The `level_flight` scenario: one trimmed, excited JSBSim flight per sample, on an aircraft loaded
once and reused (`JSBSimFlight`, on the engine of ../jsbsim.py). Keys: flight {altitude_ft,
airspeed_ktas}, excitation {kind, amplitude_deg, start_s, duration_s}, duration_s, output_rate_hz, trim.

`JSBSimFlight` is the worker-side object: it loads the aircraft once, then for every sample
resets the model, sets the sample's properties, trims in unaccelerated level flight, applies
the elevator excitation and records the outputs. A reused instance gives the same
trajectories as a freshly loaded one (the reset restores every property the previous sample
touched and the controls' values at load time).
"""
from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import jsbsim
import numpy as np

from ..base import DivergenceError, Field, FlightError, ScenarioKind, TrimError, check_fields
from ..engines import prepare_engines
from ..jsbsim import (ATMOSPHERE, DEFAULT_OUTPUTS, OUTPUT_RATE, FlightResult, Observer, PropertyAccess,
                      Watch, check_finite, default_root, ready_to_load)
from ..trim import ENGINE_STOPPED, STALL_PROPERTY, LevelTrim, lift_shortfall, speed_range_shortfall
from ..spec import SimulatorSpec

# Controls the trim writes: restored to their load-time values before every sample.
TRIM_CONTROLS = (
    "fcs/throttle-cmd-norm[0]", "fcs/throttle-cmd-norm[1]", "fcs/elevator-cmd-norm",
    "fcs/pitch-trim-cmd-norm", "fcs/aileron-cmd-norm", "fcs/roll-trim-cmd-norm",
    "fcs/rudder-cmd-norm", "fcs/yaw-trim-cmd-norm", "fcs/elevator-excitation-deg",
)
# Trim acceptance: JSBSim's own tolerances (FGTrim.cpp) with a margin of 10.
TRIM_TOLERANCES = {
    "accelerations/udot-ft_sec2": 1e-2,
    "accelerations/wdot-ft_sec2": 1e-2,
    "accelerations/qdot-rad_sec2": 1e-3,
}
RANDOM_SEED = "atmosphere/randomseed"  # the wind and turbulence generator's seed (jsbsim >= 1.3)
DIVERGENCE_LIMITS = {"aero/alpha-deg": 30.0, "attitude/phi-deg": 60.0}


@dataclass(frozen=True)
class Excitation:
    """Elevator excitation added to the trimmed elevator: pulse, step, doublet or none.

    Positive amplitude is trailing edge down (JSBSim's sign: nose-down moment). A doublet is
    +amplitude for the first half of `duration_s` and -amplitude for the second half.
    """

    kind: str = "pulse"
    amplitude_deg: float = 1.0
    start_s: float = 1.0
    duration_s: float = 1.0

    KINDS = ("pulse", "step", "doublet", "none")

    def __post_init__(self):
        if self.kind not in self.KINDS:
            raise ValueError(f"excitation.kind: expected one of {', '.join(self.KINDS)}, got {self.kind!r}")
        if self.duration_s < 0 or self.start_s < 0:
            raise ValueError("excitation.start_s and duration_s must be >= 0")

    def values(self, t: np.ndarray) -> np.ndarray:
        """Elevator increment [deg] at times `t` [s]."""
        t = np.asarray(t, dtype=float)
        after = t >= self.start_s
        if self.kind == "none":
            return np.zeros_like(t)
        if self.kind == "step":
            return self.amplitude_deg * after
        end = self.start_s + self.duration_s
        if self.kind == "pulse":
            return self.amplitude_deg * (after & (t < end))
        mid = self.start_s + 0.5 * self.duration_s
        return self.amplitude_deg * ((after & (t < mid)).astype(float) - ((t >= mid) & (t < end)))


@dataclass(frozen=True)
class FlightSetup:
    """Everything that is the same for every sample of a campaign."""

    aircraft: str = "bacm"
    root: Path = field(default_factory=default_root)
    altitude_ft: float = 15000.0
    airspeed_ktas: float = 200.0
    excitation: Excitation = field(default_factory=Excitation)
    duration_s: float = 50.0
    rate_hz: float = 120.0
    output_rate_hz: float = 20.0
    outputs: tuple[str, ...] = DEFAULT_OUTPUTS
    trim: str = "newton"

    TRIMS = ("newton", "jsbsim")

    def __post_init__(self):
        if self.trim not in self.TRIMS:
            raise ValueError(f"trim: expected one of {', '.join(self.TRIMS)}, got {self.trim!r}")
        problem = self.rate_problem(self.rate_hz, self.output_rate_hz)
        if problem:
            raise ValueError(f"output_rate_hz: {problem}")
        if self.duration_s <= 0:
            raise ValueError(f"duration_s: expected a positive number, got {self.duration_s:g}")

    @staticmethod
    def rate_problem(rate_hz: float, output_rate_hz: float) -> str | None:
        """Why `output_rate_hz` cannot record a flight integrated at `rate_hz` (None: it can)."""
        ratio = rate_hz / output_rate_hz if output_rate_hz > 0 else 0.0
        if abs(ratio - round(ratio)) <= 1e-9 and round(ratio) >= 1:
            return None
        divisors = ", ".join(f"{rate_hz / k:g}" for k in range(1, 7))
        return f"expected a divisor of the {rate_hz:g} Hz integration rate ({divisors}, ...), got {output_rate_hz:g}"

    @property
    def steps_per_output(self) -> int:
        return int(round(self.rate_hz / self.output_rate_hz))

    @property
    def n_times(self) -> int:
        """The number of recorded times (without building them: a size estimate reads it)."""
        return int(round(self.duration_s * self.output_rate_hz)) + 1

    @property
    def time(self) -> np.ndarray:
        """Recorded times [s]: 0 (the trimmed state) to duration_s at the output rate."""
        return np.arange(self.n_times) / self.output_rate_hz

    @property
    def aircraft_file(self) -> Path:
        return Path(self.root) / "aircraft" / self.aircraft / f"{self.aircraft}.xml"


@dataclass
class TrimResult:
    """The trimmed state and controls, and the residual accelerations that prove it."""

    alpha_deg: float
    theta_deg: float
    throttle: tuple[float, ...]
    elevator_deg: float
    residuals: dict[str, float]

    def describe(self) -> str:
        res = ", ".join(f"{k.split('/')[-1]} = {v:.2e}" for k, v in self.residuals.items())
        thr = ", ".join(f"{x:.4f}" for x in self.throttle)
        return (f"trim: alpha = {self.alpha_deg:.4f} deg, theta = {self.theta_deg:.4f} deg, "
                f"throttle = [{thr}], elevator = {self.elevator_deg:.4f} deg\n"
                f"residuals: {res}")


SURFACE = "fcs/elevator-pos-deg"  # the surface the excitation must move
UNMOVED_FRACTION = 0.1  # a surface that moves less than this share of the commanded amplitude is unmoved


class JSBSimFlight(PropertyAccess):
    """A loaded aircraft that flies any number of samples: reset, set, trim, excite, record."""

    diagnose_trim_failures = True  # a failed trim says why (stall, speed range); false: the state only
    surface_warning: str | None = None  # after a flight: the excitation left the elevator unmoved (why), or None

    def __init__(self, setup: FlightSetup = FlightSetup(), preflight: bool = True):
        """`preflight` false: the caller reloads an aircraft this process has already loaded (and so
        checked, see preflight.py); the check would only hash its files again."""
        ready_to_load(setup, preflight)
        self.setup = setup
        self._bind(jsbsim.FGFDMExec(str(setup.root)), setup.aircraft)
        self.fdm.set_debug_level(0)
        self.fdm.set_output_path(os.devnull)  # no state file (directives.py)
        if not self.fdm.load_model(setup.aircraft):
            raise RuntimeError(f"JSBSim could not load aircraft {setup.aircraft!r} from {setup.root}")
        self.fdm.set_dt(1.0 / setup.rate_hz)
        self._engines = self.fdm.get_propulsion().get_num_engines()
        self._load_values = {p: self.node(p).get_double_value() for p in TRIM_CONTROLS if self.has_property(p)}
        self._touched: dict[str, float] = {}
        self._random_seed = self.node(RANDOM_SEED).get_double_value() if self.has_property(RANDOM_SEED) else 0.0
        self._recorded = [self._output_source(name) for name in setup.outputs]

    # -- properties -------------------------------------------------------------------------
    def property_value(self, name: str) -> float | None:
        """The value of `name` as loaded (None when the aircraft has no such property)."""
        if name in self._touched:
            return self._touched[name]
        return self.node(name).get_double_value() if self.has_property(name) else None

    def prepare_for_validation(self) -> None:
        """The state campaign validation reads nominal values in: the flight condition's initial
        conditions set, as `trim` sets them (so `ic/vc-kts` reads the matching calibrated airspeed)."""
        self.fdm["ic/h-sl-ft"] = self.setup.altitude_ft
        self.fdm["ic/vt-kts"] = self.setup.airspeed_ktas

    # -- one sample -------------------------------------------------------------------------
    def fly(self, settings: dict[str, float] | None = None, observers: Sequence[Observer] = ()) -> FlightResult:
        """Fly one sample with the given property values, watched by `observers`; raises a FlightError subclass.
        The trim is flown in still air: `atmosphere/...` settings (turbulence, gusts, winds, the random
        seed) are applied after it, so that they start at t = 0 of the recorded flight."""
        settings = settings or {}
        trim = self.trim({k: v for k, v in settings.items() if not k.startswith(ATMOSPHERE)})
        for observer in observers:
            if hasattr(observer, "at_trim"):
                observer.at_trim(self.fdm)
        self._apply({k: v for k, v in settings.items() if k.startswith(ATMOSPHERE)})
        return self.run_trimmed(trim, observers)

    def trim(self, settings: dict[str, float]) -> TrimResult:
        """Reset, apply `settings`, trim in unaccelerated level flight and settle the engines.

        `setup.trim` chooses the trim: "newton" (uqflight.simulators.trim, falling back to
        JSBSim's when it does not converge) or "jsbsim" (`simulation/do_simple_trim`).
        """
        level = self._level_trim() if self.setup.trim == "newton" else None
        if level is not None:
            self._reset(settings, settle_engines=False)
            if level.solve(level.nominal) is not None:
                return self._checked_trim()
            level.fallbacks += 1
        return self._jsbsim_trim(settings)

    def _level_trim(self):
        """The Newton trim, with the nominal it starts every sample from (see LevelTrim.prepare);
        None when the nominal itself cannot be trimmed (then JSBSim's trim does every sample)."""
        if not hasattr(self, "_level"):
            level = LevelTrim(self)
            try:
                level.prepare()
            except (FlightError, RuntimeError):
                level = None
            self._level = level
        return self._level

    def _jsbsim_trim(self, settings: dict[str, float]) -> TrimResult:
        fdm = self.fdm
        self._reset(settings)
        try:
            fdm["simulation/do_simple_trim"] = 1
        except jsbsim.TrimFailureError as exc:
            raise TrimError(self._trim_failure(exc)) from exc
        fdm.get_propulsion().get_steady_state()
        return self._checked_trim()

    def _reset(self, settings: dict[str, float], settle_engines: bool = True) -> None:
        """Controls as loaded, the flight condition's ICs, reset, `settings`, engines running
        (and at their steady state at full throttle, unless `settle_engines` is false: the
        Newton trim runs its own steady states)."""
        fdm, s = self.fdm, self.setup
        for name, value in self._load_values.items():
            self.node(name).set_double_value(value)
        for name, value in self._touched.items():
            self.node(name).set_double_value(value)
        if self.has_property(RANDOM_SEED) and RANDOM_SEED not in settings:
            # the wind generator restarts its stream at every run: without a seed parameter every run flies
            # the same turbulence, whatever it flew before on this model
            self.node(RANDOM_SEED).set_double_value(self._random_seed)
        fdm["ic/h-sl-ft"] = s.altitude_ft
        fdm["ic/vt-kts"] = s.airspeed_ktas
        # ic/alpha-deg first: the Newton trim leaves its alpha there, the reset must not see it.
        for ic in ("ic/alpha-deg", "ic/gamma-deg", "ic/beta-deg", "ic/phi-deg", "ic/psi-true-deg"):
            fdm[ic] = 0.0
        # Initial conditions are read by the reset; every other property must be set after
        # it, because the reset restores the values declared in the aircraft's XML.
        initial = {k: v for k, v in settings.items() if k.startswith("ic/")}
        self._apply(initial)
        fdm.reset_to_initial_conditions(0)
        self._apply({k: v for k, v in settings.items() if k not in initial})
        prepare_engines(fdm, settle=settle_engines)  # per engine kind (engines.py)

    def _trim_failure(self, exc) -> str:
        """Why the trim failed: the axis furthest outside its tolerance, and the state and
        controls JSBSim leaves after the failure (it restores the pre-trim controls)."""
        fdm = self.fdm
        ratios = {name: abs(fdm[name]) / tol for name, tol in TRIM_TOLERANCES.items()}
        worst = max(ratios, key=ratios.get)
        acc = ", ".join(f"{k.split('/')[-1].split('-')[0]} = {fdm[k]:.3g}" for k in TRIM_TOLERANCES)
        thr = ", ".join(f"{fdm[f'fcs/throttle-cmd-norm[{i}]']:.3f}" for i in range(self._engines))
        left = (f"{acc}; alpha = {fdm['aero/alpha-deg']:.2f} deg, throttle = [{thr}], "
                f"pitch trim = {fdm['fcs/pitch-trim-cmd-norm']:.3f}, elevator = {fdm['fcs/elevator-pos-deg']:.2f} deg")
        where = (f"JSBSim trim failed ({str(exc).strip() or 'no convergence'}) at {self.setup.altitude_ft:g} ft, "
                 f"{self.setup.airspeed_ktas:g} KTAS")
        if not self.diagnose_trim_failures:
            return f"{where} ({left})"
        stopped = self.stopped_engines()  # before the diagnoses below fly this aircraft again
        cause = lift_shortfall(self) or speed_range_shortfall(self)
        if stopped:
            engines = (f"engine{'s' if len(stopped) > 1 else ''} {', '.join(map(str, stopped))} stopped during the "
                       f"trim ({ENGINE_STOPPED})")
            cause = f"{engines}; {cause}" if cause else (
                f"{engines}: trim at another airspeed or altitude where the engine keeps running (`uqflight simulate "
                "--altitude-ft H --airspeed-ktas V` tries one), or fly a script that sets its own throttle "
                "(scenario: {kind: script, ...})")
        if cause:
            return f"{where}: {cause} (JSBSim's trim left {left})"
        return f"{where}: {worst.split('/')[-1].split('-')[0]} not trimmable ({left})"

    def stopped_engines(self) -> list[int]:
        """The engines that are not running (JSBSim's `propulsion/engine[i]/set-running` reads 0)."""
        return [i for i in range(self._engines) if not self.fdm[f"propulsion/engine[{i}]/set-running"]]

    def _apply(self, settings: dict[str, float]) -> None:
        for name, value in settings.items():
            node = self.node(name)
            self._touched.setdefault(name, node.get_double_value())
            node.set_double_value(float(value))

    def _checked_trim(self) -> TrimResult:
        fdm = self.fdm
        residuals = {name: fdm[name] for name in TRIM_TOLERANCES}
        result = TrimResult(
            alpha_deg=fdm["aero/alpha-deg"],
            theta_deg=fdm["attitude/theta-deg"],
            throttle=tuple(fdm[f"fcs/throttle-cmd-norm[{i}]"] for i in range(self._engines)),
            elevator_deg=fdm["fcs/elevator-pos-deg"],
            residuals=residuals,
        )
        bad = [f"{k} = {v:.3g} (tolerance {TRIM_TOLERANCES[k]:g})"
               for k, v in residuals.items() if not abs(v) <= TRIM_TOLERANCES[k]]
        if bad:
            raise TrimError("trim residual too large: " + "; ".join(bad))
        if not all(0.0 <= x <= 1.0 for x in result.throttle):
            raise TrimError(f"trim throttle outside [0, 1]: {result.throttle}")
        if self.has_property("fcs/pitch-trim-sum") and abs(fdm["fcs/pitch-trim-sum"]) >= 1.0:
            raise TrimError(f"trim elevator saturated at {result.elevator_deg:.2f} deg")
        if self.has_property(STALL_PROPERTY) and fdm[STALL_PROPERTY] != 0.0:
            raise TrimError(f"trim angle of attack {result.alpha_deg:.2f} deg is past the stall")
        return result

    def run_trimmed(self, trim: TrimResult, observers: Sequence[Observer] = ()) -> FlightResult:
        """Excite and integrate from the trimmed state, recording at the output rate; `observers` see
        t = 0 and every step (t = steps / rate_hz)."""
        s = self.setup
        time = s.time
        k = s.steps_per_output
        n_steps = (len(time) - 1) * k
        step_times = np.arange(n_steps) / s.rate_hz
        excitation = s.excitation.values(step_times)
        changes = np.flatnonzero(np.diff(excitation, prepend=0.0))
        change_at = dict(zip(changes.tolist(), excitation[changes].tolist()))
        exc_node, exc_base, exc_per_deg = self._excitation_input()
        run = self.fdm.run
        data = np.empty((len(time), len(self._recorded)))
        data[0] = [node.get_double_value() for node, _ in self._recorded]
        watch = Watch(self, observers) if observers else None
        if watch:
            watch(0.0)
        surface = self.node(SURFACE) if changes.size and self.has_property(SURFACE) else None
        excited = np.flatnonzero(excitation) if surface is not None else ()
        first, last = (int(excited[0]), int(excited[-1])) if len(excited) else (n_steps, -1)
        trimmed_surface, moved = (surface.get_double_value() if surface is not None else 0.0), 0.0
        for i in range(n_steps):
            if i in change_at:
                exc_node.set_double_value(exc_base + exc_per_deg * change_at[i])
            run()
            if first <= i <= last:  # the excitation is on: how far has the surface gone from its trim
                moved = max(moved, abs(surface.get_double_value() - trimmed_surface))
            if watch:
                watch((i + 1) / s.rate_hz)
            if (i + 1) % k == 0:
                data[(i + 1) // k] = [node.get_double_value() for node, _ in self._recorded]
        exc_node.set_double_value(exc_base)
        commanded = float(np.max(np.abs(excitation))) if len(excited) else 0.0
        self.surface_warning = None if not commanded or moved >= UNMOVED_FRACTION * commanded else (
            f"the {s.excitation.kind} of {s.excitation.amplitude_deg:g} deg never moved the elevator: {SURFACE} "
            f"went {moved:.3g} deg from its trimmed {trimmed_surface:.3g} deg while it was commanded (below "
            f"{UNMOVED_FRACTION:.0%} of the amplitude: a dead band or hysteresis in the aircraft's actuator, e.g. "
            "c172x's 2.9 deg), so the flight is not excited: give a larger amplitude (excitation.amplitude_deg in "
            "a campaign, --amplitude-deg on the command line)")
        data *= np.array([scale for _, scale in self._recorded])
        self._check_envelope(data)
        return FlightResult(time=time, outputs=dict(zip(s.outputs, data.T.copy())), trim=trim,
                            warnings=[self.surface_warning] if self.surface_warning else [])

    def _excitation_input(self):
        """(node, trimmed value, command per degree) of the elevator excitation: the aircraft's
        `fcs/elevator-excitation-deg` (degrees added to the elevator) when it has one; otherwise
        `fcs/elevator-cmd-norm` (added to the pitch command, which the trim leaves at its value and
        trims with fcs/pitch-trim-cmd-norm), converted by the elevator's travel read from the
        aircraft's flight controls (its down travel for a positive amplitude, up travel for a negative one)."""
        if self.has_property("fcs/elevator-excitation-deg"):
            return self.node("fcs/elevator-excitation-deg"), 0.0, 1.0
        node = self.node("fcs/elevator-cmd-norm")
        travel = self.elevator_travel_deg
        per_deg = 1.0 / (travel[0] if self.setup.excitation.amplitude_deg >= 0 else travel[1])
        return node, node.get_double_value(), per_deg

    @property
    def elevator_travel_deg(self) -> tuple[float, float]:
        """(down, up) elevator travel [deg] from the aircraft's flight controls (20 deg if not found)."""
        if not hasattr(self, "_travel"):
            from ..aircraft import elevator_travel_deg

            self._travel = elevator_travel_deg(self.setup.aircraft_file.read_bytes()) or (20.0, 20.0)
        return self._travel

    def _check_envelope(self, data: np.ndarray) -> None:
        check_finite(data)
        for name, limit in DIVERGENCE_LIMITS.items():
            value = self.fdm[name]
            if not abs(value) <= limit:
                raise DivergenceError(f"{name} = {value:.1f} at the end of the flight (limit {limit:g})")


class LevelFlight(ScenarioKind):
    """Trim in unaccelerated level flight, elevator excitation, record (keys `flight`, `excitation`,
    `duration_s`, `output_rate_hz`, `trim`).

    Examples
    --------
    >>> spec = SimulatorSpec("jsbsim", {"aircraft": "bacm", "excitation": {"kind": "doublet"}})
    >>> flight = LevelFlight().flight_summary(spec)
    >>> flight["excitation"]
    'elevator doublet 1 deg at 1 s for 1 s'
    """

    kind = "level_flight"
    default_aircraft = "bacm"
    level_trim = True
    example = {"kind": "jsbsim", "duration_s": 2.0, "output_rate_hz": 10.0}
    fields = {
        "flight": Field("The trim condition; default: the aircraft's (bacm 15,000 ft, 200 KTAS). "
                        "`flight: {altitude_ft: 15000, airspeed_ktas: 200}`", keys={
            "altitude_ft": Field("Trim altitude [ft], >= 0. `altitude_ft: 8000`", number=True, minimum=0.0),
            "airspeed_ktas": Field("Trim true airspeed [kt], > 0. `airspeed_ktas: 150`", number=True, minimum=0.0,
                                   strict=True)}),
        "excitation": Field("The elevator excitation after the trim. Default a 1° pulse at 1 s for 1 s. "
                            "`excitation: {kind: doublet, amplitude_deg: 2}`", keys={
            "kind": Field("`pulse` (default), `step`, `doublet` or `none`.", choices=Excitation.KINDS),
            "amplitude_deg": Field("Amplitude [deg], positive trailing edge down. Default 1.", number=True),
            "start_s": Field("Start [s] after the trim, >= 0. Default 1.", number=True, minimum=0.0),
            "duration_s": Field("Duration [s] of a pulse or doublet, >= 0. Default 1.", number=True, minimum=0.0)}),
        "duration_s": Field("Flight time after the trim [s], > 0. Default 50.", number=True, minimum=0.0, strict=True),
        "output_rate_hz": OUTPUT_RATE,
        "trim": Field("`newton` (uqflight's trim, JSBSim's as fallback; the default) or `jsbsim` (JSBSim's own trim "
                      "for every sample).", choices=FlightSetup.TRIMS),
    }

    def check(self, check, sim: SimulatorSpec, folder: Path) -> SimulatorSpec:
        """The scenario's keys checked as their fields say, the output rate against the integration rate."""
        check_fields(check, sim.as_mapping(), "simulator", self.fields)
        rate = float(sim.get("output_rate_hz", FlightSetup.output_rate_hz))
        problem = FlightSetup.rate_problem(FlightSetup.rate_hz, rate)
        if problem:
            check.fail("simulator.output_rate_hz", problem)
        return sim

    @staticmethod
    def _timing(config: SimulatorSpec) -> FlightSetup:
        """The timing alone, FlightSetup's defaults where the campaign gives none (its own checks apply)."""
        return FlightSetup(**{key: float(config[key]) for key in ("duration_s", "rate_hz", "output_rate_hz")
                              if key in config})

    def span(self, config: SimulatorSpec) -> float:
        """The flight's last time [s]: duration_s."""
        return self._timing(config).duration_s

    def times(self, config: SimulatorSpec) -> int:
        """The number of recorded times (the trimmed state, then duration_s at output_rate_hz)."""
        return self._timing(config).n_times

    def setup(self, config: SimulatorSpec, root: Path | None = None, base: Path | None = None,
              properties=()) -> FlightSetup:
        """A FlightSetup from a campaign's `simulator:` spec. The aircraft is located (a path relative to
        `base`, the project's, JSBSim's; see `aircraft.locate`) and patched when `properties` scale or offset
        its functions, unless `root` or config.root is given."""
        from ..aircraft import default_condition
        from ..patch import PreparedAircraft

        name = config.get("aircraft", self.default_aircraft)
        root = config.root or root
        if root is None:
            prepared = PreparedAircraft(config.aircraft_path or name, base, properties)
            name, root = prepared.name, prepared.root
        flight = {**default_condition(name), **config.get("flight", {})}
        given = {key: float(config[key]) for key in ("duration_s", "rate_hz", "output_rate_hz") if key in config}
        if "outputs" in config:
            given["outputs"] = tuple(config["outputs"])
        if "trim" in config:
            given["trim"] = config["trim"]
        return FlightSetup(aircraft=name, root=Path(root), altitude_ft=float(flight["altitude_ft"]),
                           airspeed_ktas=float(flight["airspeed_ktas"]),
                           excitation=Excitation(**config.get("excitation", {})), **given)  # FlightSetup's defaults

    def flight_summary(self, config: SimulatorSpec) -> dict[str, str]:
        """The flight condition and excitation a campaign's `simulator:` spec flies, defaults resolved
        (the report's campaign table), without locating the aircraft."""
        from ..aircraft import default_condition

        condition = {**default_condition(str(config.get("aircraft", self.default_aircraft))),
                     **(config.get("flight") or {})}
        excitation = Excitation(**(config.get("excitation") or {}))
        shape = (f"{excitation.kind}" if excitation.kind == "none" else
                 f"{excitation.kind} {excitation.amplitude_deg:g} deg at {excitation.start_s:g} s"
                 + (f" for {excitation.duration_s:g} s" if excitation.kind != "step" else ""))
        return {"flight": f"level, {condition['altitude_ft']:g} ft, {condition['airspeed_ktas']:g} KTAS, "
                          f"trim {config.get('trim', FlightSetup.trim)}",
                "excitation": f"elevator {shape}"}

    def flight(self, setup: FlightSetup, preflight: bool = True) -> JSBSimFlight:
        return JSBSimFlight(setup, preflight=preflight)

    def resolution(self, setup: FlightSetup, settings: dict[str, float], ours: dict[str, np.ndarray] | None = None
                   ) -> dict[str, np.ndarray] | None:
        """{output: (T,)}: how far the flight of `settings` with the campaign's trim (`ours`, the outputs it
        gave, flown here when None) and with the other trim (Newton's, JSBSim's) have drifted apart so far,
        max over t' ≤ t of |y₁(t') − y₂(t')|. Both trims pass the same acceptance checks, so a spread of the
        outputs below this is the trims' residual dynamics, not the inputs': the simulator does not resolve
        it. None when either trim fails."""
        other = replace(setup, trim="jsbsim" if setup.trim == "newton" else "newton")
        try:
            ours = ours if ours is not None else JSBSimFlight(setup, preflight=False).fly(settings).outputs
            theirs = JSBSimFlight(other, preflight=False).fly(settings).outputs  # same files as the simulator checked
        except FlightError:
            return None
        return {name: np.maximum.accumulate(np.abs(ours[name] - theirs[name])) for name in ours}
