"""Script and aircraft set-ups (issue 45): `uqflight aircraft` lists without flying and trims only with
--trim; a trim that cannot exist says why in true numbers (never -inf or 0 KTAS) and what speeds to fly;
an excitation that leaves the elevator unmoved is warned about. JSBSim's own c172x, as it ships."""
import re

import pytest
from conftest import cli_in_process

from uqflight.simulators.scenarios.level_flight import Excitation, FlightSetup, JSBSimFlight
from uqflight.simulators.trim import level_speed_range


def _setup(aircraft="c172x", **condition):
    from uqflight.cli.commands import _prepared

    located = _prepared(aircraft, [], [])
    return FlightSetup(aircraft=located.name, root=located.root, duration_s=4.0, **condition)


def test_aircraft_lists_the_functions_without_trimming():
    shown = cli_in_process("aircraft", "c172x", "--altitude-ft", "15000", "--airspeed-ktas", "200")
    assert shown.returncode == 0, shown.stderr
    assert re.search(r"PITCH +aero/coefficient/Cmde ", shown.stdout)
    assert "trim:" not in shown.stdout and "trim failed" not in shown.stdout + shown.stderr
    assert "`uqflight aircraft c172x --trim` trims it at 15000 ft, 200 KTAS" in shown.stdout
    assert re.search(r"reference factors at 15000 ft, 200 KTAS .*qbar·S = [0-9.]+ lbf", shown.stdout)


@pytest.mark.slow
def test_a_trim_too_fast_for_the_aircraft_says_its_speed_range():
    failed = cli_in_process("aircraft", "c172x", "--trim", "--altitude-ft", "15000", "--airspeed-ktas", "200")
    assert failed.returncode == 1
    assert "-inf" not in failed.stderr and " 0 KTAS" not in failed.stderr
    found = re.search(r"200 KTAS is faster than the aircraft trims level at 15000 ft from ([0-9.]+) to ([0-9.]+) KTAS",
                      failed.stderr)
    assert found, failed.stderr
    slowest, fastest = map(float, found.groups())
    assert "--airspeed-ktas" in failed.stderr
    # the range it gives is true: JSBSim's trim succeeds inside it, at both ends, and fails past them
    for speed, ok in ((slowest, True), (fastest, True), (0.5 * (slowest + fastest), True), (fastest + 10, False)):
        flight = JSBSimFlight(_setup(altitude_ft=15000.0, airspeed_ktas=speed, trim="jsbsim"))
        flight.diagnose_trim_failures = False
        try:
            flight.trim({})
            trimmed = True
        except Exception:
            trimmed = False
        assert trimmed == ok, speed


def test_a_trim_above_the_ceiling_says_to_fly_lower():
    failed = cli_in_process("aircraft", "c172x", "--trim", "--altitude-ft", "30000", "--airspeed-ktas", "100")
    assert failed.returncode == 1
    assert "no level trim at 30000 ft at any airspeed" in failed.stderr and "fly lower" in failed.stderr


def test_the_speed_range_is_scanned_once_per_condition():
    setup = _setup(altitude_ft=4000.0, airspeed_ktas=100.0)
    first = level_speed_range(setup, JSBSimFlight)
    (slowest, fastest), stopped = first
    assert slowest < 100.0 < fastest and stopped == 0 and level_speed_range(setup, JSBSimFlight) is first


@pytest.mark.slow
def test_a_trim_whose_engine_stops_says_so_not_only_fly_lower():
    """pa28's piston engine stops at the closed throttle JSBSim's trim tries at 5000 ft, 100 KTAS (and stays
    stopped: FGPiston restarts above 0.8 idle rpm only): the failure names the engine, and the speed scan
    counts the speeds where it stopped, where it said only that the altitude was too high."""
    failed = cli_in_process("simulate", "--aircraft", "pa28", "--altitude-ft", "5000", "--airspeed-ktas", "100",
                            "--no-files", "--duration-s", "1")
    assert failed.returncode == 1, failed.stderr  # the flight failed: no number to give
    assert "engine 0 stopped during the trim (JSBSim's throttle search reaches the closed throttle" in failed.stderr
    assert re.search(r"at [0-9]+ of the speeds an engine stopped at the closed throttle the trim tries", failed.stderr)
    assert "fly a script that sets its own throttle" in failed.stderr
    # the state JSBSim's trim leaves, on its own: the engine is not running
    flight = JSBSimFlight(_setup("pa28", altitude_ft=5000.0, airspeed_ktas=100.0, trim="jsbsim"))
    flight.diagnose_trim_failures = False
    with pytest.raises(Exception, match="Trim Failed"):
        flight.trim({})
    assert flight.stopped_engines() == [0]


def test_a_pulse_that_never_moves_the_elevator_is_warned_about():
    # c172x's elevator actuator has a 2.9-deg hysteresis: a 1-deg pulse leaves it where the trim put it
    flight = JSBSimFlight(_setup(altitude_ft=4000.0, airspeed_ktas=100.0))
    result = flight.fly({})
    assert len(result.warnings) == 1 and "never moved the elevator" in result.warnings[0]
    bigger = JSBSimFlight(_setup(altitude_ft=4000.0, airspeed_ktas=100.0,
                                 excitation=Excitation(kind="pulse", amplitude_deg=5.0)))
    assert bigger.fly({}).warnings == []
    still = JSBSimFlight(_setup(altitude_ft=4000.0, airspeed_ktas=100.0, excitation=Excitation(kind="none")))
    assert still.fly({}).warnings == []  # nothing commanded, nothing to warn about


def test_simulate_warns_on_the_command_line():
    shown = cli_in_process("simulate", "--aircraft", "c172x", "--duration-s", "3", "--no-files")
    assert shown.returncode == 0, shown.stderr
    assert "warning: the pulse of 1 deg never moved the elevator" in shown.stderr
    assert "--amplitude-deg" in shown.stderr
    quiet = cli_in_process("simulate", "--duration-s", "3", "--no-files")  # bacm: the pulse moves it
    assert quiet.returncode == 0 and "warning" not in quiet.stderr


@pytest.mark.slow
def test_plan_warns_when_the_nominal_flights_pulse_leaves_the_elevator_unmoved(tmp_path):
    text = """
name: c172x-pulse
simulator:
  kind: jsbsim
  aircraft: c172x
  flight: {altitude_ft: 4000, airspeed_ktas: 100}
  excitation: {kind: pulse, amplitude_deg: AMPLITUDE, start_s: 0.5, duration_s: 1.0}
  duration_s: 3
parameters:
  CL: {function: aero/coefficient/CLwbh, perturbation: scale, distribution: normal, interval_pct: 10}
design: {kind: sparse_grid, rule: gauss_hermite, level: 1}
method: {kind: pseudo_galerkin, order: 1}
storage: {path: c.h5}
"""
    for amplitude, warned in (("1.0", True), ("5.0", False)):
        (tmp_path / "c.yaml").write_text(text.replace("AMPLITUDE", amplitude))
        shown = cli_in_process("plan", tmp_path / "c.yaml", cwd=tmp_path)
        assert shown.returncode == 0, shown.stderr
        assert ("warning: the nominal flight: the pulse of 1 deg never moved the elevator" in shown.stderr) == warned
    (tmp_path / "c.yaml").write_text(text.replace("AMPLITUDE", "1.0"))
    ran = cli_in_process("run", tmp_path / "c.yaml", cwd=tmp_path)  # run says it too, in its summary
    assert ran.returncode == 0, ran.stderr
    assert "warning: the nominal flight: the pulse of 1 deg never moved the elevator" in ran.stdout


def test_aircraft_list_names_the_projects_and_jsbsims_aircraft():
    # `uqflight aircraft --list` (and `uqflight aircraft` alone) raised a NameError before it printed a line
    for args in (("aircraft", "--list"), ("aircraft",)):
        listed = cli_in_process(*args)
        assert listed.returncode == 0, listed.stderr
        lines = dict(line.split(": ", 1) for line in listed.stdout.splitlines())
        assert any("bacm" in names.split() for names in lines.values()), listed.stdout
        assert any({"c172x", "737"} <= set(names.split()) for names in lines.values()), listed.stdout
