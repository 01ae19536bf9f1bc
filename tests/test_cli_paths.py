"""The command line's files: an output that cannot be written is refused before any work with one
message for every command, a file of the wrong kind is named for what it is, a closed pipe ends
quietly, a Dask run without workers says what it waits for, and a full disk leaves no partial file."""
import errno
import os
import select
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import (NORMAL_2D, UQFLIGHT, cli, cli_in_process, closed_form_campaign, hostile_campaign, mounted_tmpfs,
                      run_python_campaign, scheduler_address)

from uqflight.running.runner import run_campaign

BIN = Path(sys.executable).parent
TEXT = closed_form_campaign("sq", "sum_of_squares", NORMAL_2D, "{kind: tensor_grid, points: 3}",
                "method: {kind: pseudo_galerkin, order: 2}\n")


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    return run_python_campaign(tmp_path_factory.mktemp("paths"), TEXT)  # 9 runs in 3 chunks of 4


def writers(results, folder):
    """Every command that writes a file or folder, its output option, and the rest of its arguments."""
    yaml = results.with_suffix(".yaml")
    data = folder / "flight.csv"
    data.write_text("time_s,y\n0,15000\n1,15002\n")
    return {
        "simulate --out": (["simulate", "--duration-s", "1"], "--out"),
        "simulate --plot": (["simulate", "--duration-s", "1"], "--plot"),
        "design --csv": (["design", yaml], "--csv"),
        "surrogate export --out": (["surrogate", "export", results], "--out"),
        "report --write-baseline": (["report", results, "--out", folder / "report"], "--write-baseline"),
        "report --out": (["report", results], "--out"),
        "run --out": (["run", yaml], "--out"),
        "calibrate --out": (["calibrate", results, "--data", data], "--out"),
    }


CREATES_FOLDERS = ("report --out", "run --out", "calibrate --out")  # their missing folders are made


@pytest.mark.parametrize("command", ["simulate --out", "simulate --plot", "design --csv", "surrogate export --out",
                                     "report --write-baseline", "report --out", "run --out", "calibrate --out"])
def test_an_unwritable_output_is_refused_before_any_work_with_one_message(results, tmp_path, command):
    args, option = writers(results, tmp_path)[command]
    (tmp_path / "a-file").write_text("not a folder")
    target = tmp_path / "a-file" / "out.x"
    result = cli_in_process(*args, option, target)
    assert result.returncode == 2, (result.stdout, result.stderr)
    assert result.stderr == f"error: {option} {target}: {tmp_path / 'a-file'} is not a folder; choose another path\n"
    assert result.stdout == ""  # nothing flown, fitted or written first
    if command not in CREATES_FOLDERS:
        missing = tmp_path / "missing" / "out.x"
        result = cli_in_process(*args, option, missing)
        assert result.returncode == 2 and result.stdout == ""
        assert result.stderr == (f"error: {option} {missing}: the folder {tmp_path / 'missing'} does not exist; "
                                 "choose another path\n")
        assert not (tmp_path / "missing").exists()
    if command == "calibrate --out":  # a file where the folder goes: refused before the sampling, not after
        result = cli_in_process(*args, option, tmp_path / "a-file")
        assert result.returncode == 2
        assert result.stderr == f"error: --out {tmp_path / 'a-file'}: is a file, not a folder; choose another path\n"


def test_an_output_that_is_the_commands_own_input_is_refused(results, tmp_path):
    copy = tmp_path / "r.h5"  # a copy: the refusal must leave it whole, and a failure must not spoil the fixture
    copy.write_bytes(results.read_bytes())
    yaml = results.with_suffix(".yaml")
    for args, option, target in [(["surrogate", "export", copy], "--out", copy),
                                 (["report", copy, "--out", tmp_path / "rep"], "--write-baseline", copy),
                                 (["design", yaml], "--csv", yaml), (["run", yaml], "--out", yaml)]:
        before = target.read_bytes()
        result = cli_in_process(*args, option, target)
        assert result.returncode == 2, (args, result.stdout, result.stderr)
        assert result.stderr == (f"error: {option} {target}: is the input {target}: it would be overwritten; "
                                 "choose another path\n")
        assert target.read_bytes() == before


@pytest.mark.parametrize("command", ["simulate --out", "design --csv", "surrogate export --out",
                                     "report --write-baseline"])
@pytest.mark.slow
def test_an_output_that_is_a_pipe_or_device_is_refused(results, tmp_path, command):
    # surrogate export writes a temporary file and renames it: a device (/dev/full, as root) would be replaced
    args, option = writers(results, tmp_path)[command]
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    result = cli(*args, option, fifo, timeout=60)  # in a process of its own: writing to a pipe nobody reads blocks
    assert result.returncode == 2 and result.stdout == ""
    assert result.stderr == (f"error: {option} {fifo}: is not a regular file (a device, pipe or socket); "
                             "choose another path\n")
    assert fifo.is_fifo()


def test_files_of_the_wrong_kind_are_named_for_what_they_are(results, tmp_path):
    yaml = results.with_suffix(".yaml")
    for args in (["report", yaml], ["info", yaml], ["check", yaml, "--baseline", yaml],
                 ["surrogate", "export", yaml, "--out", tmp_path / "p.json"]):
        result = cli_in_process(*args)
        assert result.returncode == 2
        assert result.stderr == (f"error: {yaml} is a campaign file, not a results file: `uqflight run {yaml}` "
                                 "makes its results file\n"), args
    data = tmp_path / "flight.csv"
    data.write_text("time_s,y\n0,15000\n")
    for args in (["run", results], ["plan", results], ["design", results, "--csv", tmp_path / "d.csv"],
                 ["calibrate", results, "--data", data, "--out", tmp_path / "cal", "--campaign", results]):
        result = cli_in_process(*args)
        assert result.returncode == 2
        assert result.stderr == (f"error: {results} is a results file (HDF5), not a campaign file: "
                                 f"`uqflight info {results}` describes it\n"), args


def test_a_closed_pipe_ends_info_quietly(results):
    read, write = os.pipe()
    os.close(read)  # the reader is gone before the first line, as `| head -1` is after its line
    try:
        done = subprocess.run([UQFLIGHT, "info", results], stdout=write, stderr=subprocess.PIPE, text=True, timeout=120)
    finally:
        os.close(write)
    assert done.returncode == 141 and done.stderr == ""


@pytest.mark.slow
def test_a_dask_run_without_workers_says_what_it_waits_for(results, tmp_path):
    file = tmp_path / "scheduler.json"
    scheduler = subprocess.Popen([str(BIN / "dask"), "scheduler", "--host", "127.0.0.1", "--port", "0",
                                  "--no-dashboard", "--scheduler-file", str(file)],
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    run = None
    try:
        address = scheduler_address(file)
        run = subprocess.Popen([UQFLIGHT, "run", results.with_suffix(".yaml"), "--out", tmp_path / "r.h5",
                                "--executor", "dask", "--scheduler", address],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        said, deadline = "", time.monotonic() + 180
        while "waiting for a Dask worker" not in said and time.monotonic() < deadline and run.poll() is None:
            if select.select([run.stderr], [], [], 1.0)[0]:
                said += run.stderr.readline()
        assert f"waiting for a Dask worker: the scheduler {address} has had none for 5 s (3 of 3 chunks left; " \
               f"start one: dask worker {address}; Ctrl-C stops, a rerun resumes)" in said, said
        run.send_signal(signal.SIGINT)
        _, rest = run.communicate(timeout=60)  # drains both pipes: the client's close logs to stderr, and a full
        assert run.returncode == 130, rest     # pipe nobody reads would block the runner (it did, twice)
    finally:
        for process in (run, scheduler):
            if process is not None and process.poll() is None:
                process.kill()
                process.wait()


@pytest.fixture
def full_disk(tmp_path):
    """A small tmpfs, filled: the next write meets ENOSPC."""
    with mounted_tmpfs(tmp_path, "256k") as mount:
        try:
            with open(mount / "filler", "wb", buffering=0) as fh:
                while True:
                    fh.write(b"\0" * 4096)
        except OSError as exc:
            assert exc.errno == errno.ENOSPC
        yield mount


def test_surrogate_export_on_a_full_disk_leaves_no_partial_file(results, full_disk):
    result = cli_in_process("surrogate", "export", results, "--out", full_disk / "p.json")
    assert result.returncode == 2 and "No space left on device" in result.stderr, result.stderr
    assert sorted(p.name for p in full_disk.iterdir()) == ["filler"]


@pytest.mark.parametrize("where", ["a file/r.h5", "/proc/uqflight-test.h5"])
def test_a_results_path_that_cannot_be_written_is_refused(tmp_path, where):
    """A file where a folder should be; a filesystem that takes no new files (procfs)."""
    (tmp_path / "a file").write_text("not a folder")
    with pytest.raises(ValueError, match=r"cannot write the results file .*r?\.h5 \((File exists|No such file)"
                                         r".*\); choose another path with --out or storage.path"):
        run_campaign(hostile_campaign("slow", samples=1), out=tmp_path / where)
