"""Long checks of the aircraft over the whole uncertainty box (`make test-slow`)."""
import itertools

import numpy as np
import pytest

from uqflight.paper import TABLE1
from uqflight.simulators.base import FlightError
from uqflight.simulators.jsbsim import JSBSimFlight

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def flight():
    return JSBSimFlight()


def table1_values(flight, factors):
    return {prop: flight.property_value(prop) * (1 + f * pct / 100)
            for (prop, pct), f in zip(TABLE1.values(), factors)}


def test_every_corner_of_the_table1_box_flies_50_s(flight):
    """All 128 corners trim and fly the pulse without leaving the envelope; drag stays positive."""
    for signs in itertools.product((-1, 1), repeat=len(TABLE1)):
        result = flight.fly(table1_values(flight, signs))
        assert flight.fdm["aero/force/drag-polar"] > 0, signs
        assert np.ptp(result.outputs["h_ft"]) < 200, signs


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
