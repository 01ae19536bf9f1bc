"""An adaptive grid's state in its results file: the group /design.

    /design/index_set (K, d) int      the multi-indices (1-D levels from 0), in the order they were added
    /design/old (K,) int8             1: refined (its forward neighbours were considered), 0: active
    /design/round (K,) int            the refinement round that added it (0: the centre)
    /design/indicator (K,) float      its error indicator when last computed (NaN: not yet)
    attributes: rounds, stopped ("" while refining; "budget", "tolerance", "levels" or "failed"),
                eta (Σ of the active indicators when last computed)

The group is replaced whole (store.staged: written as /design_next, marked complete, then moved in place;
a reader prefers a complete staged group), so a kill leaves the old or the new state, never a mix.
"""
from __future__ import annotations

import h5py
import numpy as np

from ..designs.adaptive import IndexSet
from .staged import current_group, replace_group

GROUP = "design"


def read_index_set(f: h5py.File) -> IndexSet | None:
    """The state recorded in `f`, or None when the file holds none."""
    group = current_group(f, GROUP)
    if group is None:
        return None
    indices = [tuple(int(level) for level in row) for row in group["index_set"][()]]
    return IndexSet(indices, [bool(v) for v in group["old"][()]], [int(v) for v in group["round"][()]],
                    [float(v) for v in group["indicator"][()]], int(group.attrs["rounds"]),
                    str(group.attrs["stopped"]), float(group.attrs["eta"]))


def write_index_set(f: h5py.File, state: IndexSet) -> None:
    """Replace the recorded state by `state` (see the module docstring)."""
    def fill(staged: h5py.Group) -> None:
        d = len(state.indices[0])
        staged.create_dataset("index_set", data=np.array(state.indices, dtype=np.int64).reshape(-1, d))
        staged.create_dataset("old", data=np.array(state.old, dtype=np.int8))
        staged.create_dataset("round", data=np.array(state.added, dtype=np.int64))
        staged.create_dataset("indicator", data=np.array(state.indicator, dtype=float))
        staged.attrs.update({"rounds": state.rounds, "stopped": state.stopped, "eta": state.eta,
                             "description": "adaptive sparse grid: multi-indices (1-D levels from 0), refined (old) "
                                            "or active, the round that added each and its error indicator"})

    replace_group(f, GROUP, fill)
