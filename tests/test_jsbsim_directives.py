"""What JSBSim's own directives may do when uqflight flies a script or an aircraft (issue 44: D01-D04, D22).

JSBSim writes an `<output>` directive's file, connects an output socket and listens on an `<input>`
port at `run_ic`, reads every file a `file=` names and loads a `<child>` aircraft by name. A name
leading outside its folder is refused at `plan` (exit 2, one line naming the file and the element);
every `<input>` and `<output>` directive is removed before JSBSim reads the file, so nothing else is
written, connected to or listened on either. Real JSBSim, JSBSim's own script and aircraft."""
import os
import shutil
import socket
import tempfile
from pathlib import Path

import numpy as np
import pytest
import yaml
from conftest import cli, cli_in_process
from test_path_safety import home  # noqa: F401 - the sentinel folder holding only the cache

from uqflight.simulators import make_simulator
from uqflight.simulators.aircraft import AircraftFiles, AircraftUnsafe, jsbsim_root, locate
from uqflight.simulators.base import SimulatorSettingError
from uqflight.simulators.scenarios.script import ScriptFile, jsbsim_scripts
from uqflight.simulators.spec import SimulatorSpec

CRUISE = jsbsim_scripts() / "c172_cruise_8K.xml"  # c172x, its reset01 from the aircraft folder
RUN = '<run start="0.0" end="40" dt="0.0083333">'
PROBE = '<property>velocities/vt-fps</property>'
C172 = {"altitude_ft": 4000, "airspeed_ktas": 100}  # inside the c172's envelope
WIND = {"wind": {"property": "atmosphere/wind-north-fps", "distribution": "uniform", "lower": -1, "upper": 1}}


@pytest.fixture
def scratch(tmp_path, monkeypatch):
    """The temporary directory of this process and of the workers it starts: tmp_path/tmp."""
    folder = tmp_path / "tmp"
    folder.mkdir()
    monkeypatch.setenv("TMPDIR", str(folder))
    monkeypatch.setattr(tempfile, "tempdir", None)  # read TMPDIR again
    return folder


def hostile_script(folder: Path, directives: str = "", run: str = RUN) -> Path:
    """JSBSim's c172_cruise_8K with `directives` added to <runscript> and its <run> element replaced."""
    text = CRUISE.read_text().replace(RUN, run).replace("</runscript>", f"{directives}\n</runscript>")
    assert RUN in CRUISE.read_text()
    path = folder / "hostile.xml"
    path.write_text(text)
    return path


def script_simulator(scenario=None) -> dict:
    return {"kind": "jsbsim", "scenario": scenario or {"kind": "script", "script": "hostile.xml", "end_s": 1.5},
            "output_rate_hz": 10, "outputs": ["h_ft"]}


def campaign(folder: Path, simulator: dict, samples: int = 2) -> Path:
    path = folder / "c.yaml"
    path.write_text(yaml.safe_dump({"name": "hostile", "simulator": simulator, "parameters": WIND,
                                    "design": {"kind": "monte_carlo", "samples": samples}}))
    return path


def refused(result) -> str:
    """The one line of a refusal (exit 2); the traceback or the success otherwise fails the test."""
    assert result.returncode == 2, result.stdout + result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    return lines[0]


def copied_aircraft(tmp_path: Path, name: str, edit, root: bool = False) -> Path:
    """JSBSim's c172p as tmp_path/planes/NAME (or a root of its own, tmp_path/root/aircraft/NAME, whose
    engine/ and systems/ JSBSim reads) with `edit` applied to its main file; the folder."""
    folder = tmp_path / ("root/aircraft" if root else "planes") / name
    shutil.copytree(jsbsim_root() / "aircraft" / "c172p", folder)
    if root:
        shutil.copytree(jsbsim_root() / "engine", tmp_path / "root" / "engine")
        (tmp_path / "root" / "systems").mkdir()
    (folder / "c172p.xml").rename(folder / f"{name}.xml")
    (folder / f"{name}.xml").write_text(edit((folder / f"{name}.xml").read_text()))
    return folder


def appended(text: str):
    return lambda xml: xml.replace("</fdm_config>", f"{text}\n</fdm_config>")


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def listening(port: int) -> bool:
    try:
        socket.create_connection(("127.0.0.1", port), timeout=2).close()
        return True
    except OSError:
        return False


# -- D01: a script's output file ----------------------------------------------------------------
@pytest.mark.parametrize("where", ["absolute", "../"])
def test_a_script_output_file_outside_is_refused_at_plan_and_nothing_is_written(where, tmp_path, scratch, home):
    """JSBSim writes a relative output name below its output path (the scratch folder in the temporary
    directory): `../precious.txt` reaches the temporary directory itself."""
    precious = scratch / "precious.txt"
    precious.write_text("keep")
    name = str(precious) if where == "absolute" else "../precious.txt"
    hostile_script(tmp_path, f'<output name="{name}" type="CSV" rate="10">{PROBE}</output>')
    line = refused(cli_in_process("plan", campaign(tmp_path, script_simulator())))
    assert f'hostile.xml: <output name="{name}">' in line and "simulator.scenario.script" in line
    assert precious.read_text() == "keep"


def test_a_script_flight_writes_connects_and_listens_nowhere(tmp_path, scratch, home, monkeypatch):
    """Directives whose names stay inside (a CSV file, an output directives file, an output socket, an input
    port) are removed before JSBSim reads the script: no file in the temporary directory, the working
    directory or beside the script, no connection, no listener, while the flight is loaded."""
    monkeypatch.chdir(tmp_path)
    server = socket.create_server(("127.0.0.1", 0))
    server.setblocking(False)
    port, inbound = server.getsockname()[1], free_port()
    (tmp_path / "directives.xml").write_text(f'<output name="directed.csv" type="CSV" rate="10">{PROBE}</output>')
    hostile_script(tmp_path, f'<output name="log.csv" type="CSV" rate="10">{PROBE}</output>\n'
                             '<output file="directives.xml"/>\n'
                             f'<output name="127.0.0.1" type="SOCKET" port="{port}" protocol="TCP" rate="10">'
                             f'{PROBE}</output>\n<input port="{inbound}"/>')
    before = sorted(os.listdir(tmp_path))
    simulator = make_simulator(SimulatorSpec.from_checked(script_simulator()), ["wind"], ["atmosphere/wind-north-fps"],
                               tmp_path)
    result = simulator.evaluate(np.array([1.0]))
    assert np.all(np.isfinite(result["h_ft"]))
    assert not listening(inbound)
    with pytest.raises(BlockingIOError):
        server.accept()
    server.close()
    assert sorted(os.listdir(tmp_path)) == before
    assert os.listdir(scratch) == []


def test_run_leaves_no_scratch_folder_in_the_temporary_directory(tmp_path, scratch, home):
    """Two workers fly a script campaign; the temporary directory they share is empty afterwards."""
    hostile_script(tmp_path)
    path = campaign(tmp_path, script_simulator(), samples=4)
    result = cli_in_process("run", path, "--workers", "2", "--out", tmp_path / "c.h5")
    assert result.returncode == 0, result.stdout + result.stderr
    assert os.listdir(scratch) == []


# -- D03: sockets of the aircraft ----------------------------------------------------------------
def test_an_aircraft_flies_without_its_output_socket_and_input_port(tmp_path, scratch, home):
    """JSBSim's 737 listens on an <input> port and its c310 sends <output type="SOCKET">: a copy doing both
    on free ports (one input in a namespace, which JSBSim does not see) flies a level flight that neither
    connects nor listens."""
    server = socket.create_server(("127.0.0.1", 0))
    server.setblocking(False)
    port, inbound = server.getsockname()[1], free_port()
    copied_aircraft(tmp_path, "talky", appended(
        f'<output name="127.0.0.1" type="SOCKET" port="{port}" rate="10">{PROBE}</output>\n'
        f'<output name="127.0.0.1" type="FLIGHTGEAR" port="{port}" protocol="TCP" rate="10"/>\n'
        f'<input xmlns="urn:x" port="{inbound}"/>\n<input port="{free_port()}" type="QTJSBSIM"/>'))
    spec = SimulatorSpec("jsbsim", {"aircraft": "planes/talky", "duration_s": 0.5, "flight": C172})
    simulator = make_simulator(spec, ["wind"], ["atmosphere/wind-north-fps"], tmp_path)
    assert np.all(np.isfinite(simulator.evaluate(np.array([1.0]))["h_ft"]))
    assert not listening(inbound)
    with pytest.raises(BlockingIOError):
        server.accept()
    server.close()
    assert os.listdir(scratch) == []


def test_an_aircraft_output_file_inside_is_written_nowhere(tmp_path, scratch, home, monkeypatch):
    """JSBSim's c172x names `JSBout172B.csv`, written below JSBSim's output path (the root: JSBSim's package
    for its own aircraft): flown, it writes (or truncates) nothing there, in the working directory or in
    the cache's root."""
    monkeypatch.chdir(tmp_path)
    package = {p.name: p.stat().st_mtime_ns for p in jsbsim_root().iterdir()}
    spec = SimulatorSpec("jsbsim", {"aircraft": "c172x", "duration_s": 0.5, "flight": C172})
    simulator = make_simulator(spec, ["wind"], ["atmosphere/wind-north-fps"], tmp_path)
    simulator.evaluate(np.array([1.0]))
    assert {p.name: p.stat().st_mtime_ns for p in jsbsim_root().iterdir()} == package
    assert not [p for p in (home / "cache").rglob("*.csv")] and sorted(os.listdir(tmp_path)) == ["home", "tmp"]


# -- D02: files Python cannot parse --------------------------------------------------------------
HIDDEN = {  # what makes Python refuse a file JSBSim reads (expat without namespaces, external entities skipped)
    "external entity": ('<!DOCTYPE output [<!ENTITY e SYSTEM "nowhere.ent">]>\n', "&e;"),
    "unbound prefix": ("", "<x:note>JSBSim reads x:note as a name</x:note>"),
}


@pytest.mark.parametrize("how", list(HIDDEN))
def test_an_output_directives_file_python_cannot_parse_is_refused(how, tmp_path, home):
    """The main file names `directives.xml` (inside the folder); that file's <output> writes at an absolute
    path, hidden from a Python check by what it cannot parse."""
    precious = tmp_path / "precious.txt"
    precious.write_text("keep")
    folder = copied_aircraft(tmp_path, "hidden", appended('<output file="directives.xml"/>'))
    doctype, body = HIDDEN[how]
    (folder / "directives.xml").write_text(f'<?xml version="1.0"?>\n{doctype}<output name="{precious}" type="CSV" '
                                           f'rate="1">{body}{PROBE}</output>\n')
    line = refused(cli_in_process("plan", campaign(tmp_path, {"kind": "jsbsim", "aircraft": "planes/hidden",
                                                              "duration_s": 0.5})))
    assert f"{folder / 'directives.xml'} is not well-formed XML" in line
    assert precious.read_text() == "keep"


def test_a_shared_system_file_python_cannot_parse_is_refused(tmp_path, home):
    """A system file from the root's systems/ folder is read by JSBSim like the aircraft's own."""
    copied_aircraft(tmp_path, "shared", appended('<system file="hidden"/>'), root=True)
    doctype, body = HIDDEN["external entity"]
    shared = tmp_path / "root" / "systems" / "hidden.xml"
    shared.write_text(f'<?xml version="1.0"?>\n{doctype.replace("output", "system")}<system name="x">{body}</system>\n')
    with pytest.raises(AircraftUnsafe, match=f"{shared} is not well-formed XML"):
        AircraftFiles.read(locate(tmp_path / "root" / "aircraft" / "shared"))


# -- D22: a namespace ---------------------------------------------------------------------------
def test_an_output_in_a_namespace_is_checked_as_jsbsim_reads_it(tmp_path, home):
    """JSBSim reads element names without namespaces: <output xmlns="urn:x"> is an output directive."""
    precious = tmp_path / "precious.txt"
    precious.write_text("keep")
    copied_aircraft(tmp_path, "spaced", appended(f'<output xmlns="urn:x" name="{precious}" type="CSV" rate="1">'
                                                 f'{PROBE}</output>'))
    line = refused(cli_in_process("plan", campaign(tmp_path, {"kind": "jsbsim", "aircraft": "planes/spaced",
                                                              "duration_s": 0.5})))
    assert f'spaced.xml: <output name="{precious}">' in line
    assert precious.read_text() == "keep"


def test_a_default_namespaced_aircraft_is_patched_and_flown_with_the_names_jsbsim_reads(tmp_path, home):
    """JSBSim ignores a default namespace: a c172p whose <fdm_config xmlns="urn:x"> holds an <output> (removed)
    is patched (aero/uq/scale/CLwbh scales its lift) and flown; the file JSBSim reads names its elements as
    the original did, without the ns0: prefix Python's writer would give them (which JSBSim cannot read)."""
    def spaced(xml):
        return appended(f'<output name="out.csv" type="CSV" rate="1">{PROBE}</output>')(
            xml.replace("<fdm_config ", '<fdm_config xmlns="urn:x" ', 1))
    copied_aircraft(tmp_path, "spaced", spaced)
    spec = SimulatorSpec("jsbsim", {"aircraft": "planes/spaced", "duration_s": 1.0, "flight": C172,
                                    "outputs": ["alpha_deg"]})
    simulator = make_simulator(spec, ["CL"], ["aero/uq/scale/CLwbh"], tmp_path)
    nominal, scaled = (simulator.evaluate(np.array([x]))["alpha_deg"] for x in (1.0, 1.2))
    assert np.all(np.isfinite(nominal)) and scaled[0] < nominal[0] - 0.1  # more lift per alpha trims lower
    flown = [p.read_text() for p in (home / "cache").rglob("spaced.xml")]
    assert flown and all("ns0:" not in text and 'xmlns="urn:x"' in text and "aero/uq/scale/CLwbh" in text
                         and "out.csv" not in text for text in flown)


def test_a_default_namespaced_script_trims_as_jsbsim_reads_it(tmp_path):
    """JSBSim's 737_cruise sets simulation/do_simple_trim in one event; with <runscript xmlns="urn:x"> JSBSim
    reads the same script, and so does uqflight (one trim event, its <output> removed, no prefix added)."""
    text = (jsbsim_scripts() / "737_cruise.xml").read_text().replace("<runscript ", '<runscript xmlns="urn:x" ', 1)
    path = tmp_path / "spaced.xml"
    path.write_text(text.replace("</runscript>", '<output name="o.csv" type="CSV" rate="1"/>\n</runscript>'))
    script = ScriptFile.read(path)
    assert script.trims == 1 and script.initialize == "cruise_init"
    from uqflight.simulators.directives import without_io
    written = without_io(path.read_bytes()).decode()
    assert "ns0:" not in written and "<output" not in written and 'name="simulation/do_simple_trim"' in written


def test_a_child_aircraft_is_refused(tmp_path, home):
    """JSBSim loads a <child name=NAME> aircraft from the root's aircraft/NAME/NAME.xml: files no check saw."""
    copied_aircraft(tmp_path, "mother", appended(
        '<child name="../../elsewhere/evil"><location unit="IN"><x>0</x><y>0</y><z>0</z></location></child>'))
    line = refused(cli_in_process("plan", campaign(tmp_path, {"kind": "jsbsim", "aircraft": "planes/mother",
                                                              "duration_s": 0.5})))
    assert 'mother.xml: <child name="../../elsewhere/evil">' in line


@pytest.mark.slow
def test_a_script_setting_the_linearization_is_refused(tmp_path, home):
    """`simulation/do_linearization` makes JSBSim write NAME_lin.sce in the working directory."""
    hostile_script(tmp_path, run=RUN + '\n<event name="lin"><condition> simulation/sim-time-sec ge 0.1 </condition>'
                                       '<set name="simulation/do_linearization" value="1"/></event>')
    line = refused(cli("plan", campaign(tmp_path, script_simulator()), cwd=tmp_path, timeout=120))
    assert "hostile.xml" in line and "simulation/do_linearization" in line
    assert not list(tmp_path.glob("*_lin.sce"))


# -- D04: the steps a script sets ---------------------------------------------------------------
@pytest.mark.parametrize("run, end_s", [('<run start="0" end="100000" dt="0.000001">', None),  # 10^11 steps
                                        ('<run start="0" end="1e400" dt="0.0083333">', None),  # an infinite end
                                        ('<run start="0" end="1000000" dt="0.0083333">', 900000)])
def test_a_script_with_too_many_steps_is_refused_before_anything_is_allocated(run, end_s, tmp_path, home):
    """The integration steps are counted from <run> (and end_s) before any step time is held."""
    hostile_script(tmp_path, run=run)
    scenario = {"kind": "script", "script": "hostile.xml", **({"end_s": end_s} if end_s else {})}
    line = refused(cli_in_process("plan", campaign(tmp_path, script_simulator(scenario))))
    assert "hostile.xml" in line and "simulator.scenario" in line
    assert "integration steps" in line or "finite" in line


def test_the_step_count_is_bounded_where_it_is_computed(tmp_path):
    from uqflight.simulators.scenarios.script import MAX_STEPS

    hostile_script(tmp_path, run='<run start="0" end="100000" dt="0.000001">')
    script = ScriptFile.read(tmp_path / "hostile.xml")
    with pytest.raises(SimulatorSettingError, match=f"more than {MAX_STEPS}"):
        script.times()
    assert len(ScriptFile.read(jsbsim_scripts() / "ball_orbit.xml").times(10.0)) == 2001  # 10 s at dt = 0.005


def test_a_parameter_setting_the_linearization_is_refused(tmp_path, home):
    """The same property set by a campaign's parameter (a stored campaign flown again by `calibrate`)."""
    path = tmp_path / "c.yaml"
    path.write_text(yaml.safe_dump({
        "name": "lin", "simulator": {"kind": "jsbsim", "aircraft": "c172p", "duration_s": 0.5, "flight": C172},
        "parameters": {"lin": {"property": "simulation/do_linearization", "distribution": "uniform", "lower": 0,
                               "upper": 1}}, "design": {"kind": "monte_carlo", "samples": 2}}))
    line = refused(cli_in_process("plan", path, cwd=tmp_path))
    assert "parameters.lin.property" in line and "simulation/do_linearization" in line
    assert not list(tmp_path.glob("*_lin.sce"))


def test_an_initialisation_file_beside_the_script_that_python_cannot_parse_is_refused(tmp_path, home):
    """JSBSim reads the initialisation file beside the script (before the aircraft folder's): checked too."""
    hostile_script(tmp_path)
    doctype, body = HIDDEN["external entity"]
    (tmp_path / "reset01.xml").write_text(f'<?xml version="1.0"?>\n{doctype.replace("output", "initialize")}'
                                          f'<initialize name="r">{body}<altitude unit="FT">4000</altitude></initialize>\n')
    line = refused(cli_in_process("plan", campaign(tmp_path, script_simulator())))
    assert f"{tmp_path / 'reset01.xml'} is not well-formed XML" in line and "simulator.scenario.script" in line
