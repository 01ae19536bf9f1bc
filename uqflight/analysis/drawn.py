"""The runs a report draws, read with its statistics from the results file the analysis has open (the
report itself never opens a results file): every run's design point, weight and status for the design
figure; a seeded subset of successful runs' histories for the spaghetti plot; a larger seeded subset at
one time for the scatter of the outputs and quantities against the inputs."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..simulators.base import Status
from .angles import angle_period, on_branch

SPAGHETTI_RUNS = 50  # runs drawn per output over time
SCATTER_RUNS = 1000  # points drawn per scatter panel at most


@dataclass
class DrawnRuns:
    """What the report's figures of the runs themselves show of one results file.

    Attributes
    ----------
    parameter_names : list of str
        The inputs, in the columns' order.
    xi, kappa : ndarray (N, d)
        Every run's design point, standard (ξ) and in physical values (κ).
    weights, status : ndarray (N,)
        Every run's design weight and status (`uqflight.simulators.base.Status`).
    spaghetti_rows : ndarray
        The `SPAGHETTI_RUNS` successful runs drawn over time (all when fewer), ascending.
    histories : dict of str to ndarray
        Each output recorded over time: its values (len(spaghetti_rows), T) as its statistics see them
        (`as_analysed`).
    scatter_rows : ndarray
        The `SCATTER_RUNS` successful runs drawn against the inputs (all when fewer), ascending.
    at_time : dict of str to (int, ndarray)
        Each output: the index of the recorded time nearest the scatter's time and its values there at the
        scatter rows, as its statistics see them.
    quantities : dict of str to ndarray
        Each quantity with statistics: its values at the scatter rows, as its statistics see them.
    """

    parameter_names: list[str]
    xi: np.ndarray
    kappa: np.ndarray
    weights: np.ndarray
    status: np.ndarray
    spaghetti_rows: np.ndarray
    histories: dict[str, np.ndarray]
    scatter_rows: np.ndarray
    at_time: dict[str, tuple[int, np.ndarray]]
    quantities: dict[str, np.ndarray]


def run_subset(status: np.ndarray, count: int, seed: int) -> np.ndarray:
    """`count` successful runs (all when fewer), drawn without replacement with `seed`, ascending: the same
    runs for the same file and seed, whatever else the report draws."""
    ok = np.flatnonzero(status == Status.OK)
    if ok.size <= count:
        return ok
    return np.sort(np.random.default_rng(seed).choice(ok, size=count, replace=False))


def nearest_time_index(time: np.ndarray, t: float) -> int:
    """The index of the recorded time nearest `t` (inf: the final time)."""
    return int(np.argmin(np.abs(time - np.clip(t, time[0], time[-1]))))


def as_analysed(runs: np.ndarray, out) -> np.ndarray:
    """The runs (N, T; a quantity's (N, 1)) as the statistics `out` see them: an angle's unwrapped along
    time onto the statistics' branch (analysis.angles), the others as stored."""
    period = angle_period(out.units)
    if not out.unwrapped or period is None or not np.isfinite(out.mean[0]):
        return runs
    return on_branch(runs, float(out.mean[0]), period)


def read_drawn(store, stats, scatter_time: float) -> DrawnRuns:
    """The runs the report draws of the open results file `store` whose statistics are `stats` (their
    outputs, quantities and seed): the subsets drawn with the campaign's seed, the scatter's outputs at the
    recorded time nearest `scatter_time`."""
    status = store.status
    spaghetti_rows = run_subset(status, SPAGHETTI_RUNS, stats.seed)
    scatter_rows = run_subset(status, SCATTER_RUNS, stats.seed)
    rows = np.union1d(spaghetti_rows, scatter_rows)  # each output read once for both subsets
    spaghetti_at, scatter_at = np.searchsorted(rows, spaghetti_rows), np.searchsorted(rows, scatter_rows)
    histories, at_time = {}, {}
    for name, out in stats.outputs.items():
        runs = as_analysed(store.output_matrix(name, rows), out)
        if out.time.size > 1:
            histories[name] = runs[spaghetti_at]
        i = nearest_time_index(out.time, scatter_time)
        at_time[name] = (i, runs[scatter_at, i])
    quantities = {name: as_analysed(store.quantity(name)[scatter_rows][:, None], q.output)[:, 0]
                  for name, q in stats.quantities.items() if q.output is not None}
    return DrawnRuns(list(store.parameter_names), store.xi, store.kappa, store.weights, status, spaghetti_rows,
                     histories, scatter_rows, at_time, quantities)
