"""The HDF5 results file: fixed layout, design order, tSVD determinism, and resuming after a kill.

Run as a script (`python test_store.py PATH SEED`), this file is the writer that the SIGKILL test kills.
"""
import hashlib
import inspect
import json
import os
import re
import shutil
import signal
import struct
import subprocess
import sys
import time

import h5py
import numpy as np
import pytest
from conftest import read_results

import uqflight.store.compressed
import uqflight.store.results
from uqflight.analysis.moments import weighted_moments
from uqflight.analysis.statistics import output_basis
from uqflight.store import CorruptFile, ResultStore, Status, open_for_campaign
from uqflight.store.results import STORAGES
from uqflight.store.storage import OutputStorage

N, T = 240, 400
XI, TIME = np.random.default_rng(7).standard_normal((N, 2)), np.linspace(0.0, 20.0, T)
OUTPUTS = ["alpha_deg", "h_ft"]
CAMPAIGN = "name: store-test\nparameters: {CL0: {distribution: normal}, Cmq: {distribution: normal}}\n"


def create_args(raw=True, tsvd=True):
    return dict(xi=XI, kappa=1.0 + 0.1 * XI, weights=np.full(N, 1.0 / N), parameter_names=["CL0", "Cmq"],
                outputs=OUTPUTS, time=TIME, raw=raw,
                tsvd={"tol": 1e-10, "batch": 8} if tsvd else None,
                attrs={"versions": {"numpy": np.__version__}, "aircraft_hash": "ab12"},
                units={"alpha_deg": "deg", "h_ft": "ft"})


def expected_runs(indices):
    """Status, reasons and histories of the runs `indices`: a pure function of the index."""
    status = np.where(indices % 9 == 4, Status.DIVERGED, np.where(indices % 13 == 7, Status.TRIM_FAILURE, Status.OK))
    reasons = [{Status.OK: "", Status.DIVERGED: "NaN in alpha", Status.TRIM_FAILURE: "udot not trimmable"}[s]
               for s in status]
    a, b, t = XI[indices, :1], XI[indices, 1:], TIME
    outputs = {"alpha_deg": 2.0 + 0.3 * a * np.sin(t) + 0.1 * b * t / 20 + 0.02 * a * b * np.cos(2 * t),
               "h_ft": 15000.0 + 20.0 * b * (1 - np.cos(t / 3)) + a ** 2 * t}
    return status, reasons, outputs


def write_runs(store, batches):
    for indices in batches:
        store.write_batch(indices, *expected_runs(np.asarray(indices)))


def shuffled_batches(seed):
    """All runs in a random order, in batches of random sizes 1..12 (as workers would finish them)."""
    rng = np.random.default_rng(seed)
    cuts = np.cumsum(rng.integers(1, 13, size=N))
    return np.split(rng.permutation(N), cuts[cuts < N])


def in_design_order(batch):
    return np.array_split(np.arange(N), N // batch)


def assert_same_results(a, b):
    """Same datasets; identical samples and raw outputs; tSVD factors equal to 1e-12."""
    ca, cb = read_results(a), read_results(b)
    assert ca.keys() == cb.keys()
    for key in ca:
        if key.startswith("tsvd/") and ca[key].dtype.kind == "f":
            np.testing.assert_allclose(ca[key], cb[key], rtol=0, atol=1e-12, err_msg=key)
        else:
            np.testing.assert_array_equal(ca[key], cb[key], err_msg=key)


@pytest.fixture
def reference(tmp_path):
    """A raw + tSVD file written without interruption, in design order."""
    path = tmp_path / "reference.h5"
    with ResultStore.create(path, campaign_text=CAMPAIGN, **create_args()) as store:
        write_runs(store, in_design_order(8))
    return path


def test_create_writes_the_fixed_layout_and_reopens(tmp_path):
    path = tmp_path / "r.h5"
    args = create_args()
    ResultStore.create(path, campaign_text=CAMPAIGN, **args).close()
    datasets = set(read_results(path))
    with h5py.File(path, "r") as f:
        assert {"samples/xi", "samples/kappa", "samples/weight", "samples/status", "samples/reason", "time",
                "outputs/alpha_deg", "outputs/h_ft"} <= datasets
        assert {f"tsvd/h_ft/{k}" for k in ("U", "s", "V", "columns", "buffer", "buffer_index")} <= datasets
        assert f["outputs/h_ft"].shape == (N, T) and f["outputs/h_ft"].chunks[1] == T
        assert f["samples/status"].dtype == np.int8 and np.all(f["samples/status"][()] == -1)
        assert f.attrs["campaign"] == CAMPAIGN
        assert f.attrs["campaign_hash"] == hashlib.sha256(CAMPAIGN.encode()).hexdigest()
        assert json.loads(f.attrs["versions"]) == {"numpy": np.__version__} and f.attrs["aircraft_hash"] == "ab12"
        assert "created" in f.attrs and f["time"].attrs["units"] == "s"
        assert list(f["samples/kappa"].attrs["names"]) == ["CL0", "Cmq"]
        assert f["outputs/alpha_deg"].attrs["units"] == "deg"
        assert list(f["outputs/alpha_deg"].attrs["dimensions"]) == ["sample", "time"]
    with ResultStore.open(path) as store:
        np.testing.assert_array_equal(store.xi, args["xi"])
        np.testing.assert_array_equal(store.kappa, args["kappa"])
        np.testing.assert_array_equal(store.weights, args["weights"])
        np.testing.assert_array_equal(store.time, args["time"])
        np.testing.assert_array_equal(store.pending(), np.arange(N))
        assert store.parameter_names == ["CL0", "Cmq"] and store.output_names == OUTPUTS
        assert store.units == {"alpha_deg": "deg", "h_ft": "ft"} and store.reasons == [""] * N
        assert store.output_factors("h_ft") is None  # the raw histories are there
        assert (store.campaign_text, store.storage_description) == (
            CAMPAIGN, "raw; tsvd tol 1e-10, batch 8, ranks alpha_deg 0, h_ft 0")
    with pytest.raises(FileExistsError, match="r.h5"):
        ResultStore.create(path, campaign_text=CAMPAIGN, **args)
    h5py.File(tmp_path / "other.h5", "w").close()
    with pytest.raises(ValueError, match="other.h5 is not a uqflight results file"):
        ResultStore.open(tmp_path / "other.h5")


def test_compressed_only_file_has_no_raw_outputs(tmp_path):
    with ResultStore.create(tmp_path / "c.h5", campaign_text=CAMPAIGN, **create_args(raw=False)) as store:
        write_runs(store, in_design_order(12))
        assert store.output_names == OUTPUTS
    with h5py.File(tmp_path / "c.h5", "r") as f:
        assert "outputs" not in f
    with pytest.raises(ValueError, match="nothing would be stored"):
        ResultStore.create(tmp_path / "n.h5", campaign_text=CAMPAIGN, **create_args(raw=False, tsvd=False))


def test_runs_arriving_out_of_order_land_in_design_order(tmp_path):
    with ResultStore.create(tmp_path / "r.h5", campaign_text=CAMPAIGN, **create_args(tsvd=False)) as store:
        write_runs(store, shuffled_batches(seed=1))
        status, reasons, outputs = expected_runs(np.arange(N))
        ok = status == Status.OK
        assert store.pending().size == 0 and not ok.all()
        np.testing.assert_array_equal(store.status, status)
        assert store.reasons == reasons
        for name in OUTPUTS:
            np.testing.assert_array_equal(store.output_matrix(name), np.where(ok[:, None], outputs[name], np.nan))
            np.testing.assert_array_equal(store.output_matrix(name, rows=[5, 3]), outputs[name][[5, 3]])
        blocks = list(store.iter_output_blocks("h_ft", block=50))
        np.testing.assert_array_equal(np.concatenate([rows for rows, _ in blocks]), np.flatnonzero(ok))
        np.testing.assert_array_equal(np.vstack([v for _, v in blocks]), outputs["h_ft"][ok])
        with pytest.raises(ValueError, match="already stored"):
            write_runs(store, [[3]])


@pytest.mark.slow
def test_tsvd_factors_do_not_depend_on_the_arrival_order(tmp_path, reference):
    for seed in (2, 3):
        path = tmp_path / f"shuffled{seed}.h5"
        with ResultStore.create(path, campaign_text=CAMPAIGN, **create_args()) as store:
            write_runs(store, shuffled_batches(seed))
        assert_same_results(path, reference)
    status, _, outputs = expected_runs(np.arange(N))
    ok = status == Status.OK
    contents = read_results(reference)
    np.testing.assert_array_equal(contents["tsvd/h_ft/columns"], np.flatnonzero(ok))
    assert contents["tsvd/h_ft/buffer"].shape == (0, T)
    compressed = tmp_path / "compressed.h5"
    with ResultStore.create(compressed, campaign_text=CAMPAIGN, **create_args(raw=False)) as store:
        write_runs(store, shuffled_batches(seed=4))
        for name in OUTPUTS:
            rebuilt = store.output_matrix(name)
            assert np.isnan(rebuilt[~ok]).all()
            np.testing.assert_allclose(rebuilt[ok], outputs[name][ok], rtol=1e-9)


@pytest.mark.parametrize("raw", [True, False])
def test_moments_equal_numpy_on_the_raw_data(tmp_path, raw):
    weights = np.random.default_rng(5).uniform(0.5, 1.5, N)
    with ResultStore.create(tmp_path / "m.h5", campaign_text=CAMPAIGN, **create_args(raw=raw)) as store:
        write_runs(store, shuffled_batches(seed=6))
        status, _, outputs = expected_runs(np.arange(N))
        ok = status == Status.OK
        w = weights[ok] / weights[ok].sum()
        for name in OUTPUTS:
            basis, scale = output_basis(store, name, ok)
            mean, variance = weighted_moments(basis, weights[ok], scale)
            expected_mean = w @ outputs[name][ok]
            np.testing.assert_allclose(mean, expected_mean, rtol=1e-12)
            np.testing.assert_allclose(variance, w @ (outputs[name][ok] - expected_mean) ** 2,
                                       rtol=1e-7, atol=1e-9 * variance.max())


def test_a_partial_compressed_file_reads_its_buffered_runs(tmp_path):
    with ResultStore.create(tmp_path / "p.h5", campaign_text=CAMPAIGN, **create_args(raw=False)) as store:
        write_runs(store, [np.arange(0, 30), np.arange(40, 45)])  # a gap: 40..44 wait in the buffer
        np.testing.assert_array_equal(store.pending(), np.r_[30:40, 45:N])
        written = np.r_[0:30, 40:45]
        status, _, outputs = expected_runs(written)
        ok = status == Status.OK
        rebuilt = store.output_matrix("alpha_deg", np.r_[written, 35])
        np.testing.assert_allclose(rebuilt[:-1][ok], outputs["alpha_deg"][ok], rtol=1e-9)
        assert np.isnan(rebuilt[:-1][~ok]).all() and np.isnan(rebuilt[-1]).all()
        U, s, V, columns = store.output_factors("alpha_deg")
        np.testing.assert_array_equal(columns, written[ok])
        np.testing.assert_allclose((V * s) @ U.T, outputs["alpha_deg"][ok], rtol=1e-9)


def test_every_storage_form_implements_every_interface_method():
    """Each form is one entry of results.STORAGES, under its layout group (raw first: it is read when
    kept), and defines every method of OutputStorage itself, with the interface's parameters."""
    assert set(OutputStorage.__subclasses__()) == set(STORAGES)
    assert [form.GROUP for form in STORAGES] == ["outputs", "tsvd"]
    interface = sorted(OutputStorage.__abstractmethods__)
    assert {"write", "settle", "matrix", "blocks", "factors", "lost_runs", "problems", "description"} <= set(interface)
    for form in STORAGES:
        assert not form.__abstractmethods__, form
        for name in interface:
            assert name in vars(form), f"{form.__name__} does not define {name}"
            ours, theirs = vars(form)[name], vars(OutputStorage)[name]
            if isinstance(theirs, property):
                assert isinstance(ours, property), f"{form.__name__}.{name} is not a property"
                ours, theirs = ours.fget, theirs.fget
            assert list(inspect.signature(ours).parameters) == list(inspect.signature(theirs).parameters), name


@pytest.mark.slow
def test_raw_and_tsvd_forms_hold_the_same_runs(tmp_path):
    """The two forms of one raw + tSVD file, fed the same runs out of order, half of them and then all:
    the same matrix (NaN rows where not run or failed), the same runs in design order block by block,
    nothing lost, no problem. The tSVD rebuild is within K·tol·σ₁ of the raw data in the 2-norm, so in
    every entry: each of the K ≤ N/batch updates drops singular values below tol·σ₁ (σ₁ of the data)."""
    batches = shuffled_batches(seed=8)
    with ResultStore.create(tmp_path / "both.h5", campaign_text=CAMPAIGN, **create_args()) as store:
        raw, tsvd = store._storages
        for written in (batches[:len(batches) // 2], batches[len(batches) // 2:]):
            write_runs(store, written)
            status = store.status
            ok = np.flatnonzero(status == Status.OK)
            rows = np.r_[N - 1:-1:-1, 5, 5]  # any order, repeats allowed
            for name in OUTPUTS:
                exact = raw.matrix(name, rows, status)
                bound = (N / 8) * 1e-10 * np.linalg.norm(exact[np.isfinite(exact[:, 0])], 2)
                rebuilt = tsvd.matrix(name, rows, status)
                np.testing.assert_array_equal(np.isnan(rebuilt), np.isnan(exact))
                assert np.nanmax(np.abs(rebuilt - exact)) <= bound
                for form in (raw, tsvd):
                    indices, histories = zip(*form.blocks(name, status, 50))
                    np.testing.assert_array_equal(np.concatenate(indices), ok)
                    assert np.abs(np.vstack(histories) - raw.matrix(name, ok, status)).max() <= bound
                U, s, V, columns = tsvd.factors(name, status)
                np.testing.assert_array_equal(np.sort(columns), ok)
                assert raw.factors(name, status) is None
            for form in (raw, tsvd):
                assert form.problems(status, 64) == [] and not form.lost_runs(status, 64).any()
                assert form.output_names == OUTPUTS and form.units == {"alpha_deg": "deg", "h_ft": "ft"}
        assert (raw.tolerance, tsvd.tolerance) == (0.0, 1e-10)
        assert (raw.description, tsvd.description) == ("raw", "tsvd tol 1e-10, batch 8, ranks alpha_deg 4, h_ft 3")


def kill_writer_midway(path, batches_before_kill, delay) -> None:
    """Run this file as the writer of `path` and SIGKILL it `delay` seconds after it has written that many
    batches (a batch takes a few milliseconds: the delay moves the kill across the steps of the next ones).
    The writer waits for the go after those batches, so a slow reader cannot let it run ahead, and
    blocks after its last batch, so the kill always finds it alive: wherever it lands, the file must
    resume to the same bits (no retry on timing)."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    child = subprocess.Popen([sys.executable, __file__, str(path), "8", str(batches_before_kill)],
                             stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env)
    assert child.stdout.readline().strip() == "paused"
    child.stdin.write("go\n")
    child.stdin.flush()
    time.sleep(delay)
    os.kill(child.pid, signal.SIGKILL)
    assert child.wait() == -signal.SIGKILL


@pytest.mark.slow
@pytest.mark.parametrize("batches_before_kill, delay", [(2, 0.0), (9, 0.003), (20, 0.006)])
def test_resume_after_sigkill_equals_an_uninterrupted_file(tmp_path, reference, batches_before_kill, delay):
    path = tmp_path / "killed.h5"
    ResultStore.create(path, campaign_text=CAMPAIGN, **create_args()).close()
    kill_writer_midway(path, batches_before_kill, delay)
    with ResultStore.open(path, "a") as store:
        pending, status = store.pending(), store.status
        assert pending.size < N
        reported = np.concatenate(shuffled_batches(8)[:batches_before_kill])
        # runs reported written stay written, unless the kill tore their chunk: then they are rerun
        assert np.isin(reported, pending).sum() <= store.repaired
        np.testing.assert_array_equal(status[status >= 0], expected_runs(np.flatnonzero(status >= 0))[0])
        if pending.size:
            write_runs(store, np.array_split(pending, min(5, pending.size)))
    assert_same_results(path, reference)


def test_data_past_the_end_the_superblock_records_is_refused_with_the_remedy_and_resumes_to_the_same_bits(
        tmp_path, reference):
    """A kill inside HDF5's flush can write objects before the superblock that records the end of the
    file's space (seen under load in the test above: "addr overflow ... eoa"). Here the recorded end
    (a version-0 superblock's end-of-file address, bytes 40-48) is set back to 90 % of the file."""
    path = tmp_path / "short.h5"
    shutil.copy(reference, path)
    size = path.stat().st_size
    with open(path, "r+b") as fh:
        assert fh.read(9)[8] == 0  # superblock version 0
        fh.seek(40)
        assert struct.unpack("<Q", fh.read(8))[0] == size
        fh.seek(40)
        fh.write(struct.pack("<Q", size * 9 // 10))
    with pytest.raises(uqflight.store.results.CorruptFile, match=r"addr overflow.*resuming the campaign"):
        ResultStore.open(path).status
    with ResultStore.open(path, "a") as store:  # the recorded end moved to the file's: nothing is lost
        assert store.pending().size == 0 and store.repaired == 0
    assert_same_results(path, reference)
    with open(path, "rb") as fh:
        fh.seek(40)
        assert struct.unpack("<Q", fh.read(8))[0] >= size  # written back: a plain read works too
    cut = tmp_path / "cut.h5"  # the same, but the bytes past the recorded end are gone too: not mendable
    shutil.copy(reference, cut)
    with open(cut, "r+b") as fh:
        fh.seek(40)
        fh.write(struct.pack("<Q", size * 9 // 10))
        fh.truncate(size * 9 // 10)
    with pytest.raises(uqflight.store.results.CorruptFile, match=r"cut short.*--restart"):
        ResultStore.open(cut, "a")


def set_recorded_end(path, end: int) -> None:
    """A version-0 superblock's end-of-file address (bytes 40-48) set to `end`."""
    with open(path, "r+b") as fh:
        assert fh.read(9)[8] == 0
        fh.seek(40)
        fh.write(struct.pack("<Q", end))


def test_a_resume_whose_first_look_at_the_file_reads_past_its_recorded_end_mends_it(tmp_path, reference):
    """The same kill, where what the resume reads first (the root's attributes, the /samples/status link)
    lies past the recorded end: before, the resume called the file damaged and advised --force, which
    would have thrown away every run. The recorded end is set below each place where that first look
    fails in its own way (the root's metadata lies in the file's first 16 KiB)."""
    path = tmp_path / "short.h5"

    def first_look(end: int) -> str:
        shutil.copy(reference, path)
        set_recorded_end(path, end)
        try:
            with h5py.File(path, "r") as f:
                f.attrs.get("campaign_hash"), f.attrs.get("aircraft_hash"), "samples/status" in f
        except (OSError, RuntimeError) as exc:
            return re.sub(r"\d+", "N", " ".join(str(exc).split()))  # HDF5's reason, without its addresses
        return "read"

    failures: dict[str, int] = {}
    for end in range(16384, 1024, -128):
        failures.setdefault(first_look(end), end)
    opened = {reason: end for reason, end in failures.items() if reason != "read" and "open file" not in reason}
    assert len(opened) == 4, failures  # the link check, and three ways of failing to read the attributes
    for reason, end in opened.items():
        first_look(end)
        with open_for_campaign(path, campaign_text=CAMPAIGN, **create_args()) as store:
            assert store.pending().size == 0 and store.repaired == 0, reason
        assert_same_results(path, reference)
    unopened = max(end for reason, end in failures.items() if "open file" in reason)
    first_look(unopened)  # below the root group's own header: HDF5 cannot open the file to move the end
    with pytest.raises(FileExistsError, match="past the end its superblock records, and that end could not be mended"):
        open_for_campaign(path, campaign_text=CAMPAIGN, **create_args())


@pytest.mark.parametrize("dataset, tsvd", [("outputs/alpha_deg", False), ("outputs/alpha_deg", True),
                                           ("samples/reason", True)])
@pytest.mark.slow
def test_a_torn_chunk_is_rewritten_and_its_runs_rerun_on_resume(tmp_path, dataset, tsvd):
    """A kill during HDF5's write of a chunk leaves it failing its checksum: a resume reruns its runs
    (the ok runs of an output chunk, the failed runs of a reason chunk), which restores the file bit for
    bit (the tSVD factors, which hold the ok runs already, stay as they are)."""
    reference, path = tmp_path / "whole.h5", tmp_path / "torn.h5"
    for target in (reference, path):
        with ResultStore.create(target, campaign_text=CAMPAIGN, **create_args(tsvd=tsvd)) as store:
            write_runs(store, shuffled_batches(4))
    with h5py.File(path, "r") as f:
        offset = f[dataset].id.get_chunk_info(0).byte_offset
    with open(path, "r+b") as fh:  # one byte of the first chunk's data changed, as a torn write leaves it
        fh.seek(offset + 3)
        byte = fh.read(1)
        fh.seek(offset + 3)
        fh.write(bytes([byte[0] ^ 0x10]))
    with ResultStore.open(path, "a") as store:
        assert store.repaired > 0 and store.pending().size == store.repaired
        if dataset == "samples/reason":  # the chunk holds all 240 runs: exactly the failed ones are rerun
            np.testing.assert_array_equal(store.pending(), np.flatnonzero(expected_runs(np.arange(N))[0] > 0))
        write_runs(store, [store.pending()])
    assert_same_results(path, reference)


def test_reasons_are_checksummed_fixed_length_strings_cut_at_a_character(tmp_path):
    """No variable-length strings: their global heap has no checksum, and a kill can leave the dataset
    pointing at heap objects that never reached the disk (HDF5 then fails or crashes on the next write).
    A reason longer than 256 bytes is cut before a whole character and ends in "…"."""
    long_reason = "é" * 200  # 400 bytes: 126 characters (252 bytes) and "…" (3) fit in 256
    with ResultStore.create(tmp_path / "r.h5", campaign_text=CAMPAIGN, **create_args()) as store:
        status, reasons, outputs = expected_runs(np.arange(8))
        reasons[4] = long_reason
        store.write_batch(np.arange(8), status, reasons, outputs)
        assert store.reasons[:8] == [""] * 4 + ["é" * 126 + "…"] + [""] * 2 + ["udot not trimmable"]
        data = store._file["samples/reason"]
        assert h5py.check_string_dtype(data.dtype).length == 256 and data.fletcher32
    assert uqflight.store.results.fit_reason("abc", 3) == b"abc"
    assert uqflight.store.results.fit_reason("abcd", 3) == "…".encode()


def test_reasons_of_runs_left_pending_by_a_crash_are_cleared_on_resume(tmp_path, reference, monkeypatch):
    """A crash after the data and reasons reached the disk but before the status: the runs stay pending,
    their reasons are cleared on reopening, and the resume gives the uninterrupted file."""
    path, flush = tmp_path / "crashed.h5", ResultStore._flush

    def crash_after_the_first_flush(store, sync):
        flush(store, sync)
        raise Crash

    with ResultStore.create(path, campaign_text=CAMPAIGN, **create_args()) as store:
        write_runs(store, [np.arange(0, 8)])
        monkeypatch.setattr(ResultStore, "_flush", crash_after_the_first_flush)
        with pytest.raises(Crash):
            write_runs(store, [np.arange(8, 40)])  # runs 13, 20, 22, 31 and 33 fail
        monkeypatch.undo()
        assert store.reasons[13] == "NaN in alpha"
    with ResultStore.open(path, "a") as store:
        np.testing.assert_array_equal(store.pending(), np.arange(8, N))
        assert store.reasons == expected_runs(np.arange(8))[1] + [""] * (N - 8)
        write_runs(store, [store.pending()])
    assert_same_results(path, reference)


def test_a_file_with_variable_length_reasons_is_refused_naming_the_dataset_and_the_fix(tmp_path):
    """Reasons are fixed-length strings (variable-length ones live in HDF5's unchecked heap): a file holding
    variable-length ones is refused on opening, in one line naming the dataset and `run --restart`."""
    path = tmp_path / "other.h5"
    with ResultStore.create(path, campaign_text=CAMPAIGN, **create_args(tsvd=False)) as store:
        pass
    with h5py.File(path, "r+") as f:
        del f["samples/reason"]
        f["samples"].create_dataset("reason", shape=(N,), dtype=h5py.string_dtype())
    for mode in ("r", "a"):
        with pytest.raises(CorruptFile) as refused:
            ResultStore.open(path, mode)
        assert str(refused.value) == (
            f"{path}: /samples/reason holds variable-length strings, expected fixed-length strings of at most 256 "
            "bytes: the file is damaged or was not written by uqflight: fly its campaign again (`uqflight run "
            "CAMPAIGN --out FILE --restart`)")


@pytest.mark.slow
def test_run_refuses_a_file_with_variable_length_reasons_in_one_line_and_restart_flies_it_again(tmp_path):
    from conftest import DECAY_TWO_INPUTS, cli_in_process

    (tmp_path / "c.yaml").write_text(DECAY_TWO_INPUTS)
    out = tmp_path / "r.h5"
    assert cli_in_process("run", tmp_path / "c.yaml", "--out", out).returncode == 0
    with h5py.File(out, "r+") as f:
        n = f["samples/status"].shape[0]
        del f["samples/reason"]
        f["samples"].create_dataset("reason", shape=(n,), dtype=h5py.string_dtype())
    refused = cli_in_process("run", tmp_path / "c.yaml", "--out", out)
    assert refused.returncode == 2 and "Traceback" not in refused.stderr
    assert refused.stderr.strip().splitlines() == [
        f"error: {out}: /samples/reason holds variable-length strings, expected fixed-length strings of at most 256 "
        f"bytes: the file is damaged or was not written by uqflight; `uqflight run {tmp_path / 'c.yaml'} --out {out} "
        "--restart` starts it over"]
    assert cli_in_process("run", tmp_path / "c.yaml", "--out", out, "--restart").returncode == 0
    with ResultStore.open(out) as store:
        assert store.pending().size == 0 and h5py.check_string_dtype(store._file["samples/reason"].dtype).length == 256


class Crash(Exception):
    """Stands for a kill at one step of a write."""


def crash_after(step):
    def crashing(*args):
        step(*args)
        raise Crash

    return crashing


def crash_before(step):
    def crashing(*args):
        raise Crash

    return crashing


def crash_halfway(step):
    def crashing(group):  # _apply_staged moves U in, then dies
        del group["U"]
        group.move("next/U", "U")
        raise Crash

    return crashing


@pytest.mark.parametrize("step, crash", [("append_rows", crash_after), ("write_state", crash_after),
                                         ("apply_staged", crash_before), ("apply_staged", crash_halfway)])
def test_a_crash_between_two_steps_is_mended_on_reopening(tmp_path, reference, monkeypatch, step, crash):
    """Rows in the buffer without their status; factors staged but incomplete; staged but not moved
    in; moved in half-way."""
    path = tmp_path / "crashed.h5"
    with ResultStore.create(path, campaign_text=CAMPAIGN, **create_args()) as store:
        write_runs(store, [np.arange(0, 6)])
        module = uqflight.store.compressed  # the tSVD form's buffering and staging steps
        monkeypatch.setattr(module, step, crash(getattr(module, step)))
        with pytest.raises(Crash):
            write_runs(store, [np.arange(6, 20)])  # enough runs to fold a batch of 8 columns
    monkeypatch.undo()
    with ResultStore.open(path, "a") as store:
        first_pending = 6 if step == "append_rows" else 20
        np.testing.assert_array_equal(store.pending(), np.arange(first_pending, N))
        write_runs(store, [store.pending()])
    assert_same_results(path, reference)


def test_open_for_campaign_resumes_only_the_same_campaign(tmp_path):
    path = tmp_path / "r.h5"
    with open_for_campaign(path, campaign_text=CAMPAIGN, **create_args(tsvd=False)) as store:
        write_runs(store, [np.arange(10)])
    with open_for_campaign(path, campaign_text=CAMPAIGN, **create_args(tsvd=False)) as store:
        np.testing.assert_array_equal(store.pending(), np.arange(10, N))
    other = CAMPAIGN + "seed: 2\n"
    with pytest.raises(FileExistsError, match=r"r\.h5 holds the results of another campaign"):
        open_for_campaign(path, campaign_text=other, **create_args(tsvd=False))
    with open_for_campaign(path, campaign_text=other, force=True, **create_args(tsvd=False)) as store:
        assert store.campaign_text == other and store.pending().size == N


if __name__ == "__main__":
    target, seed, pause_after = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    with ResultStore.open(target, "a") as writer:
        for k, batch in enumerate(shuffled_batches(seed)):
            if k == pause_after:
                print("paused", flush=True)
                sys.stdin.readline()
            write_runs(writer, [batch])
        print("done", flush=True)
        sys.stdin.readline()  # wait to be killed: the test's kill must find a live writer


@pytest.mark.parametrize("batch_rows, rows", [(16, 21), (24, 24), (None, 240), (1000, 240)])
def test_raw_chunks_hold_whole_batches_of_at_most_a_mebibyte(tmp_path, batch_rows, rows):
    """A batch of the runner's chunk fills whole HDF5 chunks (no read-modify-write of part-filled
    ones); chunks stay under 1 MiB (400 times x 8 B: 327 rows), within the design (240 runs) and
    above 64 KiB (21 rows)."""
    path = tmp_path / "r.h5"
    ResultStore.create(path, campaign_text=CAMPAIGN, batch_rows=batch_rows, **create_args()).close()
    with h5py.File(path, "r") as f:
        assert f["outputs/h_ft"].chunks == (rows, T)
