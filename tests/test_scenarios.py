"""Scenario kinds (simulator.scenario): a JSBSim run script flown as a campaign records what plain JSBSim
records, writes and prints nothing, travels to workers in the bundle, and is refused at plan when it
cannot be flown; both kinds' flight loops feed per-step observers the values plain JSBSim steps give."""
import itertools
import os
import shutil
from pathlib import Path

import h5py
import jsbsim
import numpy as np
import pytest
import yaml

from conftest import ROOT, assert_same_results, cli
from test_distributed_aircraft import cluster  # noqa: F401 - the separately started Dask workers
from uqflight.campaign import CampaignError, load_campaign, parse_campaign
from uqflight.running.runner import run_campaign, worker_spec
from uqflight.simulators import make_simulator
from uqflight.simulators.bundle import AircraftMismatch
from uqflight.simulators.kinds import localized
from uqflight.simulators.jsbsim import quiet_jsbsim
from uqflight.simulators.scenarios.level_flight import FlightSetup, JSBSimFlight
from uqflight.simulators.aircraft_properties import AircraftProperties
from uqflight.simulators.scenarios.script import ScriptFile, jsbsim_scripts
from uqflight.simulators.spec import SimulatorSpec

CRUISE = jsbsim_scripts() / "c172_cruise_8K.xml"  # c172x, trims itself at 1 s, autopilot from 5 s, gust at 10 s
PARAMETERS = {
    "CL": {"function": "CLwbh", "perturbation": "scale", "distribution": "uniform", "interval_pct": 5},
    "wind": {"property": "atmosphere/wind-north-fps", "distribution": "uniform", "lower": -5, "upper": 5},
}


def script_campaign(tmp_path, scenario=None, name="cruise", **simulator):
    """A script campaign file in tmp_path: c172_cruise_8K cut at 6 s, 10 Hz, a lift scale and a wind."""
    simulator = {"kind": "jsbsim", "scenario": scenario or {"kind": "script", "script": "c172_cruise_8K", "end_s": 6},
                 "output_rate_hz": 10, "outputs": ["h_ft", "vtas_kt", "attitude/phi-deg"], **simulator}
    text = yaml.safe_dump({"name": name, "simulator": simulator, "parameters": PARAMETERS,
                           "design": {"kind": "sparse_grid", "level": 1}, "execution": {"chunk": 2}})
    path = tmp_path / f"{name}.yaml"
    path.write_text(text)
    return path


def plain_jsbsim(script: Path, steps: int, every: int, properties, out: Path, initfile: str = ""):
    """JSBSim's own loop over `script`: load_script, run_ic, run; `properties` at t = 0 and every `every`
    steps, and the simulator's times. Its output files go to `out` (not into JSBSim's package)."""
    quiet_jsbsim()
    fdm = jsbsim.FGFDMExec(jsbsim.get_default_root_dir())
    fdm.set_debug_level(0)
    fdm.set_output_path(str(out))
    assert fdm.load_script(str(script), 0.0, initfile)
    fdm.disable_output()
    fdm.run_ic()
    rows, times = [[fdm[p] for p in properties]], [fdm.get_sim_time()]
    for i in range(1, steps + 1):
        assert fdm.run()
        if i % every == 0:
            rows.append([fdm[p] for p in properties])
            times.append(fdm.get_sim_time())
    return np.array(rows), np.array(times)


def test_a_shipped_script_at_nominal_records_what_plain_jsbsim_records_and_a_perturbation_changes_it(tmp_path):
    campaign = load_campaign(script_campaign(tmp_path), AircraftProperties)
    summary = run_campaign(campaign, out=tmp_path / "cruise.h5", workers=1)
    with h5py.File(summary.path, "r") as f:
        xi, status, time = f["samples/xi"][()], f["samples/status"][()], f["time"][()]
        outputs = {name: f["outputs/" + name.replace("/", "|")][()] for name in ("h_ft", "vtas_kt", "attitude/phi-deg")}
        assert '"kind": "script"' in f.attrs["scenario"]
    assert np.all(status == 0)
    steps = int(round(6 / 0.0083333))  # 720 steps of dt = 0.0083333 s end at 5.99998 s, within 0.99 dt of 6
    plain, plain_time = plain_jsbsim(CRUISE, steps, 12, ("position/h-sl-ft", "velocities/vtrue-kts",
                                                         "attitude/phi-deg"), tmp_path)
    np.testing.assert_array_equal(time, plain_time)  # the simulator's own times, not k / rate
    assert time[1] == pytest.approx(0.0999996, abs=1e-12)
    centre = int(np.flatnonzero(np.all(xi == 0, axis=1))[0])  # the sparse grid's centre: every parameter nominal
    for column, name in enumerate(outputs):
        # 1e-9 relative: the nominal scale multiplies CLwbh by exactly 1 and the wind is 0, so only the
        # patched copy's XML differs from JSBSim's aircraft; the values agree far below this
        np.testing.assert_allclose(outputs[name][centre], plain[:, column], rtol=1e-9, atol=1e-9 * 4000)
    others = [row for row in range(len(xi)) if row != centre]
    # a 5 % lift change or a 5 ft/s wind moves the altitude by more than a foot within 6 s (the trim at 1 s
    # resets the state, the autopilot holds 4000 ft from 5 s); 1 ft is a million times the agreement above
    for row in others:
        assert np.max(np.abs(outputs["h_ft"][row] - outputs["h_ft"][centre])) > 1e-3


def test_a_script_writes_and_prints_nothing(tmp_path, monkeypatch, capfd):
    """c172_head_wind names an <output> file and c172x an <output> of its own: without care JSBSim writes
    them beside the root (here JSBSim's package); its notify messages would go to stdout. (Nothing in the
    temporary directory either: test_jsbsim_directives.py.)"""
    monkeypatch.chdir(tmp_path)
    watched = [tmp_path, Path(jsbsim.get_default_root_dir()), jsbsim_scripts()]
    before = [sorted(os.listdir(folder)) for folder in watched]
    config = {"kind": "jsbsim", "scenario": {"kind": "script", "script": "c172_head_wind", "end_s": 1.5},
              "output_rate_hz": 10, "outputs": ["h_ft"]}
    simulator = make_simulator(SimulatorSpec.from_checked(config), ["w"], ["atmosphere/wind-east-fps"], tmp_path)
    result = simulator.evaluate(np.array([2.0]))
    assert result["h_ft"].shape == (len(simulator.setup.time),) and np.all(np.isfinite(result["h_ft"]))
    assert [sorted(os.listdir(folder)) for folder in watched] == before
    captured = capfd.readouterr()
    assert captured.out == "" and captured.err == ""


@pytest.mark.slow
def test_what_a_script_prints_in_the_workers_never_reaches_the_terminal(tmp_path):
    """c3104's events <notify format="kml">, which JSBSim writes to its standard output whatever its
    logger and debug level: 20 lines per run in every worker, flooding the runner's terminal."""
    text = yaml.safe_dump({"name": "c310", "simulator": {
        "kind": "jsbsim", "scenario": {"kind": "script", "script": "c3104", "end_s": 1}, "output_rate_hz": 10,
        "outputs": ["h_ft"]}, "parameters": {"CL": {"function": "CLalpha", "perturbation": "scale",
                                                     "distribution": "uniform", "interval_pct": 5}},
        "design": {"kind": "monte_carlo", "samples": 2}, "execution": {"workers": 1}})
    (tmp_path / "c310.yaml").write_text(text)
    done = cli("run", tmp_path / "c310.yaml", "--out", tmp_path / "c310.h5")
    assert done.returncode == 0, done.stderr
    assert "Placemark" not in done.stdout + done.stderr and "Start engine" not in done.stdout + done.stderr
    assert len(done.stdout.splitlines()) == 1, done.stdout  # run's summary line alone


class Altitude:
    """An observer: the altitude and the time at every integration step."""

    properties = ("position/h-sl-ft", "simulation/sim-time-sec")

    def __init__(self):
        self.t, self.values, self.trims = [], [], 0

    def step(self, t, values):
        self.t.append(t)
        self.values.append(list(values))

    def at_trim(self, fdm):
        assert not self.t  # after the trim, before the first step
        self.trims += 1


def test_a_script_that_sets_an_output_property_flies_without_the_outputs(tmp_path):
    """c1723 sets simulation/output/log_rate_hz at about 21.9 s, a property JSBSim ties to c172x's <output>,
    which uqflight removes: the flight declares it instead, so the event sets it and the flight goes on."""
    assert ScriptFile.read(jsbsim_scripts() / "c1723.xml").output_properties == ("simulation/output/log_rate_hz",)
    config = {"kind": "jsbsim", "scenario": {"kind": "script", "script": "c1723", "end_s": 23},
              "output_rate_hz": 10, "outputs": ["h_ft"]}
    simulator = make_simulator(SimulatorSpec.from_checked(config), ["CL"], ["aero/uq/scale/CLwbh"], tmp_path)
    result = simulator.evaluate(np.array([1.0]))
    assert simulator.setup.time[-1] > 22.9 and np.all(np.isfinite(result["h_ft"]))


def test_a_script_observer_sees_every_step_as_plain_jsbsim_steps(tmp_path):
    config = {"kind": "jsbsim", "scenario": {"kind": "script", "script": "c172_cruise_8K", "end_s": 1.5},
              "output_rate_hz": 20, "outputs": ["h_ft"]}
    simulator = make_simulator(SimulatorSpec.from_checked(config), [], [], tmp_path)
    observer = Altitude()
    result = simulator.flight.fly({}, observers=(observer,))
    steps = simulator.setup.steps
    plain, plain_time = plain_jsbsim(CRUISE, steps, 1, Altitude.properties, tmp_path)
    assert len(observer.t) == steps + 1 == 180 + 1 and observer.trims == 0  # a script has no trim of ours
    np.testing.assert_array_equal(np.array(observer.values), plain)  # the same steps, bit for bit
    np.testing.assert_array_equal(observer.t, plain_time)
    np.testing.assert_array_equal(result.outputs["h_ft"], plain[::6, 0])  # the history is every 6th step


def test_a_level_flight_observer_sees_the_trimmed_state_and_every_step():
    flight = JSBSimFlight(FlightSetup(duration_s=1.0, output_rate_hz=20.0, outputs=("h_ft",)))
    observer = Altitude()
    result = flight.fly({}, observers=(observer,))
    assert observer.trims == 1 and len(observer.t) == 121  # t = 0, then 120 steps of 1/120 s
    np.testing.assert_array_equal(observer.t, np.arange(121) / 120.0)
    # the recorded history is the observer's altitude at every 6th step, bit for bit
    np.testing.assert_array_equal(result.outputs["h_ft"], np.array(observer.values)[::6, 0])
    unwatched = JSBSimFlight(FlightSetup(duration_s=1.0, output_rate_hz=20.0, outputs=("h_ft",))).fly({})
    np.testing.assert_array_equal(unwatched.outputs["h_ft"], result.outputs["h_ft"])  # watching changes nothing


REFUSALS = [
    ({"scenario": {"kind": "scripted", "script": "c172_cruise_8K"}}, "simulator.scenario.kind",
     "expected one of level_flight, script, got 'scripted'"),
    ({"scenario": {"kind": "script", "script": "c172_cruise_8X"}}, "simulator.scenario.script",
     "no script 'c172_cruise_8X'.*did you mean c172_cruise_8K"),
    ({"scenario": {"kind": "script", "script": "scripts/none.xml"}}, "simulator.scenario.script", "no script"),
    ({"scenario": {"kind": "script"}}, "simulator.scenario.script", "is required"),
    ({"output_rate_hz": 7}, "simulator.output_rate_hz",
     r"expected a divisor of the script's 120.0005 Hz rate \(dt = 0.0083333 s: 120, 60, 40, 30, 24, 20, ...\), got 7"),
    ({"aircraft": "c172p"}, "simulator.aircraft", "'c172p' is not the script's aircraft 'c172x'"),
    ({"scenario": {"kind": "script", "script": "c172_cruise_8K", "end_s": 41}}, "simulator.scenario.end_s",
     "expected a time after the script's start 0 s and at most its end 40 s, got 41"),
    ({"duration_s": 5}, "simulator.duration_s", "unknown key"),
    ({"scenario": {"kind": "level_flight", "end_s": 5}}, "simulator.scenario.end_s", "unknown key"),
]


@pytest.mark.parametrize("change, field, message", REFUSALS, ids=[r[1] + ":" + r[2][:20] for r in REFUSALS])
def test_a_script_campaign_that_cannot_be_flown_is_refused_naming_the_field(tmp_path, change, field, message):
    path = script_campaign(tmp_path, **{k: v for k, v in change.items() if k != "scenario"},
                           scenario=change.get("scenario"))
    with pytest.raises(CampaignError, match=f"{field}: {message}"):
        parse_campaign(path.read_text(), str(path))


@pytest.mark.slow
def test_plan_refuses_an_unknown_scenario_kind_with_exit_2(tmp_path):
    path = script_campaign(tmp_path, scenario={"kind": "scripted", "script": "c172_cruise_8K"})
    result = cli("plan", path)
    assert result.returncode == 2 and "simulator.scenario.kind" in result.stderr


def test_an_output_rate_divides_a_rounded_dt_only_within_its_rounding():
    script = ScriptFile.read(jsbsim_scripts() / "737_cruise_steady_turn.xml")  # dt="0.008333": 120.0048 Hz
    assert script.steps_per_output(10) == 12  # 12 dt = 0.099996 s, within 12 x 5e-7 of 0.1
    assert script.steps_per_output(120) == 1 and script.steps_per_output(7) is None
    assert script.steps_per_output(1000) is None  # less than one step
    c310 = ScriptFile.read(jsbsim_scripts() / "c3104.xml")  # dt="0.02": JSBSim steps by 0.02 s, 50 Hz
    assert c310.steps_per_output(20) is None and c310.steps_per_output(30) is None  # were 2 steps, 25 Hz, and 33 Hz
    assert c310.steps_per_output(25) == 2 and c310.steps_per_output(10) == 5


@pytest.mark.slow
def test_without_an_output_rate_a_script_records_at_a_divisor_of_its_own_rate(tmp_path):
    # ah1s_flight_test's dt = 0.0075 s (133.3 Hz), c3104's 0.02 s (50 Hz): 20 Hz divides neither, and a
    # campaign that names no rate was refused for the default it never chose
    helicopter, c310 = (ScriptFile.read(jsbsim_scripts() / f"{name}.xml") for name in ("ah1s_flight_test", "c3104"))
    assert helicopter.default_output_rate_hz == pytest.approx(400 / 21) and helicopter.steps_per_output(400 / 21) == 7
    assert c310.default_output_rate_hz == pytest.approx(50 / 3) and c310.steps_per_output(50 / 3) == 3
    assert ScriptFile.read(CRUISE).default_output_rate_hz == 20.0  # 120 Hz: the default as it was
    assert c310.output_rate_hz({"output_rate_hz": 10}) == 10.0
    path = script_campaign(tmp_path, {"kind": "script", "script": "ah1s_flight_test", "end_s": 1}, name="ah1s",
                           outputs=["h_ft"])
    text = yaml.safe_load(path.read_text())
    del text["simulator"]["output_rate_hz"]
    text["parameters"] = {"wind": PARAMETERS["wind"]}
    path.write_text(yaml.safe_dump(text))
    done = cli("run", path, "--out", tmp_path / "ah1s.h5")
    assert done.returncode == 0, done.stderr
    with h5py.File(tmp_path / "ah1s.h5") as f:
        time = f["time"][:]
    np.testing.assert_allclose(np.diff(time), 7 * 0.0075, rtol=1e-9)


def test_a_script_and_its_initialisation_travel_in_the_bundle_hashed(tmp_path, monkeypatch):
    """A worker with its own cache and no access to the campaign's folder flies the script from the bundle
    (the script and the initialisation file beside it), bit-identical to the client, and refuses an edited copy."""
    shutil.copytree(ROOT / "campaigns" / "scripts", tmp_path / "scripts")
    path = tmp_path / "landing.yaml"
    path.write_text(yaml.safe_dump({
        "name": "landing", "simulator": {"kind": "jsbsim", "scenario": {"kind": "script", "script":
                                         "scripts/c172p-landing.xml", "end_s": 1.0}, "output_rate_hz": 10,
                                         "outputs": ["h_ft"]},
        "parameters": {"CL": PARAMETERS["CL"]}, "design": {"kind": "sparse_grid", "level": 1}}))
    campaign = load_campaign(path, AircraftProperties)
    spec = worker_spec(campaign)
    assert len(spec.bundle["scenario"]["hash"]) == 64
    client = spec.build().evaluate(np.array([1.02]))
    shutil.rmtree(tmp_path / "scripts")  # the worker's machine has no such folder
    monkeypatch.setenv("UQFLIGHT_CACHE", str(tmp_path / "worker-cache"))
    remote = localized(spec)
    assert remote.simulator.script_path.startswith(str(tmp_path / "worker-cache" / "scenario"))
    folder = Path(remote.simulator.script_path).parent
    assert sorted(os.listdir(folder)) == ["c172p-landing-init.xml", "c172p-landing.xml"]
    np.testing.assert_array_equal(remote.build().evaluate(np.array([1.02]))["h_ft"], client["h_ft"])
    (folder / "c172p-landing-init.xml").write_text("<initialize/>")
    with pytest.raises(AircraftMismatch, match="scenario files .* differ from the client's"):
        localized(spec)


SCRIPT_WITH_RESET = """<?xml version="1.0"?>
<runscript name="resets">
  <use aircraft="c172x" initialize="reset01"/>
  <run start="0.0" end="1.0" dt="0.0083333">
    <event name="Reset"><condition> simulation/sim-time-sec ge 0.5 </condition>
      <set name="simulation/reset" value="1"/></event>
  </run>
</runscript>
"""


@pytest.mark.slow
def test_a_script_that_resets_fails_every_run_with_the_reason_and_resumes_as_done(tmp_path):
    (tmp_path / "resets.xml").write_text(SCRIPT_WITH_RESET)  # its own file; reset01 from c172x's folder
    path = script_campaign(tmp_path, scenario={"kind": "script", "script": "resets.xml"})
    campaign = load_campaign(path, AircraftProperties)
    first = run_campaign(campaign, out=tmp_path / "resets.h5", workers=1)
    with h5py.File(first.path, "r") as f:
        assert np.all(f["samples/status"][()] == 3)
        assert "does the script reset the simulation?" in f["samples/reason"][0].decode()
    again = run_campaign(campaign, out=tmp_path / "resets.h5", workers=1)
    assert again.ran == 0 and again.skipped == campaign.runs


@pytest.mark.slow
def test_a_script_campaign_is_bit_identical_with_one_or_two_workers(tmp_path):
    campaign = load_campaign(script_campaign(tmp_path), AircraftProperties)
    one = run_campaign(campaign, out=tmp_path / "one.h5", workers=1)
    two = run_campaign(campaign, out=tmp_path / "two.h5", workers=2)
    assert_same_results(one.path, two.path)


class FirstContact:
    """An observer: the first time each gear unit carries weight."""

    properties = ("gear/unit[0]/WOW", "gear/unit[1]/WOW", "gear/unit[2]/WOW")

    def __init__(self):
        self.first = {}

    def step(self, t, values):
        for name, value in zip(self.properties, values):
            if value > 0.5:
                self.first.setdefault(name, t)


@pytest.mark.slow
def test_the_landing_campaign_touches_down_at_every_corner_of_its_box():
    campaign = load_campaign(ROOT / "campaigns" / "c172p-landing.yaml", AircraftProperties)
    properties = [p.property for p in campaign.parameters]
    simulator = make_simulator(campaign.simulator, [p.name for p in campaign.parameters], properties,
                               ROOT / "campaigns")
    end = simulator.setup.time[-1]
    for corner in itertools.product(*[(p.lower, p.upper) for p in campaign.parameters]):
        observer = FirstContact()
        simulator.flight.fly(dict(zip(properties, corner)), observers=(observer,))
        assert set(observer.first) == set(FirstContact.properties), corner  # both mains and the nose wheel
        mains = min(observer.first["gear/unit[1]/WOW"], observer.first["gear/unit[2]/WOW"])
        assert 20 < mains < observer.first["gear/unit[0]/WOW"] < end - 2, corner  # mains first, 2 s to spare


@pytest.mark.slow
def test_separate_dask_workers_fly_a_script_campaign_bit_identical_to_the_local_pool(cluster, tmp_path, monkeypatch):
    """Workers started apart, in another folder with their own cache, fly the landing script from the
    bundle (the script and its initialisation unpacked in their cache) and give the local pool's results."""
    monkeypatch.setenv("UQFLIGHT_CACHE", str(tmp_path / "client-cache"))
    address, worker_cache = cluster
    shutil.copytree(ROOT / "campaigns" / "scripts", tmp_path / "scripts")
    path = script_campaign(tmp_path, scenario={"kind": "script", "script": "scripts/c172p-landing.xml", "end_s": 3})
    campaign = load_campaign(path, AircraftProperties)
    local = run_campaign(campaign, out=tmp_path / "local.h5", workers=2, executor="local")
    remote = run_campaign(campaign, out=tmp_path / "dask.h5", workers=1, executor="dask", scheduler=address)
    assert_same_results(local.path, remote.path)
    unpacked = worker_cache / "scenario" / worker_spec(campaign).bundle["scenario"]["hash"][:24]
    assert sorted(os.listdir(unpacked)) == ["c172p-landing-init.xml", "c172p-landing.xml"]


def test_a_quantity_at_a_time_past_the_scripts_end_is_refused_at_plan(tmp_path):
    """c172_cruise_8K ends at 40 s: at_s 1200 lies outside the flight."""
    from uqflight.campaign import CampaignError, load_campaign

    path = tmp_path / "late.yaml"
    path.write_text("name: late\nsimulator: {kind: jsbsim, scenario: {kind: script, script: c172_cruise_8K}}\n"
                    "parameters:\n  h: {property: ic/h-sl-ft, distribution: uniform, lower: 7900, upper: 8100}\n"
                    "design: {kind: monte_carlo, samples: 4}\n"
                    "quantities:\n  late: {of: h_ft, take: at, at_s: 1200}\n")
    with pytest.raises(CampaignError, match=r"quantities\.late\.at_s: 1200 s is outside the flight"):
        load_campaign(path)


def test_a_results_file_of_an_edited_script_is_not_resumed(tmp_path):
    """The script's files are part of what a file's runs flew: an edited script refuses the resume."""
    from uqflight.campaign import load_campaign
    from uqflight.running.runner import run_campaign

    scripts = Path(__file__).resolve().parents[1] / "campaigns" / "scripts"
    shutil.copytree(scripts, tmp_path / "scripts")
    path = tmp_path / "s.yaml"
    path.write_text("name: s\nsimulator: {kind: jsbsim, scenario: {kind: script, script: scripts/c172p-landing.xml, "
                    "end_s: 2}, output_rate_hz: 10, outputs: [h_ft]}\nparameters:\n"
                    "  wind: {property: landing/head-wind-fps, distribution: uniform, lower: 0, upper: 5}\n"
                    "design: {kind: monte_carlo, samples: 2}\n")
    run_campaign(load_campaign(path), out=tmp_path / "s.h5", workers=1)
    script = tmp_path / "scripts" / "c172p-landing.xml"
    script.write_text(script.read_text().replace("landing/turbulence-severity </property>",
                                                 "landing/turbulence-severity </property>\n    <!-- edited -->"))
    with pytest.raises(FileExistsError, match="other script files"):
        run_campaign(load_campaign(path), out=tmp_path / "s.h5", workers=1)
