"""The HDF5 chunks of a results file's per-run datasets: how many rows each holds (`chunk_rows`), and
reading a dataset by whole chunks, mending those a kill tore (`chunk_blocks`)."""
from __future__ import annotations

from collections.abc import Iterator

import h5py
import numpy as np

_CHUNK_BYTES = 1 << 20


def chunk_rows(n_times: int, n_rows: int) -> int:
    """Rows per chunk of an (n_rows, n_times) float64 dataset, for chunks of about 1 MiB."""
    return int(np.clip(_CHUNK_BYTES // (8 * n_times), 1, max(n_rows, 1)))


def chunk_blocks(data: h5py.Dataset, block: int, fill) -> Iterator[tuple[int, int, np.ndarray | None]]:
    """(start, stop, rows) over `data` in blocks of whole chunks; a block that fails its checksum (a chunk
    a kill tore) is overwritten with `fill`, chunk by chunk, and comes as (start, stop, None)."""
    rows = data.chunks[0] if data.chunks else block
    step = max(rows, block - block % rows)
    for start in range(0, data.shape[0], step):
        stop = min(start + step, data.shape[0])
        try:
            values = data[start:stop]
        except OSError:
            for first in range(start, stop, rows):
                data[first:min(first + rows, stop)] = fill
            values = None
        yield start, stop, values


def grow_rows(group: h5py.Group, n: int) -> None:
    """Resize every dataset of `group` (per-run, resizable along the runs) to `n` rows."""
    for data in group.values():
        data.resize(n, axis=0)
