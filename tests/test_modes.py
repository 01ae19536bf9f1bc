"""The modes of the linearised model: the classifier on a system with known eigenvalues, and bacm's
nominal phugoid and short period from JSBSim's FGLinearization against the flight's."""
import math

import numpy as np
import pytest
from conftest import ROOT

from uqflight.campaign import load_campaign
from uqflight.quantities.modes import classified_modes
from uqflight.quantities.recorder import QuantityRecorder
from uqflight.simulators.aircraft_properties import AircraftProperties

NAMES = ["Vt", "Alpha", "Theta", "Q", "Rpm0", "Rpm1", "Beta", "Phi", "P", "Psi", "R", "Latitude", "Longitude",
         "Alt"]


def oscillation(system, first: str, second: str, sigma: float, omega: float) -> None:
    """Put the pair σ ± iω on the plane of two states."""
    i, j = NAMES.index(first), NAMES.index(second)
    system[np.ix_([i, j], [i, j])] = [[sigma, omega], [-omega, sigma]]


def test_the_classifier_reads_the_eigenvectors_not_the_frequencies():
    # a phugoid in (Vt, Theta), a short period in (Alpha, Q) and a Dutch roll in (Beta, R) that is
    # faster than the short period: picking the fastest oscillation would take the Dutch roll
    system = np.diag(-np.arange(1.0, 15.0))
    oscillation(system, "Vt", "Theta", -0.0084, 0.1359)
    oscillation(system, "Alpha", "Q", -0.597, 1.392)
    oscillation(system, "Beta", "R", -0.164, 1.9)
    modes = classified_modes(NAMES, system, np.r_[337.5, np.zeros(13)])
    phugoid, short = complex(-0.0084, 0.1359), complex(-0.597, 1.392)
    assert modes["phugoid_period_s"] == pytest.approx(2 * math.pi / 0.1359, rel=1e-12)
    assert modes["phugoid_damping"] == pytest.approx(0.0084 / abs(phugoid), rel=1e-12)
    assert modes["short_period_frequency_rad_s"] == pytest.approx(abs(short), rel=1e-12)
    assert modes["short_period_damping"] == pytest.approx(0.597 / abs(short), rel=1e-12)


def test_an_overdamped_short_period_is_undefined():
    system = np.diag(-np.arange(1.0, 15.0))
    oscillation(system, "Vt", "Theta", -0.0084, 0.1359)
    modes = classified_modes(NAMES, system, np.r_[337.5, np.zeros(13)])
    assert math.isnan(modes["short_period_frequency_rad_s"]) and math.isnan(modes["short_period_damping"])
    assert modes["phugoid_period_s"] == pytest.approx(2 * math.pi / 0.1359, rel=1e-12)


@pytest.mark.slow  # one linearisation of bacm: 5-20 s (JSBSim settles both turboprops at every perturbation)
def test_bacm_nominal_modes_match_the_flight_and_leave_the_flight_as_it_was():
    from uqflight.simulators import make_simulator

    campaign = load_campaign(ROOT / "campaigns" / "bacm-modes.yaml", read_aircraft=AircraftProperties)
    names = [p.name for p in campaign.parameters]
    properties = [p.property for p in campaign.parameters]
    nominal = np.array([p.nominal for p in campaign.parameters])
    simulator = make_simulator(campaign.simulator, names, properties, ROOT / "campaigns")
    recorder = QuantityRecorder(campaign.quantities, simulator.source)
    recorder.reset()
    with_modes = simulator.evaluate(nominal, (recorder,))
    found = recorder.result()
    # the phugoid measured from the 300-s flight: 46.2 s, ζ 0.060 (notes/jsbsim-scripts-turbulence-modes.md);
    # "within a few percent": 2 % on the period, 0.005 on the damping ratio
    assert found["phugoid_period"] == pytest.approx(46.2, rel=0.02)
    assert found["phugoid_damping"] == pytest.approx(0.060, abs=0.005)
    assert found["short_period_omega"] == pytest.approx(1.515, rel=0.01)  # not the Dutch roll's 1.354
    assert found["short_period_zeta"] == pytest.approx(0.394, abs=0.005)
    # the linearisation restores the trimmed state to ~1e-12 (dt, wind, engines): the flight after it
    # differs from a flight without it by 6e-10 of the output at most (measured), 1e-8 allowed
    simulator.restart()
    without = simulator.evaluate(nominal)
    for name, history in without.items():
        assert np.abs(with_modes[name] - history).max() <= 1e-8 * np.abs(history).max(), name


@pytest.mark.slow  # three linearisations of bacm: 15-60 s
def test_a_runs_modes_do_not_depend_on_the_run_flown_before_it_in_its_chunk():
    # JSBSim's linearisation of a reused aircraft differs (0.1 % on the phugoid period of one Table 1
    # point) and can take minutes: each run with modes is flown on a freshly loaded one
    from uqflight.running.runner import worker_spec
    from uqflight.parameters import to_physical
    from uqflight.running.worker import run_chunk

    campaign = load_campaign(ROOT / "campaigns" / "bacm-modes.yaml", read_aircraft=AircraftProperties)
    kappa = to_physical(campaign.parameters, campaign.design().xi)[16:18]
    spec, outputs = worker_spec(campaign), list(campaign.simulator["outputs"])
    pair = run_chunk(spec, np.arange(16, 18), kappa, 1001, outputs)[3]
    alone = run_chunk(spec, np.arange(17, 18), kappa[1:], 1001, outputs)[3]
    for key, values in alone.items():
        np.testing.assert_array_equal(pair[key][1:], values, err_msg=str(key))
