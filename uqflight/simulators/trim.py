"""A trim of our own for unaccelerated, wings-level flight: Newton against JSBSim's accelerations.

JSBSim's `simulation/do_simple_trim` costs ~15 ms a sample on bacm. This trim solves the same
three equations (u̇ = ẇ = q̇ = 0 in body axes, γ = 0 so θ = α) for the same three unknowns
(α, the throttle of all engines together, `fcs/pitch-trim-cmd-norm`, the control FGTrim's
tQdot axis uses), with JSBSim's own accelerations, evaluated without advancing time:
`run_ic()` suspends the integration, initialises the state from the IC (`ic/alpha-rad`) and
runs every model once with dt = 0, like FGTrimAxis::Run (fdmex->Initialize(fgic); Run()).

The engines. During a dt = 0 run the turboprop is in its trim phase and makes no power: the
propeller keeps the rpm and blade angle it had and gives the thrust of that frozen state
(FGTurboProp::Calculate, FGPropeller::Calculate). Its thrust only follows the throttle through
`get_propulsion().get_steady_state()` (time marching at 0.5 s), which JSBSim's trim calls on
every throttle change (FGTrimAxis::setThrottlesPct) and uqflight calls once after it, and
which costs ~0.4 ms here (N1 restarts from idle after every dt = 0 run). So:

* the inner Newton works on (α, pitch trim, total thrust T) with the propellers frozen: the
  residual is JSBSim's (u̇, ẇ, q̇) plus B (T − T_frozen), where B is the acceleration per
  pound of thrust (body-axis thrust line, measured once at the nominal). Chord iterations on
  the nominal Jacobian, one dt = 0 run (~15 µs) each, refreshed by finite differences when
  they stall;
* the throttle giving T is read off T_ss(throttle), the steady-state thrust tabulated once at
  the nominal on a 0.025 grid (the power table is piecewise linear in N1: kinks at integer
  N1, throttle multiples of 0.025 on bacm), shifted by dT_ss/dα at first, then by this
  sample's own offset from the table once a steady state has been run;
* the outer loop runs the engines' steady state at that throttle and re-evaluates JSBSim's
  full residual; it stops when the residual is within 1/100 of JSBSim's own tolerances
  (FGTrim.cpp: 1e-3 ft/s² on u̇, ẇ; 1e-4 rad/s² on q̇). Measured on 1128 samples (Table 1
  corners and normal draws): two steady states in the loop, a few samples one.

The final state is the one uqflight flies today after JSBSim's trim: the trimmed IC evaluated
at dt = 0, then one `get_steady_state()` that leaves the turboprops in their run phase. So
three steady states a sample, against one per throttle step inside JSBSim's trim.

Warm start: every sample starts from the nominal trim (all properties as loaded), computed once
per process (JSBSim's trim refined by this one, see `LevelTrim.prepare`), so a sample's result
does not depend on the samples flown before it. When this trim does not converge the caller
falls back to JSBSim's trim (`fallbacks` counts them); the acceptance checks are the same.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from .jsbsim import aircraft_hash

STALL_PROPERTY = "aero/coefficient/CL-stall"  # non-zero past the stall (bacm)
RESIDUALS = ("accelerations/udot-ft_sec2", "accelerations/wdot-ft_sec2", "accelerations/qdot-rad_sec2")
LATERAL = ("accelerations/vdot-ft_sec2", "accelerations/pdot-rad_sec2", "accelerations/rdot-rad_sec2")
# JSBSim's trim tolerances (FGTrim.cpp: Tolerance 1e-3, A_Tolerance 1e-4).
JSBSIM_TOLERANCE = np.array([1e-3, 1e-3, 1e-4])
# Converged when every residual is below this fraction of JSBSim's tolerance. The engines'
# steady state stops at 1e-4 lbf thrust change a 0.5-s step, ~1e-5 ft/s² of u̇ at most:
# 1/100 of JSBSim's tolerance is reachable and 100 times tighter than JSBSim's trim.
FRACTION = 1e-2
INNER_FRACTION = 1e-3      # the frozen-propeller model is solved tighter than the outer loop
MAX_INNER = 30           # chord iterations cost one dt = 0 run (~15 µs) each
MAX_OUTER = 6
FD_STEP = (1e-4, 1e-4)     # α [rad], pitch trim [-]: forward differences (see _inner)
THROTTLE_GRID = np.linspace(0.0, 1.0, 41)
ALPHA_LIMITS = (math.radians(-10.0), math.radians(20.0))

# Nominals computed in this process: (aircraft hash, file, altitude, airspeed, rate) -> values.
_NOMINALS: dict[tuple, dict] = {}
NOMINAL_FIELDS = ("nominal", "thrust_grid", "B", "jacobian", "nominal_alpha", "dthrust_dalpha")


class LevelTrim:
    """Newton trim in wings-level, unaccelerated flight for one JSBSimFlight (see module doc)."""

    def __init__(self, flight):
        self.flight = flight
        self.fdm = flight.fdm
        self._prop = self.fdm.get_propulsion()
        n = flight.node
        self._alpha = n("ic/alpha-rad")
        self._pitch = n("fcs/pitch-trim-cmd-norm")
        self._throttles = [n(f"fcs/throttle-cmd-norm[{i}]") for i in range(flight._engines)]
        self._thrusts = [n(f"propulsion/engine[{i}]/thrust-lbs") for i in range(flight._engines)]
        self._res = [n(p) for p in RESIDUALS]
        self.nominal: np.ndarray | None = None     # (α [rad], throttle, pitch trim)
        self.thrust_grid: np.ndarray | None = None  # steady-state total thrust at THROTTLE_GRID
        self.B: np.ndarray | None = None            # d(u̇, ẇ, q̇)/dT [per lbf]
        self.jacobian: np.ndarray | None = None     # the inner model's, at the nominal
        self.nominal_alpha = 0.0                    # alpha [rad] of the thrust table
        self.dthrust_dalpha = 0.0                   # its steady thrust's slope in alpha [lbf/rad]
        self.fallbacks = 0

    # -- evaluations at dt = 0 ---------------------------------------------------------------
    def _set(self, alpha: float, pitch: float, throttle: float | None = None) -> None:
        self._alpha.set_double_value(alpha)
        self._pitch.set_double_value(pitch)
        if throttle is not None:
            for node in self._throttles:
                node.set_double_value(throttle)

    def _evaluate(self) -> tuple[np.ndarray, float]:
        """JSBSim's (u̇, ẇ, q̇) and total thrust of the state set, time not advanced."""
        self.fdm.run_ic()
        return (np.array([node.get_double_value() for node in self._res]),
                sum(node.get_double_value() for node in self._thrusts))

    def _steady(self, alpha: float, pitch: float, throttle: float) -> tuple[np.ndarray, float]:
        """Engines at their steady state for this state and throttle, then the full residual."""
        self._set(alpha, pitch, throttle)
        self.fdm.run_ic()                   # the throttle and the air data reach the engines
        self._prop.get_steady_state()
        return self._evaluate()

    def _model(self, alpha: float, pitch: float, thrust: float) -> np.ndarray:
        """Residual with the propellers frozen plus the thrust increment to `thrust`."""
        self._set(alpha, pitch)
        r, frozen = self._evaluate()
        return r + self.B * (thrust - frozen)

    # -- the solve ---------------------------------------------------------------------------
    def _jacobian(self, y: np.ndarray) -> np.ndarray:
        """d(model residual)/d(α, pitch trim, T): finite differences for α and the pitch trim
        (each point evaluated twice, see `_inner`), B for the thrust."""
        jac = np.empty((3, 3))
        self._model(*y)
        base = self._model(*y)
        for j, h in enumerate(FD_STEP):
            z = y.copy()
            z[j] += h
            self._model(*z)
            jac[:, j] = (self._model(*z) - base) / h
        jac[:, 2] = self.B
        return jac

    def _inner(self, y: np.ndarray) -> np.ndarray | None:
        """Newton on y = (α, pitch trim, T) with the propellers frozen.

        Chord iterations with the nominal Jacobian (one dt = 0 run each), refreshed by finite
        differences when the residual stops halving. JSBSim's alpha-dot comes from the
        accelerations of the previous run, so a run's residual depends (weakly, ~1e-4 of the
        previous one's) on the run before it: the differences use steps of 1e-4 and evaluate
        every point twice, and the chord iterations converge through it as the residual does.
        """
        tol = JSBSIM_TOLERANCE * INNER_FRACTION
        jac = self.jacobian
        last = math.inf
        for _ in range(MAX_INNER):
            r = self._model(*y)
            if not np.all(np.isfinite(r)):
                return None
            size = float(np.max(np.abs(r) / tol))
            if size <= 1.0:
                return y
            if size > 0.5 * last:
                jac = self._jacobian(y)
            last = size
            try:
                y = y - np.linalg.solve(jac, r)
            except np.linalg.LinAlgError:
                return None
            if not (ALPHA_LIMITS[0] < y[0] < ALPHA_LIMITS[1]) or abs(y[1]) > 2.0:
                return None
        return None

    def solve(self, start: np.ndarray) -> np.ndarray | None:
        """(α, throttle, pitch trim) trimmed from `start`; None if not converged.

        The first Newton step uses the propellers as the reset left them (stopped: any frozen
        state will do, the model adds B (T − T_frozen)). It lands within a few hundredths of
        JSBSim's tolerance, not closer: JSBSim's alpha-dot (in CL and Cm) comes from the
        accelerations of the previous dt = 0 run, which the frozen thrust biases. The second
        step starts from propellers at their steady state near the trim and converges. The
        aircraft is left in the trimmed state, evaluated at dt = 0, and the engines run once
        more to their steady state, as after JSBSim's trim: three steady states in all.
        """
        alpha, throttle, pitch = (float(v) for v in start)
        wanted = float(np.interp(throttle, THROTTLE_GRID, self.thrust_grid))
        tol = JSBSIM_TOLERANCE * FRACTION
        offset = None                 # steady thrust minus the nominal table's, at this sample's state
        for _ in range(MAX_OUTER):
            y = self._inner(np.array([alpha, pitch, wanted]))
            if y is None:
                return None
            alpha, pitch, wanted = (float(v) for v in y)
            if offset is None:        # before any steady state: the table's slope in alpha
                offset = self.dthrust_dalpha * (alpha - self.nominal_alpha)
            shifted = wanted - offset
            if not self.thrust_grid[0] <= shifted <= self.thrust_grid[-1]:
                return None
            throttle = float(np.interp(shifted, self.thrust_grid, THROTTLE_GRID))
            r, thrust = self._steady(alpha, pitch, throttle)
            if not np.all(np.isfinite(r)):
                return None
            if np.all(np.abs(r) <= tol):
                self._prop.get_steady_state()   # leave the turboprops in their run phase
                return np.array([alpha, throttle, pitch])
            offset = thrust - float(np.interp(throttle, THROTTLE_GRID, self.thrust_grid))
        return None

    # -- the nominal, once per process ------------------------------------------------------
    def prepare(self) -> None:
        """The nominal (α, throttle, pitch trim), thrust table, B and dT/dα for this flight
        condition, from this process's cache or computed on a freshly loaded, throw-away copy of
        the aircraft and cached.

        A worker restarts its simulator at every chunk: the cache keeps the nominal's cost
        (~50 ms) to once per process. The throw-away copy keeps this instance exactly as loaded,
        so a chunk's results do not depend on whether its process computed the nominal first
        (bit for bit: an instance that ran other trims differs in the last bits).
        """
        setup = self.flight.setup
        key = (aircraft_hash(setup), str(setup.aircraft_file), setup.altitude_ft, setup.airspeed_ktas,
               setup.rate_hz)
        cached = _NOMINALS.get(key)
        if cached is None:
            scratch = type(self.flight)(replace(setup, trim="jsbsim"))
            helper = LevelTrim(scratch)
            helper.compute(lambda: scratch.trim({}))
            _NOMINALS[key] = cached = {name: getattr(helper, name) for name in NOMINAL_FIELDS}
        for name, value in cached.items():
            setattr(self, name, value.copy() if isinstance(value, np.ndarray) else value)

    def compute(self, jsbsim_trim) -> None:
        """Nominal trim by JSBSim (`jsbsim_trim()` trims with all properties as loaded), then
        the thrust table and B at the nominal, then the nominal refined by this trim."""
        result = jsbsim_trim()
        alpha, pitch = math.radians(result.alpha_deg), self._pitch.get_double_value()
        throttle = float(np.mean(result.throttle))
        self.thrust_grid = np.array([self._steady(alpha, pitch, float(x))[1] for x in THROTTLE_GRID])
        if not np.all(np.diff(self.thrust_grid) > 0):
            raise RuntimeError(f"steady-state thrust is not increasing with the throttle: {self.thrust_grid}")
        # B from two steady states around the nominal throttle at the nominal α and pitch trim.
        h = 0.02 if throttle < 0.98 else -0.02
        base_r, base_t = self._steady(alpha, pitch, throttle)
        r2, t2 = self._steady(alpha, pitch, throttle + h)
        self.B = (r2 - base_r) / (t2 - base_t)
        # How the steady thrust at a fixed throttle moves with alpha (the advance ratio).
        self.nominal_alpha = alpha
        self.dthrust_dalpha = (self._steady(alpha + 0.01, pitch, throttle)[1] - base_t) / 0.01
        self._steady(alpha, pitch, throttle)
        self.jacobian = self._jacobian(np.array([alpha, pitch, base_t]))
        refined = self.solve(np.array([alpha, throttle, pitch]))
        if refined is None:
            raise RuntimeError("the Newton trim does not converge at the nominal")
        self.nominal = refined


# -- why a level trim cannot exist: the stall -------------------------------------------------
STALL_SWEEP_DEG = np.arange(0.0, 30.01, 0.25)  # α swept at dt = 0 (three ~0.1-ms runs a point)


def lift_shortfall(flight) -> str | None:
    """When level flight needs more lift than the aircraft gives before its stall: the reason and
    what to do, else None. Called after a failed trim (it moves `ic/alpha-deg` and the pitch trim).

    Needed: CL = W / (q̄ S) (lift = weight at γ = 0; the thrust's share is neglected). Available: the
    largest trimmed CL(α) of a dt = 0 sweep of α from 0 up to the stall, where CL first stops
    increasing, the aircraft's stall property (`aero/coefficient/CL-stall` on bacm) turns non-zero or
    the pitch trim saturates, whichever comes first. Trimmed: at each α the pitch trim that zeroes q̇
    (q̇ is linear in it: one secant step), since the elevator's own lift is a few % of CL. CL is
    JSBSim's stability-axis aerodynamic force over q̄ S. The slowest level flight is then
    V √(CL needed / CL max) at this altitude and weight."""
    fdm = flight.fdm
    fdm["ic/alpha-deg"] = 0.0
    fdm.run_ic()
    area, weight, qbar = fdm["metrics/Sw-sqft"], fdm["inertia/weight-lbs"], fdm["aero/qbar-psf"]
    if not (area > 0 and weight > 0 and qbar > 0):
        return None
    stall_property = flight.has_property(STALL_PROPERTY)
    best, best_alpha = -math.inf, 0.0
    for alpha in STALL_SWEEP_DEG:
        fdm["ic/alpha-deg"] = float(alpha)
        qdot = []
        for pitch in (0.0, 0.1):
            fdm["fcs/pitch-trim-cmd-norm"] = pitch
            fdm.run_ic()
            qdot.append(fdm["accelerations/qdot-rad_sec2"])
        if qdot[1] == qdot[0]:
            return None
        pitch = -0.1 * qdot[0] / (qdot[1] - qdot[0])
        fdm["fcs/pitch-trim-cmd-norm"] = pitch
        fdm.run_ic()
        lift = fdm["forces/fsz-aero-lbs"] / (qbar * area)
        if lift <= best or abs(pitch) >= 1.0 or (stall_property and fdm[STALL_PROPERTY] != 0.0):
            break
        best, best_alpha = lift, float(alpha)
    needed = weight / (qbar * area)
    if not (np.isfinite(best) and best > 0) or not needed > best:  # no α trimmed with lift: no stall to say
        return None  # (speed_range_shortfall says what the speed is)
    slowest = flight.setup.airspeed_ktas * math.sqrt(needed / best)
    return (f"the stall: level flight needs a lift coefficient W/(qbar S) = {needed:.3f}, above the {best:.3f} "
            f"the aircraft reaches trimmed before it stalls (at alpha {best_alpha:.1f} deg); fly faster than "
            f"{math.ceil(slowest)} KTAS at this altitude, or lower, or lighter")


# -- why a level trim cannot exist: the speed ---------------------------------------------------
# what stops an engine in JSBSim's trim (FGTrimAxis sets the throttle over its whole range; FGPiston stops
# below 0.8 of its idle rpm and restarts only above it)
ENGINE_STOPPED = ("JSBSim's throttle search reaches the closed throttle, where the engine falls below its idle rpm "
                  "and a windmilling propeller does not restart it")
SPEED_SCAN_KTAS = np.arange(20.0, 601.0, 20.0)  # JSBSim's trim at each: ~60 ms a point, ~2 s in all
_SPEED_RANGES: dict[tuple, tuple[tuple[float, float] | None, int]] = {}


def level_speed_range(setup, flight_type) -> tuple[tuple[float, float] | None, int]:
    """((slowest, fastest) true airspeed [KTAS] of SPEED_SCAN_KTAS (every 20 kt) at which the aircraft, as
    loaded, trims in level flight at `setup.altitude_ft` with JSBSim's trim (flown on `flight_type`, a
    JSBSimFlight), None when none does; and at how many of the speeds that fail an engine stopped during the
    trim). Computed once per process and flight condition, on fresh copies of the aircraft, so the flight
    that failed is left as it was. (A trim near the range's edges can take a second each: no finer search.)"""
    from .base import FlightError

    key = (aircraft_hash(setup), str(setup.aircraft_file), setup.altitude_ft, setup.rate_hz)
    if key in _SPEED_RANGES:
        return _SPEED_RANGES[key]

    def trims(speed: float) -> str:
        flight = flight_type(replace(setup, airspeed_ktas=float(speed), trim="jsbsim"), preflight=False)
        flight.diagnose_trim_failures = False  # a failure is an answer here, not a question
        try:
            flight.trim({})
        except FlightError:
            return "stopped" if flight.stopped_engines() else "failed"
        return "trimmed"

    outcomes = {float(v): trims(v) for v in SPEED_SCAN_KTAS}
    found = [speed for speed, outcome in outcomes.items() if outcome == "trimmed"]
    stopped = sum(outcome == "stopped" for outcome in outcomes.values())
    _SPEED_RANGES[key] = found_range = ((min(found), max(found)) if found else None), stopped
    return found_range


def speed_range_shortfall(flight) -> str | None:
    """When the flight condition's airspeed lies outside the speeds the aircraft trims level at at its
    altitude (`level_speed_range`), or none trims there: the reason and what to do, else None."""
    setup = flight.setup
    speeds, stopped = level_speed_range(setup, type(flight))
    scanned = (f"{SPEED_SCAN_KTAS[0]:g} to {SPEED_SCAN_KTAS[-1]:g} KTAS scanned every "
               f"{SPEED_SCAN_KTAS[1] - SPEED_SCAN_KTAS[0]:g} kt with JSBSim's trim, the aircraft as loaded")
    if stopped:
        scanned += f"; at {stopped} of the speeds an engine stopped at the closed throttle the trim tries"
    if speeds is None and stopped:
        return (f"no level trim at {setup.altitude_ft:g} ft at any airspeed ({scanned}): fly lower (simulator."
                "altitude_ft in a campaign, --altitude-ft on the command line), or fly a script that sets its own "
                "throttle (scenario: {kind: script, ...})")
    if speeds is None:
        return (f"no level trim at {setup.altitude_ft:g} ft at any airspeed ({scanned}): the altitude is above "
                "what the aircraft holds level; fly lower (simulator.altitude_ft in a campaign, "
                "--altitude-ft on the command line)")
    slowest, fastest = speeds
    where = (f"the aircraft trims level at {setup.altitude_ft:g} ft from {slowest:g} to {fastest:g} KTAS ({scanned})")
    if setup.airspeed_ktas > fastest:
        return (f"{setup.airspeed_ktas:g} KTAS is faster than {where}; fly within that range (simulator.airspeed_ktas "
                "in a campaign, --airspeed-ktas on the command line)")
    if setup.airspeed_ktas < slowest:
        return (f"{setup.airspeed_ktas:g} KTAS is slower than {where}; fly within that range (simulator.airspeed_ktas "
                "in a campaign, --airspeed-ktas on the command line)")
    return None
