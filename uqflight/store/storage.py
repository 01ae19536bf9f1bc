"""How a results file keeps the outputs' time histories: the interface of a storage form.

A campaign's `storage:` keeps the raw histories (`raw.RawStorage`, /outputs), their incremental thin-SVD
factors (`compressed.TsvdStorage`, /tsvd), or both. `results.ResultStore` holds the forms its file has,
writes every batch to each of them and reads from the first (raw when kept: it is exact).
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Iterator

import h5py
import numpy as np


def key_of(name: str) -> str:
    """HDF5 name of an output: JSBSim property outputs contain "/", which HDF5 reads as groups."""
    return name.replace("/", "|")


def name_of(key: str) -> str:
    """The output an HDF5 name stands for (`key_of` undone)."""
    return key.replace("|", "/")


class OutputStorage(ABC):
    """One storage form in an open results file: its outputs under the group `/GROUP`, one member each.

    `status` arguments are the file's whole /samples/status; `idx` are run indices, ascending.
    """

    GROUP: str

    def __init__(self, file: h5py.File):
        self._file = file

    @property
    def output_names(self) -> list[str]:
        return [name_of(key) for key in self._file[self.GROUP]]

    @property
    def units(self) -> dict[str, str]:
        group = self._file[self.GROUP]
        return {name_of(key): str(group[key].attrs.get("units", "")) for key in group}

    # -- writing ----------------------------------------------------------------------------
    @abstractmethod
    def mend(self) -> None:
        """Finish or drop a step a killed writer left half done (on opening to resume, before any check)."""

    @abstractmethod
    def grow(self, n: int) -> None:
        """Make room for a design grown to `n` runs (an adaptive grid, `ResultStore.set_design`)."""

    @abstractmethod
    def write(self, name: str, idx: np.ndarray, ok: np.ndarray, rows: np.ndarray) -> None:
        """Store output `name` of the runs `idx`: rows (n, T), of which only the `ok` ones are data."""

    @abstractmethod
    def settle(self, status: np.ndarray) -> None:
        """Bring the stored state up to `status`, once the runs' status is written (tSVD: fold runs in)."""

    @abstractmethod
    def batch_bytes(self, n: int) -> int:
        """An upper estimate of the bytes a batch of `n` runs may add to the file in this form."""

    # -- checking ---------------------------------------------------------------------------
    @abstractmethod
    def lost_runs(self, status: np.ndarray, block: int) -> np.ndarray:
        """(N,) True for the ok runs whose data this form lacks, after overwriting what a kill tore."""

    @abstractmethod
    def problems(self, status: np.ndarray, block: int) -> list[str]:
        """What is wrong with the stored runs, one line each (reads every checksummed chunk)."""

    # -- reading ----------------------------------------------------------------------------
    @abstractmethod
    def matrix(self, name: str, rows: np.ndarray, status: np.ndarray) -> np.ndarray:
        """The histories of the runs `rows` (any order, repeats allowed) as (n, T), NaN where not held."""

    @abstractmethod
    def blocks(self, name: str, status: np.ndarray, block: int) -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """(indices, histories (n, T)) of the ok runs, at most `block` runs at a time."""

    @abstractmethod
    def factors(self, name: str, status: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None:
        """(U, s, V, columns) with V row c being run columns[c], or None when the form holds no factors."""

    @property
    @abstractmethod
    def description(self) -> str:
        """How this form keeps the outputs, for `uqflight info`."""

    @property
    @abstractmethod
    def tolerance(self) -> float:
        """The relative truncation tolerance of what is read back (0: exact)."""
