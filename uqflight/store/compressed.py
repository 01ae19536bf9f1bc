"""The compressed (tSVD) storage form: per output, the incremental thin-SVD factors of the ok runs and a
buffer of ok runs not folded in yet, /tsvd/<name>/{U, s, V, columns, buffer, buffer_index} (/tsvd attributes:
the truncation tolerance tol and the fold size batch).

The buffer takes the runs as they come; the runs are folded into the factors in design order, `batch`
columns at a time, only over the contiguous completed prefix (and the last partial batch once no run is
pending), with one BLAS thread, so the factors depend neither on the workers nor on interruptions.
An output's factors and buffer are replaced together: written into `/tsvd/<name>/next` (store.staged),
marked complete, flushed, then moved in place; `apply_staged` finishes or discards such a half-done step
when the file is reopened, so a killed writer leaves either the old or the new state.
"""
from __future__ import annotations

from collections.abc import Iterator

import h5py
import numpy as np
from threadpoolctl import threadpool_limits

from ..simulators.base import Status
from .tsvd import IncrementalSVD, iter_column_blocks
from .chunks import chunk_rows
from .staged import COMPLETE, complete_staged, drop_staged, new_staged
from .storage import OutputStorage, key_of, name_of

STAGED = "next"  # an output's staged factors and buffer (store.staged)


def ingest(svd: IncrementalSVD, rows: np.ndarray, batch: int) -> None:
    """Append the runs `rows` (n, T), in their order, `batch` columns per update."""
    for start in range(0, len(rows), batch):
        svd.update(rows[start:start + batch].T)


def append_rows(group: h5py.Group, rows: np.ndarray, index: np.ndarray) -> None:
    """Append ok runs to an output's tSVD buffer (rows first, their indices after)."""
    n = group["buffer_index"].shape[0]
    for key, data in (("buffer", rows), ("buffer_index", index)):
        group[key].resize(n + len(index), axis=0)
        group[key][n:] = data


def buffer_rows(group: h5py.Group, status: np.ndarray) -> tuple[np.ndarray, np.ndarray, bool]:
    """Positions of the valid buffer rows sorted by sample, their samples, and whether any row is stale.

    A row is valid when its index was written and its run's status is ok; a writer killed between
    the buffer and the status leaves stale rows (their runs are still pending and will be rerun).
    """
    n_rows = group["buffer"].shape[0]
    index = group["buffer_index"][:n_rows]
    valid = index >= 0
    valid[valid] = status[index[valid]] == Status.OK
    positions = np.flatnonzero(valid)
    positions = positions[np.argsort(index[positions], kind="stable")]
    return positions, index[positions], positions.size < max(n_rows, group["buffer_index"].shape[0])


def write_state(group: h5py.Group, svd: IncrementalSVD, columns, rows, index) -> None:
    """Create the factor and buffer datasets of one output in `group`."""
    for key, data in (("U", svd.U), ("s", svd.s), ("V", svd.V), ("columns", columns)):
        group.create_dataset(key, data=data, chunks=True, fletcher32=True)
    n_times = rows.shape[1]
    chunk = chunk_rows(n_times, group.file["tsvd"].attrs["batch"])
    group.create_dataset("buffer", data=rows, maxshape=(None, n_times), chunks=(chunk, n_times),
                         fletcher32=True)
    group.create_dataset("buffer_index", data=index.astype(np.int64), maxshape=(None,), chunks=(chunk,), fletcher32=True,
                         fillvalue=-1)


def commit(group: h5py.Group, svd: IncrementalSVD, columns, rows, index) -> None:
    """Replace an output's factors and buffer together: staged in `next` (store.staged), marked complete,
    moved in."""
    staged = new_staged(group, STAGED)
    write_state(staged, svd, columns, rows, index)
    staged.attrs[COMPLETE] = True
    group.file.flush()
    apply_staged(group)
    group.file.flush()


def apply_staged(group: h5py.Group) -> None:
    """Move a complete staged state in place (also after a kill half-way through); drop an incomplete one."""
    staged = complete_staged(group, STAGED)
    if staged is not None:
        for key in list(staged):
            if key in group:
                del group[key]
            group.move(f"{staged.name}/{key}", key)
    drop_staged(group, STAGED)


class TsvdStorage(OutputStorage):
    GROUP = "tsvd"

    @staticmethod
    def settings(tsvd: dict) -> tuple[float, int]:
        """(tol, batch) of a campaign's {"tol": ..., "batch": ...} (batch defaults to the paper's 1000
        samples); ValueError for a tolerance outside [0, 1)."""
        return IncrementalSVD(float(tsvd["tol"])).tol, int(tsvd.get("batch", 1000))

    @classmethod
    def create(cls, f: h5py.File, outputs: list[str], units: dict, n_times: int, tol: float, batch: int) -> None:
        """The empty /tsvd: rank-0 factors and an empty buffer per output."""
        empty = IncrementalSVD.from_factors(np.zeros((n_times, 0)), np.zeros(0), np.zeros((0, 0)), tol)
        group = f.create_group(cls.GROUP, track_order=True)
        group.attrs.update({"tol": empty.tol, "batch": batch,
                            "description": "column c of A (run columns[c]) ≈ U diag(s) V[c]; the buffer "
                                           "rows (runs buffer_index) are not folded in yet"})
        for name in outputs:
            out = group.create_group(key_of(name))
            out.attrs["units"] = units.get(name, "")
            write_state(out, empty, np.zeros(0, np.int64), np.zeros((0, n_times)), np.zeros(0, np.int64))

    def mend(self) -> None:
        """Finish or drop every output's half-done replacement (`apply_staged`)."""
        for group in self._file[self.GROUP].values():
            if isinstance(group, h5py.Group):
                apply_staged(group)

    def grow(self, n: int) -> None:
        """Nothing to resize: the buffer grows with the runs it takes, the factors with those folded in."""

    def write(self, name: str, idx: np.ndarray, ok: np.ndarray, rows: np.ndarray) -> None:
        """Buffer the ok runs; a run the factors already hold (rerun after its raw rows were lost) stays out."""
        group = self._file[self.GROUP][key_of(name)]
        new = ok & ~np.isin(idx, self._held_runs(group))
        append_rows(group, rows[new], idx[new])

    def settle(self, status: np.ndarray) -> None:
        """Fold every output's ready runs in (`_fold_ready`)."""
        for group in self._file[self.GROUP].values():
            self._fold_ready(group, status)

    def batch_bytes(self, n: int) -> int:
        """A staged copy of every output's factors and buffer, with the batch's rows."""
        n_times, total = self._file["time"].shape[0], self._file["samples/status"].shape[0]
        estimate = 0
        for group in self._file[self.GROUP].values():
            size = sum(group[key].size * group[key].dtype.itemsize for key in ("U", "s", "V", "buffer"))
            estimate += 2 * (size + 8 * n_times * (n + self._batch)) + 8 * total
        return estimate

    def lost_runs(self, status: np.ndarray, block: int) -> np.ndarray:
        """Ok runs neither in the factors nor in the buffer (their order in the factors then follows the
        rerun: equal data, other rounding)."""
        lost = np.zeros(status.size, dtype=bool)
        for group in self._file[self.GROUP].values():
            _, index, _ = buffer_rows(group, status)
            held = np.zeros(status.size, dtype=bool)
            held[np.union1d(group["columns"][()], index).astype(np.int64)] = True
            lost |= (status == Status.OK) & ~held
        return lost

    def problems(self, status: np.ndarray, block: int) -> list[str]:
        """Ok runs missing from an output's factors and buffer; the factors and buffer are read once, so
        their checksums are verified."""
        problems, ok = [], np.flatnonzero(status == Status.OK)
        for name in self.output_names:
            group = self._file[self.GROUP][key_of(name)]
            _, index, _ = buffer_rows(group, status)
            for key in ("U", "s", "V", "buffer"):
                group[key][()]
            missing = np.setdiff1d(ok, np.union1d(group["columns"][()], index))
            if missing.size:
                problems.append(f"output {name}: {missing.size} ok runs missing (e.g. run {missing[0]})")
        return problems

    def matrix(self, name: str, rows: np.ndarray, status: np.ndarray) -> np.ndarray:
        """Rebuilt from the factors (the buffered runs folded in)."""
        U, s, V, columns = self.factors(name, status)
        column_of = np.full(status.size, -1)
        column_of[columns] = np.arange(columns.size)
        column = column_of[rows]
        matrix = np.full((rows.size, U.shape[0]), np.nan)
        matrix[column >= 0] = (V[column[column >= 0]] * s) @ U.T
        return matrix

    def blocks(self, name: str, status: np.ndarray, block: int) -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """In the factors' order (design order, but for runs rerun after they were lost)."""
        U, s, V, columns = self.factors(name, status)
        for start, histories in zip(range(0, columns.size, block), iter_column_blocks(U, s, V, block)):
            yield columns[start:start + block], histories

    def factors(self, name: str, status: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Runs still in the buffer are folded in (in memory, not in the file)."""
        group = self._file[self.GROUP][key_of(name)]
        positions, index, _ = buffer_rows(group, status)
        svd, columns = self._stored_factors(group)
        with threadpool_limits(limits=1):
            ingest(svd, group["buffer"][()][positions], self._batch)
        return svd.U, svd.s, svd.V, np.concatenate([columns, index])

    @property
    def description(self) -> str:
        """E.g. "tsvd tol 1e-08, batch 1000, ranks alpha_deg 11, h_ft 4"."""
        group = self._file[self.GROUP]
        ranks = ", ".join(f"{name_of(key)} {group[key]['s'].size}" for key in group)
        return f"tsvd tol {group.attrs['tol']:g}, batch {group.attrs['batch']}, ranks {ranks}"

    @property
    def tolerance(self) -> float:
        return float(self._file[self.GROUP].attrs["tol"])

    def _fold_ready(self, group: h5py.Group, status: np.ndarray) -> None:
        """Fold the buffered ok runs of the completed design-order prefix into the factors, `batch` at
        a time (all of them once nothing is pending); drop buffer rows a killed writer left behind."""
        positions, index, stale = buffer_rows(group, status)
        pending = np.flatnonzero(status == Status.PENDING)
        if pending.size:
            ready = np.searchsorted(index, pending[0])
            ready -= ready % self._batch
        else:
            ready = index.size
        if ready == 0 and not stale:
            return
        rows = group["buffer"][()][positions]
        svd, columns = self._stored_factors(group)
        with threadpool_limits(limits=1):
            ingest(svd, rows[:ready], self._batch)
        commit(group, svd, np.concatenate([columns, index[:ready]]), rows[ready:], index[ready:])

    def _stored_factors(self, group: h5py.Group) -> tuple[IncrementalSVD, np.ndarray]:
        """The factors as written in the file (without the buffer), and the run of each V row."""
        svd = IncrementalSVD.from_factors(group["U"][()], group["s"][()], group["V"][()],
                                          self._file[self.GROUP].attrs["tol"])
        return svd, group["columns"][()]

    @staticmethod
    def _held_runs(group: h5py.Group) -> np.ndarray:
        """The runs an output's factors or buffer hold."""
        n = group["buffer_index"].shape[0]
        return np.union1d(group["columns"][()], group["buffer_index"][:n])

    @property
    def _batch(self) -> int:
        return int(self._file[self.GROUP].attrs["batch"])
