"""Run a campaign's samples in worker processes (local or Dask) and stream them to HDF5.

The design is cut into fixed chunks of consecutive samples (`execution.chunk`, smaller ones at the
design's end: `chunk_starts`). A worker keeps
its simulator between chunks and restarts it at the start of each chunk, so every sample's
result depends only on its chunk: results are identical whatever the number of workers, the
executor, or an interruption. Chunks are written to the store as they finish, so a killed run
loses only the chunks in flight and resumes from there.

Nothing lost, nothing hung:
- Simulators never run in the runner's process (not even with one worker): each worker is a
  `python -m uqflight.running.worker` child (see `WorkerProcess`) that announces every sample before
  flying it. A worker that dies (exit, signal, out of memory) or runs one sample past the time
  limit is killed and replaced; the sample it was flying is recorded with Status.WORKER_DIED or
  Status.TIMEOUT and its reason, and its chunk is flown again from the start without that sample
  (the simulator restarts at the chunk start, so the other samples get the results they would
  have had). The campaign goes on. Dask tasks run their chunk the same way, in a supervised child
  of the Dask worker.
- The per-run limit is `execution.timeout_s`; by default max(60 s, 50 x the cost of one flight at
  the nominal point, measured in a worker before the campaign starts).
- One writer per file (`store.lock`); a free-space check before every batch stops the run cleanly
  (`DiskFull`) before HDF5 could hit a full disk half-way through a write.
- Workers die with their runner (PR_SET_PDEATHSIG and a parent watchdog).
"""
from __future__ import annotations

import errno
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from collections import Counter, deque
from dataclasses import asdict, dataclass, field, replace
from importlib import metadata
from multiprocessing.connection import Connection
from multiprocessing.connection import wait as wait_connections
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from ..campaign import Campaign
from ..campaign.record import ATTRIBUTE, record_text
from ..campaign.schema import WORKER_BYTES
from ..text import Refusal
from ..text.console import one_line
from ..designs import REGISTRY as DESIGNS
from ..designs import Design
from .stopping import check as check_stop
from .progress import Progress
from .rare_rounds import run_rare
from .adaptive_rounds import run_rounds
from ..store import ResultStore, Status, compact, open_for_campaign
from ..store.lock import LockHeld, ResultsLock
from .worker import NominalFlight, WorkerSpec

DEFAULT_TIMEOUT_FLOOR_S = 60.0   # default timeout: max(this, TIMEOUT_FLIGHTS x one nominal flight)
TIMEOUT_FLIGHTS = 50
NOMINAL_TIMEOUT_S = 600.0          # the nominal flight that measures the cost (no limit known yet)
STARTUP_GRACE_S = 60.0           # a chunk's limit before its first sample (worker start, simulator build)
SPACE_MARGIN_BYTES = 1 << 20     # free space kept beyond a batch's estimate (HDF5 metadata)
TAPER = 4                        # the design's last TAPER chunks are flown in chunks TAPER times smaller


class DiskFull(OSError):
    """The results file's filesystem has no room for the next batch; the file is closed intact."""


class IncompleteFile(OSError):
    """Runs counted as done did not reach the file (a write failed late); a resume reruns them."""


class WorkerError(RuntimeError):
    """A worker could not build the simulator (not a sample's failure: the campaign cannot run)."""


@dataclass
class RunSummary:
    path: Path
    total: int
    ran: int
    skipped: int
    seconds: float
    failures: Counter = field(default_factory=Counter)
    timeout_s: float = float("nan")
    nominal_failure: str | None = None  # why the nominal flight (ξ = 0) failed, when it did
    nominal_warnings: list[str] = field(default_factory=list)  # what it warned of (an unmoved surface)

    def describe(self) -> str:
        rate = self.ran / self.seconds if self.seconds > 0 else float("nan")
        lines = [f"{self.path}: {self.total} runs, {self.ran} run now ({rate:.1f}/s), "
                 f"{self.skipped} already done, {sum(self.failures.values())} failed"]
        if self.nominal_failure:
            lines.append(f"  warning: the nominal flight (every parameter at its law's centre) failed: "
                         f"{one_line(self.nominal_failure)}; runs near it fail the same way: check the campaign's flight with "
                         "`uqflight simulate` and its --set")
        lines += [f"  warning: the nominal flight: {one_line(warning)}" for warning in self.nominal_warnings]
        lines += [f"  failed ({n}): {one_line(reason)}" for reason, n in self.failures.most_common(10)]
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


def prepare_store(campaign: Campaign, design: Design, out: Path, force: bool, nominal=None,
                  restart: bool = False) -> ResultStore:
    """Open the campaign's results file to resume it, or create it with the design and provenance.
    `nominal`: the NominalFlight a worker measured (`WorkerPool.nominal_flight`);
    measured here in a worker process when not given."""
    kappa = campaign.to_physical(design.xi)
    if nominal is None:
        pool = WorkerPool(worker_spec(campaign), 1, NOMINAL_TIMEOUT_S)
        try:
            nominal = pool.nominal_flight(nominal_kappa(campaign))
        finally:
            pool.close()
    attrs = {ATTRIBUTE: record_text(campaign, design.kind, design.info, versions()),
             "campaign_path": str(Path(campaign.source).resolve())}
    from ..simulators import simulator_provenance

    attrs.update(simulator_provenance(campaign.simulator, Path(campaign.source).resolve().parent,
                                      properties=[p.property for p in campaign.parameters]))
    out.parent.mkdir(parents=True, exist_ok=True)
    return open_for_campaign(
        out, campaign_text=campaign.text, force=force, restart=restart, xi=design.xi, kappa=kappa, weights=design.weights,
        parameter_names=[p.name for p in campaign.parameters], outputs=nominal.outputs, time=nominal.time,
        raw=campaign.storage.raw, tsvd=campaign.storage.tsvd and asdict(campaign.storage.tsvd), attrs=attrs, units=nominal.units,
        batch_rows=campaign.execution.chunk, resolution=nominal.resolution,
        quantities=list(campaign.quantities), capacity=campaign.runs if DESIGNS[design.kind].adaptive else None)


def simulate(campaign: Campaign, kappa: np.ndarray, outputs: list[str], processes: int = 1, meanwhile=None):
    """Fly (or call) the campaign's simulator at every row of kappa (M, d) as `uqflight run` flies its
    samples (e.g. the calibration's posterior-predictive runs): in `processes` supervised worker processes,
    each run from a fresh simulator state (the numbers do not depend on the split) and under the campaign's
    per-run limit (execution.timeout_s, else max(60 s, 50 flights at the nominal), the nominal flown first). A run
    that fails, kills its worker or runs past the limit is a failed run with its reason; the others stand.
    `meanwhile` (no arguments) is called here while the workers start, e.g. an import the caller needs next.

    Returns (time (T,), {output: (M, T)} with NaN rows for failed runs, [failure reasons in row order]).
    Raises WorkerError when no simulator can be built (the message says why)."""
    kappa = np.asarray(kappa, dtype=float)
    spec = replace(worker_spec(campaign), quantities=None)  # the outputs only
    timeout = campaign.execution.timeout_s
    pool = WorkerPool(spec, max(1, min(processes, len(kappa))), timeout or NOMINAL_TIMEOUT_S)
    try:
        pool.start_warmup(nominal_kappa(campaign), measure_resolution=False)  # the time grid, a run's cost
        if meanwhile is not None:
            meanwhile()
        nominal = pool.warmup_result()
        pool.timeout = timeout or default_timeout(nominal.seconds)
        pool.spec = replace(spec, time=tuple(map(float, nominal.time)))  # every run on the nominal's times
        time = np.asarray(nominal.time, dtype=float)
        values = {name: np.full((len(kappa), time.size), np.nan) for name in outputs}
        failures = {}
        tasks = [Task(np.array([row]), kappa[row:row + 1]) for row in range(len(kappa))]  # a fresh state each
        for indices, status, reasons, flown in pool.run(tasks, time.size, list(outputs)):
            row = int(indices[0])
            if status[0] != Status.OK:
                failures[row] = str(reasons[0])
                continue
            for name in outputs:
                values[name][row] = flown[name][0]
    finally:
        pool.close()
    return time, values, [failures[row] for row in sorted(failures)]


def nominal_kappa(campaign: Campaign) -> np.ndarray:
    return campaign.to_physical(np.zeros((1, len(campaign.parameters))))[0]


def worker_spec(campaign: Campaign) -> WorkerSpec:
    from ..parameters import seed_names
    from ..simulators.kinds import make_bundle

    properties = tuple(p.property for p in campaign.parameters)
    base = str(Path(campaign.source).resolve().parent)
    simulator, seeds = campaign.simulator, seed_names(campaign.parameters)
    if seeds and simulator.entry.integer_seeds:  # a python model is given its seeds as Python ints
        simulator = replace(simulator, seed_parameters=tuple(seeds))
    return WorkerSpec(simulator=simulator,
                      parameter_names=tuple(p.name for p in campaign.parameters),
                      properties=properties, base=base,
                      bundle=make_bundle(campaign.simulator, properties, base),  # files travel with the task
                      quantities=campaign.quantities or None)


def timed_nominal(campaign: Campaign) -> NominalFlight:
    """One nominal flight of the campaign timed on this machine (`uqflight plan`'s estimate: its
    `seconds`, and its `warnings`), flown as `run` flies it: in a supervised worker process, under the
    campaign's time limit (execution.timeout_s, else NOMINAL_TIMEOUT_S, plus STARTUP_GRACE_S for the
    worker's start), a first flight warming what every later one reuses (the Newton trim's nominal),
    the second timed. Raises WorkerError when the worker dies, runs past the limit or cannot build the
    simulator (the message says which), as `run` does."""
    pool = WorkerPool(worker_spec(campaign), 1, campaign.execution.timeout_s or NOMINAL_TIMEOUT_S)
    kappa = nominal_kappa(campaign)
    try:
        pool.nominal_flight(kappa, measure_resolution=False)
        return pool.nominal_flight(kappa, measure_resolution=False)
    finally:
        pool.close()


def local_workers(campaign: Campaign, workers: int, chunk: int) -> int:
    """The worker processes to start for `workers`: at most one per chunk of the design (more would
    only idle); ValueError when their memory exceeds the campaign's limits.max_memory_gb."""
    need = workers * WORKER_BYTES / 1e9
    if need > campaign.limits.max_memory_gb:
        raise ValueError(f"{workers} workers would need about {need:.3g} GB of memory "
                         f"({WORKER_BYTES / 1e6:.0f} MB each), more than limits.max_memory_gb = "
                         f"{campaign.limits.max_memory_gb:g}; this machine has {os.cpu_count()} cores")
    if campaign.runs:
        workers = min(workers, len(chunk_starts(campaign.runs, chunk)) - 1)
    return max(1, workers)


def chunk_starts(total: int, chunk: int) -> np.ndarray:
    """The first sample of every chunk, then `total`: design-order chunks of `chunk` samples, except
    the design's last TAPER x `chunk` samples, cut in chunks of `chunk` // TAPER so that the workers
    finish together instead of all but one waiting for a last long chunk. A function of the design
    and `chunk` only, never of the workers: results stay the same whatever runs them."""
    small = max(1, chunk // TAPER)
    head = max(0, total - TAPER * chunk) // chunk * chunk
    return np.unique(np.r_[np.arange(0, head, chunk), np.arange(head, total, small), total]).astype(np.int64)


def pending_chunks(pending: np.ndarray, chunk: int, total: int) -> list[np.ndarray]:
    """The fixed design-order chunks (`chunk_starts`) that hold pending samples, whole."""
    starts = chunk_starts(total, chunk)
    held = np.unique(np.searchsorted(starts, pending, side="right") - 1)
    return [np.arange(starts[c], starts[c + 1]) for c in held]


def default_timeout(flight_seconds: float) -> float:
    """The per-run limit when the campaign sets none: max(60 s, 50 nominal flights)."""
    return max(DEFAULT_TIMEOUT_FLOOR_S, TIMEOUT_FLIGHTS * flight_seconds)


def free_bytes(path: Path) -> int:
    return shutil.disk_usage(path.parent if not path.is_dir() else path).free


def ensure_space(path: Path, needed: int, kept: int) -> None:
    """DiskFull unless the filesystem of `path` has `needed` bytes and the margin free."""
    free = free_bytes(path)
    if free < needed + SPACE_MARGIN_BYTES:
        raise DiskFull(errno.ENOSPC, disk_full_message(path, kept, free, needed + SPACE_MARGIN_BYTES))


def disk_full_message(path: Path, kept: int, free: int | None = None, needed: int | None = None) -> str:
    detail = f" ({free / 2**20:.1f} MiB free, {needed / 2**20:.1f} MiB needed for the next batch)" \
        if free is not None else ""
    return (f"no space left on {path}'s filesystem{detail}; {kept} runs kept; "
            "free space and rerun to resume")


def is_disk_full(exc: BaseException) -> bool:
    text = str(exc)
    return getattr(exc, "errno", None) == errno.ENOSPC or "No space left" in text or "errno = 28" in text


def run_campaign(campaign: Campaign, out: Path | None = None, workers: int | None = None,
                 executor: str | None = None, scheduler: str | None = None, force: bool = False,
                 progress: bool = False, restart: bool = False) -> RunSummary:
    """Run every pending sample of the campaign into its results file; returns a summary.
    `progress` shows a progress bar (a terminal) or log lines (otherwise) on stderr. `restart` starts a
    results file of this campaign over (a resume otherwise); `force` replaces another campaign's.

    Raises LockHeld (another run writes the file), FileExistsError (a file that is not this
    campaign's), DiskFull (stopped cleanly, resumable), WorkerError (no simulator could be built)."""
    execution = campaign.execution
    executor = executor or execution.executor
    scheduler = scheduler or execution.scheduler
    chunk = execution.chunk
    workers = workers or execution.workers
    if executor == "local" or not scheduler:  # processes on this machine (dask's own LocalCluster too)
        workers = local_workers(campaign, workers, chunk)
    out = Path(out or campaign.storage.path)
    started = time.perf_counter()
    spec = worker_spec(campaign)
    lock = ResultsLock(out)
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        lock.acquire()
    except LockHeld:
        raise
    except OSError as exc:
        if is_disk_full(exc) and not isinstance(exc, FileExistsError):
            raise DiskFull(errno.ENOSPC, disk_full_message(out, _stored_runs(out) if out.is_file() else 0)) from exc
        where = f": {exc.filename}" if exc.filename else ""
        raise Refusal(f"cannot write the results file {out} ({exc.strerror or exc}{where}); choose "
                      "another path with --out or storage.path") from exc
    pool = None
    try:
        pool = WorkerPool(spec, workers if executor == "local" else 1,
                          execution.timeout_s or NOMINAL_TIMEOUT_S)
        pool.start_warmup(nominal_kappa(campaign))
        design = campaign.design()  # built while the workers start
        nominal = pool.warmup_result()
        seconds = nominal.seconds
        # every run is stored against the nominal's times: a model giving other times fails the run
        pool.spec = spec = replace(spec, time=tuple(map(float, nominal.time)))
        timeout = execution.timeout_s or default_timeout(seconds)
        pool.timeout = timeout
        # One BLAS thread here, for the folds on opening too: the workers keep every core busy, a
        # multi-threaded BLAS competing with them is 10-100x slower, and the tSVD factors must not
        # depend on where a resume starts (the same limit for every fold makes them bit-identical).
        with threadpool_limits(limits=1):
            try:
                store = prepare_store(campaign, design, out, force, nominal=nominal, restart=restart)
            except (OSError, RuntimeError) as exc:
                if is_disk_full(exc) and not isinstance(exc, FileExistsError):
                    raise DiskFull(errno.ENOSPC, disk_full_message(out, 0)) from exc
                raise
            try:
                def fly():
                    return _run_pending(store, campaign, pool, spec, chunk, workers, executor, scheduler,
                                        timeout, out, progress)

                entry = DESIGNS[design.kind]
                rounds = run_rare if entry.rare else run_rounds if entry.adaptive else None
                summary = rounds(store, campaign, fly) if rounds else fly()
                complete = store.pending().size == 0
            finally:
                try:
                    store.close()
                except (OSError, RuntimeError) as exc:  # HDF5 reports a late write failure oddly
                    if is_disk_full(exc) or free_bytes(out) < 2 * SPACE_MARGIN_BYTES:
                        raise DiskFull(errno.ENOSPC, disk_full_message(out, _stored_runs(out))) from exc
                    raise
        pool.close()
        verify_written(out, summary)
        if complete and campaign.storage.tsvd:
            if free_bytes(out) > 2 * out.stat().st_size + SPACE_MARGIN_BYTES:
                compact(out)
    finally:
        if pool is not None:
            pool.close()
        lock.release()
    summary.seconds = time.perf_counter() - started
    summary.timeout_s = timeout
    summary.nominal_failure = nominal.failure
    summary.nominal_warnings = list(getattr(nominal, "warnings", []))
    return summary


def _run_pending(store, campaign, pool, spec, chunk, workers, executor, scheduler, timeout, out, progress):
    total = store.status.size
    pending = store.pending()
    chunks = pending_chunks(pending, chunk, total)
    kappa = store.kappa
    n_times, outputs = store.time.size, store.output_names
    summary = RunSummary(out, total, 0, total - pending.size, 0.0)
    bar = Progress(total, done=total - pending.size, quiet=not progress)
    # A chunk with some samples already stored (impossible with this writer, but a file
    # written elsewhere may have one) is rerun whole; only its pending rows are written.
    tasks = [Task(c, kappa[c]) for c in chunks]
    if executor == "dask":
        results = _execute_dask(tasks, spec, n_times, outputs, workers, scheduler, timeout, bar.note)
    else:
        results = pool.run(tasks, n_times, outputs)
    try:
        for indices, status, reasons, values in results:
            keep = store.status[indices] == Status.PENDING
            ensure_space(out, store.batch_bytes(int(keep.sum())), summary.skipped + summary.ran)
            try:
                store.write_batch(indices[keep], status[keep], np.asarray(reasons, dtype=object)[keep],
                                  {k: v[keep] for k, v in values.items()})
            except (OSError, RuntimeError) as exc:
                if is_disk_full(exc):
                    raise DiskFull(errno.ENOSPC, disk_full_message(out, total - store.pending().size)) from exc
                raise
            summary.ran += int(keep.sum())
            summary.failures.update(r for r, s in zip(np.asarray(reasons)[keep], status[keep]) if s != 0)
            bar.advance(int(keep.sum()))
    finally:
        bar.close()  # a rich bar gives the terminal back, also on Ctrl-C
    return summary


def _stored_runs(path: Path) -> str:
    """How many runs a file holds, for a message (as many as a resume will find)."""
    try:
        with ResultStore.open(path) as store:
            return str(int(np.count_nonzero(store.status != Status.PENDING)))
    except Exception:
        return "the stored"


def verify_written(path: Path, summary: RunSummary) -> None:
    """Reread the file: every run counted as done must be stored (its status written, ok rows
    finite). A file that disagrees is an error, never a silent success."""
    with ResultStore.open(path) as store:
        problems = store.verify()
        done = int(np.count_nonzero(store.status != Status.PENDING))
    if done < summary.ran + summary.skipped:
        problems.append(f"{summary.ran + summary.skipped} runs were counted as done but {done} are stored")
    if problems:
        message = (f"{path}: the file does not hold what was written: " + "; ".join(problems[:5])
                   + "; rerun to resume: the missing runs are run again")
        if free_bytes(path) < 2 * SPACE_MARGIN_BYTES:
            raise DiskFull(errno.ENOSPC, disk_full_message(path, done - summary.ran) + f" ({message})")
        raise IncompleteFile(message)


# -- supervised worker processes ------------------------------------------------------------------
@dataclass
class Task:
    """One chunk, and the rows that killed or hung a worker (row -> (status, reason))."""

    indices: np.ndarray
    kappa: np.ndarray
    failed: dict = field(default_factory=dict)
    attempts: int = 0  # deaths before the first sample (building the simulator)

    @property
    def settled(self) -> bool:
        return len(self.failed) == len(self.indices)

    def result(self, flown, n_times: int, outputs: list[str]):
        """(indices, status, reasons, values) with the failed rows put in."""
        n = len(self.indices)
        if flown is None:
            status, reasons = np.zeros(n, np.int8), [""] * n
            values = {name: np.full((n, n_times), np.nan) for name in outputs}
        else:
            _, status, reasons, values = flown
            status, reasons = np.array(status, np.int8), list(reasons)
        for row, (code, reason) in self.failed.items():
            status[row], reasons[row] = code, reason
            for name in values:
                values[name][row] = np.nan
        return self.indices, status, reasons, values


def death_reason(returncode: int | None) -> str:
    if returncode is None:
        return "worker process died: no exit status"
    if returncode < 0:
        try:
            name = signal.Signals(-returncode).name
        except ValueError:
            name = "unknown"
        hint = " (out of memory, or killed)" if -returncode == signal.SIGKILL else ""
        return f"worker process died: signal {-returncode} ({name}){hint}"
    return f"worker process died: exit code {returncode}"


class WorkerProcess:
    """One `python -m uqflight.running.worker` child and its socket."""

    def __init__(self):
        parent, child = socket.socketpair()
        try:
            self.proc = subprocess.Popen(
                [sys.executable, "-m", "uqflight.running.worker", str(child.fileno()), str(os.getpid())],
                pass_fds=[child.fileno()], stdin=subprocess.DEVNULL)
        finally:
            child.close()
        self.conn = Connection(parent.detach())
        self.task: Task | None = None
        self.row: int | None = None
        self.since = time.monotonic()

    def send(self, message) -> bool:
        try:
            self.conn.send(message)
            return True
        except OSError:
            return False

    def kill(self) -> int | None:
        """Kill the child (if alive) and return its exit status."""
        if self.proc.poll() is None:
            try:
                self.proc.kill()
            except ProcessLookupError:
                pass
        try:
            code = self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            code = None
        self.conn.close()
        return code

    def died(self) -> int | None:
        """The exit status of a child whose socket closed."""
        try:
            code = self.proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            code = None
        self.kill()
        return code


class WorkerPool:
    """`workers` supervised worker processes flying chunks; see the module docstring."""

    def __init__(self, spec: WorkerSpec, workers: int, timeout: float):
        self.spec, self.workers, self.timeout = spec, max(1, int(workers)), float(timeout)
        self.slots: list[WorkerProcess] = []

    def nominal_flight(self, kappa: np.ndarray, measure_resolution: bool = True) -> NominalFlight:
        """The NominalFlight at `kappa` (worker.nominal_flight), from a worker:
        `start_warmup`, then `warmup_result`."""
        self.start_warmup(kappa, measure_resolution)
        return self.warmup_result()

    def start_warmup(self, kappa: np.ndarray, measure_resolution: bool = True) -> None:
        """Start every worker of the pool and ask each to fly the nominal `kappa`, so that all are warm
        (imports, aircraft, the Newton trim's nominal) when the chunks start. Returns at once: the
        caller may work meanwhile, then call `warmup_result`. `measure_resolution` false: the first
        worker does not measure the simulator's resolution either (a second flight for JSBSim)."""
        slot = self._slot()
        while len(self.slots) < self.workers:
            self.slots.append(WorkerProcess())
        for other in self.slots[1:]:  # a warm-up only: the trims' drift is measured once, by the first
            if not other.send(("nominal", self.spec, kappa, False)):
                self._drop(other)
        if not slot.send(("nominal", self.spec, kappa, measure_resolution)):
            raise WorkerError(death_reason(self._drop(slot)))

    def warmup_result(self) -> NominalFlight:
        """The first worker's answer to `start_warmup`. The others' answers are not awaited: `run`
        reads them before their workers' first chunk, so that no worker waits for the slowest start."""
        slot = self.slots[0]
        limit = self.timeout + STARTUP_GRACE_S  # the worker starts, imports and builds its simulator first
        if not wait_connections([slot.conn], timeout=limit):
            self._drop(slot, dead=False)
            raise WorkerError(f"the nominal flight did not finish within {limit:g} s (execution.timeout_s "
                              f"{self.timeout:g} s plus {STARTUP_GRACE_S:g} s for the worker's start)")
        try:
            kind, payload = slot.conn.recv()
        except (EOFError, OSError):
            raise WorkerError(death_reason(self._drop(slot)) + " during the nominal flight") from None
        if kind != "nominal":
            raise WorkerError(str(payload))
        return payload

    def run(self, tasks, n_times: int, outputs: list[str]):
        """Yield (indices, status, reasons, values) per chunk as they finish; every chunk is
        yielded once, whatever its samples do to the workers."""
        queue = deque(tasks)
        busy: list[WorkerProcess] = []
        finished: deque = deque()  # results held back until every idle worker has its next chunk
        while queue or busy or finished:
            check_stop()  # a SIGINT or SIGTERM whose exception was lost in a callback
            while queue and len(busy) < self.workers:
                task = queue.popleft()
                if task.settled:
                    finished.append(task.result(None, n_times, outputs))
                    continue
                slot = self._idle_slot(busy)
                slot.task, slot.row, slot.since = task, None, time.monotonic()
                skip = tuple(task.failed)
                if not slot.send(("chunk", self.spec, task.indices, task.kappa, n_times, outputs, skip)):
                    self._lost(slot, busy, queue, death_reason(self._drop(slot)), Status.WORKER_DIED)
                    continue
                busy.append(slot)
            while finished:  # the caller writes them while the workers fly on
                yield finished.popleft()
            if not busy:
                continue
            deadline = min(slot.since + self._limit(slot) for slot in busy)
            ready = wait_connections([slot.conn for slot in busy], timeout=max(0.0, deadline - time.monotonic()))
            for conn in ready:
                slot = next(s for s in busy if s.conn is conn)
                while True:  # every message already there, so that a backlog never looks like a hang
                    try:
                        kind, payload = conn.recv()
                    except (EOFError, OSError):
                        self._lost(slot, busy, queue, death_reason(self._drop(slot)), Status.WORKER_DIED)
                        break
                    if kind == "start":
                        slot.row, slot.since = payload, time.monotonic()
                    elif kind == "nominal":  # the warm-up `start_warmup` asked for
                        pass
                    elif kind == "done":
                        task = slot.task
                        slot.task = None
                        busy.remove(slot)
                        finished.append(task.result(payload, n_times, outputs))
                        break
                    else:
                        raise WorkerError(str(payload))
                    try:
                        if not conn.poll():
                            break
                    except (EOFError, OSError):
                        continue  # closed: the next recv reports the death
            now = time.monotonic()
            for slot in [s for s in busy if now - s.since > self._limit(s)]:
                self._drop(slot, dead=False)
                self._lost(slot, busy, queue, f"timed out: still running after {self.timeout:g} s "
                           "(execution.timeout_s); its worker was replaced", Status.TIMEOUT)

    def _limit(self, slot: WorkerProcess) -> float:
        """The time `slot` may take from `since`: the per-run limit once a sample has started; before
        the chunk's first sample (a fresh worker starting, the simulator being built) at least
        STARTUP_GRACE_S, so that a loaded machine does not turn a slow start into timeouts."""
        return self.timeout if slot.row is not None else max(self.timeout, STARTUP_GRACE_S)

    def _lost(self, slot, busy, queue, reason: str, status: Status) -> None:
        """The slot's worker is gone: blame the sample it was flying, fly its chunk again."""
        task, row = slot.task, slot.row
        if slot in busy:
            busy.remove(slot)
        if row is not None:
            task.failed[row] = (int(status), reason)
        else:
            task.attempts += 1
            if task.attempts >= 2:  # twice before its first sample: no sample of it can be flown
                for r in range(len(task.indices)):
                    task.failed.setdefault(r, (int(status), reason + " (before the chunk's first sample)"))
        queue.appendleft(task)

    def _slot(self) -> WorkerProcess:
        if not self.slots:
            self.slots.append(WorkerProcess())
        return self.slots[0]

    def _idle_slot(self, busy) -> WorkerProcess:
        for slot in self.slots:
            if slot not in busy:
                return slot
        slot = WorkerProcess()
        self.slots.append(slot)
        return slot

    def _drop(self, slot: WorkerProcess, dead: bool = True) -> int | None:
        """Forget a worker: `dead` (its socket closed) waits for its own exit status, else kill it."""
        code = slot.died() if dead else slot.kill()
        if slot in self.slots:
            self.slots.remove(slot)
        return code

    def close(self) -> None:
        for slot in self.slots:
            slot.kill()
        self.slots = []


_DASK_POOLS: dict[str, WorkerPool] = {}


def supervised_chunk(spec: WorkerSpec, indices, kappa, n_times: int, outputs: list[str], timeout: float):
    """A Dask task: fly one chunk in a supervised child of this Dask worker (kept between tasks),
    so that a sample that kills or hangs the child is recorded like on the local executor."""
    pool = _DASK_POOLS.get(spec.key)
    if pool is None:
        pool = _DASK_POOLS[spec.key] = WorkerPool(spec, 1, timeout)
    pool.spec, pool.timeout = spec, timeout  # this campaign's nominal times (WorkerSpec.time)
    return next(iter(pool.run([Task(np.asarray(indices), np.asarray(kappa))], n_times, outputs)))


NO_WORKERS_NOTICE_S = 5.0  # no chunk finished for this long and the scheduler has no worker: say so


def _execute_dask(tasks, spec, n_times, outputs, workers: int, scheduler: str | None, timeout: float,
                  note=lambda text: None):
    """Yield chunk results as they finish, keeping about four chunks per worker in flight; `note(text)`
    is told when the scheduler has had no worker for NO_WORKERS_NOTICE_S (none started, or all gone)."""
    if not tasks:
        return
    from dask.distributed import Client, LocalCluster, wait

    cluster = None
    if scheduler:
        client = Client(scheduler)
    else:
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                               dashboard_address=None)
        client = Client(cluster)
    try:
        queue = list(reversed(tasks))

        def submit(task):
            return client.submit(supervised_chunk, spec, task.indices, task.kappa, n_times, outputs, timeout,
                                 pure=False)

        # a deeper queue than the local pool's: it hides the scheduler round trip of a remote cluster
        in_flight = 4 * max(workers, len(client.scheduler_info().get("workers", {})) or 1)
        running = {submit(queue.pop()) for _ in range(min(in_flight, len(queue)))}
        told = False
        while running:
            check_stop()
            try:
                done, running = wait(running, timeout=NO_WORKERS_NOTICE_S, return_when="FIRST_COMPLETED")
            except TimeoutError:
                if not told and not client.scheduler_info().get("workers"):
                    address = scheduler or cluster.scheduler_address
                    note(f"waiting for a Dask worker: the scheduler {address} has had none for "
                         f"{NO_WORKERS_NOTICE_S:g} s ({len(running) + len(queue)} of {len(tasks)} chunks left; "
                         f"start one: dask worker {address}; Ctrl-C stops, a rerun resumes)")
                    told = True
                continue
            told = False
            for future in done:
                yield future.result()
                if queue:
                    running.add(submit(queue.pop()))
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
