"""Any aircraft: locating, hashing, patching functions (exactly), campaign keys, stock aircraft."""
import hashlib
import re
import shutil
from pathlib import Path

import jsbsim
import numpy as np
import pytest
from conftest import cli_in_process

from uqflight.campaign import CampaignError, load_campaign
from uqflight.simulators.aircraft import AircraftFiles, AircraftNotFound, locate
from uqflight.simulators.jsbsim import REPO_ROOT, quiet_jsbsim
from uqflight.simulators.scenarios import flight_setup_from
from uqflight.simulators.scenarios.level_flight import JSBSimFlight
from uqflight.simulators.spec import SimulatorSpec
from uqflight.simulators.aircraft_properties import AircraftProperties
from uqflight.simulators.patch import PreparedAircraft

CAMPAIGNS = REPO_ROOT / "campaigns"


@pytest.fixture(autouse=True)
def private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("UQFLIGHT_CACHE", str(tmp_path / "cache"))


def test_locate_project_jsbsim_and_path(tmp_path):
    assert locate("bacm").origin == "project"
    assert locate("c172p").origin == "jsbsim"
    copy = tmp_path / "planes" / "myplane"
    shutil.copytree(REPO_ROOT / "aircraft" / "bacm", copy)
    (copy / "bacm.xml").rename(copy / "myplane.xml")
    found = locate("planes/myplane", tmp_path)
    assert found.origin == "path" and found.folder == copy.resolve() and not found.loadable_from_root
    with pytest.raises(AircraftNotFound, match="did you mean .*c172p"):
        locate("c172q")


def test_bacm_hash_is_the_documented_length_prefixed_sha256():
    """Recomputed by hand from the definition in docs/own-aircraft.md: per file in key order, the 8-byte big-endian
    length of its key, the key, the length of its bytes, the bytes."""
    digest = hashlib.sha256()
    folder = REPO_ROOT / "aircraft" / "bacm"
    for key in sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*.xml")):
        for part in (key.encode(), (folder / key).read_bytes()):
            digest.update(len(part).to_bytes(8, "big") + part)
    assert AircraftFiles.read(locate("bacm")).hash() == digest.hexdigest()


def _function_values(root, name, settings, functions, h=4000.0, v=100.0):
    quiet_jsbsim()
    fdm = jsbsim.FGFDMExec(str(root))
    fdm.set_debug_level(0)
    assert fdm.load_model(name)
    for k, val in settings.items():
        fdm[k] = val
    fdm["ic/h-sl-ft"], fdm["ic/vt-kts"], fdm["ic/alpha-deg"] = h, v, 4.0
    fdm["fcs/elevator-cmd-norm"] = 0.3
    fdm.run_ic()
    return np.array([fdm[f] for f in functions])


@pytest.mark.parametrize("aircraft", ["c172p", "737"])
def test_the_patch_is_exact(aircraft):
    plain = PreparedAircraft(aircraft)
    functions = [f for f in plain.functions if f.rsplit("/", 1)[-1] in ("CLwbh", "CLalpha", "CDwbh", "CD0", "Cmalpha")]
    original = _function_values(plain.root, aircraft, {}, functions)
    assert np.all(original != 0.0)
    patched = PreparedAircraft(aircraft, patches=[(f, k) for f in functions for k in ("scale", "offset_value")])
    assert patched.root != plain.root and patched.hash != plain.hash
    short = [f.rsplit("/", 1)[-1] for f in functions]
    nominal = _function_values(patched.root, aircraft, {}, functions)
    np.testing.assert_array_equal(nominal, original)
    s, o = 1.0 + np.arange(1, len(functions) + 1) * 0.037, np.arange(1, len(functions) + 1) * 0.0011
    scaled = _function_values(patched.root, aircraft, {f"aero/uq/scale/{n}": x for n, x in zip(short, s)}, functions)
    np.testing.assert_allclose(scaled, s * original, rtol=1e-12, atol=0)
    offset = _function_values(patched.root, aircraft, {f"aero/uq/offset_value/{n}": x for n, x in zip(short, o)}, functions)
    np.testing.assert_allclose(offset, original + o, rtol=1e-12, atol=1e-15)


def test_unknown_function_is_refused_with_suggestions(tmp_path):
    text = (CAMPAIGNS / "c172p-scale-l2.yaml").read_text().replace("aero/coefficient/CLwbh", "aero/coefficient/CLwb")
    (tmp_path / "bad.yaml").write_text(text)
    with pytest.raises(CampaignError, match=r"parameters\.CL\.function: .*did you mean aero/coefficient/CLwbh"):
        load_campaign(tmp_path / "bad.yaml", read_aircraft=AircraftProperties)


def test_function_parameters_have_nominal_one_and_set_the_patch_property():
    campaign = load_campaign(CAMPAIGNS / "c172p-scale-l2.yaml", read_aircraft=AircraftProperties)
    assert [p.property for p in campaign.parameters] == [
        "aero/uq/scale/CLwbh", "aero/uq/scale/CDwbh", "aero/uq/scale/Cmalpha"]
    assert all(p.nominal == 1.0 and p.lower == pytest.approx(0.9) for p in campaign.parameters)


def test_excitation_without_excitation_property_goes_through_the_pitch_command():
    setup = flight_setup_from(SimulatorSpec("jsbsim", {"aircraft": "c172p", "duration_s": 5.0}))
    flight = JSBSimFlight(setup)
    assert not flight.has_property("fcs/elevator-excitation-deg")
    assert flight.elevator_travel_deg == pytest.approx((23.0, 28.0), abs=0.01)  # range x gain 0.01745
    result = flight.fly()
    quiet = JSBSimFlight(flight_setup_from(SimulatorSpec("jsbsim", {"aircraft": "c172p", "duration_s": 5.0,
                                                                "excitation": {"kind": "none"}}))).fly()
    assert np.max(np.abs(result.outputs["q_degps"] - quiet.outputs["q_degps"])) > 0.5


# Stock aircraft with different propulsion, at their default condition: (|dh| ft, |dtheta| deg, |dV| kt) limits.
HOLD = {"c172p": (0.5, 0.01, 0.05), "737": (5.0, 0.03, 0.2), "f16": (25.0, 0.06, 0.4)}


@pytest.mark.slow
@pytest.mark.parametrize("aircraft", sorted(HOLD))
def test_stock_aircraft_trim_and_hold_level_flight_for_50_s(aircraft):
    setup = flight_setup_from(SimulatorSpec("jsbsim", {"aircraft": aircraft, "excitation": {"kind": "none"}}))
    out = JSBSimFlight(setup).fly().outputs
    drift = [np.max(np.abs(out[k] - out[k][0])) for k in ("h_ft", "theta_deg", "vtas_kt")]
    print(aircraft, drift)
    assert all(d < lim for d, lim in zip(drift, HOLD[aircraft]))


def _broken_c172p(tmp_path, edit) -> str:
    """A copy of JSBSim's c172p under tmp_path/planes/c172x with `edit` applied to its main file."""
    copy = tmp_path / "planes" / "c172x"
    shutil.copytree(Path(jsbsim.get_default_root_dir()) / "aircraft" / "c172p", copy)
    (copy / "c172p.xml").rename(copy / "c172x.xml")
    (copy / "c172x.xml").write_text(edit((copy / "c172x.xml").read_text()))
    return "planes/c172x"


@pytest.mark.parametrize("edit, message", [
    (lambda xml: xml.replace("aero/qbar-psf", "aero/qbar-typo", 1),
     ".*JSBSim kills the process that loads aircraft 'c172x' .*The property aero/qbar-typo does not exist"),
    (lambda xml: xml[:len(xml) // 2], r".*c172x\.xml is not well-formed XML \(no element found"),
])
def test_an_aircraft_that_would_kill_the_process_is_refused_with_exit_2(tmp_path, edit, message):
    """JSBSim aborts (std::terminate in FGFDMExec's destructor) the process that loaded an aircraft
    whose function reads a property nobody defines: the load is tried in a throw-away process first."""
    aircraft = _broken_c172p(tmp_path, edit)
    text = (CAMPAIGNS / "c172p-scale-l2.yaml").read_text().replace("aircraft: c172p", f"aircraft: {aircraft}")
    (tmp_path / "c.yaml").write_text(text)
    with pytest.raises(CampaignError, match="simulator.aircraft: " + message):
        load_campaign(tmp_path / "c.yaml", read_aircraft=AircraftProperties)  # in this process: it survives
    for command in (["plan", tmp_path / "c.yaml"], ["aircraft", aircraft]):
        result = cli_in_process(*command, cwd=tmp_path)
        assert result.returncode == 2 and re.search(message, result.stderr), result.stderr


def test_a_sound_aircraft_is_checked_once_per_version(tmp_path):
    setup = flight_setup_from(SimulatorSpec("jsbsim", {"aircraft": "c172p"}))
    markers = tmp_path / "cache" / "loads"
    JSBSimFlight(setup)
    assert len(list(markers.iterdir())) == 1
    JSBSimFlight(setup)
    assert len(list(markers.iterdir())) == 1
