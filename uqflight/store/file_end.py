"""The end of an HDF5 file as its superblock records it, mended after a writer killed while flushing.

HDF5 records where the file's allocated space ends (its EOA) in the superblock, which a flush writes
after the objects it allocated space for. A writer killed part-way through a flush can leave objects
on disk that point past that recorded end, with their bytes written: every read of them then fails
("addr overflow ... eoa"). HDF5's own remedy (`h5clear --increment`) is H5Fincrement_filesize, which
moves the recorded end to the end of the file on disk; `extend_to_file_end` calls it through the HDF5
library h5py runs on, for a file opened to resume (and `extend_file` for a file whose resume check
failed on it). What the kill left half written is then found as
after any kill: by the checksums and the status (see uqflight.store.results).
"""
from __future__ import annotations

import ctypes
import functools
import os

import h5py

HINT = ("a writer was killed while HDF5 flushed the file, which left data past its recorded end: resuming "
        "the campaign (`uqflight run CAMPAIGN --out FILE`) mends it (where uqflight cannot reach the HDF5 "
        "library, as off Linux, HDF5's `h5clear --increment FILE` does, before the resume)")


def past_recorded_end(text: str) -> bool:
    """Whether an HDF5 error message says a read went past the file's recorded end (its end of allocation,
    EOA: "addr overflow ... eoa = ...", "actual len exceeds EOA", "address of object past end of
    allocation", "len not positive after adjustment for EOA")."""
    text = text.lower()
    return "eoa" in text or "end of allocation" in text


def extend_to_file_end(f: h5py.File) -> bool:
    """Move the recorded end of `f` (opened for writing) to the end of the file on disk, when the disk
    holds more (a no-op otherwise); False when the HDF5 library cannot be reached (then nothing changes)."""
    increment = _increment_filesize()
    if increment is None:
        return False
    return increment(f.id.id, 0) >= 0


def extend_file(path) -> bool:
    """extend_to_file_end of the file at `path`, opened for writing and closed again; False when it cannot
    be opened or the library cannot be reached."""
    try:
        with h5py.File(path, "r+") as f:
            return extend_to_file_end(f)
    except (OSError, RuntimeError):
        return False


@functools.lru_cache(maxsize=1)
def _increment_filesize():
    """H5Fincrement_filesize of the HDF5 library loaded by h5py, found among the process's mapped files
    (Linux); None elsewhere or when it lacks the call (HDF5 before 1.10.2)."""
    try:
        with open("/proc/self/maps") as maps:
            paths = {line.split(maxsplit=5)[-1].strip() for line in maps if "libhdf5" in line}
    except OSError:
        return None
    for path in sorted(paths):
        name = os.path.basename(path)
        if name.startswith("libhdf5") and not name.startswith("libhdf5_hl") and ".so" in name:
            try:
                call = ctypes.CDLL(path).H5Fincrement_filesize
            except (OSError, AttributeError):
                continue
            call.argtypes, call.restype = (ctypes.c_int64, ctypes.c_uint64), ctypes.c_int
            return call
    return None
