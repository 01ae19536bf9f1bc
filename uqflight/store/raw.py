"""The raw storage form: every run's histories as they came, /outputs/<name> (N, T), NaN rows where not
run or failed; exact, and N·T·8 bytes per output."""
from __future__ import annotations

from collections.abc import Iterator

import h5py
import numpy as np

from ..simulators.base import Status
from .chunks import chunk_blocks, chunk_rows, grow_rows
from .storage import OutputStorage, key_of

MIN_CHUNK_BYTES = 64 * 1024  # raw chunks hold whole batches, but no fewer bytes than this (tiny runs)


class RawStorage(OutputStorage):
    GROUP = "outputs"

    @classmethod
    def create(cls, f: h5py.File, outputs: list[str], units: dict, n: int, n_times: int, *,
               batch_rows: int | None, rows_hint: int, growable: bool) -> None:
        """The empty /outputs of `n` runs: chunks of `batch_rows` rows (at least 64 KiB, at most ~1 MiB),
        resizable along the runs when `growable`."""
        group = f.create_group(cls.GROUP, track_order=True)
        rows = min(chunk_rows(n_times, rows_hint),
                   max(batch_rows or rows_hint, -(-MIN_CHUNK_BYTES // (8 * n_times))))
        for name in outputs:
            ds = group.create_dataset(key_of(name), shape=(n, n_times), dtype="f8", fillvalue=np.nan,
                                      chunks=(rows, n_times), fletcher32=True,
                                      **({"maxshape": (None, n_times)} if growable else {}))
            ds.attrs.update({"units": units.get(name, ""), "dimensions": ["sample", "time"]})

    def mend(self) -> None:
        """Nothing to mend: rows are written in place, and a torn chunk is found by `lost_runs`."""

    def grow(self, n: int) -> None:
        grow_rows(self._file[self.GROUP], n)

    def write(self, name: str, idx: np.ndarray, ok: np.ndarray, rows: np.ndarray) -> None:
        self._file[self.GROUP][key_of(name)][idx] = np.where(ok[:, None], rows, np.nan)

    def settle(self, status: np.ndarray) -> None:
        """Nothing to do: the rows were final when written."""

    def batch_bytes(self, n: int) -> int:
        """The batch's rows, and a new chunk per output at worst."""
        n_times, estimate = self._file["time"].shape[0], 0
        for ds in self._file[self.GROUP].values():
            rows = ds.chunks[0] if ds.chunks else n
            estimate += 8 * n_times * (n + 2 * rows)
        return estimate

    def lost_runs(self, status: np.ndarray, block: int) -> np.ndarray:
        """Ok runs whose rows are not finite (a write that failed late, e.g. a full disk hit by HDF5's
        cache at flush), and those of a chunk whose checksum fails (overwritten with NaN)."""
        lost = np.zeros(status.size, dtype=bool)
        for data in self._file[self.GROUP].values():
            for start, stop, values in chunk_blocks(data, block, np.nan):
                ok = status[start:stop] == Status.OK
                lost[start:stop] |= ok if values is None else ok & ~np.isfinite(values).all(axis=1)
        return lost

    def problems(self, status: np.ndarray, block: int) -> list[str]:
        """Ok runs whose histories are not finite, the first of each output."""
        problems = []
        for name in self.output_names:
            data = self._file[self.GROUP][key_of(name)]
            for start in range(0, status.size, block):
                ok = status[start:start + block] == Status.OK
                rows = data[start:start + block]
                bad = start + np.flatnonzero(ok & ~np.isfinite(rows).all(axis=1))
                if bad.size:
                    problems.append(f"output {name}: {bad.size} ok runs without data (e.g. run {bad[0]})")
                    break
        return problems

    def matrix(self, name: str, rows: np.ndarray, status: np.ndarray) -> np.ndarray:
        unique, inverse = np.unique(rows, return_inverse=True)
        return self._file[self.GROUP][key_of(name)][unique][inverse]

    def blocks(self, name: str, status: np.ndarray, block: int) -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """In design order."""
        data = self._file[self.GROUP][key_of(name)]
        for start in range(0, status.size, block):
            ok = np.flatnonzero(status[start:start + block] == Status.OK)
            if ok.size:
                yield start + ok, data[start:start + block][ok]

    def factors(self, name: str, status: np.ndarray) -> None:
        return None

    @property
    def description(self) -> str:
        return "raw"

    @property
    def tolerance(self) -> float:
        return 0.0
