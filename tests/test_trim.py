"""The Newton level-flight trim (uqflight.simulators.trim) against JSBSim's own, on real JSBSim.

Agreement tolerance, per sample: the change of (alpha, throttle, pitch trim) that moves JSBSim's
accelerations (u̇, ẇ, q̇) by JSBSim's own trim tolerances (1e-3 ft/s², 1e-3 ft/s², 1e-4 rad/s²;
FGTrim.cpp), |J⁻¹|·tol with J the Jacobian of the residual (engines at steady state) at the
sample's trim. JSBSim's trim is only determined that closely; ours converges to 1/100 of it.
The elevator's tolerance follows from the pitch trim's (elevator = 0.349 rad × pitch-trim-sum).
"""
import itertools
import math

import numpy as np
import pytest

import uqflight.simulators.trim as trim_module
from paper import TABLE1
from uqflight.simulators.scenarios.level_flight import FlightSetup, JSBSimFlight
from uqflight.simulators.trim import FRACTION, JSBSIM_TOLERANCE, LATERAL

UQ = list(TABLE1)
PCT = np.array([pct for _, pct in TABLE1.values()]) / 100
ELEVATOR_DEG_PER_UNIT = math.degrees(0.349)   # bacm: fcs/elevator-control range ±0.349 rad


@pytest.fixture(scope="module")
def newton():
    return JSBSimFlight(FlightSetup(trim="newton"))


@pytest.fixture(scope="module")
def reference():
    return JSBSimFlight(FlightSetup(trim="jsbsim"))


@pytest.fixture(scope="module")
def nominal(newton):
    return np.array([newton.property_value(f"aero/uq/{p}") for p in UQ])


def settings_of(row):
    return {f"aero/uq/{p}": float(v) for p, v in zip(UQ, row)}


def state_tolerance(flight: JSBSimFlight, alpha_deg: float, throttle: float, pitch: float,
                    towards: float) -> np.ndarray:
    """|J⁻¹|·(JSBSim's tolerances) at a trimmed state: (alpha [deg], throttle, elevator [deg]).

    The throttle's difference is one-sided, 1e-4 towards `towards` (JSBSim's throttle): the
    engine's power table has kinks in N1 (bacm: at throttle 0.65, where dT/dthrottle triples),
    and a step across one would take the slope of the other side.
    """
    level = flight._level_trim()
    x = np.array([math.radians(alpha_deg), pitch, throttle])
    steps = (1e-4, 1e-4, 1e-4 if towards >= throttle else -1e-4)
    base, _ = level._steady(x[0], x[1], x[2])
    jac = np.empty((3, 3))
    for j, h in enumerate(steps):
        z = x.copy()
        z[j] += h
        jac[:, j] = (level._steady(z[0], z[1], z[2])[0] - base) / h
    bound = np.abs(np.linalg.inv(jac)) @ JSBSIM_TOLERANCE     # (alpha rad, pitch trim, throttle)
    return np.array([math.degrees(bound[0]), bound[2], bound[1] * ELEVATOR_DEG_PER_UNIT])


def compare(newton: JSBSimFlight, reference: JSBSimFlight, settings: dict) -> np.ndarray:
    """Trim both ways; check ours; return |difference| / tolerance for alpha, theta, throttle (each
    engine) and elevator."""
    fallbacks = newton._level_trim().fallbacks
    ours = newton.trim(settings)
    assert newton._level_trim().fallbacks == fallbacks, f"Newton trim fell back to JSBSim's for {settings}"
    pitch = newton.fdm["fcs/pitch-trim-cmd-norm"]
    residuals = np.array(list(ours.residuals.values()))
    assert np.all(np.abs(residuals) <= FRACTION * JSBSIM_TOLERANCE), ours.describe()
    lateral = np.array([newton.fdm[p] for p in LATERAL])
    assert np.all(np.abs(lateral) <= FRACTION * JSBSIM_TOLERANCE), f"lateral accelerations {lateral}"
    assert ours.theta_deg == pytest.approx(ours.alpha_deg, abs=1e-9)          # gamma = 0
    assert ours.throttle[0] == ours.throttle[1]
    theirs = reference.trim(settings)
    tol = state_tolerance(newton, ours.alpha_deg, ours.throttle[0], pitch, theirs.throttle[0])
    diff = np.abs([ours.alpha_deg - theirs.alpha_deg, ours.theta_deg - theirs.theta_deg,
                   ours.throttle[0] - theirs.throttle[0], ours.throttle[1] - theirs.throttle[1],
                   ours.elevator_deg - theirs.elevator_deg])
    return diff / tol[[0, 0, 1, 1, 2]]


def test_trim_choice_is_validated():
    with pytest.raises(ValueError, match="trim"):
        FlightSetup(trim="simplex")


def test_nominal_trim_agrees_with_jsbsim(newton, reference):
    ratio = compare(newton, reference, {})
    assert np.all(ratio <= 1.0), ratio


@pytest.mark.parametrize("name", UQ)
@pytest.mark.parametrize("sign", [-1, 1])
def test_trim_agrees_with_jsbsim_at_each_end_of_the_table1_intervals(newton, reference, nominal, name, sign):
    row = nominal.copy()
    row[UQ.index(name)] *= 1 + sign * PCT[UQ.index(name)]
    ratio = compare(newton, reference, settings_of(row))
    print(f"{name} {sign:+d}: |difference| / tolerance = {np.array2string(ratio, precision=3)}")
    assert np.all(ratio <= 1.0), ratio


def test_fallback_to_jsbsims_trim_when_newton_does_not_converge(newton, reference, monkeypatch):
    settings = {"aero/uq/CL0": 0.21}
    level = newton._level_trim()
    before = level.fallbacks
    monkeypatch.setattr(trim_module, "MAX_OUTER", 0)       # the Newton loop gives up at once
    fell_back = newton.trim(settings)
    assert level.fallbacks == before + 1
    theirs = reference.trim(settings)
    assert fell_back.alpha_deg == pytest.approx(theirs.alpha_deg, abs=1e-9)
    assert fell_back.throttle == pytest.approx(theirs.throttle, abs=1e-9)
    assert fell_back.residuals == pytest.approx(theirs.residuals, abs=1e-9)


def test_a_chunk_is_the_same_bit_for_bit_whether_or_not_its_process_computed_the_nominal():
    samples = [{"aero/uq/CL0": 0.25, "aero/uq/k2": 0.03}, {"aero/uq/Cm0": 0.055, "aero/uq/CD0": 0.033}]
    trim_module._NOMINALS.clear()
    computed = JSBSimFlight()                 # computes the nominal (on a throw-away copy)
    first = [computed.fly(s) for s in samples]
    assert trim_module._NOMINALS
    cached = JSBSimFlight()                   # takes it from the cache
    second = [cached.fly(s) for s in samples]
    for a, b in zip(first, second):
        for name in a.outputs:
            np.testing.assert_array_equal(a.outputs[name], b.outputs[name])
        assert (a.trim.alpha_deg, a.trim.throttle, a.trim.elevator_deg) == \
            (b.trim.alpha_deg, b.trim.throttle, b.trim.elevator_deg)


@pytest.mark.slow
def test_trim_agrees_with_jsbsim_at_the_128_corners_and_1000_normal_draws(newton, reference, nominal):
    corners = [nominal * (1 + np.array(signs) * PCT) for signs in itertools.product([-1, 1], repeat=len(UQ))]
    rng = np.random.default_rng(2026)
    draws = list(nominal + np.abs(nominal) * PCT / 3 * rng.standard_normal((1000, len(UQ))))
    for label, rows in (("corners", corners), ("normal draws", draws)):
        ratios = np.array([compare(newton, reference, settings_of(row)) for row in rows])
        print(f"{label}: max |difference| / tolerance (alpha, theta, throttle x2, elevator) = "
              f"{np.array2string(ratios.max(axis=0), precision=3)}")
        assert np.all(ratios <= 1.0), ratios.max(axis=0)
