"""Run an adaptive sparse grid round by round into one results file, resumably.

Each round: the points of the recorded index set (`designs.adaptive.grid_points`, a function of the
state alone) are made the file's design (`ResultStore.set_design`: new rows pending, the combination
weights of the whole set), the pending runs are flown and written, then the error indicators are
computed from the stored results and the refined state is recorded in /design (`store.rounds`). A run
killed anywhere resumes from the file: the state, its rows and the stored results give the same next
round, so the file ends bit-identical to an uninterrupted run's.
"""
from __future__ import annotations

import numpy as np

from ..campaign import Campaign
from ..designs.adaptive import IndexSet, adaptive_grid, combination_weights, grid_points, refine
from ..parameters import to_physical
from ..store import ResultStore, Status


def stored_values(store: ResultStore) -> list[np.ndarray]:
    """What the indicators measure: every output's histories (N, T) and every quantity (N, 1) defined
    in every run (a quantity undefined somewhere has no mean to refine)."""
    values = [store.output_matrix(name) for name in store.output_names]
    for name in store.quantity_names:
        column = store.quantity(name)
        if np.isfinite(column).all():
            values.append(column[:, None])
    return values


def run_rounds(store: ResultStore, campaign: Campaign, fly):
    """Refine the campaign's adaptive grid until it stops (budget, tolerance, levels, a failed run);
    `fly()` runs the file's pending runs and returns their RunSummary. Returns the summary of all rounds."""
    spec = campaign.design_spec
    grid, budget, tolerance = adaptive_grid(spec, campaign.germs), spec["budget"], float(spec["tolerance"])
    state = store.index_set() or IndexSet.initial(len(campaign.germs))
    summary = None
    while True:
        points = grid_points(grid, state)
        store.set_design(points.xi, to_physical(campaign.parameters, points.xi),
                         combination_weights(grid, points, state.indices))
        part = fly()
        if summary is None:
            summary = part
        else:
            summary.total, summary.ran = part.total, summary.ran + part.ran
            summary.failures.update(part.failures)
        if state.stopped or store.pending().size:
            return summary
        if np.any(store.status != Status.OK):
            state.stopped = "failed"
        else:
            state = refine(grid, state, points, stored_values(store), budget, tolerance)
        store.write_index_set(state)
