"""Run a campaign's samples in worker processes (local pool or Dask) and stream them to HDF5.

The design is cut into fixed chunks of consecutive samples (`execution.chunk`). A worker keeps
its simulator between chunks and restarts it at the start of each chunk, so every sample's
result depends only on its chunk: results are identical whatever the number of workers, the
executor, or an interruption. Chunks are written to the store as they finish (data, then
status, then a flush), so a killed run loses only the chunks in flight and resumes from there.
"""
from __future__ import annotations

import json
import sys
import time
from collections import Counter
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from dataclasses import dataclass, field
from importlib import metadata
from multiprocessing import get_context
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from .campaign import Campaign
from .designs import Design
from .parameters import to_physical
from .store import ResultStore, Status, compact, open_for_campaign
from .worker import WorkerSpec, run_chunk


@dataclass
class RunSummary:
    path: Path
    total: int
    ran: int
    skipped: int
    seconds: float
    failures: Counter = field(default_factory=Counter)

    def describe(self) -> str:
        rate = self.ran / self.seconds if self.seconds > 0 else float("nan")
        lines = [f"{self.path}: {self.total} runs, {self.ran} run now ({rate:.1f}/s), "
                 f"{self.skipped} already done, {sum(self.failures.values())} failed"]
        lines += [f"  failed ({n}): {reason}" for reason, n in self.failures.most_common(10)]
        return "\n".join(lines)


def versions() -> dict[str, str]:
    """Versions of uqflight and the packages results depend on (stored with the results)."""
    found = {}
    for package in ("uqflight", "jsbsim", "numpy", "scipy", "chaospy", "h5py"):
        try:
            found[package] = metadata.version(package)
        except metadata.PackageNotFoundError:
            found[package] = "not installed"
    found["python"] = sys.version.split()[0]
    return found


def prepare_store(campaign: Campaign, design: Design, out: Path, force: bool) -> ResultStore:
    """Open the campaign's results file to resume it, or create it with the design and provenance."""
    spec = worker_spec(campaign)
    kappa = to_physical(campaign.parameters, design.xi)
    simulator = spec.build()
    time_grid, outputs = simulator.probe(to_physical(campaign.parameters, np.zeros((1, len(campaign.parameters))))[0])
    attrs = {"versions": json.dumps(versions()), "campaign_name": campaign.name,
             "campaign_path": str(Path(campaign.source).resolve()),
             "method": json.dumps(campaign.method), "germs": json.dumps(campaign.germs),
             "analysis": json.dumps(campaign.analysis),
             "design_kind": design.kind, "design_info": json.dumps(design.info, default=str)}
    if campaign.simulator["kind"] == "jsbsim":
        from .simulators.jsbsim import aircraft_hash
        attrs["aircraft_hash"] = aircraft_hash(simulator.setup)
    out.parent.mkdir(parents=True, exist_ok=True)
    return open_for_campaign(
        out, campaign_text=campaign.text, force=force, xi=design.xi, kappa=kappa, weights=design.weights,
        parameter_names=[p.name for p in campaign.parameters], outputs=outputs, time=time_grid,
        raw=campaign.storage["raw"], tsvd=campaign.storage.get("tsvd"), attrs=attrs,
        units=getattr(simulator, "units", {}))


def worker_spec(campaign: Campaign) -> WorkerSpec:
    from .simulators.bundle import make_bundle

    properties = tuple(p.property for p in campaign.parameters)
    base = str(Path(campaign.source).resolve().parent)
    return WorkerSpec(simulator=campaign.simulator,
                      parameter_names=tuple(p.name for p in campaign.parameters),
                      properties=properties, base=base,
                      bundle=make_bundle(campaign.simulator, properties, base))  # files travel with the task


def pending_chunks(pending: np.ndarray, chunk: int, total: int) -> list[np.ndarray]:
    """The fixed design-order chunks [c*chunk, (c+1)*chunk) ∩ [0, total) that hold pending samples."""
    return [np.arange(c * chunk, min((c + 1) * chunk, total)) for c in np.unique(pending // chunk)]


def run_campaign(campaign: Campaign, out: Path | None = None, workers: int | None = None,
                 executor: str | None = None, scheduler: str | None = None, force: bool = False,
                 progress: bool = False) -> RunSummary:
    """Run every pending sample of the campaign into its results file; returns a summary.
    `progress` shows a progress bar (a terminal) or log lines (otherwise) on stderr."""
    execution = campaign.execution
    workers = workers or execution["workers"]
    executor = executor or execution["executor"]
    scheduler = scheduler or execution.get("scheduler")
    chunk = execution["chunk"]
    out = Path(out or campaign.storage["path"])
    design = campaign.design()
    started = time.perf_counter()
    store = prepare_store(campaign, design, out, force)
    try:
        total = len(design.xi)
        pending = store.pending()
        chunks = pending_chunks(pending, chunk, total)
        kappa = store.kappa
        spec = worker_spec(campaign)
        n_times, outputs = store.time.size, store.output_names
        summary = RunSummary(out, total, 0, total - pending.size, 0.0)
        bar = Progress(pending.size, quiet=not progress)
        # A chunk with some samples already stored (impossible with this writer, but a file
        # written elsewhere may have one) is rerun whole; only its pending rows are written.
        tasks = [(spec, c, kappa[c], n_times, outputs) for c in chunks]
        # One BLAS thread here: the workers keep every core busy, and a multi-threaded BLAS
        # competing with them makes the tSVD updates of this process 10-100x slower.
        with threadpool_limits(limits=1):
            for indices, status, reasons, values in _execute(tasks, workers, executor, scheduler):
                keep = store.status[indices] == Status.PENDING
                store.write_batch(indices[keep], status[keep], np.asarray(reasons, dtype=object)[keep],
                                  {k: v[keep] for k, v in values.items()})
                summary.ran += int(keep.sum())
                summary.failures.update(r for r, s in zip(np.asarray(reasons)[keep], status[keep]) if s != 0)
                bar.advance(int(keep.sum()))
        bar.close()
        complete = store.pending().size == 0
    finally:
        store.close()
    if complete and campaign.storage.get("tsvd"):
        compact(out)
    summary.seconds = time.perf_counter() - started
    return summary


def _execute(tasks, workers: int, executor: str, scheduler: str | None):
    """Yield chunk results as they finish, keeping about two chunks per worker in flight."""
    if not tasks:
        return
    if executor == "dask":
        yield from _execute_dask(tasks, workers, scheduler)
        return
    if workers == 1:
        for task in tasks:
            yield run_chunk(*task)
        return
    with ProcessPoolExecutor(max_workers=workers, mp_context=get_context("spawn")) as pool:
        queue = list(reversed(tasks))
        running = set()
        while queue or running:
            while queue and len(running) < 2 * workers:
                running.add(pool.submit(run_chunk, *queue.pop()))
            done, running = wait(running, return_when=FIRST_COMPLETED)
            for future in done:
                yield future.result()


def _execute_dask(tasks, workers: int, scheduler: str | None):
    from dask.distributed import Client, LocalCluster, as_completed

    cluster = None
    if scheduler:
        client = Client(scheduler)
    else:
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                               dashboard_address=None)
        client = Client(cluster)
    try:
        queue = list(reversed(tasks))
        # a deeper queue than the local pool's: it hides the scheduler round trip of a remote cluster
        in_flight = 4 * max(workers, len(client.scheduler_info().get("workers", {})) or 1)
        futures = as_completed([client.submit(run_chunk, *queue.pop(), pure=False)
                                for _ in range(min(in_flight, len(queue)))])
        for future in futures:
            yield future.result()
            if queue:
                futures.add(client.submit(run_chunk, *queue.pop(), pure=False))
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


class Progress:
    """A progress bar with rate and ETA on a terminal; a log line every ~10 % otherwise."""

    def __init__(self, total: int, quiet: bool = False, stream=sys.stderr):
        self.total, self.done, self.quiet, self.stream = total, 0, quiet, stream
        self.start = time.perf_counter()
        self.tty = stream.isatty()
        self._next_log = 0.1

    def advance(self, n: int) -> None:
        self.done += n
        if self.quiet or self.total == 0:
            return
        elapsed = time.perf_counter() - self.start
        rate = self.done / elapsed if elapsed > 0 else 0.0
        eta = (self.total - self.done) / rate if rate > 0 else float("inf")
        fraction = self.done / self.total
        if self.tty:
            bar = "#" * int(30 * fraction)
            self.stream.write(f"\r[{bar:<30}] {self.done}/{self.total} {rate:6.1f} runs/s ETA {eta:6.0f} s")
            self.stream.flush()
        elif fraction >= self._next_log or self.done == self.total:
            self.stream.write(f"{self.done}/{self.total} runs ({100 * fraction:.0f} %), {rate:.1f} runs/s, "
                              f"ETA {eta:.0f} s\n")
            self._next_log = fraction + 0.1

    def close(self) -> None:
        if self.tty and not self.quiet and self.total:
            self.stream.write("\n")

