"""A rare-event design's estimate in its results file: the group /rare_event (docs/results-file.md).

    attributes: method (the design kind), of (the event's quantity), side ("above" or "below"), threshold,
                budget, probability, lower, upper (95 %), cov, beta, runs, failed, stopped, notes (JSON list)
    /rare_event/round_runs (R,) int        runs so far at the end of each round of the algorithm
    /rare_event/round_probability (R,)     the estimate after each round (NaN: none yet)
    /rare_event/round_cov (R,)             its coefficient of variation (NaN: undefined)
    /rare_event/batch_end (B,) int         the rows at the end of each `evaluate` call (a batch of runs)
    /rare_event/design_point_u (d,)        the most probable failure point in standard-normal space
    /rare_event/design_point_xi (d,)       ... in the germs ξ
    /rare_event/design_point (d,)          ... in physical values κ (NaN everywhere when no run failed)
    /rare_event/importance (d,)            each input's share α_k² of it (summing to 1)

Written once, when the algorithm returns (store.staged: as /rare_event_next, then moved in place: a kill
leaves no half-written estimate). A file without it holds rounds of a design that has not finished.
"""
from __future__ import annotations

import json

import h5py
import numpy as np

from .staged import current_group, replace_group

GROUP = "rare_event"
NUMBERS = ("threshold", "probability", "lower", "upper", "cov", "beta")
COUNTS = ("budget", "runs", "failed")
TEXTS = ("method", "of", "side", "stopped")
ROUND_ARRAYS = ("round_runs", "round_probability", "round_cov")
POINT_ARRAYS = ("design_point_u", "design_point_xi", "design_point", "importance")
MAX_NOTES_BYTES = 1 << 16


def write_rare_event(f: h5py.File, record: dict) -> None:
    """Record the estimate (see the module docstring), replacing any."""
    def fill(staged: h5py.Group) -> None:
        for key in (*ROUND_ARRAYS, "batch_end", *POINT_ARRAYS):
            staged.create_dataset(key, data=np.asarray(record[key]))
        staged.attrs.update({key: record[key] for key in (*NUMBERS, *COUNTS, *TEXTS)})
        staged.attrs["notes"] = json.dumps(record["notes"])
        staged.attrs["description"] = ("rare-event design: the probability of the event (of above or below "
                                       "threshold), its 95 % interval, c.o.v., the rounds and the most probable "
                                       "failure point")

    replace_group(f, GROUP, fill)


def read_rare_event(f: h5py.File, n: int, d: int) -> dict | None:
    """The recorded estimate, or None when the file holds none; ValueError naming what is wrong when the group
    is not such a record (`n` runs and `d` parameters bound its arrays)."""
    group = current_group(f, GROUP)
    if group is None:
        return None
    if not isinstance(group, h5py.Group):
        raise ValueError("not a group")
    record = {}
    for key in NUMBERS:
        value = group.attrs[key]
        if np.ndim(value) != 0 or not np.isreal(value):
            raise ValueError(f"attribute {key} is no number")
        record[key] = float(value)
    for key in COUNTS:
        value = group.attrs[key]
        if np.ndim(value) != 0 or not np.issubdtype(np.asarray(value).dtype, np.integer) or not 0 <= value <= 10**12:
            raise ValueError(f"attribute {key} is no count")
        record[key] = int(value)
    for key in TEXTS:
        value = group.attrs[key]
        if not isinstance(value, str) or len(value) > 200:
            raise ValueError(f"attribute {key} is no short text")
        record[key] = value
    notes = group.attrs["notes"]
    if not isinstance(notes, str) or len(notes) > MAX_NOTES_BYTES:
        raise ValueError("attribute notes is no JSON text")
    record["notes"] = json.loads(notes)
    if not isinstance(record["notes"], list) or not all(isinstance(note, str) for note in record["notes"]):
        raise ValueError("attribute notes is no list of sentences")
    if record["side"] not in ("above", "below") or record["runs"] > n:
        raise ValueError(f"side {record['side']!r} or runs {record['runs']} (of {n}) out of place")
    for key in (*ROUND_ARRAYS, "batch_end"):
        data = group[key]
        if data.ndim != 1 or data.shape[0] > n or data.dtype.kind not in "iuf":
            raise ValueError(f"{key} is not a list of at most {n} numbers")
        record[key] = data[()]
    if len({record[key].size for key in ROUND_ARRAYS}) != 1:
        raise ValueError("round_runs, round_probability and round_cov differ in length")
    for key in POINT_ARRAYS:
        data = group[key]
        if data.shape != (d,) or data.dtype.kind != "f":
            raise ValueError(f"{key} is not {d} numbers")
        record[key] = data[()]
    return record
