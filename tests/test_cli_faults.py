"""The commands under a model's faults: plan flies its nominal in a supervised worker under the campaign's
time limit (a hang or a crash there is one line, exit 2), plans every method and design kind, a reason on
several lines is shown on one, and Ctrl-C while uqflight starts is one line with exit 130. Real worker
processes, real python models (tests/data/hostile_model.py)."""
import os
import signal
import subprocess
import sys

import pytest
from conftest import DATA, ROOT, UQFLIGHT, cli_in_process, hostile_campaign_text

import uqflight.running.runner
from uqflight.designs import REGISTRY as DESIGNS
from uqflight.methods import METHODS


def write(tmp_path, function, **kwargs):
    path = tmp_path / "c.yaml"
    path.write_text(hostile_campaign_text(function, **kwargs))
    return path


@pytest.mark.slow
def test_plan_flies_its_nominal_under_the_campaigns_time_limit(tmp_path, monkeypatch):
    # the model never returns at the nominal: plan ran for ever; now it gives up as run does, after
    # execution.timeout_s plus the worker's start (shortened here from 60 s to 2 s: the same code path)
    monkeypatch.setattr(uqflight.running.runner, "STARTUP_GRACE_S", 2.0)
    campaign = write(tmp_path, "hanging_at_centre", extra=", timeout_s: 1")
    planned = cli_in_process("plan", campaign)
    assert planned.returncode == 2, planned.stderr
    assert planned.stderr.count("\n") == 1 and "Traceback" not in planned.stderr, planned.stderr
    assert planned.stderr.startswith(f"error: {campaign}: the nominal flight did not finish within 3 s "
                                     "(execution.timeout_s 1 s plus 2 s for the worker's start)"), planned.stderr


def test_plan_reports_a_model_that_kills_its_process_at_the_nominal_as_run_does(tmp_path):
    campaign = write(tmp_path, "segfault_at_centre")
    planned = cli_in_process("plan", campaign)
    ran = cli_in_process("run", campaign, "--out", tmp_path / "c.h5")
    for done in (planned, ran):
        assert done.returncode == 2, done.stderr
        assert done.stderr.count("\n") == 1 and "Traceback" not in done.stderr, done.stderr
        assert done.stderr.startswith(f"error: {campaign}: worker process died: signal 11 (SIGSEGV)"), done.stderr


@pytest.mark.slow
def test_plan_in_a_process_of_its_own_does_not_die_with_the_model(tmp_path):
    # as a user runs it: the uqflight process itself, not the test's (exit 139 before)
    done = subprocess.run([UQFLIGHT, "plan", str(write(tmp_path, "segfault_at_centre"))], capture_output=True,
                          text=True, timeout=300, env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert done.returncode == 2 and "SIGSEGV" in done.stderr, (done.returncode, done.stderr)


def _method_design_cases():
    """Every design kind with a method kind, the methods taken in turn (a grid skips the ones that need a
    sampled design), then any method no design took on a Monte Carlo design: every entry of both
    registries is planned once."""
    methods, cases = list(METHODS), []
    for i, design in enumerate(DESIGNS):
        turn = methods[i % len(methods):] + methods[:i % len(methods)]
        cases.append((next(m for m in turn if DESIGNS[design].sampled or not METHODS[m].sampled_only), design))
    cases += [(m, "monte_carlo") for m in methods if m not in {method for method, _ in cases}]
    return cases


@pytest.mark.parametrize("method, design", _method_design_cases())
def test_plan_plans_every_method_and_design_kind(tmp_path, method, design):
    entry, spec = METHODS[method], dict(DESIGNS[design].example)
    settings = f", {entry.order_key}: 1" if entry.expands else ""
    body = ", ".join(f"{k}: {v}" for k, v in spec.items())  # a rare-event design's event: the quantity below
    (tmp_path / "c.yaml").write_text(
        f"name: every\nseed: 5\nsimulator: {{kind: python, function: \"{DATA / 'trust_models.py'}:sum_of_squares\"}}\n"
        "parameters:\n  x1: {distribution: normal, lower: -3, upper: 3}\n"
        "  x2: {distribution: normal, lower: -3, upper: 3}\n"
        f"design: {{{body}}}\nmethod: {{kind: {method}{settings}}}\n"
        + (f"quantities: {{{spec['event']['of']}: {{of: y, take: final}}}}\n" if "event" in spec else ""))
    planned = cli_in_process("plan", tmp_path / "c.yaml")
    assert planned.returncode == 0, planned.stderr
    assert "Traceback" not in planned.stderr
    assert "estimated time: " in planned.stdout
    assert ("event: " if "event" in spec else f"method: {method}") in planned.stdout  # a rare design: its event


def test_a_reason_on_several_lines_is_summarised_on_one_as_plain_text(tmp_path):
    campaign = write(tmp_path, "multi_line_failure", samples=20)
    ran = cli_in_process("run", campaign, "--out", tmp_path / "c.h5")
    assert ran.returncode == 0, ran.stderr
    failed = [line for line in ran.stdout.splitlines() if "failed (" in line]
    assert failed and all("np.str_" not in line for line in failed), ran.stdout
    assert "): 'ValueError: first line\\nerror: a forged second line'" in failed[0]
    assert not any(line.startswith("error: a forged") for line in ran.stdout.splitlines())


SITE_INTERRUPT = '''
import os, signal, sys


class InterruptOnImport:
    """Ctrl-C (a real SIGINT to this process) as uqflight's command line imports numpy."""

    def find_spec(self, name, path=None, target=None):
        if name == "numpy" and "uqflight.cli.commands" in sys.modules:
            sys.meta_path.remove(self)
            os.kill(os.getpid(), signal.SIGINT)
        return None


sys.meta_path.insert(0, InterruptOnImport())
'''


def test_ctrl_c_while_uqflight_starts_is_one_line_and_exit_130(tmp_path):
    (tmp_path / "sitecustomize.py").write_text(SITE_INTERRUPT)
    done = subprocess.run([UQFLIGHT, "--version"], capture_output=True, text=True, timeout=120,
                          env={**os.environ, "PYTHONPATH": f"{tmp_path}{os.pathsep}{ROOT}"},
                          preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    assert done.returncode == 130, (done.returncode, done.stderr)
    assert "Traceback" not in done.stderr and "KeyboardInterrupt" not in done.stderr, done.stderr
    assert done.stderr.strip() == "interrupted: uqflight was starting, nothing was done" and done.stdout == ""


def test_a_run_whose_times_differ_from_the_nominals_fails_and_is_not_stored_against_them(tmp_path):
    # shifted_time returns times 5, 6 (not 0, 1) where x > 1, with values of the same length
    from uqflight.store import ResultStore, Status

    ran = cli_in_process("run", write(tmp_path, "shifted_time", samples=20), "--out", tmp_path / "c.h5")
    assert ran.returncode == 0, ran.stderr
    with ResultStore.open(tmp_path / "c.h5") as store:
        x, status, reasons = store.kappa[:, 0], store.status, list(store.reasons)
        assert store.time.tolist() == [0.0, 1.0]
    shifted = x > 1.0
    assert shifted.any() and (~shifted).any()
    assert (status[shifted] == Status.SIMULATOR_ERROR).all() and (status[~shifted] == Status.OK).all()
    assert all("'time' differs from the nominal run's" in str(reasons[j]) for j in range(len(x)) if shifted[j])


FORGED = """
name: forged
seed: 5
simulator: {kind: python, function: "hostile_model.py:forged_names"}
parameters:
  "x\\nerror: a forged parameter line": {distribution: uniform, lower: -2, upper: 2}
design: {kind: tensor_grid, points: 5}
method: {kind: pseudo_galerkin, order: 2}
"""


@pytest.fixture(scope="module")
def forged(tmp_path_factory):
    """A results file whose parameter and output names hold a newline and a line of uqflight's after it,
    its python model beside it (as calibrate wants it)."""
    import shutil

    folder = tmp_path_factory.mktemp("forged")
    shutil.copy(DATA / "hostile_model.py", folder / "hostile_model.py")
    (folder / "c.yaml").write_text(FORGED)
    ran = cli_in_process("run", folder / "c.yaml", "--out", folder / "c.h5")
    assert ran.returncode == 0, ran.stderr
    return folder


def forged_lines(done):
    """The lines of a command's output that a name forged (each starts 'error: a forged' or 'error: forged')."""
    return [line for line in (done.stdout + done.stderr).splitlines() if line.startswith(("error: forged",
                                                                                          "error: a forged"))]


def test_names_from_a_results_file_are_quoted_in_check_calibrate_and_plan(forged, tmp_path):
    import json

    from uqflight.analysis.check import baseline_json
    from uqflight.analysis.statistics import read_statistics

    results = forged / "c.h5"
    stats, attrs = read_statistics(results)  # the baseline `report --write-baseline` writes
    baseline = json.loads(json.dumps(baseline_json(stats, attrs["campaign_hash"])))
    baseline["outputs"]["q"] = baseline["outputs"].pop("z")
    (tmp_path / "b.json").write_text(json.dumps(baseline))
    checked = cli_in_process("check", results, "--baseline", tmp_path / "b.json")
    assert checked.returncode == 2 and checked.stderr.count("\n") == 1, checked.stderr
    assert "'y\\nerror: forged'" in checked.stderr
    data = tmp_path / "d.csv"
    data.write_text("time_s,q\n0,1\n1,2\n")
    calibrations = [("--out", tmp_path / "cal"), ("--out", tmp_path / "cal", "--output", "zz"),
                    ("--out", tmp_path / "cal", "--output", "z", "--truth", "zz=1")]
    for args in calibrations:
        refused = cli_in_process("calibrate", results, "--data", data, *args)
        assert refused.returncode == 2 and "Traceback" not in refused.stderr, refused.stderr
        assert refused.stderr.splitlines()[-1].startswith("error: ") and not forged_lines(refused), refused.stderr
    planned = cli_in_process("plan", forged / "c.yaml")
    assert planned.returncode == 0 and not forged_lines(planned), planned.stdout
    assert "'x\\nerror: a forged parameter line'" in planned.stdout


def test_a_nominal_failure_on_several_lines_is_one_line_at_plan_and_run(tmp_path):
    # multi_line_failure fails at x > 1 with a two-line reason: the nominal of U(1.5, 2.5) is 2
    campaign = tmp_path / "c.yaml"
    campaign.write_text(hostile_campaign_text("multi_line_failure").replace("lower: -2, upper: 2",
                                                                            "lower: 1.5, upper: 2.5"))
    for done in (cli_in_process("plan", campaign), cli_in_process("run", campaign, "--out", tmp_path / "c.h5")):
        assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
        assert "the nominal sample failed" in done.stderr and not forged_lines(done), done.stderr


def test_an_aircrafts_function_names_are_quoted_by_the_aircraft_command(tmp_path):
    # `&#10;` in an XML attribute is a newline in the name Python reads; JSBSim itself refuses the name later
    import shutil

    folder = tmp_path / "root" / "aircraft" / "odd"
    shutil.copytree(ROOT / "uqflight" / "aircraft" / "bacm", folder)
    xml = (folder / "bacm.xml").read_text()
    (folder / "bacm.xml").unlink()
    forged = xml.replace('<function name="aero/force/drag-beta">',
                         '<function name="aero/force/drag-beta&#10;error: forged">')
    assert forged != xml
    (folder / "odd.xml").write_text(forged)
    listed = cli_in_process("aircraft", folder)
    assert "'aero/force/drag-beta\\nerror: forged'" in listed.stdout, listed.stdout
    assert not forged_lines(listed), listed.stdout + listed.stderr


def test_info_prints_a_results_files_texts_on_their_own_lines(forged, tmp_path):
    # the texts info shows as they are (the design's facts and the versions in the record, the aircraft's
    # hash), edited to hold newlines followed by lines of uqflight's
    import json
    import shutil

    import h5py

    shutil.copy(forged / "c.h5", tmp_path / "c.h5")
    with h5py.File(tmp_path / "c.h5", "a") as f:
        record = json.loads(f.attrs["record"])
        record["design"]["info"]["points\nerror: forged"] = "5\nerror: forged"
        record["versions"]["numpy\nerror: forged"] = "2\nerror: forged"
        f.attrs["record"] = json.dumps(record)
        f.attrs["aircraft_hash"] = "abc\nerror: forged"
    shown = cli_in_process("info", tmp_path / "c.h5")
    assert shown.returncode == 0, shown.stderr
    assert not forged_lines(shown), shown.stdout
    assert "aircraft sha256: 'abc\\nerror: forged'" in shown.stdout


@pytest.mark.slow
def test_ctrl_c_while_plan_flies_its_nominal_is_one_line_and_exit_130_and_ends_its_worker(tmp_path):
    import time
    from pathlib import Path

    from test_run_faults import alive, children

    campaign = write(tmp_path, "hanging_at_centre")
    planner = subprocess.Popen([UQFLIGHT, "plan", str(campaign)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True, env={**os.environ, "PYTHONPATH": str(ROOT)},
                               preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        for _ in range(600):  # its worker started (a bound, not a speed test)
            workers = [pid for pid in children(planner.pid)
                       if b"uqflight.running.worker" in Path(f"/proc/{pid}/cmdline").read_bytes()]
            if workers:
                break
            time.sleep(0.1)
        assert workers
        time.sleep(1.0)  # flying the nominal, which never returns
        planner.send_signal(signal.SIGINT)
        _, stderr = planner.communicate(timeout=120)
    finally:
        if planner.poll() is None:
            planner.kill()
    assert planner.returncode == 130, stderr
    assert stderr.strip() == "interrupted" and "Traceback" not in stderr, stderr
    for _ in range(100):
        if not any(alive(pid) for pid in workers):
            break
        time.sleep(0.1)
    assert not any(alive(pid) for pid in workers)


def test_run_quotes_what_it_read_from_another_campaigns_file_it_refuses(forged, tmp_path):
    # the key where the stored campaign differs first (a parameter's name holding a newline), and the
    # stored campaign hash when the stored text cannot be read (edited to hold a newline)
    import shutil

    import h5py

    shutil.copy(forged / "c.h5", tmp_path / "c.h5")
    shutil.copy(forged / "hostile_model.py", tmp_path / "hostile_model.py")
    (tmp_path / "other.yaml").write_text(FORGED.replace("upper: 2", "upper: 3"))
    refused = cli_in_process("run", tmp_path / "other.yaml", "--out", tmp_path / "c.h5")
    assert refused.returncode == 2 and refused.stderr.count("\n") == 1, refused.stderr
    assert "differs first at 'parameters.x\\nerror: a forged parameter line.upper'" in refused.stderr
    with h5py.File(tmp_path / "c.h5", "a") as f:
        f.attrs["campaign_hash"], f.attrs["campaign"] = "abc\nerror: forged", ""
    refused = cli_in_process("run", write(tmp_path, "slow", samples=2), "--out", tmp_path / "c.h5")
    assert refused.returncode == 2 and refused.stderr.count("\n") == 1, refused.stderr
    assert "(campaign_hash 'abc\\nerror: forged')" in refused.stderr and not forged_lines(refused)


def test_a_damaged_outputs_name_is_quoted_by_surrogate_export_and_report(forged, tmp_path):
    import shutil

    import h5py

    shutil.copy(forged / "c.h5", tmp_path / "c.h5")
    with h5py.File(tmp_path / "c.h5", "a") as f:  # a run with status ok holding NaN: refused as damaged
        values = f["outputs"]["y\nerror: forged"]
        edited = values[...]
        edited[1, 0] = float("nan")
        values[...] = edited
    for args in (("surrogate", "export", tmp_path / "c.h5", "--out", tmp_path / "s.json"),
                 ("report", tmp_path / "c.h5", "--out", tmp_path / "r")):
        refused = cli_in_process(*args)
        assert refused.returncode == 2 and refused.stderr.count("\n") == 1, refused.stderr
        assert "output 'y\\nerror: forged': 1 runs with status ok" in refused.stderr and not forged_lines(refused)
