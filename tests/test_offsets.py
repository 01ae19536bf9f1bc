"""`perturbation: offset` is a coefficient increment ΔC, added as ΔC times the function's reference
factor (qbar·S, qbar·S·c̄, qbar·S·b); `offset_value` adds a value in the function's own unit.
The patched copies are flown by plain JSBSim (jsbsim.FGFDMExec on the patched root)."""
import re
import xml.etree.ElementTree as ET

import h5py
import jsbsim
import pytest
from conftest import cli_in_process

from uqflight.campaign import CampaignError, load_campaign
from uqflight.running.runner import run_campaign
from uqflight.simulators.aircraft import AircraftFiles
from uqflight.simulators.jsbsim import REPO_ROOT, quiet_jsbsim
from uqflight.simulators.aircraft_properties import AircraftProperties
from uqflight.simulators.base import SimulatorSettingError
from uqflight.simulators.patch import PreparedAircraft
from uqflight.simulators.aero_factors import AeroFactor, aero_factors, axis_factor

# Floating point: the patched function is fl(fl(ΔC·qbar·S[·l]) + f), so (patched - f) differs from
# ΔC·qbar·S[·l] by a few ulps of f; with f at most a few times the increment here, 1e-9 relative
# is ~1e6 ulps of margin and still fails on any wrong factor (the smallest wrong one, c̄ = 4.9).
RTOL = 1e-9
# c172p: CDo = qbar·S·0.027, Cmo = qbar·S·c̄·0.1 (its file); one function of each axis.
C172P = {"aero/coefficient/CDo": 0.01, "aero/coefficient/CYb": 0.003, "aero/coefficient/CLwbh": 0.05,
         "aero/coefficient/Clb": 0.002, "aero/coefficient/Cmo": 0.02, "aero/coefficient/Cnb": 0.004}
FACTOR = {"CDo": ("aero/qbar-psf", "metrics/Sw-sqft"), "CYb": ("aero/qbar-psf", "metrics/Sw-sqft"),
          "CLwbh": ("aero/qbar-psf", "metrics/Sw-sqft"), "Clb": ("aero/qbar-psf", "metrics/Sw-sqft", "metrics/bw-ft"),
          "Cmo": ("aero/qbar-psf", "metrics/Sw-sqft", "metrics/cbarw-ft"),
          "Cnb": ("aero/qbar-psf", "metrics/Sw-sqft", "metrics/bw-ft")}


@pytest.fixture(autouse=True)
def private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("UQFLIGHT_CACHE", str(tmp_path / "cache"))


def _campaign(tmp_path, parameters: str):
    """c172p-scale-l2 with its parameters replaced by `parameters` (YAML lines)."""
    text = (REPO_ROOT / "campaigns" / "c172p-scale-l2.yaml").read_text()
    head, tail = text.split("parameters:\n")
    (tmp_path / "c.yaml").write_text(f"{head}parameters:\n{parameters}design:{tail.split('design:', 1)[1]}")
    return tmp_path / "c.yaml"


def _plain(root, name="c172p"):
    quiet_jsbsim()
    fdm = jsbsim.FGFDMExec(str(root))
    fdm.set_debug_level(0)
    assert fdm.load_model(name)
    return fdm


def _factor(fdm, function):
    value = 1.0
    for prop in FACTOR[function.rsplit("/", 1)[-1]]:
        value *= fdm[prop]
    return value


def test_an_offset_adds_delta_c_times_the_reference_factor_at_a_fixed_state():
    patched = PreparedAircraft("c172p", patches=[(f, "offset") for f in C172P])
    fdm = _plain(patched.root)
    fdm["ic/h-sl-ft"], fdm["ic/vt-kts"], fdm["ic/alpha-deg"], fdm["ic/beta-deg"] = 4000.0, 100.0, 4.0, 2.0
    values = {}
    for on in (False, True):
        for function, delta in C172P.items():
            fdm[f"aero/uq/offset/{function.rsplit('/', 1)[-1]}"] = delta if on else 0.0
        fdm.run_ic()  # the same initial state both times
        values[on] = {f: fdm[f] for f in C172P}
    for function, delta in C172P.items():
        expected = delta * _factor(fdm, function)
        assert values[True][function] - values[False][function] == pytest.approx(expected, rel=RTOL), function
    qs = fdm["aero/qbar-psf"] * fdm["metrics/Sw-sqft"]
    assert values[False]["aero/coefficient/CDo"] == pytest.approx(0.027 * qs, rel=1e-14)  # closed form
    assert values[True]["aero/coefficient/CDo"] == pytest.approx((0.027 + 0.01) * qs, rel=RTOL)


def test_the_drag_and_pitch_functions_change_by_delta_c_times_the_factor_at_the_trimmed_state():
    patched = PreparedAircraft("c172p", patches=[("CDo", "offset"), ("Cmo", "offset")])
    fdm = _plain(patched.root)
    fdm["aero/uq/offset/CDo"], fdm["aero/uq/offset/Cmo"] = 0.01, 0.02
    fdm["ic/h-sl-ft"], fdm["ic/vt-kts"] = 4000.0, 100.0
    fdm["fcs/mixture-cmd-norm"], fdm["propulsion/magneto_cmd"], fdm["propulsion/set-running"] = 1.0, 3, -1
    fdm.run_ic()
    fdm.do_trim(1)
    trimmed = {p: fdm[p] for p in ("aero/coefficient/CDo", "aero/coefficient/Cmo", "aero/qbar-psf", "aero/alpha-deg")}
    fdm["aero/uq/offset/CDo"], fdm["aero/uq/offset/Cmo"] = 0.0, 0.0
    fdm.suspend_integration()  # evaluate the models again at the same state (dt = 0)
    fdm.run()
    assert fdm["aero/qbar-psf"] == trimmed["aero/qbar-psf"] and fdm["aero/alpha-deg"] == trimmed["aero/alpha-deg"]
    q, s, c = fdm["aero/qbar-psf"], fdm["metrics/Sw-sqft"], fdm["metrics/cbarw-ft"]
    drag = trimmed["aero/coefficient/CDo"] - fdm["aero/coefficient/CDo"]
    pitch = trimmed["aero/coefficient/Cmo"] - fdm["aero/coefficient/Cmo"]
    assert drag == pytest.approx(0.01 * q * s, rel=RTOL)
    assert pitch == pytest.approx(0.02 * q * s * c, rel=RTOL)


def _throttle(result):
    assert result.returncode == 0, result.stderr
    return float(re.search(r"throttle = \[([0-9.]+)\]", result.stdout).group(1))


@pytest.mark.slow
def test_simulate_with_a_drag_offset_needs_clearly_more_throttle(tmp_path):
    nominal = cli_in_process("simulate", "--aircraft", "c172p", "--duration-s", "0.5", cwd=tmp_path)
    offset = cli_in_process("simulate", "--aircraft", "c172p", "--duration-s", "0.5",
                            "--offset", "aero/coefficient/CDo=0.01", cwd=tmp_path)
    # measured 0.6923 -> 0.7445: ΔCD0 = 0.01 is 37 % of c172p's CD0 = 0.027, ~52 lbf at 100 KTAS
    assert _throttle(offset) > _throttle(nominal) + 0.03
    added = re.search(r"offset aero/coefficient/CDo: 0.01 x qbar·S = 0.01 x ([0-9.]+) = ([0-9.]+) lbf", offset.stdout)
    assert float(added.group(2)) == pytest.approx(0.01 * float(added.group(1)), rel=1e-5)  # printed to 6 digits
    assert 40.0 < float(added.group(2)) < 70.0  # qbar·S at 100 KTAS, 4000 ft: about 30 psf x 174 ft²


def test_offset_on_a_function_outside_the_axes_is_refused_naming_it(tmp_path):
    refused = cli_in_process("simulate", "--aircraft", "c172p", "--offset", "kCLge=0.01", cwd=tmp_path)
    assert refused.returncode == 2
    assert "aero/function/kCLge" in refused.stderr and "offset_value" in refused.stderr
    with pytest.raises(SimulatorSettingError, match=r"aero/function/kCLge.*outside the <axis> elements"):
        PreparedAircraft("c172p", patches=[("kCLge", "offset")])
    path = _campaign(tmp_path, "  G: {function: aero/function/kCLge, perturbation: offset, distribution: normal, "
                               "lower: -0.01, upper: 0.01}\n")
    with pytest.raises(CampaignError, match=r"parameters\.G\.perturbation: .*aero/function/kCLge.*offset_value"):
        load_campaign(path, read_aircraft=AircraftProperties)


def test_a_function_the_aircraft_lacks_is_refused_naming_the_option_and_the_aircraft(tmp_path):
    refused = cli_in_process("simulate", "--aircraft", "c172p", "--scale", "nonexistent=1.1", "--no-files", cwd=tmp_path)
    assert refused.returncode == 2
    assert refused.stderr.startswith("error: --scale nonexistent: expected one of the aircraft's aerodynamic functions")
    assert refused.stderr.strip().endswith("got 'nonexistent' (aircraft 'c172p')")


def test_offset_value_adds_in_the_function_own_unit():
    functions = ("aero/function/kCLge", "aero/coefficient/CDo")
    patched = PreparedAircraft("c172p", patches=[(f, "offset_value") for f in functions])
    fdm = _plain(patched.root)
    fdm["ic/h-sl-ft"], fdm["ic/vt-kts"], fdm["ic/alpha-deg"] = 4000.0, 100.0, 4.0
    fdm.run_ic()
    before = [fdm[f] for f in functions]
    fdm["aero/uq/offset_value/kCLge"], fdm["aero/uq/offset_value/CDo"] = 0.25, 3.0
    fdm.run_ic()
    assert [fdm[f] - b for f, b in zip(functions, before)] == pytest.approx([0.25, 3.0], rel=1e-12)


def test_campaign_parameters_name_the_offset_kinds(tmp_path):
    path = _campaign(tmp_path, "  CD: {function: aero/coefficient/CDo, perturbation: offset, distribution: normal, "
                               "lower: -0.002, upper: 0.002}\n"
                               "  Cm: {function: Cmo, perturbation: offset_value, distribution: normal, "
                               "lower: -5, upper: 5}\n")
    campaign = load_campaign(path, read_aircraft=AircraftProperties)
    assert [(p.property, p.nominal) for p in campaign.parameters] == [
        ("aero/uq/offset/CDo", 0.0), ("aero/uq/offset_value/Cmo", 0.0)]


def test_a_patch_property_written_directly_is_checked_as_a_function_parameter(tmp_path):
    path = _campaign(tmp_path, "  CD: {property: aero/uq/offset/CDo, distribution: normal, lower: -0.002, upper: 0.002}\n"
                               "  CL: {property: aero/uq/scale/CLwbh, distribution: normal, lower: 0.9, upper: 1.1}\n")
    campaign = load_campaign(path, read_aircraft=AircraftProperties)
    assert [p.nominal for p in campaign.parameters] == [0.0, 1.0]
    path = _campaign(tmp_path, "  G: {property: aero/uq/offset/kCLge, distribution: normal, lower: -0.01, upper: 0.01}\n")
    with pytest.raises(CampaignError, match=r"parameters\.G\.property: .*aero/function/kCLge.*offset_value"):
        load_campaign(path, read_aircraft=AircraftProperties)


def test_a_copy_patched_to_the_old_lbf_semantics_has_another_cache_key():
    # Before, `offset` wrote <sum> aero/uq/offset/F BODY </sum> (lbf). That text is today's
    # offset_value patch with the property renamed; the cache key is the hash of the patched text.
    value = PreparedAircraft("c172p", patches=[("CDo", "offset_value")])
    old_text = value.files.main.replace(b"aero/uq/offset_value/CDo", b"aero/uq/offset/CDo")
    old = AircraftFiles("c172p", {**value.files.files, "c172p.xml": old_text})
    new = PreparedAircraft("c172p", patches=[("CDo", "offset")])
    assert b"<property> aero/qbar-psf </property><property> metrics/Sw-sqft </property>" in new.files.main
    assert len({old.hash()[:24], new.hash[:24], value.hash[:24]}) == 3
    assert new.root.name == new.hash[:24]
    assert (new.root / "aircraft" / "c172p" / "c172p.xml").read_bytes() == new.files.main


def test_references_of_every_axis_system_and_what_has_none():
    metrics = ET.fromstring("<metrics><wingarea unit='FT2'>100</wingarea><wingspan unit='FT'>30</wingspan></metrics>")
    force = ("aero/qbar-psf", "metrics/Sw-sqft")
    for axis in ("DRAG", "SIDE", "LIFT", "X", "Y", "Z", "AXIAL", "NORMAL"):
        assert axis_factor(axis, metrics) == AeroFactor(axis, "lbf", force)
    assert axis_factor("ROLL", metrics).factor == force + ("metrics/bw-ft",)
    assert axis_factor("YAW", metrics).symbol == "qbar·S·b" and not axis_factor("YAW", metrics).refusal
    assert "no chord" in axis_factor("PITCH", metrics).refusal  # no <chord>: c̄ is 0 in JSBSim
    assert "outside the <axis>" in axis_factor("", metrics).refusal
    assert "none of JSBSim's" in axis_factor("THRUST", metrics).refusal
    c172p = aero_factors(AircraftFiles.read(PreparedAircraft("c172p").location).main)
    assert c172p["aero/coefficient/Cmo"].symbol == "qbar·S·c̄" and c172p["aero/coefficient/Cmo"].unit == "lbf·ft"


def test_aircraft_command_prints_each_function_unit_and_reference_factor(tmp_path):
    shown = cli_in_process("aircraft", "c172p", cwd=tmp_path)
    assert shown.returncode == 0, shown.stderr
    assert re.search(r"DRAG +aero/coefficient/CDo +lbf +ΔC x qbar·S ", shown.stdout)
    assert re.search(r"PITCH +aero/coefficient/Cmo +lbf·ft +ΔC x qbar·S·c̄ ", shown.stdout)
    assert re.search(r"ROLL +aero/coefficient/Clb +lbf·ft +ΔC x qbar·S·b ", shown.stdout)
    assert re.search(r"- +aero/function/kCLge +own +offset_value only", shown.stdout)
    factors = re.search(r"qbar·S = ([0-9.e+]+) lbf, qbar·S·c̄ = ([0-9.e+]+) lbf·ft, qbar·S·b = ([0-9.e+]+) lbf·ft",
                        shown.stdout)
    qs, qsc, qsb = (float(g) for g in factors.groups())
    assert qsc == pytest.approx(qs * 4.9, rel=1e-5) and qsb == pytest.approx(qs * 35.8, rel=1e-5)  # c̄, b of c172p


@pytest.mark.slow
def test_a_campaign_with_an_offset_records_the_patched_copy_flown(tmp_path):
    # The results file keys a resume by aircraft_hash: it is the patched copy's (the patch text
    # included), so a file made when offsets were in lbf (it recorded the unpatched aircraft's
    # hash) is refused, not resumed into a mix of two models.
    path = _campaign(tmp_path, "  CD: {function: aero/coefficient/CDo, perturbation: offset, distribution: normal, "
                               "lower: -0.002, upper: 0.002}\n")
    text = path.read_text().replace("duration_s: 50", "duration_s: 1").replace("order: 2", "order: 1")
    path.write_text(text.replace("results/c172p-scale-l2.h5", str(tmp_path / "r.h5")))
    campaign = load_campaign(path, read_aircraft=AircraftProperties)
    summary = run_campaign(campaign, workers=1)
    with h5py.File(summary.path, "r") as f:
        recorded, status = f.attrs["aircraft_hash"], f["samples/status"][:]
    patched = PreparedAircraft("c172p", properties=["aero/uq/offset/CDo"])
    assert (status == 0).all() and recorded == patched.hash != PreparedAircraft("c172p").hash
