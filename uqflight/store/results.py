"""The HDF5 results file of a campaign: the design, the status of every run, and the time histories
(raw, or compressed on the fly by the incremental thin SVD), appended batch by batch and resumable.

Layout (docs/results-file.md; N runs, d parameters, T recorded times):
    /samples/xi (N, d)  /samples/kappa (N, d; attr names)  /samples/weight (N)
    /samples/status (N int8, see Status)  /samples/reason (N str of at most 256 UTF-8 bytes, "" when ok)
    /time (T)
    /outputs/<name> (N, T)  raw histories, NaN rows where not run or failed
    /tsvd/<name>/U (T, r), s (r), V (n, r), columns (n)   A_:c ≈ U diag(s) V_c: is sample columns[c]
    /tsvd/<name>/buffer (m, T), buffer_index (m)          ok runs not folded into the factors yet
    /quantities/<name> (N)  optional: one number per run (uqflight.quantities), NaN where undefined in
                            the run, not run or failed
    /resolution/<name> (T)  optional: the simulator's own resolution of the output (level flight:
                            its two trims' drift, see JSBSimSimulator.resolution); a spread below it
                            is not the inputs'
    root attributes: campaign (YAML text), campaign_hash (its sha256), created, and the caller's
    (versions, aircraft_hash, ...)

Storage forms: the outputs are kept raw (`raw`), compressed (`compressed`), or both, each behind one
interface (`storage.OutputStorage`); every batch is written to each form the file holds, and read from
the first (raw when kept: it is exact).

Crash safety: every batch writes its data and the failed runs' reasons first, flushes and fsyncs, then
writes the status,
flushes and fsyncs again (one flush would let HDF5 write its cached chunks in its own order, and a
kill or full disk could then leave a status without its data), so a killed process loses at most
the batch in flight and `pending()` tells exactly what to rerun. The tSVD form replaces an output's
factors and buffer together, staged in `/tsvd/<name>/next`; reopening with mode "a" finishes or
discards such a half-done step (`compressed`). A kill inside a flush can leave objects past the
end the superblock records; reopening with mode "a" moves that end to the file's (`file_end`).

Determinism: runs complete in any order; the raw rows land in their design rows, and the tSVD folds
the ok runs in design order with one BLAS thread (`compressed`), so the file depends neither on the
number of workers nor on interruptions: a resume gives the same bits.

Integrity: every dataset is chunked with HDF5's fletcher32 checksum, so a flipped byte is reported
on reading (`CorruptFile`) instead of read back as a valid value; status codes outside `Status`
are refused on opening. The reasons are fixed-length strings: variable-length ones live in HDF5's
global heap, which takes no checksum and which a kill can leave pointing at heap objects that never
reached the disk (HDF5 then fails, or crashes, on the next write).
"""
from __future__ import annotations

import contextlib
import gc
import hashlib
import json
import os
import sys
import traceback
from collections.abc import Iterator
from datetime import datetime, timezone

import h5py
import numpy as np

from ..quantities import is_quantity_key
from ..simulators.base import Status
from .chunks import chunk_blocks, grow_rows
from .compressed import TsvdStorage
from .file_end import HINT as END_HINT
from .file_end import extend_to_file_end, past_recorded_end
from .layout import is_time_grid, layout_problems
from .lock import LockHeld, held_message, is_lock_error
from .raw import RawStorage
from .rare import read_rare_event, write_rare_event
from .rounds import read_index_set, write_index_set
from .storage import OutputStorage, key_of, name_of
from ..text import Refusal

STORAGES = (RawStorage, TsvdStorage)  # the storage forms, in the order they are read from


def text_hash(text: str) -> str:
    """sha256 of a campaign's text, as stored in the campaign_hash attribute."""
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


REASON_BYTES = 256  # a failure's reason is stored in at most this many UTF-8 bytes, longer ones cut with "…"
REFLY = "fly its campaign again (`uqflight run CAMPAIGN --out FILE --restart`)"
REASON_ROWS = 256  # reasons per HDF5 chunk (64 KiB); only chunks holding a failed run are ever written
QUANTITY_ROWS = 8192  # quantity values per HDF5 chunk (64 KiB)
CHECKED = {"chunks": True, "fletcher32": True}  # every fixed-size dataset: chunked and checksummed


class CorruptFile(Refusal):
    """A results file whose contents fail their checks (checksum, unknown status codes)."""


READ_ERRORS = (OSError, RuntimeError)  # what h5py raises for data or links it cannot read


def error_line(exc: BaseException) -> str:
    """An error's message on one line (h5py's span several)."""
    return " ".join(str(exc).split())


def read_error(exc: BaseException) -> str:
    """One line on an HDF5 read error; a failed checksum is called what it is."""
    text = error_line(exc)
    if "filter" in text.lower() or "checksum" in text.lower():
        return f"data corrupted: a checksum (fletcher32) does not match ({text})"
    if past_recorded_end(text):
        return f"{text}: {END_HINT}"
    return text


def _unreadable(path, exc: BaseException, extended: bool) -> CorruptFile:
    """The CorruptFile for a file that fails a read on opening; `extended`: its recorded end was moved to
    the file's already (file_end), so a read past it is past the bytes on disk."""
    if extended and past_recorded_end(str(exc)):
        return CorruptFile(f"{path}: {error_line(exc)}: data past the end of the file on disk (the file was cut short, "
                           "e.g. copied or written out incompletely): it cannot be mended; fly the campaign "
                           "again (`uqflight run CAMPAIGN --out FILE --restart`)")
    return CorruptFile(f"{path}: {read_error(exc)}")


def fit_reason(reason: str, size: int) -> bytes:
    """`reason` in UTF-8, cut to at most `size` bytes (ending in "…" when cut, never inside a character)."""
    data = reason.encode("utf-8")
    if len(data) <= size:
        return data
    return data[:size - 3].decode("utf-8", "ignore").encode("utf-8") + "…".encode("utf-8")


@contextlib.contextmanager
def _release_failures() -> Iterator[list]:
    """h5py reports a write that fails while it releases an object (HDF5 writing the object's metadata
    back, e.g. into a full disk) as an "Exception ignored" traceback on stderr, and goes on. Within the
    block such failures are collected in the list yielded instead (h5py prints the traceback through
    sys.excepthook, then the line through sys.unraisablehook); other reports pass through."""
    caught: list[BaseException] = []
    previous_unraisable, previous_except = sys.unraisablehook, sys.excepthook

    def unraisable(report) -> None:
        if isinstance(report.exc_value, READ_ERRORS):
            caught.append(report.exc_value)
        else:
            previous_unraisable(report)

    def excepthook(kind, value, tb) -> None:
        if isinstance(value, READ_ERRORS):
            caught.append(value)
        else:
            previous_except(kind, value, tb)

    sys.unraisablehook, sys.excepthook = unraisable, excepthook
    try:
        yield caught
    finally:
        sys.unraisablehook, sys.excepthook = previous_unraisable, previous_except


def _abandon(f: h5py.File, exc: BaseException) -> None:
    """Close a file whose writing failed (a full disk) while `exc` is raised, quietly: its objects are
    released here (the frames of the traceback hold some), each failing again to write its metadata."""
    traceback.clear_frames(exc.__traceback__)
    with _release_failures():
        try:
            f.close()
        except READ_ERRORS:
            pass
        gc.collect()


class ResultStore:
    """One campaign's results file. Build it with `create`, `open` or `open_for_campaign`."""

    def __init__(self, file: h5py.File):
        self._file = file
        self._storages: list[OutputStorage] = [form(file) for form in STORAGES
                                               if isinstance(file.get(form.GROUP), h5py.Group)]
        self.repaired = 0  # ok runs found without their data on opening to resume, made pending again

    @classmethod
    def create(cls, path, *, campaign_text: str, xi, kappa, weights, parameter_names, outputs, time,
               raw: bool = True, tsvd: dict | None = None, attrs: dict | None = None,
               units: dict | None = None, batch_rows: int | None = None,
               resolution: dict | None = None, quantities=(), capacity: int | None = None) -> ResultStore:
        """A new file (refused if `path` exists) holding the design, with every run pending.

        `tsvd` = {"tol": ..., "batch": ...} turns on compression (batch defaults to the paper's 1000
        samples); `attrs` become root attributes (dicts as JSON text); `units` maps output name → unit.
        `batch_rows`: the runs the writer stores at a time (the runner's chunk): raw chunks of that many
        rows (at least 64 KiB, at most ~1 MiB), so that a batch fills whole HDF5 chunks instead of
        rewriting part-filled ones. `resolution` maps output name → (T,) the simulator's own resolution.
        `quantities`: the names of the campaign's quantities of interest, one value per run each.
        `capacity`: the runs the design may grow to (an adaptive grid's budget, `set_design`); None: fixed.
        """
        xi, kappa = np.atleast_2d(xi).astype(float), np.atleast_2d(kappa).astype(float)
        weights, time = np.asarray(weights, dtype=float), np.asarray(time, dtype=float)
        parameter_names, outputs, units = list(parameter_names), list(outputs), units or {}
        n, d = xi.shape
        if kappa.shape != (n, d) or weights.shape != (n,) or len(parameter_names) != d:
            raise ValueError(f"design shapes disagree: xi {xi.shape}, kappa {kappa.shape}, "
                             f"weights {weights.shape}, {len(parameter_names)} parameter names")
        if time.ndim != 1 or not outputs or len(set(outputs)) != len(outputs):
            raise ValueError(f"need a 1-D time and distinct output names, got time {time.shape}, outputs {outputs}")
        if not is_time_grid(time):
            raise ValueError("the recorded times must be finite and strictly increasing")
        if not raw and tsvd is None:
            raise ValueError("nothing would be stored: turn on raw storage or tsvd compression")
        settings = None if tsvd is None else TsvdStorage.settings(tsvd)  # a bad tolerance: refused before the file

        f = h5py.File(path, "w-")
        try:
            with _release_failures() as failed:
                cls._lay_out(f, campaign_text, xi, kappa, weights, parameter_names, outputs, time, raw, settings,
                             attrs, units, batch_rows, resolution, quantities, capacity)
                f.flush()
            if failed:  # a write failed where h5py could not raise it
                raise failed[0]
        except BaseException as exc:  # e.g. a full disk: closed here, without h5py's "Exception ignored"
            _abandon(f, exc)
            raise
        return cls(f)

    @staticmethod
    def _lay_out(f: h5py.File, campaign_text, xi, kappa, weights, parameter_names, outputs, time, raw, settings,
                 attrs, units, batch_rows, resolution, quantities, capacity) -> None:
        """Write `create`'s layout into the new file `f`."""
        n, d = xi.shape
        grow = {} if capacity is None else {"maxshape": (None,)}  # resizable along the runs
        rows_hint = n if capacity is None else max(n, capacity)
        f.attrs.update({"campaign": campaign_text, "campaign_hash": text_hash(campaign_text),
                        "created": datetime.now(timezone.utc).isoformat(timespec="seconds")})
        f.attrs.update({k: json.dumps(v) if isinstance(v, dict) else v for k, v in (attrs or {}).items()})
        samples = f.create_group("samples")
        design = {} if capacity is None else {"maxshape": (None, d)}
        samples.create_dataset("xi", data=xi, **CHECKED, **design).attrs["dimensions"] = ["sample", "parameter"]
        samples.create_dataset("kappa", data=kappa, **CHECKED, **design).attrs.update(
            {"names": parameter_names, "dimensions": ["sample", "parameter"]})
        samples.create_dataset("weight", data=weights, **CHECKED, **grow)
        samples.create_dataset("status", shape=(n,), dtype="i1", fillvalue=Status.PENDING,
                               **CHECKED, **grow).attrs["codes"] = json.dumps({s.name.lower(): s.value for s in Status})
        samples.create_dataset("reason", shape=(n,), dtype=h5py.string_dtype("utf-8", REASON_BYTES),
                               chunks=(min(rows_hint, REASON_ROWS),), fletcher32=True, **grow)
        f.create_dataset("time", data=time, **CHECKED).attrs["units"] = "s"
        if resolution:
            group = f.create_group("resolution", track_order=True)
            group.attrs["description"] = ("per output and time, how far the nominal flights with two trims that "
                                          "both pass the checks drift apart (max so far): a spread below this is "
                                          "not resolved by the simulator")
            for name in outputs:
                group.create_dataset(key_of(name), data=np.asarray(resolution[name], dtype=float), **CHECKED)
        if raw:
            RawStorage.create(f, outputs, units, n, time.size, batch_rows=batch_rows, rows_hint=rows_hint,
                              growable=capacity is not None)
        if quantities:
            group = f.create_group("quantities", track_order=True)
            group.attrs["description"] = "one number per run (the campaign's quantities:), NaN where undefined"
            for name in quantities:
                group.create_dataset(key_of(name), shape=(n,), dtype="f8", fillvalue=np.nan,
                                     chunks=(min(rows_hint, QUANTITY_ROWS),), fletcher32=True, **grow)
        if settings is not None:
            TsvdStorage.create(f, outputs, units, time.size, *settings)

    @classmethod
    def open(cls, path, mode: str = "r", while_written: bool = False) -> ResultStore:
        """An existing file, read-only ("r") or to resume ("a": half-done steps of a killed writer are mended).
        `while_written`: read a file that a live run is writing (HDF5's file lock off; the writer flushes
        whole batches, so what is read is a consistent earlier state, or an OSError to retry). LockHeld
        (an OSError) naming the process when another one holds the file under HDF5's lock."""
        if mode not in ("r", "a"):
            raise ValueError(f"mode must be 'r' or 'a', got {mode!r}")
        try:
            f = h5py.File(path, "r", locking=False) if while_written and mode == "r" else \
                h5py.File(path, "r" if mode == "r" else "r+")
        except OSError as exc:  # held by another process: in use, not damaged
            if is_lock_error(exc):
                raise LockHeld(held_message(path, "read" if mode == "r" else "written")) from None
            raise
        # before anything is written: space past the recorded end is not free (file_end)
        extended = mode == "a" and extend_to_file_end(f)
        try:
            ours = "samples/status" in f
            store = cls(f) if ours else None
        except READ_ERRORS as exc:
            f.close()
            raise _unreadable(path, exc, extended) from exc
        if not ours:
            f.close()
            raise ValueError(f"{path} is not a uqflight results file (no /samples/status)")
        try:
            if mode == "a":  # finish or drop a step a killed writer left half done, first
                for storage in store._storages:
                    storage.mend()
            problems = layout_problems(f)
            status = None if problems else store.status
        except READ_ERRORS as exc:
            f.close()
            raise _unreadable(path, exc, extended) from exc
        if problems:
            f.close()
            raise CorruptFile(f"{path}: {'; '.join(problems[:3])}{' (and more)' if len(problems) > 3 else ''}: "
                              f"the file is damaged or was not written by uqflight: {REFLY}")
        unknown = np.setdiff1d(np.unique(status), [s.value for s in Status])
        if unknown.size:
            f.close()
            raise CorruptFile(f"{path}: /samples/status holds unknown status codes {unknown.tolist()} "
                              f"(known: {', '.join(f'{s.value} {s.name.lower()}' for s in Status)}); "
                              "the file is damaged or was written by a newer uqflight")
        if mode == "a":
            try:
                store.repaired = store._repair_lost_runs()
            except READ_ERRORS as exc:
                f.close()
                raise _unreadable(path, exc, extended) from exc
            status = store.status
            for storage in store._storages:
                storage.settle(status)
        return store

    @property
    def path(self) -> str:
        """The file's path, as it was opened."""
        return self._file.filename

    def close(self) -> None:
        self._file.close()

    def __enter__(self) -> ResultStore:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # -- the design and the runs ------------------------------------------------------------
    @property
    def xi(self) -> np.ndarray:
        return self._file["samples/xi"][()]

    @property
    def kappa(self) -> np.ndarray:
        return self._file["samples/kappa"][()]

    @property
    def weights(self) -> np.ndarray:
        return self._file["samples/weight"][()]

    @property
    def status(self) -> np.ndarray:
        return self._file["samples/status"][()]

    @property
    def reasons(self) -> list[str]:
        return list(self._file["samples/reason"].asstr()[()])

    @property
    def time(self) -> np.ndarray:
        return self._file["time"][()]

    @property
    def parameter_names(self) -> list[str]:
        return [str(name) for name in self._file["samples/kappa"].attrs["names"]]

    @property
    def output_names(self) -> list[str]:
        return self._read.output_names

    @property
    def units(self) -> dict[str, str]:
        return self._read.units

    @property
    def quantity_names(self) -> list[str]:
        """The campaign's quantities of interest ([] for a file without them)."""
        group = self._file.get("quantities")
        return [] if group is None else [name_of(key) for key in group]

    def quantity(self, name: str) -> np.ndarray:
        """(N,) the values of quantity `name`, NaN where undefined, not run or failed."""
        return self._file["quantities"][key_of(name)][()]

    def resolution(self, name: str) -> np.ndarray | None:
        """(T,) the simulator's own resolution of output `name` (level flight: its two trims' drift), None when the
        file holds none (a Python simulator)."""
        group = self._file.get("resolution")
        return None if group is None or key_of(name) not in group else group[key_of(name)][()]

    @property
    def campaign_text(self) -> str:
        return str(self._file.attrs["campaign"])

    @property
    def campaign_hash(self) -> str:
        return str(self._file.attrs["campaign_hash"])

    @property
    def attrs(self) -> dict:
        """All root attributes (campaign, campaign_hash, created, versions, aircraft_hash, ...)."""
        return dict(self._file.attrs)

    @property
    def storage_description(self) -> str:
        """How the outputs are kept, e.g. "raw; tsvd tol 1e-08, batch 1000, ranks alpha_deg 11"."""
        return "; ".join(storage.description for storage in self._storages)

    @property
    def tsvd_tolerance(self) -> float:
        """The relative truncation tolerance of the tSVD factors (0 without compression)."""
        return max(storage.tolerance for storage in self._storages)

    @property
    def _read(self) -> OutputStorage:
        """The storage form the outputs are read from."""
        return self._storages[0]

    def pending(self) -> np.ndarray:
        """Indices of the runs not written yet, ascending."""
        return np.flatnonzero(self.status == Status.PENDING)

    # -- a growing design (adaptive grids) --------------------------------------------------
    def set_design(self, xi, kappa, weights) -> None:
        """Make the design these N rows (a file made with `capacity`): rows beyond the file's are added,
        pending; the pending rows' xi and kappa are (re)written and every weight is replaced. The rows
        already run must keep their points (ValueError otherwise). Idempotent, so that a writer killed
        half-way through is mended by calling it again."""
        xi, kappa = np.atleast_2d(xi).astype(float), np.atleast_2d(kappa).astype(float)
        weights = np.asarray(weights, dtype=float)
        status, samples = self.status, self._file["samples"]
        n = len(weights)
        if n < status.size or xi.shape != kappa.shape or len(xi) != n:
            raise ValueError(f"a design can only grow: {n} rows for a file of {status.size}")
        done = np.flatnonzero(status != Status.PENDING)
        if not np.array_equal(samples["xi"][()][done], xi[done]):
            raise ValueError("the runs already made would move: the design is not the file's")
        if n > status.size:
            if samples["status"].maxshape[0] is not None:
                raise ValueError("this results file holds a fixed design; it cannot grow")
            grow_rows(samples, n)
            for storage in self._storages:
                storage.grow(n)
            if "quantities" in self._file:
                grow_rows(self._file["quantities"], n)
        pending = np.flatnonzero(np.r_[status, np.full(n - status.size, Status.PENDING)] == Status.PENDING)
        if pending.size:
            samples["xi"][pending[0]:] = xi[pending[0]:]  # the pending rows follow the run ones (set_design's order)
            samples["kappa"][pending[0]:] = kappa[pending[0]:]
        samples["weight"][...] = weights
        self._flush(sync=True)

    def index_set(self):
        """The adaptive grid's state (`designs.adaptive.IndexSet`) written by `write_index_set`, or None;
        CorruptFile when /design is not such a state (a missing or mistyped part, lengths that differ)."""
        try:
            state = read_index_set(self._file)
        except (KeyError, ValueError, TypeError, IndexError) as exc:
            raise CorruptFile(f"{self._file.filename}: /design: the adaptive grid's recorded state cannot be read "
                              f"({error_line(exc)}): the file is damaged or was not written by uqflight") from None
        if state is not None and (not state.indices or len({len(state.indices), len(state.old), len(state.added),
                                                             len(state.indicator)}) != 1):
            raise CorruptFile(f"{self._file.filename}: /design: the adaptive grid's index_set, old, round and "
                              "indicator differ in length: the file is damaged or was not written by uqflight")
        return state

    def write_index_set(self, state) -> None:
        """Record an adaptive grid's state in /design (replaced whole, see `rounds`)."""
        write_index_set(self._file, state)
        self._flush(sync=True)

    def rare_event(self) -> dict | None:
        """A rare-event design's recorded estimate (`store.rare`), or None when the file holds none (another
        design, or rounds not finished); CorruptFile when /rare_event is not such a record."""
        try:
            return read_rare_event(self._file, int(self._file["samples/status"].shape[0]),
                                   int(self._file["samples/xi"].shape[1]))
        except (KeyError, ValueError, TypeError, IndexError, OSError, RuntimeError) as exc:
            raise CorruptFile(f"{self._file.filename}: /rare_event: the rare-event estimate cannot be read "
                              f"({error_line(exc)}): the file is damaged or was not written by uqflight") from None

    def write_rare_event(self, record: dict) -> None:
        """Record a rare-event design's estimate in /rare_event (`store.rare`)."""
        write_rare_event(self._file, record)
        self._flush(sync=True)

    # -- writing ----------------------------------------------------------------------------
    def write_batch(self, indices, status, reasons, outputs: dict) -> None:
        """Store finished runs, in any order: outputs[name] is (n, T) for the n `indices`.

        Rows of failed runs are stored as NaN (their values are ignored); ok rows must be finite.
        The quantities come under `quantity_key(name)`, (n,) each, NaN where undefined; a batch
        without them must hold no ok run.
        Data and reasons first, status last, each followed by a flush; then the completed
        design-order prefix is folded into the tSVD factors.
        """
        outputs, quantities = self._split_quantities(indices, status, outputs)
        idx, status, reasons, values, all_status = self._checked_batch(indices, status, reasons, outputs)
        ok = status == Status.OK
        if not ok.all():  # ok runs keep the fill value "": a campaign without failures writes no reason
            self._write_reasons(idx[~ok], reasons[~ok])
        for name, column in quantities.items():
            self._file["quantities"][key_of(name)][idx] = np.where(ok, column, np.nan)
        for name, rows in values.items():
            for storage in self._storages:
                storage.write(name, idx, ok, rows)
        self._flush(sync=True)
        self._file["samples/status"][idx] = status
        self._flush(sync=True)
        all_status[idx] = status
        for storage in self._storages:
            storage.settle(all_status)

    def _split_quantities(self, indices, status, outputs: dict) -> tuple[dict, dict]:
        """(outputs, quantities sorted as _checked_batch sorts the runs), the quantities checked
        against the file's."""
        quantities = {key[1]: value for key, value in outputs.items() if is_quantity_key(key)}
        outputs = {key: value for key, value in outputs.items() if not is_quantity_key(key)}
        names, order = self.quantity_names, np.argsort(np.asarray(indices, dtype=np.int64).ravel())
        any_ok = bool(np.any(np.asarray(status).ravel() == Status.OK))
        if (quantities or any_ok) and set(quantities) != set(names):
            raise ValueError(f"batch quantities {sorted(quantities)} differ from the file's {names}")
        for name, column in quantities.items():
            column = np.asarray(column, dtype=float).ravel()
            if column.shape != order.shape:
                raise ValueError(f"quantity {name}: expected {order.size} values, got {column.size}")
            quantities[name] = column[order]
        return outputs, quantities

    def _flush(self, sync: bool) -> None:
        """HDF5's caches to the OS, then (sync) the OS's to the disk."""
        self._file.flush()
        if sync and self._file.filename:
            fd = os.open(self._file.filename, os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)

    def _repair_lost_runs(self, block: int = 1000) -> int:
        """Mark pending again the runs a resume must fly again, and return how many: ok runs whose raw
        histories did not reach the disk (a write that failed late, e.g. a full disk hit by HDF5's cache
        at flush), and the runs of a chunk a kill left half written, whose checksum fails (it is
        overwritten: ok runs of a torn output chunk, failed runs of a torn reason chunk, whose rerun
        gives their reason again). Reasons written for runs that are pending are cleared."""
        status = self.status
        lost = self._read.lost_runs(status, block)
        for key in self._file.get("quantities", {}):  # NaN is a valid value here: only torn chunks are lost
            for start, stop, values in chunk_blocks(self._file["quantities"][key], block, np.nan):
                if values is None:
                    lost[start:stop] |= status[start:stop] == Status.OK
        reasons = self._file["samples/reason"]
        stale = np.zeros(status.size, dtype=bool)
        for start, stop, values in chunk_blocks(reasons, block, np.zeros(1, dtype=reasons.dtype)[0]):
            if values is None:
                lost[start:stop] |= status[start:stop] > Status.OK
            else:
                stale[start:stop] = np.asarray(values, dtype=bytes) != b""
        stale &= (status == Status.PENDING) | lost
        if lost.any() or stale.any():
            self._file["samples/status"][np.flatnonzero(lost)] = Status.PENDING
            self._file["samples/reason"][np.flatnonzero(stale)] = np.zeros(int(stale.sum()), dtype=reasons.dtype)
            self._flush(sync=True)
        return int(lost.sum())

    def _write_reasons(self, idx: np.ndarray, reasons) -> None:
        """Store the reasons of the runs `idx` (ascending), cut to what the dataset holds."""
        data = self._file["samples/reason"]
        length = h5py.check_string_dtype(data.dtype).length
        data[idx] = np.array([fit_reason(str(r), length) for r in reasons], dtype=data.dtype)

    def batch_bytes(self, n: int) -> int:
        """An upper estimate of the bytes the next batch of `n` runs may add to the file: its rows
        (a new chunk per output at worst), and for tSVD a staged copy of the factors and buffer."""
        return int(64 * 1024 + n * 1024 + sum(storage.batch_bytes(n) for storage in self._storages))

    def verify(self, block: int = 1000) -> list[str]:
        """Problems of the stored runs (empty when sound): ok runs whose raw histories are not
        finite, buffered tSVD runs missing. Reads every checksummed chunk once."""
        return self._read.problems(self.status, block)

    def _checked_batch(self, indices, status, reasons, outputs):
        """The batch sorted by index, after checking it against the file, and the file's status before it."""
        idx = np.asarray(indices, dtype=np.int64).ravel()
        order = np.argsort(idx)
        idx, status = idx[order], np.asarray(status, dtype=np.int8).ravel()[order]
        reasons = np.asarray(reasons, dtype=object).ravel()[order]
        stored = self.status
        n, n_samples, n_times = idx.size, stored.size, self._file["time"].shape[0]
        if status.size != n or reasons.size != n:
            raise ValueError(f"batch of {n} indices with {status.size} statuses and {reasons.size} reasons")
        if np.any(np.diff(idx) == 0) or (n and (idx[0] < 0 or idx[-1] >= n_samples)):
            raise ValueError(f"batch indices must be distinct and in [0, {n_samples}): {idx}")
        written = idx[stored[idx] != Status.PENDING]
        if written.size:
            raise ValueError(f"runs {written} are already stored")
        if not np.isin(status, [s.value for s in Status if s != Status.PENDING]).all():
            raise ValueError(f"unknown status codes {np.unique(status)}; see uqflight.simulators.base.Status")
        if set(outputs) != set(self.output_names):
            raise ValueError(f"batch outputs {sorted(outputs)} differ from the file's {self.output_names}")
        values = {name: np.asarray(outputs[name], dtype=float)[order] for name in self.output_names}
        ok = status == Status.OK
        for name, rows in values.items():
            if rows.shape != (n, n_times):
                raise ValueError(f"output {name}: expected shape ({n}, {n_times}), got {rows.shape}")
            bad = idx[ok & ~np.isfinite(rows).all(axis=1)]
            if bad.size:
                raise ValueError(f"output {name} of runs {bad} is not finite but their status is ok")
        return idx, status, reasons, values, stored

    # -- reading ----------------------------------------------------------------------------
    def output_matrix(self, name: str, rows=None) -> np.ndarray:
        """The histories of `rows` (default: all runs) as (n, T), NaN where not run or failed;
        from the raw data when stored, else rebuilt from the tSVD factors."""
        status = self.status
        rows = np.arange(status.size) if rows is None else np.asarray(rows, dtype=np.int64)
        return self._read.matrix(name, rows, status)

    def iter_output_blocks(self, name: str, block: int = 1000) -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """(indices, histories (n, T)) of the ok runs in design order, at most `block` runs at a time."""
        return self._read.blocks(name, self.status, block)

    def output_factors(self, name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None:
        """(U, s, V, columns) of a compressed output, V row c being run columns[c]; None when the raw
        histories are stored. Runs still in the buffer are folded in (in memory, not in the file)."""
        return self._read.factors(name, self.status)
