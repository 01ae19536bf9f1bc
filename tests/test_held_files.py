"""A results file another process holds open (HDF5's file lock) is in use, not damaged: `run` refuses it in
one line naming that process (exit 2), and no flag replaces it. Real processes hold real files."""
from __future__ import annotations

import contextlib
import shutil
import subprocess
import sys

import h5py
import numpy as np
import pytest

from conftest import DECAY_TWO_INPUTS, cli


@contextlib.contextmanager
def held_open(path, mode: str):
    """A separate Python process holding `path` open with h5py in `mode` ("r": a reader, "a": a writer
    without uqflight's lock) until the block ends."""
    holder = subprocess.Popen([sys.executable, "-c", f"import h5py, sys\nf = h5py.File({str(path)!r}, {mode!r})\n"
                               "print('held', flush=True)\nsys.stdin.read()"],
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        yield holder.pid
    finally:
        holder.stdin.close()
        holder.wait(timeout=30)


def _copy(decay_results, tmp_path):
    (tmp_path / "decay.yaml").write_text(DECAY_TWO_INPUTS)
    out = tmp_path / "decay.h5"
    shutil.copy(decay_results, out)
    with h5py.File(out, "r") as f:
        return out, f["samples/status"][()]


def _refused_as_held(done, pid: int) -> None:
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr and len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert f"is open in pid {pid}" in done.stderr and "wait until that process closes it" in done.stderr
    assert "damaged" not in done.stderr and "force" not in done.stderr and "rm " not in done.stderr


@pytest.mark.slow
def test_a_healthy_file_another_process_writes_is_refused_as_held_and_never_replaced(decay_results, tmp_path):
    """D17: the file held by a writer without uqflight's lock was called damaged, with "force to overwrite
    it" as the advice; --force then deleted every completed run."""
    out, status = _copy(decay_results, tmp_path)
    with held_open(out, "a") as pid:
        for flags in ((), ("--force",), ("--restart",)):
            _refused_as_held(cli("run", tmp_path / "decay.yaml", "--out", out, "--workers", 1, *flags), pid)
    with h5py.File(out, "r") as f:  # every run kept
        np.testing.assert_array_equal(f["samples/status"][()], status)
    again = cli("run", tmp_path / "decay.yaml", "--out", out, "--workers", 1)
    assert again.returncode == 0 and f"{status.size} already done" in again.stdout, again.stderr


@pytest.mark.slow
def test_resuming_a_file_another_process_reads_is_one_line_naming_it(decay_results, tmp_path):
    """D20: a reader's shared lock let the campaign check pass, then opening to write raised BlockingIOError
    (a traceback)."""
    out, _ = _copy(decay_results, tmp_path)  # resuming opens the file to write, even when every run is done
    with held_open(out, "r") as pid:
        _refused_as_held(cli("run", tmp_path / "decay.yaml", "--out", out, "--workers", 1), pid)


@pytest.mark.slow
def test_reading_a_file_another_process_writes_names_that_process(decay_results, tmp_path):
    """D20's sibling for the readers: `report` and `check` of a file a writer without uqflight's lock holds
    said "cannot analyse the results file ([Errno 11] Unable to synchronously open file (unable to lock
    file...))"; `info` reads it as it is now."""
    out, _ = _copy(decay_results, tmp_path)
    baseline = tmp_path / "baseline.json"
    assert cli("report", out, "--out", tmp_path / "first", "--write-baseline", baseline).returncode == 0
    with held_open(out, "a") as pid:
        for args in (("report", out, "--out", tmp_path / "rep"), ("check", out, "--baseline", baseline)):
            done = cli(*args)
            assert done.returncode == 2, done.stderr
            errors = [line for line in done.stderr.splitlines() if "error" in line]
            assert len(errors) == 1, done.stderr
            named, _, why = errors[0].partition(" (HDF5's file lock), ")
            assert why == "so it cannot be read now: wait until that process closes it, or stop it, then run again"
            assert named.startswith(f"error: {out} is open in pid {pid} ({sys.executable} -c import h5py, sys")
            assert named.endswith("sys.stdin.read())") or named.endswith(" …)"), named  # the command, whole or cut
        shown = cli("info", out)
        assert shown.returncode == 0 and "locked by another process" in shown.stdout, shown.stderr


@pytest.mark.slow
def test_calibrating_a_file_another_process_writes_names_that_process(decay_results, tmp_path):
    """The same for `calibrate` (its --truth is read from the file first: a LockHeld traceback otherwise)."""
    out, _ = _copy(decay_results, tmp_path)
    data = tmp_path / "flight.csv"
    data.write_text("time_s,x\n0,1\n1,0.5\n")
    with held_open(out, "a") as pid:
        for extra in ((), ("--truth", "a=1")):
            done = cli("calibrate", out, "--data", data, "--out", tmp_path / "cal", *extra)
            assert done.returncode == 2, done.stderr
            errors = [line for line in done.stderr.splitlines() if "error" in line]
            assert len(errors) == 1 and f"{out} is open in pid {pid}" in errors[0], done.stderr
            assert "Traceback" not in done.stderr


def test_a_long_command_line_is_cut_and_says_so(tmp_path):
    """The holder's command is shown up to COMMAND_SHOWN bytes; a longer one ends in " …" rather than
    stopping mid-word as if it were whole (a results file deep in a long path made the line ambiguous)."""
    from uqflight.store.lock import COMMAND_SHOWN, holders
    path = tmp_path / "held.h5"
    h5py.File(path, "w").close()
    long_argument = "x" * (2 * COMMAND_SHOWN)
    holder = subprocess.Popen([sys.executable, "-c", f"import sys\nf = open({str(path)!r})\nprint('held', flush=True)\n"
                               "sys.stdin.read()", long_argument], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                              text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        (shown,) = holders(path)
    finally:
        holder.stdin.close()
        holder.wait(timeout=30)
    assert shown.startswith(f"pid {holder.pid} ({sys.executable} -c import sys f = open(") and shown.endswith(" …)")
    assert len(shown.encode()) <= len(f"pid {holder.pid} ( …)".encode()) + COMMAND_SHOWN
