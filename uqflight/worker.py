"""What runs inside a worker process: build the simulator once, fly chunks of samples.

Kept apart from the runner so that a worker imports only NumPy and the simulator (the
campaign, designs and HDF5 modules stay in the runner process): workers start faster.
"""
from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .simulators import FlightError, make_simulator
from .simulators.bundle import localized


@dataclass(frozen=True)
class WorkerSpec:
    """What a worker needs to build its simulator (picklable, sent with every chunk)."""

    simulator: dict
    parameter_names: tuple[str, ...]
    properties: tuple[str, ...]
    base: str
    bundle: dict | None = None  # the aircraft's (or file.py's) files as bytes + hash (simulators/bundle.py)

    @property
    def key(self) -> str:
        return json.dumps([self.simulator, self.parameter_names, self.properties, self.base], sort_keys=True)

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


def run_chunk(spec: WorkerSpec, indices: np.ndarray, kappa: np.ndarray, n_times: int, outputs: list[str]):
    """Fly the samples of one chunk; failures are recorded, never raised."""
    simulator = worker_simulator(spec)
    simulator.restart()
    n = len(indices)
    status = np.zeros(n, dtype=np.int8)
    reasons = [""] * n
    values = {name: np.full((n, n_times), np.nan) for name in outputs}
    for row, k in enumerate(kappa):
        try:
            result = simulator.evaluate(k)
            for name in outputs:
                if name not in result:
                    raise FlightError(f"the simulator returned no output {name!r}")
                if result[name].shape != (n_times,):
                    raise FlightError(f"output {name} has {result[name].size} values, expected {n_times}")
                values[name][row] = result[name]
        except FlightError as exc:
            status[row], reasons[row] = exc.status, str(exc)
        except Exception as exc:  # a simulator bug must not stop the campaign: record it
            status[row], reasons[row] = FlightError.status, f"{type(exc).__name__}: {exc}"
    return indices, status, reasons, values
