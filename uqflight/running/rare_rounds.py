"""Run a rare-event design round by round into one results file, resumably, by replay.

The algorithm (`designs.rare`) is a deterministic function of the campaign's seed, its settings and the
values its `evaluate` calls return. `evaluate(u)` maps the round's standard normals u to the germs ξ (each
germ's `from_normal`), appends the rows beyond the file's to the design (`ResultStore.set_design`: written,
pending, before they are flown), flies the pending runs with the ordinary runner, reads the event's quantity
back and returns the margin (NaN for a failed run or an undefined quantity). A resumed campaign calls the
algorithm again from the start: the rounds already stored are found in the file (their ξ checked equal bit
for bit) and their values returned without a run, so a SIGKILL loses only the runs in flight and the
resumed file ends bit-identical to an uninterrupted run's. The estimate is recorded in /rare_event
(`store.rare`) once the algorithm returns.
"""
from __future__ import annotations

import numpy as np

from ..campaign import Campaign
from ..designs import DesignSpec
from ..designs.rare import germs_from_normal, run_algorithm
from ..designs.rare.record import estimate_record
from ..store import ResultStore, Status
from ..text import Refusal


class Replay:
    """The `evaluate` of a rare-event design over one results file (see the module docstring)."""

    def __init__(self, store: ResultStore, campaign: Campaign, spec: DesignSpec, fly):
        self.store, self.campaign, self.spec, self.fly = store, campaign, spec, fly
        self.offset = 0  # the rows of the rounds evaluated so far
        self.ends: list[int] = []  # the row count at the end of each round
        self.summary = None

    def __call__(self, u) -> np.ndarray:
        u = np.asarray(u, dtype=float)
        xi = germs_from_normal(u.reshape(-1, len(self.campaign.germs)), self.campaign.germs)
        start, stop = self.offset, self.offset + len(xi)
        if stop > self.spec["budget"]:
            raise RuntimeError(f"{self.spec.kind} asked for {stop} runs, beyond its budget {self.spec['budget']}")
        store = self.store
        rows = store.status.size
        stored = store.xi[start:min(stop, rows)]
        if not np.array_equal(stored, xi[:len(stored)]):
            raise Refusal(f"{store._file.filename}: the stored runs {start} to {min(stop, rows) - 1} are not "
                          f"the points this campaign's {self.spec.kind} asks for (a file written by another "
                          "uqflight version): fly it again with `uqflight run CAMPAIGN --restart`")
        if stop > rows:
            design = np.vstack([store.xi, xi[rows - start:]])
            store.set_design(design, self.campaign.to_physical(design), np.full(stop, 1.0 / stop))
        if store.pending().size:
            self._fly()
        status = store.status[start:stop]
        event = self.spec["event"]
        margin = event.margin(store.quantity(event.of)[start:stop])
        margin[status != Status.OK] = np.nan
        self.offset = stop
        self.ends.append(stop)
        return margin

    def _fly(self) -> None:
        part = self.fly()
        if self.summary is None:
            self.summary = part
        else:
            self.summary.total, self.summary.ran = part.total, self.summary.ran + part.ran
            self.summary.failures.update(part.failures)
        if self.store.pending().size:
            raise RuntimeError(f"{self.store.pending().size} runs are still pending after a round was flown")


def run_rare(store: ResultStore, campaign: Campaign, fly):
    """Fly the campaign's rare-event design until its algorithm returns, and record its estimate;
    `fly()` runs the file's pending runs and returns their RunSummary. Returns the summary of all rounds
    (a finished file resumes to nothing)."""
    spec = campaign.design_spec
    if store.rare_event() is not None:  # finished: every round is stored with its estimate
        return fly()
    replay = Replay(store, campaign, spec, fly)
    estimate = run_algorithm(spec, replay, len(campaign.germs), campaign.seed, campaign.redrawn)
    if estimate.runs != replay.offset:
        raise RuntimeError(f"{spec.kind} counted {estimate.runs} runs but evaluated {replay.offset}")
    store.write_rare_event(estimate_record(estimate, spec, replay.ends, campaign))
    return replay.summary or fly()
