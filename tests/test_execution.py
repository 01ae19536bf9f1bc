"""The runner: worker-count and executor independence, failure isolation, kill and resume."""
import os
import signal
import subprocess

import h5py
import numpy as np
import pytest
from conftest import DATA, DECAY_TWO_INPUTS, UQFLIGHT, assert_same_results, cli_in_process, hostile_campaign

from uqflight.campaign import parse_campaign
from uqflight.simulators.aircraft_properties import AircraftProperties
from uqflight.running.runner import run_campaign
from uqflight.store import ResultStore, Status


JSBSIM_CAMPAIGN = """
name: small-jsbsim
seed: 7
simulator:
  kind: jsbsim
  duration_s: {duration}
  output_rate_hz: 10
parameters:
  CL0: {{property: aero/uq/CL0, distribution: normal, interval_pct: 23.05}}
  k2:  {{property: aero/uq/k2, distribution: uniform, interval_pct: 379.74}}
  V:   {{property: ic/vt-kts, distribution: normal, lower: 195, upper: 205}}
design: {{kind: monte_carlo, samples: {samples}}}
execution: {{workers: 1, chunk: 4}}
"""


def jsbsim_campaign(samples=12, duration=5):
    return parse_campaign(JSBSIM_CAMPAIGN.format(samples=samples, duration=duration), "small.yaml", AircraftProperties)


def python_campaign(samples):
    """A Monte Carlo campaign of a closed-form model: what the file checks below see without flying."""
    return parse_campaign(f"""
name: small-python
seed: 7
simulator: {{kind: python, function: "uqflight.simulators.models:linear"}}
parameters:
  x1: {{distribution: uniform, lower: -1, upper: 1}}
design: {{kind: monte_carlo, samples: {samples}}}
execution: {{workers: 1, chunk: 4}}
""", "small.yaml")


# the results-file checks do not depend on the simulator: the default suite runs them on a closed-form
# model, the slow suite on JSBSim too
KINDS = pytest.mark.parametrize("make_campaign", [
    pytest.param(python_campaign, id="python"), pytest.param(jsbsim_campaign, id="jsbsim", marks=pytest.mark.slow)])


@pytest.mark.slow  # a long real-process check; the slow suite runs it in CI
def test_results_do_not_depend_on_workers_or_executor(tmp_path):
    campaign = jsbsim_campaign()
    one = run_campaign(campaign, out=tmp_path / "one.h5", workers=1)
    two = run_campaign(campaign, out=tmp_path / "two.h5", workers=2)
    assert one.ran == two.ran == 12 and not one.failures
    assert_same_results(tmp_path / "one.h5", tmp_path / "two.h5")
    dask = run_campaign(campaign, out=tmp_path / "dask.h5", workers=2, executor="dask")
    assert dask.ran == 12
    assert_same_results(tmp_path / "one.h5", tmp_path / "dask.h5")


def test_stored_runs_match_a_fresh_flight(tmp_path):
    from uqflight.simulators.scenarios.level_flight import FlightSetup, JSBSimFlight

    campaign = jsbsim_campaign(samples=3)
    run_campaign(campaign, out=tmp_path / "r.h5")
    with ResultStore.open(tmp_path / "r.h5") as store:
        kappa, theta = store.kappa, store.output_matrix("theta_deg")
    flight = JSBSimFlight(FlightSetup(duration_s=5, output_rate_hz=10))
    fresh = flight.fly({"aero/uq/CL0": kappa[2, 0], "aero/uq/k2": kappa[2, 1], "ic/vt-kts": kappa[2, 2]})
    np.testing.assert_allclose(theta[2], fresh.outputs["theta_deg"], rtol=1e-9)


def test_failed_runs_are_recorded_and_the_campaign_goes_on(tmp_path):
    text = """
name: flaky
seed: 3
simulator: {kind: python, function: "flaky_model.py:flaky"}
parameters:
  x: {distribution: uniform, lower: -2, upper: 2}
design: {kind: monte_carlo, samples: 200}
execution: {workers: 2, chunk: 8}
"""
    campaign = parse_campaign(text, str(DATA / "flaky.yaml"))
    summary = run_campaign(campaign, out=tmp_path / "f.h5")
    with ResultStore.open(tmp_path / "f.h5") as store:
        x, status, reasons, y = store.kappa[:, 0], store.status, store.reasons, store.output_matrix("y")
    assert np.all(status[x > 1.5] == Status.SIMULATOR_ERROR)
    assert all("model blew up" in r for r in np.asarray(reasons)[x > 1.5])
    assert np.all(status[x < -1.5] == Status.DIVERGED)
    ok = np.abs(x) <= 1.5
    assert np.all(status[ok] == Status.OK)
    np.testing.assert_array_equal(y[ok], np.column_stack([x[ok], x[ok] ** 2]))
    assert np.all(np.isnan(y[~ok]))
    assert sum(summary.failures.values()) == int((~ok).sum())


@KINDS
def test_a_file_of_another_campaign_is_refused_unless_forced(tmp_path, make_campaign):
    run_campaign(make_campaign(samples=2), out=tmp_path / "r.h5")
    other = make_campaign(samples=3)
    with pytest.raises(FileExistsError, match="another campaign"):
        run_campaign(other, out=tmp_path / "r.h5")
    assert run_campaign(other, out=tmp_path / "r.h5", force=True).ran == 3


@pytest.mark.slow
@pytest.mark.parametrize("storage", ["raw", "tsvd"])
def test_resume_after_sigkill_equals_an_uninterrupted_run(tmp_path, storage):
    text = JSBSIM_CAMPAIGN.format(samples=160, duration=20)
    if storage == "tsvd":
        text += "storage: {raw: false, tsvd: {tol: 1.0e-10, batch: 32}}\n"
    (tmp_path / "c.yaml").write_text(text)
    killed = tmp_path / "killed.h5"
    proc = subprocess.Popen([UQFLIGHT, "run", str(tmp_path / "c.yaml"), "--out", str(killed)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    for line in proc.stderr:  # progress lines: "48/160 runs (30 %), ..."
        if "/160 runs" in line and int(line.split("/")[0]) >= 40:
            break
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    with ResultStore.open(killed) as store:
        remaining = store.pending().size
    assert 0 < remaining < 160, "the kill should land mid-run"
    resumed = subprocess.run([UQFLIGHT, "run", str(tmp_path / "c.yaml"), "--out", str(killed)],
                             capture_output=True, text=True)
    assert resumed.returncode == 0, resumed.stderr
    assert f"{160 - remaining} already done" in resumed.stdout
    campaign = parse_campaign(text, str(tmp_path / "c.yaml"), AircraftProperties)
    run_campaign(campaign, out=tmp_path / "whole.h5")
    assert_same_results(killed, tmp_path / "whole.h5")


@pytest.mark.slow
def test_tsvd_storage_and_property_outputs(tmp_path):
    text = JSBSIM_CAMPAIGN.format(samples=10, duration=5).replace(
        "  output_rate_hz: 10\n", "  output_rate_hz: 10\n  outputs: [theta_deg, aero/qbar-psf]\n").replace(
        "execution:", "storage: {raw: false, tsvd: {tol: 1.0e-12, batch: 4}}\nexecution:")
    run_campaign(parse_campaign(text, "t.yaml", AircraftProperties), out=tmp_path / "t.h5")
    raw_text = text.replace("raw: false", "raw: true")
    run_campaign(parse_campaign(raw_text, "r.yaml", AircraftProperties), out=tmp_path / "r.h5")
    with ResultStore.open(tmp_path / "t.h5") as compressed, ResultStore.open(tmp_path / "r.h5") as raw:
        assert compressed.output_names == raw.output_names == ["theta_deg", "aero/qbar-psf"]
        for name in raw.output_names:
            exact = raw.output_matrix(name)
            np.testing.assert_allclose(compressed.output_matrix(name), exact, rtol=0, atol=1e-9 * np.abs(exact).max())
            # the trims' drift (tests/test_trim_repeatability.py) is recorded for every output, property ones too
            assert raw.resolution(name).shape == raw.time.shape
            np.testing.assert_array_equal(compressed.resolution(name), raw.resolution(name))


@pytest.mark.slow
@KINDS
def test_an_unreadable_results_file_is_refused_unless_forced(tmp_path, make_campaign):
    run_campaign(make_campaign(samples=2), out=tmp_path / "whole.h5")
    broken = tmp_path / "r.h5"  # as if killed while the file was being created: HDF5, unreadable
    broken.write_bytes((tmp_path / "whole.h5").read_bytes()[:2048])
    with pytest.raises(FileExistsError, match="damaged HDF5 file"):
        run_campaign(make_campaign(samples=2), out=broken)
    assert run_campaign(make_campaign(samples=2), out=broken, force=True).ran == 2


@KINDS
def test_force_never_replaces_what_is_not_a_results_file(tmp_path, make_campaign):
    text = tmp_path / "notes.h5"
    text.write_text("my notes")
    with pytest.raises(FileExistsError, match="not a uqflight results file.*rm "):
        run_campaign(make_campaign(samples=2), out=text, force=True)
    assert text.read_text() == "my notes"
    with pytest.raises(FileExistsError, match="is a directory"):
        run_campaign(make_campaign(samples=2), out=tmp_path, force=True)
    with h5py.File(tmp_path / "other.h5", "w") as f:
        f["x"] = [1, 2, 3]
    with pytest.raises(FileExistsError, match="HDF5 file but not a uqflight results file"):
        run_campaign(make_campaign(samples=2), out=tmp_path / "other.h5", force=True)


@pytest.mark.slow
def test_resuming_with_changed_aircraft_files_is_refused_unless_forced(tmp_path):
    run_campaign(jsbsim_campaign(samples=2), out=tmp_path / "r.h5")
    with h5py.File(tmp_path / "r.h5", "a") as f:
        f.attrs["aircraft_hash"] = "0" * 64  # as if the file had been made with another aircraft
    with pytest.raises(FileExistsError, match="other aircraft files"):
        run_campaign(jsbsim_campaign(samples=2), out=tmp_path / "r.h5")
    assert run_campaign(jsbsim_campaign(samples=2), out=tmp_path / "r.h5", force=True).ran == 2


@pytest.mark.parametrize("total, chunk", [(589, 16), (64, 16), (65, 16), (80, 16), (10, 16), (12, 4), (1, 1), (1000, 7)])
def test_chunks_cover_the_design_and_taper_at_its_end(total, chunk):
    """Design-order chunks of `chunk` samples, the last TAPER x chunk samples in chunks a TAPER-th
    the size (so that the workers finish together); every sample in exactly one chunk."""
    from uqflight.running.runner import TAPER, chunk_starts, pending_chunks

    starts = chunk_starts(total, chunk)
    sizes = np.diff(starts)
    assert starts[0] == 0 and starts[-1] == total and np.all(sizes >= 1) and np.all(sizes <= chunk)
    small = max(1, chunk // TAPER)
    tail = starts[:-1] > total - (TAPER + 1) * chunk  # TAPER chunks' worth, from a chunk boundary
    assert np.all(sizes[tail][:-1] == small) and np.all(sizes[~tail] == chunk)
    assert sizes[tail].sum() >= min(total, TAPER * chunk)
    chunks = pending_chunks(np.arange(total), chunk, total)
    assert np.array_equal(np.concatenate(chunks), np.arange(total))
    assert [c.tolist() for c in pending_chunks(np.array([total - 1]), chunk, total)] == [chunks[-1].tolist()]


CRASHING_MODEL = '''
import os, signal
import numpy as np
T = np.linspace(0.0, 1.0, 11)

def f(p):
    if p["a"] > 5.0:  # the process itself dies, as a crashing native simulator would
        os.kill(os.getpid(), signal.SIGKILL)
    while p["a"] < 0.2:  # never returns
        pass
    return {"time": T, "y": p["a"] * T, "z": p["b"] - T}
'''


@pytest.mark.slow
def test_simulate_split_over_processes_equals_one_process_and_survives_a_dying_or_hung_run(tmp_path):
    # calibrate's predictive runs: the same numbers in 1 or 3 supervised worker processes; a run that kills
    # its worker, or runs past execution.timeout_s, fails with its reason, the other runs stand
    from uqflight.running.runner import simulate

    (tmp_path / "model.py").write_text(CRASHING_MODEL)
    campaign = parse_campaign('''
name: split
seed: 1
simulator: {kind: python, function: "model.py:f"}
parameters:
  a: {distribution: uniform, lower: 0, upper: 10}
  b: {distribution: normal, nominal: 1.0, interval_pct: 30}
design: {kind: monte_carlo, samples: 4}
''', str(tmp_path / "c.yaml"))
    kappa = np.column_stack([np.linspace(0.5, 4.5, 9), np.linspace(0.9, 1.1, 9)])
    time, one, failures = simulate(campaign, kappa, ["y", "z"])
    assert not failures
    split_time, split, split_failures = simulate(campaign, kappa, ["y", "z"], processes=3)
    assert not split_failures and np.array_equal(split_time, time)
    for name in ("y", "z"):
        assert np.array_equal(split[name], one[name])
    kappa[7, 0] = 8.0
    _, crashed, failures = simulate(campaign, kappa, ["y", "z"], processes=3)
    assert failures == ["worker process died: signal 9 (SIGKILL) (out of memory, or killed)"]
    assert np.isnan(crashed["y"][7]).all()
    others = np.arange(9) != 7
    assert np.array_equal(crashed["y"][others], one["y"][others])
    hung = parse_campaign(campaign.text.replace("design:", "execution: {timeout_s: 1}\ndesign:"), campaign.source)
    kappa[7, 0], kappa[2, 0] = 4.0, 0.1  # row 2 never returns: it is stopped after 1 s, as `run` stops it
    _, flown, failures = simulate(hung, kappa, ["y", "z"], processes=2)
    assert failures == ["timed out: still running after 1 s (execution.timeout_s); its worker was replaced"]
    assert np.isnan(flown["y"][2]).all() and np.isfinite(np.delete(flown["y"], 2, axis=0)).all()


@pytest.mark.slow
def test_restart_starts_a_same_campaign_file_over_and_force_keeps_its_meaning(tmp_path):
    campaign = tmp_path / "decay.yaml"
    campaign.write_text(DECAY_TWO_INPUTS)
    out = tmp_path / "d.h5"
    assert cli_in_process("run", campaign, "--out", out).returncode == 0
    with h5py.File(out, "a") as f:
        f.attrs["marker"] = "the first run's file"
    again = cli_in_process("run", campaign, "--out", out, "--force")  # a file of this campaign: resumed, nothing to do
    assert again.returncode == 0 and " 0 run now" in again.stdout
    with h5py.File(out, "r") as f:
        assert "marker" in f.attrs
    restarted = cli_in_process("run", campaign, "--out", out, "--restart")
    assert restarted.returncode == 0 and " 0 already done" in restarted.stdout
    with h5py.File(out, "r") as f:
        assert "marker" not in f.attrs  # a new file


@pytest.mark.slow
def test_an_idle_worker_gets_its_next_chunk_before_the_runner_writes(tmp_path):
    """The pool hands a finished chunk to its caller (who writes it to HDF5) only once the worker
    that flew it has its next chunk: workers never wait for the writer."""
    from uqflight.running.runner import Task, WorkerPool, nominal_kappa, worker_spec
    from uqflight.parameters import to_physical

    spec = hostile_campaign("slow", samples=6, chunk=2)
    kappa = to_physical(spec.parameters, spec.design().xi)
    tasks = [Task(np.arange(i, i + 2), kappa[i:i + 2]) for i in (0, 2, 4)]
    pool = WorkerPool(worker_spec(spec), 1, 60.0)
    try:
        nominal = pool.nominal_flight(nominal_kappa(spec))
        time_grid, outputs = nominal.time, nominal.outputs
        results = pool.run(tasks, len(time_grid), outputs)
        first = next(results)
        assert first[0].tolist() == [0, 1] and pool.slots[0].task is tasks[1]
        assert [r[0].tolist() for r in results] == [[2, 3], [4, 5]]
    finally:
        pool.close()
    long_runs = hostile_campaign("long_histories", samples=6, chunk=2)  # 40 kB per run
    with h5py.File(run_campaign(long_runs, out=tmp_path / "r.h5").path) as f:  # the runner's chunk = HDF5's
        assert f["outputs/y"].chunks[0] == 2

