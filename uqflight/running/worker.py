"""What runs inside a worker process: build the simulator once, fly chunks of samples.

Kept apart from the runner so that a worker imports only NumPy and the simulator (the
campaign, designs and HDF5 modules stay in the runner process): workers start faster.

A worker is a separate Python process (`python -m uqflight.running.worker FD PPID`) that talks to its
runner over a socket (pickled messages, `multiprocessing.connection.Connection`): it receives
chunks, announces each sample before flying it ("start", row) so that the runner knows which
sample a dead or hung worker was flying, and returns the chunk's results. It never outlives its
runner: the kernel kills it when the runner dies (PR_SET_PDEATHSIG), and a watchdog thread exits
when its parent process changes or the socket closes. It ignores SIGINT: the runner decides. Its
standard output goes to /dev/null: what a flight prints never reaches the runner's terminal.
"""
from __future__ import annotations

import json
import os
import signal
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..text.console import discard_output, one_line
from .forking import die_with_parent
from ..quantities import QuantitySpec, quantity_key
from ..quantities.recorder import QuantityRecorder
from ..simulators import FlightError, SimulatorSpec, make_simulator
from ..simulators.base import NominalFailed
from ..simulators.kinds import localized


@dataclass(frozen=True)
class WorkerSpec:
    """What a worker needs to build its simulator (picklable, sent with every chunk)."""

    simulator: SimulatorSpec
    parameter_names: tuple[str, ...]
    properties: tuple[str, ...]
    base: str
    bundle: dict | None = None  # the aircraft's (or file.py's) files as bytes + hash (simulators/bundle.py)
    quantities: dict[str, QuantitySpec] | None = None  # the campaign's quantities of interest by name
    time: tuple[float, ...] | None = None  # the nominal flight's times, which every run's values are stored against

    @property
    def key(self) -> str:
        return json.dumps([self.simulator.as_mapping(), self.parameter_names, self.properties, self.base],
                          sort_keys=True)

    def build(self):
        return make_simulator(self.simulator, list(self.parameter_names), list(self.properties), Path(self.base))


_WORKER_CACHE: dict[str, object] = {}


def worker_simulator(spec: WorkerSpec):
    """This process's simulator for `spec`, built on first use and kept (one load per worker)."""
    spec = localized(spec)  # unpack the files that travel with the task; refuse other aircraft files
    simulator = _WORKER_CACHE.get(spec.key)
    if simulator is None:
        simulator = _WORKER_CACHE[spec.key] = spec.build()
    return simulator


def run_chunk(spec: WorkerSpec, indices: np.ndarray, kappa: np.ndarray, n_times: int, outputs: list[str],
              skip=(), on_start=None):
    """Fly the samples of one chunk; failures are recorded, never raised.

    `skip`: rows (positions in the chunk) not to fly (they killed or hung a worker before; the
    runner records them); they are left NaN with status ok, for the runner to overwrite.
    `on_start(row)` is called before each sample is flown. The values hold every output's (n, T) rows and,
    under `quantity_key(name)`, every quantity's (n,) values, computed at every step of the flight
    (NaN where undefined or failed)."""
    simulator = worker_simulator(spec)
    simulator.restart()
    expect_time = getattr(simulator, "expect_time", None)  # a model that gives its own times (python)
    if expect_time is not None and spec.time is not None:
        expect_time(np.asarray(spec.time, dtype=float))
    n = len(indices)
    status = np.zeros(n, dtype=np.int8)
    reasons = [""] * n
    values = {name: np.full((n, n_times), np.nan) for name in outputs}
    recorder = QuantityRecorder(spec.quantities, simulator.source) if spec.quantities else None
    observers = (recorder,) if recorder else ()
    for name in spec.quantities or ():
        values[quantity_key(name)] = np.full(n, np.nan)
    skip = set(skip)
    for row, k in enumerate(kappa):
        if row in skip:
            continue
        if on_start is not None:
            on_start(row)
        try:
            if recorder:
                recorder.reset()
                if recorder.modes:  # JSBSim linearises a reused bacm in minutes (240 s), a fresh one in 4 s
                    simulator.restart()
            result = simulator.evaluate(k, observers)
            for name in outputs:
                if name not in result:
                    raise FlightError(f"the simulator returned no output {name!r}")
                if result[name].shape != (n_times,):
                    raise FlightError(f"output {name} has {result[name].size} values, expected {n_times}")
                values[name][row] = result[name]
            for name, value in (recorder.result() if recorder else {}).items():
                values[quantity_key(name)][row] = value
        except FlightError as exc:
            status[row], reasons[row] = exc.status, str(exc)
        except Exception as exc:  # a simulator bug must not stop the campaign: record it
            status[row], reasons[row] = FlightError.status, f"{type(exc).__name__}: {exc}"
    return indices, status, reasons, values


@dataclass(frozen=True)
class NominalFlight:
    """What the runner needs to create the results file and derive the default per-run time limit,
    measured in a worker: the recorded times, the output names and units, the seconds one flight at the
    nominal took, the simulator's resolution there ({output: (T,)}, or None), why that flight
    failed (None when it flew), and what its flight warned of (an excitation that left its surface unmoved)."""

    time: np.ndarray
    outputs: list[str]
    units: dict[str, str]
    seconds: float
    resolution: dict[str, np.ndarray] | None
    failure: str | None = None
    warnings: list[str] = field(default_factory=list)


def nominal_flight(spec: WorkerSpec, kappa: np.ndarray, measure_resolution: bool = True) -> NominalFlight:
    """The nominal flight at `kappa`, measured here, not in the runner. `measure_resolution` false: no
    resolution (None), for a worker that only warms up."""
    simulator = spec.build()
    time_grid, outputs = simulator.layout(kappa)
    observers = (QuantityRecorder(spec.quantities, simulator.source),) if spec.quantities else ()
    started = time.perf_counter()
    try:  # with the quantities: a linearisation costs more than the flight (5 s for bacm's two turboprops)
        flown = simulator.evaluate(kappa, observers)
    except FlightError as exc:  # still the cost of a flight; the campaign goes on, its runs say why they fail
        flown, failure = None, str(exc)
    else:
        failure = None
    seconds = time.perf_counter() - started
    resolution = getattr(simulator, "resolution", None)
    warning = getattr(getattr(simulator, "flight", None), "surface_warning", None) if flown is not None else None
    return NominalFlight(np.asarray(time_grid, dtype=float), list(outputs), dict(getattr(simulator, "units", {}) or {}),
                         seconds, resolution(kappa, flown) if measure_resolution and resolution and flown is not None
                         else None, failure, [warning] if warning else [])


def main(argv=None) -> None:
    """Serve the runner on the socket `fd` until it closes."""
    from multiprocessing.connection import Connection

    argv = sys.argv[1:] if argv is None else argv
    fd, parent = int(argv[0]), int(argv[1])
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    die_with_parent(parent, watch=True)
    # results travel on the socket: what a flight prints (a script's <notify> events, which JSBSim writes
    # whatever its debug level, a python model's print) would flood the runner's terminal, once per run
    discard_output(sys.stdout)
    conn = Connection(fd)
    while True:
        try:
            message = conn.recv()
        except (EOFError, OSError):
            os._exit(0)
        kind, args = message[0], message[1:]
        try:
            if kind == "chunk":
                result = run_chunk(*args, on_start=lambda row: conn.send(("start", row)))
                conn.send(("done", result))
            elif kind == "nominal":
                conn.send(("nominal", nominal_flight(*args)))
            else:
                conn.send(("error", f"unknown request {kind!r}"))
        except (BrokenPipeError, ConnectionResetError):
            os._exit(0)
        except NominalFailed as exc:  # its message says it all
            conn.send(("error", str(exc)))
        except Exception as exc:  # building the simulator failed: the runner reports it, on one line
            conn.send(("error", f"{type(exc).__name__}: {one_line(str(exc))}"))


if __name__ == "__main__":  # `python -m uqflight.running.worker`: the imported module's main, so that the
    from uqflight.running.worker import main as serve  # records it sends pickle as uqflight.running.worker.NominalFlight

    serve()
