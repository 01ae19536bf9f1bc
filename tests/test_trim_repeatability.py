"""The simulator's own resolution: two trims that both pass the checks leave residual accelerations that
drift the outputs apart; a spread of the outputs below that drift is not the inputs', and its Sobol'
indices are null. Closed form on a Python model first, then the aircraft."""
import h5py
import numpy as np
import pytest
from conftest import NORMAL_2D, ROOT, closed_form_campaign, run_python_campaign, strict_json

from uqflight.campaign import load_campaign
from uqflight.simulators.aircraft_properties import AircraftProperties
from uqflight.running.runner import nominal_kappa, run_campaign, worker_spec
from uqflight.analysis.statistics import analyse, summary_json
from uqflight.store import ResultStore


def test_a_spread_below_the_recorded_resolution_is_unresolved(tmp_path):
    """y = 15000 + t (x1² + x2²), t = 0, 0.25, ..., 1, on a 4×4 Gauss–Hermite grid: std(t) = 2t exactly
    (var(x1² + x2²) = 4). A recorded resolution of 0.75 at t = 0.25 (std 0.5) and 1.95 at t = 1 (std 2)
    leaves t = 0.25 unresolved and t = 1 resolved; t = 0 stays unresolved (rounding only)."""
    results = run_python_campaign(tmp_path, closed_form_campaign("sq", "sum_of_squares", NORMAL_2D,
                                                     "{kind: tensor_grid, points: 4}",
                                                     "method: {kind: pseudo_galerkin, order: 2}\n"))
    with ResultStore.open(results) as store:
        assert store.resolution("y") is None  # a Python model has no trim
        np.testing.assert_allclose(np.sqrt(analyse(results).outputs["y"].variance), 2 * store.time, atol=1e-9)
    with h5py.File(results, "r+") as f:
        f.create_group("resolution").create_dataset("y", data=[0.0, 0.75, 0.75, 0.75, 1.95])
    y = strict_json(summary_json(analyse(results)))["outputs"]["y"]
    assert y["resolved"] == [False, False, True, True, True]
    assert y["sobol_first"]["x1"][:2] == [None, None] and y["sobol_first"]["x1"][2] == pytest.approx(0.5, abs=1e-12)


@pytest.fixture(scope="module")
def nominal_resolution():
    campaign = load_campaign(ROOT / "campaigns" / "ci-small.yaml", AircraftProperties)
    simulator = worker_spec(campaign).build()
    return simulator.setup.time, simulator.resolution(nominal_kappa(campaign))


def test_the_aircraft_trims_drift_apart_slowly_and_monotonically(nominal_resolution):
    """bacm nominal, Newton against JSBSim's trim (measured 2026-11-26: q 8.6e-6 deg/s, h 6.9e-5 ft at
    1.4 s): zero at t = 0 for q and h, never decreasing, and far below the spread the pulse makes."""
    time, drift = nominal_resolution
    assert set(drift) == {"alpha_deg", "theta_deg", "h_ft", "q_degps", "vtas_kt"}
    for name, values in drift.items():
        assert values.shape == time.shape and np.all(np.diff(values) >= 0), name
    assert drift["q_degps"][0] == 0.0 and drift["h_ft"][0] == 0.0
    at_1s = np.searchsorted(time, 1.0)
    assert 1e-7 < drift["q_degps"][at_1s] < 1e-4  # deg/s: residual pitch acceleration within the tolerance
    assert drift["h_ft"][-1] < 0.05 and drift["vtas_kt"][-1] < 0.01 and drift["alpha_deg"][-1] < 1e-3


@pytest.mark.slow
def test_the_aircraft_file_records_it_and_q_before_the_pulse_is_unresolved(tmp_path, nominal_resolution):
    """ci-small: q's spread before the pulse (~5e-8 deg/s, trim residuals) is below the trims' drift
    (~1e-6): its Sobol' indices are null there, and defined once the pulse moves q (std ~1e-2)."""
    out = tmp_path / "ci.h5"
    run_campaign(load_campaign(ROOT / "campaigns" / "ci-small.yaml", AircraftProperties), out=out, workers=1)
    time, drift = nominal_resolution
    with ResultStore.open(out) as store:
        np.testing.assert_array_equal(store.resolution("q_degps"), drift["q_degps"])
    q = analyse(out).outputs["q_degps"]
    before, after = (time > 0) & (time < 1.0), (time >= 1.2) & (time <= 3.0)
    assert not q.resolved[before].any() and q.resolved[after].all()
    assert np.isnan(q.sobol_first["Cmq"][before]).all() and np.isfinite(q.sobol_first["Cmq"][after]).all()
