"""`run` removes only lock files it wrote whose holder is provably gone (issue 22, item 3): anything
else at FILE.lock survives, and the run is refused (exit 2) naming it. Real processes, real files."""
import json
import os
import socket
import subprocess
import sys
import time

import pytest
from conftest import cli, cli_in_process, hostile_campaign

from uqflight.running.runner import run_campaign
from uqflight.store import LockHeld, ResultsLock, ResultStore
from uqflight.running.forking import start_time
from uqflight.store.lock import read_holder

CAMPAIGN = """
name: locks
simulator: {kind: python, function: "uqflight.simulators.models:linear"}
parameters:
  x1: {distribution: uniform, lower: -1, upper: 1}
design: {kind: monte_carlo, samples: 4}
"""


def a_lock(pid, host=None, started=None):
    """A lock exactly as uqflight writes it."""
    return json.dumps({"pid": pid, "host": host or socket.gethostname(), "started": started,
                       "since": "2026-12-01 10:00:00", "command": "uqflight run"})


def dead_pid():
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    return child.pid


def write_campaign(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text(CAMPAIGN)
    return path


@pytest.mark.parametrize("name, content", [("X.lock", "4242\n"), ("notes.h5.lock", "my notes on notes.h5\n"),
                                           ("X.lock", '{"pid": 4242}'),
                                           ("X.lock", json.dumps({"pid": 4242, "host": "h", "owner": "me"}))])
def test_a_foreign_lock_file_a_minute_old_survives_run(tmp_path, name, content):
    """The issue's case: `echo 4242 > X.lock`, a minute old, was taken as a stale lock and deleted."""
    lock = tmp_path / name
    lock.write_text(content)
    os.utime(lock, (time.time() - 60, time.time() - 60))
    out = tmp_path / name.removesuffix(".lock")
    result = cli_in_process("run", write_campaign(tmp_path), "--out", out)
    assert result.returncode == 2, result.stdout + result.stderr
    assert f"{lock} exists and is not a uqflight lock" in result.stderr
    assert f"move {lock} away or delete it" in result.stderr
    assert lock.read_text() == content and not out.exists()


def test_a_folder_or_a_link_at_the_lock_is_refused_and_kept(tmp_path):
    out = tmp_path / "r.h5"
    lock = tmp_path / "r.h5.lock"
    lock.mkdir()
    (lock / "inside").write_text("kept")
    with pytest.raises(LockHeld, match=r"r\.h5\.lock exists and is not a uqflight lock \(a folder\)"):
        ResultsLock(out).acquire()
    assert (lock / "inside").read_text() == "kept"
    lock.rename(tmp_path / "folder")
    target = tmp_path / "target"
    target.write_text(a_lock(dead_pid()))  # even a stale lock of ours: the link is not the lock itself
    lock.symlink_to(target)
    with pytest.raises(LockHeld, match=r"r\.h5\.lock exists and is not a uqflight lock \(a symbolic link\)"):
        ResultsLock(out).acquire()
    assert lock.is_symlink() and target.exists()


def test_a_lock_from_another_host_is_refused_with_what_to_do(tmp_path):
    lock = tmp_path / "r.h5.lock"
    lock.write_text(a_lock(dead_pid(), host="elsewhere.example"))
    with pytest.raises(LockHeld, match=r"locked by a run on another host \(pid \d+ on elsewhere\.example.*"
                                       r"if you are sure it no longer runs, remove .*r\.h5\.lock"):
        ResultsLock(tmp_path / "r.h5").acquire()
    assert "elsewhere.example" in lock.read_text()


def test_a_lock_of_a_live_run_is_refused(tmp_path):
    holder = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        lock = tmp_path / "r.h5.lock"
        lock.write_text(a_lock(holder.pid, started=start_time(holder.pid)))
        with pytest.raises(LockHeld, match=rf"being written by another run \(pid {holder.pid} on"):
            ResultsLock(tmp_path / "r.h5").acquire()
        assert read_holder(tmp_path / "r.h5")["pid"] == holder.pid
    finally:
        holder.kill()
        holder.wait()


@pytest.mark.slow
@pytest.mark.parametrize("gone", ["dead", "pid reused"])
def test_a_lock_of_ours_whose_holder_is_gone_is_taken_over_by_run(tmp_path, gone):
    """Dead pid; or the pid alive but another process (its start time differs from the recorded one)."""
    if gone == "dead":
        content = a_lock(dead_pid(), started="12345")
    else:
        content = a_lock(os.getpid(), started=str(int(start_time(os.getpid())) + 1))
    lock, out = tmp_path / "r.h5.lock", tmp_path / "r.h5"
    lock.write_text(content)
    result = cli("run", write_campaign(tmp_path), "--out", out)
    assert result.returncode == 0, result.stdout + result.stderr
    assert not lock.exists()
    with ResultStore.open(out) as store:
        assert store.pending().size == 0


def test_the_lock_written_is_whole_and_removed_on_release(tmp_path):
    out = tmp_path / "r.h5"
    with ResultsLock(out):
        holder = read_holder(out)
        assert holder["pid"] == os.getpid() and holder["started"] == start_time(os.getpid())
        assert sorted(p.name for p in tmp_path.iterdir()) == ["r.h5.lock"]  # no temporary file left
    assert not list(tmp_path.iterdir())


def test_a_stale_lock_is_taken_over(tmp_path):
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    lock = tmp_path / "s.h5.lock"
    lock.write_text(json.dumps({"pid": dead.pid, "host": os.uname().nodename, "started": None,
                                "since": "2026-01-01 00:00:00", "command": "uqflight run"}))
    assert run_campaign(hostile_campaign("slow", samples=2), out=tmp_path / "s.h5").ran == 2
    assert not lock.exists()



@pytest.mark.parametrize("content", ["", "[1]", '"text"', '{"pid": "x"}', '{"pid": 99999999999999999999}',
                                     "[" * 100000, "x" * 100000])
def test_a_lock_that_is_not_ours_is_refused_and_kept_however_old(tmp_path, content):
    """Empty, foreign or damaged lock files: refused with the file named, never a traceback, never removed
    (issue 22: only a lock of ours whose holder is provably gone is taken over)."""
    lock, out = tmp_path / "s.h5.lock", tmp_path / "s.h5"
    lock.write_text(content)
    for age in (0, 3600):
        os.utime(lock, (time.time() - age, time.time() - age))
        with pytest.raises(LockHeld, match=r"s\.h5\.lock exists and is not a uqflight lock .*move .*s\.h5\.lock away"):
            ResultsLock(out).acquire()
        assert lock.read_text() == content

