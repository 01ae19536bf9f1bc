"""The atmosphere as an input: fixed settings for every run (`simulator.properties`), a still-air trim with
turbulence from t = 0 of the recorded flight, and the turbulence seed as a parameter (real JSBSim, bacm)."""
import numpy as np
import pytest
from conftest import assert_same_results, cli_in_process

from uqflight.campaign import CampaignError, load_campaign
from uqflight.running.runner import run_campaign
from uqflight.simulators import JSBSimSimulator
from uqflight.simulators.spec import SimulatorSpec
from uqflight.simulators.aircraft_properties import AircraftProperties
from uqflight.analysis.statistics import analyse, summary_json

MODERATE = {"atmosphere/turb-type": 3, "atmosphere/turbulence/milspec/severity": 4,
            "atmosphere/turbulence/milspec/windspeed_at_20ft_AGL-fps": 50}
SIMULATOR = {"kind": "jsbsim", "aircraft": "bacm", "duration_s": 5.0, "output_rate_hz": 10.0}


def simulator(properties=None, seeded=True):
    config = {**SIMULATOR, **({"properties": properties} if properties else {})}
    properties = ["aero/uq/CL0"] + (["atmosphere/randomseed"] if seeded else [])
    return JSBSimSimulator(SimulatorSpec.from_checked(config), properties)


def kappa(seed, cl0=0.2):
    return np.array([cl0, float(seed)])


def test_the_trim_is_flown_in_still_air_and_the_turbulence_starts_at_t_0():
    calm, rough = simulator(), simulator(MODERATE)
    trims = []
    for sim in (calm, rough):
        trim = sim.flight.trim({"aero/uq/CL0": 0.2})
        trims.append((trim.alpha_deg, trim.throttle, trim.elevator_deg))
    assert trims[0] == trims[1]  # bit for bit: the turbulence settings wait for the trim
    still, turbulent = calm.evaluate(kappa(7)), rough.evaluate(kappa(7))
    for name in still:
        assert still[name][0] == turbulent[name][0]  # t = 0 is the trimmed state in both
    assert np.abs(still["alpha_deg"] - turbulent["alpha_deg"]).max() > 1e-3  # then the air moves


def test_a_seed_gives_its_own_turbulence_and_the_same_seed_the_same_flight():
    sim = simulator(MODERATE)
    one, other, again = (sim.evaluate(kappa(s))["alpha_deg"] for s in (1, 2, 1))
    fresh = simulator(MODERATE).evaluate(kappa(1))["alpha_deg"]
    # a reused model agrees with a fresh one to ~1e-13 (bacm's turboprop keeps state across resets; the
    # runner reloads the aircraft at every chunk for bit-identical files): the stream itself is the same
    np.testing.assert_allclose(again, one, rtol=1e-11)
    np.testing.assert_allclose(fresh, one, rtol=1e-11)
    assert np.abs(one - other).max() > 1e-3


def test_without_turbulence_the_seed_changes_nothing():
    sim = simulator({**MODERATE, "atmosphere/turbulence/milspec/severity": 0})
    one, other = (sim.evaluate(kappa(s)) for s in (1, 123456))
    for name in one:  # the reused model's 1e-13 (see above), nothing of the seed's 1e-3
        np.testing.assert_allclose(one[name], other[name], rtol=0, atol=1e-11 * np.abs(one[name]).max())


def test_without_a_seed_parameter_every_run_flies_the_same_stream():
    """No seed parameter: the generator restarts from the aircraft's seed at every run, so a run's
    turbulence does not depend on what the model flew before."""
    sim = simulator(MODERATE, seeded=False)
    first = sim.evaluate(np.array([0.2]))["alpha_deg"]
    sim.evaluate(np.array([0.21]))  # the generator would go on from here if the run did not restart it
    np.testing.assert_allclose(sim.evaluate(np.array([0.2]))["alpha_deg"], first, rtol=1e-11)  # see above


CAMPAIGN = """name: turb
seed: {seed}
simulator:
  kind: jsbsim
  aircraft: bacm
  duration_s: 4
  output_rate_hz: 10
  outputs: [alpha_deg, h_ft]
  properties: {properties}
parameters:
  CL0: {{property: aero/uq/CL0, distribution: normal, interval_pct: 10}}
  turbulence: {{property: atmosphere/randomseed, distribution: seed}}
design: {{kind: pick_freeze, samples: 8}}
method: {{kind: monte_carlo}}
analysis: {{band_samples: 200, bootstrap: 50}}
"""


def write(folder, name, seed=3, properties=None):
    props = properties if properties is not None else MODERATE
    path = folder / f"{name}.yaml"
    path.write_text(CAMPAIGN.format(seed=seed, properties="{" + ", ".join(f"{k}: {v}" for k, v in props.items()) + "}"))
    return path


@pytest.mark.slow  # four campaigns of 32 flights; the default suite flies the same turbulence in process (above)
def test_turbulence_campaigns_are_reproducible_and_their_seed_matters_only_when_the_air_moves(tmp_path):
    runs = {}
    for name, seed, props, workers in (("a", 3, None, 1), ("b", 3, None, 2), ("c", 4, None, 1),
                                       ("calm", 3, {**MODERATE, "atmosphere/turbulence/milspec/severity": 0}, 2)):
        runs[name] = tmp_path / f"{name}.h5"
        run_campaign(load_campaign(write(tmp_path, name, seed, props), AircraftProperties), out=runs[name], workers=workers)
    assert_same_results(runs["a"], runs["b"])  # 1 or 2 workers: the same bits
    import h5py
    with h5py.File(runs["a"]) as a, h5py.File(runs["c"]) as c:
        assert not np.array_equal(a["outputs/alpha_deg"][:], c["outputs/alpha_deg"][:])
    calm = summary_json(analyse(runs["calm"]))["outputs"]["alpha_deg"]
    first, total = (np.array(calm[k]["turbulence"], dtype=float) for k in ("sobol_first", "sobol_total"))
    assert np.all(np.isnan(total) | (np.abs(total) < 1e-12))  # no turbulence: the seed explains nothing
    assert np.all(np.isnan(first) | (np.abs(first) < 1e-12))
    rough = summary_json(analyse(runs["a"]))["outputs"]["alpha_deg"]
    assert rough["variance_split"]["seeds"]["total"][-1] > 0.5  # moderate turbulence dominates ±10 % CL0


@pytest.mark.slow
def test_a_turbulence_campaign_on_dask_is_bit_identical(tmp_path):
    pytest.importorskip("dask.distributed")
    local, dask = tmp_path / "l.h5", tmp_path / "d.h5"
    campaign = load_campaign(write(tmp_path, "t"), AircraftProperties)
    run_campaign(campaign, out=local, workers=1)
    run_campaign(campaign, out=dask, workers=2, executor="dask")
    assert_same_results(local, dask)


@pytest.mark.parametrize("properties, field", [
    ({"aero/uq/CL0": 0.2}, "simulator.properties.aero/uq/CL0"),
    ({"atmosphere/turb-typo": 3}, "simulator.properties.atmosphere/turb-typo"),
])
def test_a_fixed_property_that_a_parameter_sets_or_the_aircraft_lacks_is_refused(tmp_path, properties, field):
    path = write(tmp_path, "bad", properties=properties)
    with pytest.raises(CampaignError, match=field):
        load_campaign(path, AircraftProperties)
    done = cli_in_process("plan", path)
    assert done.returncode == 2 and field in done.stderr
