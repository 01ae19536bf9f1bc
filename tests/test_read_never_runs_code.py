"""Reading results never imports or runs campaign code (issue 22, item 2): `info`, `report`, `check`,
`surrogate export` and `calibrate` up to its posterior-predictive runs.

Two campaigns are run with honest python models (a `model.py:f` file, and a `hostilepkg.model:f`
module), then every copy of those models a reader could find is made hostile: in the working
directory, beside the results file, at the campaign's recorded path, and the module on PYTHONPATH
(and in the working directory). A hostile model, when imported, writes a sentinel file holding the
stack that imported it and raises. Real CLI processes, real workers, real HDF5."""
import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest
from conftest import ROOT, UQFLIGHT

HONEST = '''
import numpy as np
T = np.linspace(0.0, 2.0, 21)

def f(p):
    return {"time": T, "y": p["a"] + p["b"] * T + 1e-4 * p["c"] * T**2}
'''
HOSTILE = '''
import traceback
with open({sentinel!r}, "w") as fh:
    fh.write("".join(traceback.format_stack()))
raise RuntimeError("campaign code ran")
'''
CAMPAIGN = """
name: {name}
seed: 3
simulator: {{kind: python, function: "{function}"}}
parameters:
  a: {{distribution: normal, nominal: 1.0, interval_pct: 30}}
  b: {{distribution: normal, nominal: -0.5, interval_pct: 30}}
  c: {{distribution: uniform, lower: -1, upper: 1}}
design: {{kind: latin_hypercube, samples: 40}}
method: {{kind: regression, order: 2}}
"""
PARAMETERS = {"a": (0.7, 1.3), "b": (-0.65, -0.35), "c": (-1.0, 1.0)}  # lower, upper: ±30 % of the nominal


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    root = tmp_path_factory.mktemp("readers")
    project, results, cwd, packages, sentinels = (root / name for name in ("proj", "res", "cwd", "pkgs", "sentinels"))
    for folder in (project, results, cwd, packages / "hostilepkg", sentinels):
        folder.mkdir(parents=True)
    (project / "model.py").write_text(HONEST)
    (packages / "hostilepkg" / "__init__.py").write_text("")
    (packages / "hostilepkg" / "model.py").write_text(HONEST)
    env = dict(os.environ, PYTHONPATH=f"{packages}{os.pathsep}{ROOT}")
    for name, function in (("file", "model.py:f"), ("module", "hostilepkg.model:f")):
        campaign = project / f"{name}.yaml"
        campaign.write_text(CAMPAIGN.format(name=name, function=function))
        ran = subprocess.run([UQFLIGHT, "run", str(campaign), "--out", str(results / f"{name}.h5")], env=env,
                             capture_output=True, text=True, timeout=300)
        assert ran.returncode == 0, ran.stderr
    for where, folder in (("recorded", project), ("beside", results), ("cwd", cwd)):
        (folder / "model.py").write_text(HOSTILE.format(sentinel=str(sentinels / where)))
    for where, folder in (("module", packages), ("module-cwd", cwd)):
        (folder / "hostilepkg").mkdir(exist_ok=True)
        (folder / "hostilepkg" / "__init__.py").write_text(HOSTILE.format(sentinel=str(sentinels / where)))
    return {"root": root, "results": results, "cwd": cwd, "sentinels": sentinels,
            "env": dict(env, PYTHONPATH=f"{packages}{os.pathsep}{cwd}{os.pathsep}{ROOT}")}


def read(world, *args):
    """`uqflight ARGS` in the hostile working directory, with the hostile package on PYTHONPATH."""
    return subprocess.run([UQFLIGHT, *map(str, args)], cwd=world["cwd"], env=world["env"], capture_output=True,
                          text=True, timeout=300)


def ran_code(world) -> dict[str, str]:
    return {path.name: path.read_text() for path in world["sentinels"].iterdir()}


@pytest.mark.slow  # four commands, a report with plots among them: ~17 s
@pytest.mark.parametrize("name", ["file", "module"])
def test_info_report_check_and_surrogate_export_import_no_model(world, name, tmp_path):
    results = world["results"] / f"{name}.h5"
    info = read(world, "info", results)
    assert info.returncode == 0, info.stderr
    report = read(world, "report", results, "--out", tmp_path / "report", "--write-baseline", tmp_path / "b.json")
    assert report.returncode == 0, report.stderr
    check = read(world, "check", results, "--baseline", tmp_path / "b.json")
    assert check.returncode == 0, check.stderr
    export = read(world, "surrogate", "export", results, "--out", tmp_path / "p.json")
    assert export.returncode == 0, export.stderr
    assert ran_code(world) == {}
    # what the readers need came from the results file: the parameters' laws with their nominal values
    exported = {p["name"]: p for p in json.loads((tmp_path / "p.json").read_text())["parameters"]}
    for parameter, (lower, upper) in PARAMETERS.items():
        assert exported[parameter]["lower"] == pytest.approx(lower, rel=1e-15)
        assert exported[parameter]["upper"] == pytest.approx(upper, rel=1e-15)
    table = (tmp_path / "report" / "tables" / "parameters.csv").read_text()
    assert "could not be read" not in table and "0.7,1.3,1.0" in table


@pytest.mark.parametrize("name", ["file", "module"])
def test_the_calibration_surrogate_imports_no_model(world, name, monkeypatch):
    """`calibrate` before its sampling: the campaign, the parameters and the PCE surrogate of the file."""
    from uqflight.calibration.surrogate import calibration_surrogate

    monkeypatch.chdir(world["cwd"])
    for folder in world["env"]["PYTHONPATH"].split(os.pathsep)[:2]:
        monkeypatch.syspath_prepend(folder)
    surrogate = calibration_surrogate(world["results"] / f"{name}.h5")
    assert [(p.name, p.lower, p.upper) for p in surrogate.parameters] == [
        (n, pytest.approx(lower, rel=1e-15), pytest.approx(upper, rel=1e-15)) for n, (lower, upper) in PARAMETERS.items()]
    assert ran_code(world) == {}


@pytest.mark.slow
def test_calibrate_imports_the_model_only_for_its_predictive_runs(world, tmp_path):
    """The model beside the results file is the one the predictive runs call: it is imported there, in their
    worker processes (and fails, being hostile), after the surrogate, the data and the sampling; no other
    copy is ever imported."""
    time = np.linspace(0.0, 2.0, 21)
    rng = np.random.default_rng(1)
    y = 1.12 - 0.46 * time + 0.05 * rng.standard_normal(time.size)
    data = tmp_path / "flight.csv"
    data.write_text("time_s,y\n" + "".join(f"{t:g},{float(v)!r}\n" for t, v in zip(time, y)))
    run = read(world, "calibrate", world["results"] / "file.h5", "--data", data, "--out", tmp_path / "cal",
               "--noise", "y=0.05", "--steps", "2000", "--predictive-draws", "2")
    assert run.returncode == 2, run.stdout + run.stderr
    assert "cannot import 'model.py': RuntimeError: campaign code ran" in run.stderr
    found = ran_code(world)
    assert set(found) == {"beside"}
    assert "uqflight/running/worker.py" in found["beside"]  # in a worker of the predictive runs (runner.simulate)
    (world["sentinels"] / "beside").unlink()


@pytest.mark.slow
@pytest.mark.parametrize("where", ["../proj/model.py", "{root}/proj/model.py"])
def test_calibrate_refuses_a_model_that_a_results_file_places_outside_its_folder(world, tmp_path, where):
    """A results file whose stored campaign names its model by a path leading out of its folder (edited, or
    of a campaign that named ../model.py) is refused before any import: it would run code elsewhere."""
    import json

    import h5py

    results = world["results"] / f"outside-{where[0]}.h5"
    results.write_bytes((world["results"] / "file.h5").read_bytes())
    with h5py.File(results, "a") as f:
        record = json.loads(f.attrs["record"])
        record["campaign"]["simulator"]["function"] = f"{where.format(root=world['root'])}:f"
        f.attrs["record"] = json.dumps(record)
    data = tmp_path / "flight.csv"
    data.write_text("time_s,y\n0,1.1\n1,0.6\n2,0.2\n")
    run = read(world, "calibrate", results, "--data", data, "--out", tmp_path / "cal", "--noise", "y=0.05")
    assert run.returncode == 2, run.stdout + run.stderr
    assert f"error: {results}: simulator.function: the python model " in run.stderr
    assert "is outside the results file's folder" in run.stderr and "--campaign" in run.stderr
    assert ran_code(world) == {} and not (tmp_path / "cal").exists()


def test_the_reading_path_never_resolves_the_simulator():
    """Structural: the modules that read a results file's campaign never call what imports code."""
    for module in ("record.py", "reading.py"):
        source = (ROOT / "uqflight" / "campaign" / module).read_text()
        assert "resolve_simulator(" not in source and "load_function" not in source and "make_simulator" not in source
    assert "resolve_simulator" in Path(ROOT / "uqflight" / "campaign" / "__init__.py").read_text()


JSBSIM = """
name: jsbsim-reading
simulator: {kind: jsbsim, duration_s: 1, output_rate_hz: 10}
parameters:
  CL0: {property: aero/uq/CL0, distribution: normal, interval_pct: 23.05}
  V: {property: ic/vt-kts, distribution: normal, lower: 195, upper: 205}
design: {kind: monte_carlo, samples: 2}
"""


def without_record(path, copy):
    """A copy of a results file without its `record` attribute (a file of an older layout)."""
    import shutil

    import h5py

    shutil.copy(path, copy)
    with h5py.File(copy, "a") as f:
        del f.attrs["record"]
    return copy


MISSING = ("the results file has no record attribute (the campaign it was made with): a file of an older layout, or "
           "not written by uqflight: fly the campaign again (`uqflight run CAMPAIGN --out FILE --restart` starts "
           "this file over)")


def test_a_jsbsim_run_stores_the_nominal_values_it_read_from_the_aircraft(tmp_path):
    """Readers take them from the file's record; a file without it is refused naming it and the fix."""
    from uqflight.campaign import parse_campaign
    from uqflight.campaign.record import parameter_rows, read_record
    from uqflight.campaign.schema import CampaignError
    from uqflight.running.runner import run_campaign
    from uqflight.simulators.aircraft_properties import AircraftProperties
    from uqflight.store import ResultStore

    campaign = parse_campaign(JSBSIM, str(tmp_path / "c.yaml"), AircraftProperties)
    run_campaign(campaign, out=tmp_path / "j.h5")
    expected = parameter_rows(campaign.parameters)
    assert expected[0]["nominal"] == AircraftProperties(campaign.simulator).value("aero/uq/CL0")  # not in the campaign
    with ResultStore.open(tmp_path / "j.h5") as store:
        assert read_record(store.attrs, "j.h5").parameter_rows == expected
    with ResultStore.open(without_record(tmp_path / "j.h5", tmp_path / "old.h5")) as store:
        with pytest.raises(CampaignError) as refused:
            read_record(store.attrs, "old.h5")
    assert str(refused.value) == f"old.h5: {MISSING}"


def test_a_file_without_its_record_is_refused_without_running_its_model(world, monkeypatch):
    from uqflight.campaign.record import read_record
    from uqflight.campaign.schema import CampaignError
    from uqflight.store import ResultStore

    old = without_record(world["results"] / "file.h5", world["results"] / "older.h5")
    monkeypatch.chdir(world["cwd"])
    with ResultStore.open(old) as store:
        with pytest.raises(CampaignError, match="no record attribute"):
            read_record(store.attrs, str(old))
    old.unlink()
    assert ran_code(world) == {}
