"""The compressed (tSVD) part of a results file: an output's factors and its buffer of runs not yet
folded in, replaced together so that a killed writer leaves either the old or the new state.

An output's factors and buffer are written into `/tsvd/<name>/next`, marked complete, flushed, then
moved in place; `apply_staged` finishes or discards such a half-done step when the file is reopened.
"""
from __future__ import annotations

import h5py
import numpy as np

from ..simulators.base import Status
from ..tsvd import IncrementalSVD

_CHUNK_BYTES = 1 << 20


def chunk_rows(n_times: int, n_rows: int) -> int:
    """Rows per chunk of an (n_rows, n_times) float64 dataset, for chunks of about 1 MiB."""
    return int(np.clip(_CHUNK_BYTES // (8 * n_times), 1, max(n_rows, 1)))


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
    """Replace an output's factors and buffer together: staged in `next`, marked complete, moved in."""
    if "next" in group:
        del group["next"]
    staged = group.create_group("next")
    write_state(staged, svd, columns, rows, index)
    staged.attrs["complete"] = True
    group.file.flush()
    apply_staged(group)
    group.file.flush()


def apply_staged(group: h5py.Group) -> None:
    """Move a complete staged state in place (also after a kill half-way through); drop an incomplete one."""
    staged = group.get("next")
    if staged is None:
        return
    if staged.attrs.get("complete", False):
        for key in list(staged):
            if key in group:
                del group[key]
            group.move(f"next/{key}", key)
    del group["next"]
