"""The bacm aircraft on real JSBSim: loading, trim, hold, excitation, corners, reuse; slow: every corner of
the Table 1 box and 1000 normal draws flown for 50 s."""
import itertools

import jsbsim
import numpy as np
import pytest

from paper import TABLE1
from uqflight.simulators.base import FlightError, TrimError
from uqflight.simulators.jsbsim import REPO_ROOT, quiet_jsbsim
from uqflight.simulators.scenarios.level_flight import Excitation, FlightSetup, JSBSimFlight

UQ = list(TABLE1)
TABLE1_PCT = {name: pct for name, (_, pct) in TABLE1.items()}


@pytest.fixture(scope="module")
def flight():
    return JSBSimFlight()


@pytest.fixture(scope="module")
def nominal(flight):
    return {p: flight.property_value(f"aero/uq/{p}") for p in UQ}


def test_plain_jsbsim_loads_the_aircraft_with_the_seven_coefficients():
    quiet_jsbsim()
    fdm = jsbsim.FGFDMExec(str(REPO_ROOT))
    fdm.set_debug_level(0)
    assert fdm.load_model("bacm")
    values = {p: fdm[f"aero/uq/{p}"] for p in UQ}
    assert all(v != 0.0 for v in values.values())
    assert fdm.get_propulsion().get_num_engines() == 2


def test_left_alone_the_trimmed_aircraft_holds_for_50_s():
    result = JSBSimFlight(FlightSetup(excitation=Excitation(kind="none"))).fly()
    out = result.outputs
    assert np.max(np.abs(out["h_ft"] - out["h_ft"][0])) < 2.0
    assert np.max(np.abs(out["theta_deg"] - out["theta_deg"][0])) < 0.05
    assert np.max(np.abs(out["vtas_kt"] - out["vtas_kt"][0])) < 0.2
    assert out["h_ft"][0] == pytest.approx(15000.0, abs=1e-6)
    assert out["vtas_kt"][0] == pytest.approx(200.0, abs=1e-6)


def phugoid_period_and_damping(time, v):
    """Period from the zero crossings of V - V_end, damping from successive peak ratios."""
    x = v - np.mean(v[len(v) // 2:])
    crossings = time[np.flatnonzero(np.diff(np.sign(x)) != 0)]
    period = 2 * np.mean(np.diff(crossings))
    peaks = [np.max(np.abs(x[(time >= a) & (time < b)])) for a, b in zip(crossings[:-1], crossings[1:])]
    log_dec = np.mean(np.log(np.array(peaks[:-1]) / np.array(peaks[1:]))) * 2
    zeta = log_dec / np.sqrt(4 * np.pi**2 + log_dec**2)
    return period, zeta


def test_pulse_excites_a_lightly_damped_phugoid():
    result = JSBSimFlight(FlightSetup(duration_s=300.0)).fly()
    t, v, h = result.time, result.outputs["vtas_kt"], result.outputs["h_ft"]
    late = t > 10
    period, zeta = phugoid_period_and_damping(t[late], v[late])
    print(f"phugoid period {period:.1f} s, damping ratio {zeta:.3f}")
    assert 30 < period < 70          # ~ pi sqrt(2) V/g = 47 s at 200 KTAS
    assert 0.0 < zeta < 0.2          # lightly damped, stable
    assert np.ptp(h[t <= 50]) > 20 and np.ptp(v[t <= 50]) > 1


@pytest.mark.parametrize("name", UQ)
@pytest.mark.parametrize("sign", [-1, 1])
def test_trim_at_each_end_of_the_table1_intervals(flight, nominal, name, sign):
    value = nominal[name] * (1 + sign * TABLE1_PCT[name] / 100)
    result = flight.fly({f"aero/uq/{name}": value})
    base = flight.fly({})
    changed = [abs(result.trim.alpha_deg - base.trim.alpha_deg), abs(result.trim.throttle[0] - base.trim.throttle[0]),
               abs(result.trim.elevator_deg - base.trim.elevator_deg),
               np.max(np.abs(result.outputs["q_degps"] - base.outputs["q_degps"]))]
    assert max(changed) > 1e-6, f"setting {name} changed nothing"


@pytest.mark.slow
def test_trim_succeeds_for_1000_normal_draws(flight, nominal):
    rng = np.random.default_rng(2026)
    nom = np.array([nominal[p] for p in UQ])
    sigma = np.abs(nom) * np.array([TABLE1_PCT[p] for p in UQ]) / 100 / 3
    failures = 0
    for row in nom + sigma * rng.standard_normal((1000, len(UQ))):
        try:
            flight.trim({f"aero/uq/{p}": v for p, v in zip(UQ, row)})
        except TrimError:
            failures += 1
    assert failures <= 10


def test_reused_model_matches_fresh_loads(flight):
    samples = [{"aero/uq/CL0": 0.25, "aero/uq/k2": 0.03, "ic/vt-kts": 195.0},
               {}, {"aero/uq/CL0": 0.15, "aero/uq/Cmq": -21.9, "aero/uq/k2": -0.02}]
    reused = [flight.fly(s) for s in samples]
    for s, r in zip(samples, reused):
        fresh = JSBSimFlight().fly(s)
        for name in fresh.outputs:
            np.testing.assert_allclose(r.outputs[name], fresh.outputs[name], rtol=1e-9, atol=1e-9)


def test_failed_trim_raises_and_leaves_no_bad_state(flight):
    with pytest.raises(TrimError, match="trim"):
        flight.fly({"ic/vt-kts": 60.0})
    np.testing.assert_allclose(flight.fly({}).outputs["h_ft"], JSBSimFlight().fly({}).outputs["h_ft"], rtol=1e-9)


def test_unknown_property_is_named(flight):
    with pytest.raises(KeyError, match="aero/uq/nope"):
        flight.fly({"aero/uq/nope": 1.0})


def test_excitation_shapes():
    t = np.array([0.0, 0.99, 1.0, 1.49, 1.5, 1.99, 2.0, 5.0])
    np.testing.assert_array_equal(Excitation("pulse", 1.0, 1.0, 1.0).values(t), [0, 0, 1, 1, 1, 1, 0, 0])
    np.testing.assert_array_equal(Excitation("step", 2.0, 1.0, 1.0).values(t), [0, 0, 2, 2, 2, 2, 2, 2])
    np.testing.assert_array_equal(Excitation("doublet", 1.0, 1.0, 1.0).values(t), [0, 0, 1, 1, -1, -1, 0, 0])
    with pytest.raises(ValueError, match="excitation.kind"):
        Excitation("ramp")


def lateral_response(flight, control: str, seconds: float = 90.0):
    """phi and beta [deg] once per second after a 1-s pulse of 0.2 on `control` from the trim."""
    flight.trim({})
    fdm, steps_per_s = flight.fdm, int(flight.setup.rate_hz)
    phi, beta = [], []
    for i in range(int(seconds * steps_per_s)):
        fdm[control] = 0.2 if steps_per_s <= i < 2 * steps_per_s else 0.0
        fdm.run()
        if (i + 1) % steps_per_s == 0:
            phi.append(fdm["attitude/phi-deg"])
            beta.append(fdm["aero/beta-deg"])
    fdm[control] = 0.0
    return np.array(phi), np.array(beta)


def test_lateral_directional_modes_are_stable(flight):
    # Spiral: the bank left by an aileron pulse decays (slowly) instead of growing.
    phi, _ = lateral_response(flight, "fcs/aileron-cmd-norm")
    assert 2.0 < abs(phi[9]) and abs(phi[-1]) < 0.9 * abs(phi[9])
    # Dutch roll: the sideslip of a rudder pulse is damped within half a minute.
    _, beta = lateral_response(flight, "fcs/rudder-cmd-norm")
    assert np.abs(beta).max() > 1.0 and np.abs(beta[29:]).max() < 0.1 * np.abs(beta).max()


def table1_values(flight, factors):
    return {prop: flight.property_value(prop) * (1 + f * pct / 100)
            for (prop, pct), f in zip(TABLE1.values(), factors)}



@pytest.mark.slow
def test_every_corner_of_the_table1_box_flies_50_s(flight):
    """All 128 corners trim and fly the pulse without leaving the envelope; drag stays positive."""
    for signs in itertools.product((-1, 1), repeat=len(TABLE1)):
        result = flight.fly(table1_values(flight, signs))
        assert flight.fdm["aero/force/drag-polar"] > 0, signs
        assert np.ptp(result.outputs["h_ft"]) < 200, signs



@pytest.mark.slow
def test_1000_normal_draws_fly_50_s(flight):
    """Trim and the whole excited flight succeed for at least 99 % of the normal model's draws."""
    rng = np.random.default_rng(7)
    failures = 0
    for factors in rng.standard_normal((1000, len(TABLE1))) / 3:
        try:
            flight.fly(table1_values(flight, factors))
        except FlightError:
            failures += 1
    assert failures <= 10

