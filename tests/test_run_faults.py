"""A run's faults lose nothing and hang nothing: worker deaths and hangs are failed runs (with their
status codes listed in the file), a second writer is refused, SIGTERM and SIGINT stop cleanly, no worker
outlives its runner, a full disk stops cleanly and resumes to an uninterrupted run's bits. Real processes,
real HDF5."""
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
from conftest import (UQFLIGHT, assert_same_results, cli_in_process, hostile_campaign, hostile_campaign_text,
                      mounted_tmpfs)

from uqflight.running.runner import run_campaign
from uqflight.store import ResultStore, Status


def children(pid):
    """Pids whose parent is `pid` (a /proc scan)."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                found.append(int(entry.name))
    return found


def alive(pid):
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] != "Z"


@pytest.mark.slow  # a long real-process check; the slow suite runs it in CI
def test_samples_that_kill_their_worker_are_failed_runs_with_any_number_of_workers(tmp_path):
    results = {}
    for workers in (1, 2):
        out = tmp_path / f"w{workers}.h5"
        summary = run_campaign(hostile_campaign("crashing"), out=out, workers=workers)
        results[workers] = summary
        with ResultStore.open(out) as store:
            x, status, reasons, y = store.kappa[:, 0], store.status, np.array(store.reasons), store.output_matrix("y")
        exited, segfaulted = x > 1.6, x < -1.6
        assert exited.any() and segfaulted.any()
        assert np.all(status[exited | segfaulted] == Status.WORKER_DIED)
        assert all(r == "worker process died: exit code 3" for r in reasons[exited])
        assert all(r == "worker process died: signal 11 (SIGSEGV)" for r in reasons[segfaulted])
        ok = ~(exited | segfaulted)
        assert np.all(status[ok] == Status.OK)
        np.testing.assert_array_equal(y[ok], np.column_stack([x[ok], x[ok] ** 2]))
        assert np.isnan(y[~ok]).all()
        assert summary.ran == 40 and sum(summary.failures.values()) == int((~ok).sum())
    assert_same_results(tmp_path / "w1.h5", tmp_path / "w2.h5")


@pytest.mark.slow
def test_a_worker_death_on_dask_is_a_failed_run(tmp_path):
    pytest.importorskip("dask.distributed")
    summary = run_campaign(hostile_campaign("crashing", samples=16), out=tmp_path / "d.h5", workers=2, executor="dask")
    run_campaign(hostile_campaign("crashing", samples=16), out=tmp_path / "l.h5", workers=1)
    assert summary.ran == 16
    assert_same_results(tmp_path / "d.h5", tmp_path / "l.h5")


@pytest.mark.slow
def test_a_hung_sample_is_stopped_by_its_timeout(tmp_path):
    summary = run_campaign(hostile_campaign("hanging", extra=", timeout_s: 1"), out=tmp_path / "h.h5", workers=2)
    with ResultStore.open(tmp_path / "h.h5") as store:
        x, status, reasons = store.kappa[:, 0], store.status, np.array(store.reasons)
    hung = x > 1.7
    assert hung.any()
    assert np.all(status[hung] == Status.TIMEOUT) and np.all(status[~hung] == Status.OK)
    assert all("timed out: still running after 1 s (execution.timeout_s)" in r for r in reasons[hung])
    assert summary.timeout_s == 1


def test_the_default_timeout_comes_from_a_measured_flight(tmp_path):
    summary = run_campaign(hostile_campaign("slow", samples=2), out=tmp_path / "s.h5")
    assert summary.timeout_s == 60.0  # max(60 s, 50 x 0.1 s)


def test_status_codes_are_listed_in_the_file(tmp_path):
    run_campaign(hostile_campaign("slow", samples=1), out=tmp_path / "s.h5")
    with h5py.File(tmp_path / "s.h5", "r") as f:
        codes = f["samples/status"].attrs["codes"]
    assert '"worker_died": 4' in codes and '"timeout": 5' in codes


def write_hostile_campaign(tmp_path, function, **kwargs):
    path = tmp_path / "c.yaml"
    path.write_text(hostile_campaign_text(function, **kwargs))
    return path


def wait_for(predicate, seconds=60.0):
    """Whether `predicate` comes true within `seconds`: a bound against a hang, far above what the event
    takes on a loaded machine, not a speed test."""
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.05)
    return False


@pytest.mark.slow  # a long real-process check; the slow suite runs it in CI
def test_one_writer_per_file_and_sigterm_stops_cleanly(tmp_path):
    # 100 s of work: the SIGTERM ends it after a few, however slowly the other commands start on a loaded machine
    yaml = write_hostile_campaign(tmp_path, "slow", samples=2000, chunk=4, workers=2)
    out = tmp_path / "r.h5"
    first = subprocess.Popen([UQFLIGHT, "run", str(yaml), "--out", str(out)], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
    try:
        assert wait_for(lambda: out.exists() and Path(str(out) + ".lock").exists())
        second = subprocess.run([UQFLIGHT, "run", str(yaml), "--out", str(out)], capture_output=True, text=True)
        assert second.returncode == 2
        assert f"being written by another run (pid {first.pid} on" in second.stderr
        forced = subprocess.run([UQFLIGHT, "run", str(yaml), "--out", str(out), "--force"],
                                capture_output=True, text=True)
        assert forced.returncode == 2 and f"pid {first.pid}" in forced.stderr
        workers = children(first.pid)
        assert workers
        first.send_signal(signal.SIGTERM)
        _, stderr = first.communicate(timeout=30)
    finally:
        if first.poll() is None:
            first.kill()
    assert first.returncode == 143, stderr
    assert f"rerun `uqflight run {yaml} --out {out}` to resume" in stderr
    assert wait_for(lambda: not any(alive(pid) for pid in workers))
    assert not Path(str(out) + ".lock").exists()
    with ResultStore.open(out) as store:
        assert 0 < store.pending().size < 2000


@pytest.mark.slow  # a long real-process check; the slow suite runs it in CI
def test_no_orphan_workers_after_the_runner_is_killed(tmp_path):
    # 100 s of work: the SIGTERM ends it after a few, however slowly the other commands start on a loaded machine
    yaml = write_hostile_campaign(tmp_path, "slow", samples=2000, chunk=4, workers=2)
    out = tmp_path / "r.h5"
    runner = subprocess.Popen([UQFLIGHT, "run", str(yaml), "--out", str(out)], stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL)
    try:
        assert wait_for(lambda: len(children(runner.pid)) >= 2 and out.exists())
        time.sleep(1.0)
        workers = children(runner.pid)
        os.kill(runner.pid, signal.SIGKILL)
        runner.wait()
        assert wait_for(lambda: not any(alive(pid) for pid in workers)), \
            [p for p in workers if alive(p)]
    finally:
        if runner.poll() is None:
            runner.kill()
    # the killed run left its lock behind: the next run takes it over (then is stopped)
    lock = Path(str(out) + ".lock")
    assert f'"pid": {runner.pid},' in lock.read_text()
    resumed = subprocess.Popen([UQFLIGHT, "run", str(yaml), "--out", str(out)], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    try:
        assert wait_for(lambda: lock.exists() and f'"pid": {resumed.pid},' in lock.read_text())
        resumed.send_signal(signal.SIGTERM)
        _, stderr = resumed.communicate(timeout=30)
    finally:
        if resumed.poll() is None:
            resumed.kill()
    assert resumed.returncode == 143, stderr


@pytest.fixture
def small_disk(tmp_path):
    with mounted_tmpfs(tmp_path, "8m") as mount:
        yield mount


@pytest.mark.slow  # a long real-process check; the slow suite runs it in CI
def test_a_full_disk_stops_cleanly_and_the_resume_equals_an_uninterrupted_run(tmp_path, small_disk):
    yaml = write_hostile_campaign(tmp_path, "long_histories", samples=300, chunk=10, workers=2)
    out = small_disk / "r.h5"
    full = subprocess.run([UQFLIGHT, "run", str(yaml), "--out", str(out)], capture_output=True, text=True,
                          timeout=300)
    assert full.returncode == 2, full.stderr
    assert f"no space left on {out}'s filesystem" in full.stderr
    kept = int(full.stderr.split("MiB needed for the next batch); ")[1].split(" runs kept")[0])
    assert "free space and rerun to resume" in full.stderr
    with ResultStore.open(out) as store:
        assert store.pending().size == 300 - kept and 0 < kept < 300
        assert store.verify() == []
    subprocess.run(["mount", "-o", "remount,size=64m", str(small_disk)], check=True)
    resumed = subprocess.run([UQFLIGHT, "run", str(yaml), "--out", str(out)], capture_output=True, text=True,
                             timeout=300)
    assert resumed.returncode == 0, resumed.stderr
    assert f"{kept} already done" in resumed.stdout
    whole = cli_in_process("run", yaml, "--out", tmp_path / "whole.h5")
    assert whole.returncode == 0, whole.stderr
    assert_same_results(out, tmp_path / "whole.h5")


# "ignored" runs the whole "default" path after the CLI restores Python's handler: "default" is for the slow suite
@pytest.mark.parametrize("inherited", [pytest.param("default", marks=pytest.mark.slow), "ignored"])
def test_sigint_to_the_runner_alone_stops_it_cleanly(tmp_path, inherited):
    """Also when the runner starts with SIGINT ignored, as a script's `uqflight run ... &` does (a test
    harness left it so once: the interrupted run then waited on its workers for ever)."""
    yaml = write_hostile_campaign(tmp_path, "hanging", samples=200, chunk=4, workers=2, extra=", timeout_s: 300")
    out = tmp_path / "r.h5"
    ignore = (lambda: signal.signal(signal.SIGINT, signal.SIG_IGN)) if inherited == "ignored" else None
    runner = subprocess.Popen([UQFLIGHT, "run", str(yaml)] + ["--out", str(out)], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True, preexec_fn=ignore)
    try:
        assert wait_for(lambda: len(children(runner.pid)) >= 2 and out.exists())
        time.sleep(1.0)  # a worker is now stuck in a hung sample
        workers = children(runner.pid)
        runner.send_signal(signal.SIGINT)
        _, stderr = runner.communicate(timeout=120)  # a bound against a hang, not a speed test (it takes ~1 s)
    finally:
        if runner.poll() is None:
            runner.kill()
    assert runner.returncode == 130, stderr
    assert f"interrupted: the finished runs are stored; rerun `uqflight run {yaml} --out {out}`" in stderr
    assert wait_for(lambda: not any(alive(pid) for pid in workers))


@pytest.mark.slow
def test_the_cli_exits_2_when_the_disk_fills_past_the_check(tmp_path, small_disk):
    """The free-space check bypassed (another process fills the disk): exit 2, never 0 or 139."""
    out = small_disk / "r.h5"
    yaml = write_hostile_campaign(tmp_path, "long_histories", samples=300, chunk=10, workers=2)
    script = ("import sys; import uqflight.running.runner as e; e.ensure_space = lambda *a, **k: None; "
              "from uqflight.cli.commands import app; sys.argv = ['uqflight', 'run', sys.argv[1], '--out', sys.argv[2]]; app()")
    done = subprocess.run([sys.executable, "-c", script, str(yaml), str(out)], capture_output=True, text=True,
                          timeout=300)
    assert done.returncode in (1, 2), done.stderr[-2000:]
    assert "rerun to resume" in done.stderr
    subprocess.run(["mount", "-o", "remount,size=64m", str(small_disk)], check=True)
    resumed = subprocess.run([UQFLIGHT, "run", str(yaml), "--out", str(out)], capture_output=True, text=True,
                             timeout=300)
    assert resumed.returncode == 0, resumed.stderr[-2000:]
    whole = cli_in_process("run", yaml, "--out", tmp_path / "whole.h5")
    assert whole.returncode == 0, whole.stderr
    assert_same_results(out, tmp_path / "whole.h5")




@pytest.mark.slow
def test_a_disk_that_fills_while_the_results_file_is_created_is_one_clean_line(tmp_path):
    """D21: HDF5 met the full disk while releasing the new file's groups, and h5py printed each failure as an
    "Exception ignored" traceback before the clean error. A real full disk: a 256 KiB tmpfs filled but for a
    few KiB (sizes at which the creation itself fails: 8 to 12 KiB left)."""
    from conftest import DECAY_TWO_INPUTS

    yaml = tmp_path / "decay.yaml"
    yaml.write_text(DECAY_TWO_INPUTS)
    with mounted_tmpfs(tmp_path, "256k") as mount:
        for free in (8, 10, 12):
            for item in mount.iterdir():
                item.unlink()
            with open(mount / "filler", "wb") as fh:
                try:
                    fh.write(b"\0" * ((256 - free) * 1024))
                except OSError:
                    pass
            out = mount / "r.h5"
            done = subprocess.run([UQFLIGHT, "run", str(yaml), "--out", str(out), "--workers", "1"],
                                  capture_output=True, text=True, timeout=120)
            assert done.returncode == 2, (free, done.stderr)
            assert "Traceback" not in done.stderr and "Exception ignored" not in done.stderr, (free, done.stderr)
            assert done.stderr.strip().splitlines()[-1].startswith(f"error: no space left on {out}'s filesystem")
            assert not out.exists()  # no half-made file that would later look damaged
