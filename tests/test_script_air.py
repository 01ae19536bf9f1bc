"""A script's own trims fly in the air the script gives (issue 45): turbulence and winds from
simulator.properties or parameters (atmosphere/...) are set at the first step after the script's trims
completed; a failed script trim says what air was active. JSBSim's c172_cruise_8K, as it ships (it trims
itself at t = 1.008 s)."""
import numpy as np
import pytest

from uqflight.simulators.jsbsim import quiet_jsbsim
from uqflight.simulators.scenarios.script import Script, ScriptFile, ScriptFlight, jsbsim_scripts
from uqflight.simulators.base import TrimError
from uqflight.simulators.spec import SimulatorSpec

CRUISE = jsbsim_scripts() / "c172_cruise_8K.xml"
TRIM_AT = 1.0083293  # "Trim (Event 2) executed at time: 1.00833"
SEVERITY = "atmosphere/turbulence/milspec/severity"
TURBULENCE = {"atmosphere/turb-type": 3.0, "atmosphere/turbulence/milspec/severity": 4.0,
              "atmosphere/turbulence/milspec/windspeed_at_20ft_AGL-fps": 50.0, "atmosphere/wind-north-fps": 20.0}


def _flight(end_s=2.0, outputs=("atmosphere/wind-north-fps", SEVERITY, "h_ft")):
    quiet_jsbsim()
    config = SimulatorSpec("jsbsim", {"scenario": {"kind": "script", "script": "c172_cruise_8K", "end_s": end_s},
                                      "output_rate_hz": 120.0, "outputs": list(outputs)}, script_path=str(CRUISE))
    return ScriptFlight(Script().setup(config))


def test_the_script_counts_its_trim_events():
    assert ScriptFile.read(CRUISE).trims == 1
    assert ScriptFile.read(jsbsim_scripts() / "rudder_kick.xml").trims >= 0  # read, whatever it holds


def test_turbulence_and_wind_start_at_the_first_step_after_the_scripts_trim():
    flight = _flight()
    result = flight.fly(TURBULENCE)
    wind, severity = result.outputs["atmosphere/wind-north-fps"], result.outputs[SEVERITY]
    before, after = result.time <= TRIM_AT, result.time > TRIM_AT + 1e-6
    # recorded every step (120 Hz): still air through the step that trimmed, then the settings from the next
    assert np.all(np.abs(wind[before]) < 1e-9) and np.all(severity[before] == 0.0)  # the trim leaves 1e-13
    assert np.all(wind[after] == 20.0) and np.all(severity[after] == 4.0)
    assert after.sum() > 100


def test_without_atmosphere_settings_the_flight_is_as_before():
    plain, held = _flight().fly({}), _flight().fly({"atmosphere/wind-north-fps": 0.0})
    np.testing.assert_array_equal(plain.outputs["h_ft"], held.outputs["h_ft"])


def test_a_failed_script_trim_says_what_air_was_active():
    # 250 KTAS is far beyond what c172x trims at (test_aircraft_setup): the script's trim at 1 s fails
    flight = _flight()
    with pytest.raises(TrimError) as failed:
        flight.fly({"ic/vt-kts": 250.0, **TURBULENCE})
    message = str(failed.value)
    assert "a trim in the script failed at t = 1.008 s" in message
    assert "the trim flew in still air" in message
    assert ("held for after the script's first trim: atmosphere/turb-type = 3, "
            "atmosphere/turbulence/milspec/severity = 4") in message


def test_a_trim_that_never_comes_before_the_end_is_said():
    flight = _flight(end_s=0.5)  # cut before the trim at 1 s: the settings would never take effect
    with pytest.raises(Exception, match="first trim did not complete before its end"):
        flight.fly({"atmosphere/wind-north-fps": 5.0})


def test_a_later_trim_that_fails_says_the_campaigns_air_was_active():
    # c172_elevator_doublet trims at 1 s and again at 20 s: the campaign's air is set after the first, so the
    # re-trim flies in it; a steady 80 ft/s down gust (no random stream) makes the re-trim fail, which it
    # does not in the script's own still air, and the message says where the gust came from
    quiet_jsbsim()
    script = jsbsim_scripts() / "c172_elevator_doublet.xml"
    config = SimulatorSpec("jsbsim", {"scenario": {"kind": "script", "script": "c172_elevator_doublet", "end_s": 21.0},
                                      "output_rate_hz": 20.0, "outputs": ["h_ft"]}, script_path=str(script))
    assert ScriptFile.read(script).trims == 2
    ScriptFlight(Script().setup(config)).fly({})  # the re-trim in still air succeeds
    with pytest.raises(TrimError) as failed:
        ScriptFlight(Script().setup(config)).fly({"atmosphere/gust-down-fps": 80.0})
    assert str(failed.value) == (
        "a trim in the script failed at t = 20.01 s: Trim Failed; active at the trim from the campaign "
        "(simulator.properties or parameters, set after the script's first trim): atmosphere/gust-down-fps = 80")
