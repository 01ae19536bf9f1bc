"""Every size a file declares is bounded before a reader allocates from it: the products of a results file's
runs, times, outputs and quantities; a baseline's bytes (`check --baseline`); a data file's bytes (`calibrate
--data`). Files crafted here with h5py and plain writes; the commands run as separate processes under a memory
limit (RLIMIT_AS), so that a reader that does allocate from a declared size fails there, not on the machine."""
from __future__ import annotations

import os
import re
import resource
import shutil
import subprocess

import h5py
import numpy as np
import pytest

from conftest import DECAY_TWO_INPUTS, UQFLIGHT

MEMORY_LIMIT = 3 * 2**30  # the command's address space: enough for the interpreter and its libraries


def _limited():
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))


def limited_cli(*args, cwd=None, timeout: float = 300) -> subprocess.CompletedProcess:
    """`uqflight ARGS...` in a process whose address space is MEMORY_LIMIT."""
    return subprocess.run([UQFLIGHT, *map(str, args)], cwd=cwd, capture_output=True, text=True, timeout=timeout,
                          preexec_fn=_limited)


def one_line_refusal(done, *fragments) -> None:
    assert done.returncode == 2, (done.returncode, done.stderr[-3000:])
    assert "Traceback" not in done.stderr and "MemoryError" not in done.stderr, done.stderr[-3000:]
    for fragment in fragments:
        assert fragment in done.stderr, done.stderr
    errors = [line for line in done.stderr.splitlines() if "error" in line]  # besides progress lines
    assert len(errors) == 1 and errors[0].count(": ") < 8, done.stderr


def declaring(decay_results, tmp_path, n_times: int):
    """A copy of the decay results file whose /time holds `n_times` times and whose outputs declare
    (29 runs, n_times) in chunks never written: the file is some MiB (the times, gzipped)."""
    out = tmp_path / "declares.h5"
    shutil.copy(decay_results, out)
    (tmp_path / "declares.yaml").write_text(DECAY_TWO_INPUTS)
    with h5py.File(out, "a") as f:
        del f["time"]
        f.create_dataset("time", data=np.arange(n_times, dtype=float), chunks=(min(n_times, 2**20),), compression="gzip")
        for key in list(f["outputs"]):
            n = f["outputs"][key].shape[0]
            del f["outputs"][key]
            f["outputs"].create_dataset(key, shape=(n, n_times), dtype="f8", fillvalue=np.nan, chunks=(1, min(n_times, 2**20)),
                                        compression="gzip")
    assert out.stat().st_size < 16 * 2**20
    return out


@pytest.mark.slow
def test_runs_times_products_are_bounded_before_any_reader_allocates(decay_results, tmp_path):
    """D08: 29 runs x 10^7 times (each within its own bound) made info, report, surrogate export and calibrate
    allocate gigabytes for a file of a few MiB."""
    out = declaring(decay_results, tmp_path, 10**7)
    data = tmp_path / "flight.csv"
    data.write_text("time_s,y\n0,1\n1,2\n")
    for args in (("info", out), ("report", out, "--out", tmp_path / "rep"),
                 ("surrogate", "export", out, "--out", tmp_path / "s.json"),
                 ("calibrate", out, "--data", data, "--out", tmp_path / "cal")):
        done = limited_cli(*args)
        one_line_refusal(done, "values per output, more than a reader holds")


def test_outputs_times_runs_together_are_bounded(decay_results, tmp_path):
    """D08's sibling: each output within its bound, but 100 of them over 29 runs x 10^6 times (2.9e9 values,
    in chunks never written) would be read whole by `info`. Refused by the layout check, nothing read."""
    from uqflight.store import CorruptFile, ResultStore

    out = declaring(decay_results, tmp_path, 10**6)
    with h5py.File(out, "a") as f:
        for k in range(99):
            f["outputs"].create_dataset(f"extra{k}", shape=(29, 10**6), dtype="f8", fillvalue=np.nan,
                                        chunks=(1, 2**16))
    with pytest.raises(CorruptFile, match=r"100 outputs and 0 quantities of 29 runs x 1000000 times = 2\.9e\+09 "
                                          "values, more than a reader reads"):
        ResultStore.open(out)


def test_a_tsvd_buffer_declaring_runs_x_times_beyond_the_bound_is_refused(decay_results, tmp_path):
    """A tSVD buffer may hold up to 2N + 1000 runs; of 10^6 times that is 1.06e9 values for 29 runs: bounded
    by a reader's N x T as well."""
    from uqflight.store import CorruptFile, ResultStore

    out = declaring(decay_results, tmp_path, 10**6)
    with h5py.File(out, "a") as f:
        keys = list(f["outputs"])
        group = f.create_group("tsvd")
        group.attrs.update({"tol": 1e-8, "batch": 1000})
        for key in keys:
            part = group.create_group(key)
            part.create_dataset("U", shape=(10**6, 1), dtype="f8", chunks=(2**16, 1))
            part.create_dataset("s", shape=(1,), dtype="f8")
            part.create_dataset("V", shape=(1, 1), dtype="f8")
            part.create_dataset("columns", data=[0])
            part.create_dataset("buffer", shape=(1000, 10**6), dtype="f8", chunks=(1, 2**16))
            part.create_dataset("buffer_index", shape=(1000,), dtype="i8", fillvalue=-1)
    with pytest.raises(CorruptFile, match=r"declares buffered runs 1000 \(at most 250\)"):
        ResultStore.open(out)


def unbounded_inputs(tmp_path) -> dict:
    """A 4 GiB file of one line (sparse: no disk taken), /dev/zero (never ends), a FIFO nobody writes (its
    reader waits for ever): what each one is called in the refusal."""
    huge = tmp_path / "huge"
    with open(huge, "wb") as fh:
        fh.truncate(4 * 2**30)
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    return {huge: "4096 MiB, more than the", "/dev/zero": "a character device, not a regular file",
            fifo: "a FIFO (named pipe), not a regular file"}


@pytest.mark.slow
def test_a_baseline_is_bounded_before_it_is_read(decay_results, tmp_path):
    """D14: `check --baseline` read a baseline of any size whole (a 4 GiB file: MemoryError); /dev/zero and
    a FIFO never ended."""
    for baseline, said in unbounded_inputs(tmp_path).items():
        done = limited_cli("check", decay_results, "--baseline", baseline, timeout=60)
        one_line_refusal(done, f"error: {baseline}: {said}", "--write-baseline FILE")


@pytest.mark.slow
def test_flight_data_is_bounded_in_bytes_and_a_regular_file(decay_results, tmp_path):
    """D15: `calibrate --data` sized the data by its lines: a 4 GiB single line passed (MemoryError), and
    /dev/zero never ended."""
    for data, said in unbounded_inputs(tmp_path).items():
        done = limited_cli("calibrate", decay_results, "--data", data, "--out", tmp_path / "cal", timeout=60)
        one_line_refusal(done, f"error: {data}: {said}", "as `uqflight simulate --out` writes it")
    assert not (tmp_path / "cal").exists() or not any((tmp_path / "cal").iterdir())


def test_a_surrogate_is_loaded_only_from_a_bounded_regular_file(tmp_path):
    """The sibling in `uqflight.analysis.surrogate.load`: a FIFO made its open wait for a writer for ever, /dev/zero was
    read up to the bound. Each is refused before a byte is read, naming the file."""
    from uqflight.analysis.surrogate import load
    from uqflight.text import Refusal

    for path, said in unbounded_inputs(tmp_path).items():
        with pytest.raises(Refusal, match=re.escape(f"{path}: cannot read the surrogate (") + ".*" + re.escape(said)):
            load(path)
