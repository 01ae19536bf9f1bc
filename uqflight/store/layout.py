"""The structure a results file must have before any of it is read as numbers: every dataset of the
layout (results.py) present, of its kind (float, integer, string) and of the shape the others imply
(N runs, d parameters, T times), the design and the times finite, the times increasing.

A file that fails is damaged or was not written by uqflight; reading it anyway would give shapes that
disagree deep inside an analysis (a traceback) or, worse, numbers from the wrong rows.
"""
from __future__ import annotations

import h5py
import numpy as np

from ..designs.adaptive import STOP_REASONS
from .staged import staged_keys

KINDS = {"float": "f", "integer": "iu"}
# Beyond any campaign (limits.max_runs defaults to 10^6), and beyond what a reader can hold in memory:
# a damaged or hostile file declaring such sizes is refused before anything is read.
MAX_RUNS, MAX_PARAMETERS, MAX_TIMES, MAX_DESIGN_VALUES = 10**8, 10**4, 10**7, 2 * 10**8
# A reader holds one output's (N, T) histories at a time (raw, or rebuilt from its tSVD factors): 2 GB of
# doubles; every other product a reader allocates from declared sizes is bounded by it too (a tSVD
# factor or buffer, an adaptive grid's index set, the failure reasons' bytes / 8). Declared sizes are no
# proof of data: a 0.3 MiB file may declare 60 runs x 10^7 times in chunks never written.
MAX_OUTPUT_VALUES = 250_000_000
MAX_STORED_VALUES = 10 * MAX_OUTPUT_VALUES  # every output's and quantity's values together: what info reads
MAX_REASON_BYTES = 256  # a fixed-length failure reason (results.REASON_BYTES)


def _dataset(f: h5py.File, path: str, kind: str, shape: tuple, problems: list[str]) -> h5py.Dataset | None:
    """The dataset `path` if it exists, is of `kind` ("float", "integer", "string") and has `shape`
    (None entries: any length); else None, with the problem appended."""
    link = f.get(path, getlink=True) if path.rsplit("/", 1)[0] in f or "/" not in path else None
    if link is not None and not isinstance(link, h5py.HardLink):
        problems.append(f"/{path} is a {type(link).__name__}, not data stored in this file")
        return None
    item = f.get(path)
    if not isinstance(item, h5py.Dataset):
        problems.append(f"/{path} is missing" if item is None else f"/{path} is a group, not a dataset")
        return None
    if item.is_virtual:
        problems.append(f"/{path} is a virtual dataset (data from other files), not data stored in this file")
        return None
    is_kind = h5py.check_string_dtype(item.dtype) is not None if kind == "string" else \
        item.dtype.kind in KINDS[kind]
    if not is_kind:
        problems.append(f"/{path} holds {item.dtype}, expected {kind} values")
        return None
    if len(item.shape) != len(shape) or any(want is not None and got != want for got, want in zip(item.shape, shape)):
        expected = "(" + ", ".join("any" if n is None else str(n) for n in shape) + ("," if len(shape) == 1 else "") + ")"
        problems.append(f"/{path} has shape {item.shape}, expected {expected}")
        return None
    return item


def is_time_grid(values: np.ndarray) -> bool:
    """At least one time, all finite, strictly increasing: the recorded times a results file holds."""
    return values.size > 0 and bool(np.isfinite(values).all()) and not np.any(np.diff(values) <= 0)


def _finite(data: h5py.Dataset, problems: list[str]) -> None:
    values = data[()]
    if not np.isfinite(values).all():
        problems.append(f"{data.name} holds {int(np.size(values) - np.isfinite(values).sum())} values that are "
                        "not finite")


def layout_problems(f: h5py.File) -> list[str]:
    """What is wrong with the structure of the open results file `f` (empty when it is sound)."""
    problems: list[str] = []
    status = _dataset(f, "samples/status", "integer", (None,), problems)
    if status is None:
        return problems
    n = status.shape[0]
    if n > MAX_RUNS:
        return [f"/samples/status declares {n} runs, more than any campaign ({MAX_RUNS})"]
    xi = _dataset(f, "samples/xi", "float", (n, None), problems)
    if xi is not None and (xi.shape[1] > MAX_PARAMETERS or xi.size > MAX_DESIGN_VALUES):
        return problems + [f"/samples/xi declares {xi.shape[1]} parameters for {n} runs, more than a reader "
                           f"holds ({MAX_PARAMETERS} parameters, {MAX_DESIGN_VALUES} values)"]
    if xi is not None:
        d = xi.shape[1]
        _finite(xi, problems)
        kappa = _dataset(f, "samples/kappa", "float", (n, d), problems)
        if kappa is not None:
            _finite(kappa, problems)
            names = kappa.attrs.get("names")
            if names is None or np.ndim(names) != 1 or len(names) != d:
                problems.append(f"/samples/kappa's attribute names lists {0 if names is None else np.size(names)} "
                                f"parameters, expected {d}")
    weight = _dataset(f, "samples/weight", "float", (n,), problems)
    if weight is not None:
        _finite(weight, problems)
    reason = _dataset(f, "samples/reason", "string", (n,), problems)
    length = None if reason is None else h5py.check_string_dtype(reason.dtype).length
    if reason is not None and length is None:
        return problems + [f"/samples/reason holds variable-length strings, expected fixed-length strings of at most "
                           f"{MAX_REASON_BYTES} bytes"]
    if length is not None and length > MAX_REASON_BYTES:
        return problems + [f"/samples/reason holds strings of {length} bytes, more than a reason takes "
                           f"({MAX_REASON_BYTES})"]
    if reason is not None and n * length > 8 * MAX_OUTPUT_VALUES:
        return problems + [f"/samples/reason declares {n} reasons of {length} bytes, more than "
                           f"a reader holds ({8 * MAX_OUTPUT_VALUES:.4g} bytes)"]
    time = _dataset(f, "time", "float", (None,), problems)
    if time is not None and time.shape[0] > MAX_TIMES:
        return problems + [f"/time declares {time.shape[0]} times, more than a reader holds ({MAX_TIMES})"]
    too_large = _declared_values(f, n, None if time is None else time.shape[0])
    if too_large:  # refused before any of it is read
        return problems + [too_large]
    if time is not None:
        if not is_time_grid(time[()]):
            problems.append(f"/time must hold at least one finite time, strictly increasing ({time.size} values)")
    if not isinstance(f.attrs.get("campaign"), str):
        problems.append("the root attribute campaign (the campaign's text) is missing")
    n_times = None if time is None else time.shape[0]
    raw, compressed = f.get("outputs"), f.get("tsvd")
    if raw is None and compressed is None:
        problems.append("no outputs: neither /outputs nor /tsvd")
    for group in (raw, compressed):
        if group is not None and (not isinstance(group, h5py.Group) or not len(group)):
            problems.append(f"{group.name} must be a group of at least one output")
    if isinstance(raw, h5py.Group):
        for key in raw:
            _dataset(f, f"outputs/{key}", "float", (n, n_times), problems)
    quantities = f.get("quantities")
    if quantities is not None and not isinstance(quantities, h5py.Group):
        problems.append("/quantities must be a group of per-run quantities")
    elif quantities is not None:
        for key in quantities:
            _dataset(f, f"quantities/{key}", "float", (n,), problems)
    resolution = f.get("resolution")
    if resolution is not None and not isinstance(resolution, h5py.Group):
        problems.append("/resolution must be a group of per-output resolutions")
    elif resolution is not None:
        for key in resolution:
            data = _dataset(f, f"resolution/{key}", "float", (n_times,), problems)
            if data is not None and not (np.isfinite(data[()]).all() and (data[()] >= 0).all()):
                problems.append(f"/resolution/{key} must hold finite values ≥ 0")
    if "design" in f:
        _index_set_problems(f, None if xi is None else xi.shape[1], problems)
    if isinstance(compressed, h5py.Group):
        _tsvd_problems(f, compressed, n, n_times, problems)
        if isinstance(raw, h5py.Group) and set(raw) != set(compressed):
            problems.append(f"/outputs ({', '.join(raw)}) and /tsvd ({', '.join(compressed)}) name other outputs")
    return problems


def _declared_values(f: h5py.File, n: int, n_times: int | None) -> str | None:
    """What the sizes the file declares would make a reader allocate beyond its bounds, or None: one
    output's N x T histories, every output's and quantity's values together."""
    outputs = set()
    for group in ("outputs", "tsvd"):
        if isinstance(f.get(group), h5py.Group):
            outputs |= set(f[group])
    quantities = f["quantities"] if isinstance(f.get("quantities"), h5py.Group) else ()
    if n_times is not None and n * n_times > MAX_OUTPUT_VALUES:
        return (f"/samples/status and /time declare {n} runs x {n_times} times = {n * n_times:.4g} values per "
                f"output, more than a reader holds ({MAX_OUTPUT_VALUES:.4g})")
    total = len(outputs) * n * (n_times or 1) + len(quantities) * n
    if total > MAX_STORED_VALUES:
        return (f"the file declares {len(outputs)} outputs and {len(quantities)} quantities of {n} runs x "
                f"{n_times} times = {total:.4g} values, more than a reader reads ({MAX_STORED_VALUES:.4g})")
    return None


def _tsvd_problems(f: h5py.File, group: h5py.Group, n: int, n_times, problems: list[str]) -> None:
    tol, batch = group.attrs.get("tol"), group.attrs.get("batch")
    if not (np.ndim(tol) == 0 and np.isreal(tol) and np.isfinite(tol) and tol >= 0):
        problems.append(f"/tsvd's attribute tol must be a finite number ≥ 0, got {tol!r}")
    if not (np.ndim(batch) == 0 and np.issubdtype(np.asarray(batch).dtype, np.integer) and batch >= 1):
        problems.append(f"/tsvd's attribute batch must be an integer ≥ 1, got {batch!r}")
    for key in group:
        if not isinstance(group[key], h5py.Group):
            problems.append(f"/tsvd/{key} is not a group of factors")
            continue
        path = f"tsvd/{key}"
        if staged_keys(group[key], "next") and not {"U", "s", "V"} <= set(group[key]):
            problems.append(f"/{path} is half replaced (its writer was killed): resume the run to finish the step")
            continue
        U = _dataset(f, f"{path}/U", "float", (n_times, None), problems)
        rank = None if U is None else U.shape[1]
        _dataset(f, f"{path}/s", "float", (rank,), problems)
        V = _dataset(f, f"{path}/V", "float", (None, rank), problems)
        columns = _dataset(f, f"{path}/columns", "integer", (None if V is None else V.shape[0],), problems)
        buffer = _dataset(f, f"{path}/buffer", "float", (None, n_times), problems)
        index = _dataset(f, f"{path}/buffer_index", "integer", (None,), problems)
        buffered = 2 * n + 1000 if n_times is None else min(2 * n + 1000, MAX_OUTPUT_VALUES // max(n_times, 1))
        sizes = {"rank": (rank, min(n, n_times or n)), "runs": (None if V is None else V.shape[0], n),
                 "buffered runs": (None if buffer is None else buffer.shape[0], buffered),
                 "buffer_index entries": (None if index is None else index.shape[0], 2 * n + 1000)}
        too_large = [f"{what} {size} (at most {most})" for what, (size, most) in sizes.items()
                     if size is not None and size > most]
        if too_large:  # not read: a declared size is no proof of data, and could exhaust the memory
            problems.append(f"/{path} declares {', '.join(too_large)} for {n} runs of {n_times} times")
            continue
        if columns is not None:
            runs = columns[()]
            if np.any((runs < 0) | (runs >= n)) or np.unique(runs).size != runs.size:
                problems.append(f"/{path}/columns must name distinct runs in [0, {n})")
        if index is not None and np.any((index[()] < -1) | (index[()] >= n)):
            problems.append(f"/{path}/buffer_index must name runs in [0, {n}) (or -1)")


def _index_set_problems(f: h5py.File, d, problems: list[str]) -> None:
    """An adaptive grid's /design (store.rounds): its datasets of one length K, its attributes."""
    index_set = _dataset(f, "design/index_set", "integer", (None, d), problems)
    if index_set is not None and index_set.size > MAX_DESIGN_VALUES:
        problems.append(f"/design/index_set declares {index_set.shape[0]} multi-indices of {index_set.shape[1]} "
                        f"levels, more than a reader holds ({MAX_DESIGN_VALUES} values)")
        return
    k = None if index_set is None else index_set.shape[0]
    for key, kind in (("old", "integer"), ("round", "integer"), ("indicator", "float")):
        _dataset(f, f"design/{key}", kind, (k,), problems)
    if index_set is not None and (k == 0 or np.any(index_set[()] < 0)):
        problems.append("/design/index_set must hold at least one multi-index of levels >= 0")
    if not {"rounds", "stopped", "eta"} <= set(f["design"].attrs):
        problems.append("/design lacks one of its attributes rounds, stopped, eta")
    elif f["design"].attrs["stopped"] not in ("", *STOP_REASONS):
        problems.append(f"/design's attribute stopped must be empty or one of {', '.join(STOP_REASONS)}")
