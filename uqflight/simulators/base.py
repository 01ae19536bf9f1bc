"""What every simulator shares: the run status codes, the errors of a failed sample.

The status codes are stored per run in `/samples/status` of a results file; they are defined here
once, and each error class carries its own code.
"""
from __future__ import annotations

import enum

from ..console import one_line, shown


class Status(enum.IntEnum):
    """Outcome of one run, as stored in /samples/status."""

    PENDING = -1
    OK = 0
    TRIM_FAILURE = 1
    DIVERGED = 2
    SIMULATOR_ERROR = 3
    WORKER_DIED = 4  # the sample killed its worker process (exit, signal, out of memory)
    TIMEOUT = 5  # the sample ran past execution.timeout_s; its worker was replaced


class FlightError(RuntimeError):
    """A sample that could not be flown; `status` is its code in the results file."""

    status = Status.SIMULATOR_ERROR


class TrimError(FlightError):
    """The trim did not converge or converged to a state outside the aircraft's envelope."""

    status = Status.TRIM_FAILURE


class DivergenceError(FlightError):
    """The flight left the envelope or produced NaN after the trim."""

    status = Status.DIVERGED


class NominalFailed(RuntimeError):
    """The nominal sample, which `layout` runs before any other to learn the outputs, failed: the
    message names it, gives its values and says what to do; `run` stops there (exit 2)."""


def nominal_failed(names, kappa, exc: Exception) -> NominalFailed:
    """The NominalFailed that says sample `kappa` of the parameters `names` failed with `exc`."""
    values = ", ".join(f"{shown(name)} = {float(value):.10g}" for name, value in zip(names, kappa))
    return NominalFailed(
        f"the nominal sample failed ({values}: the centre of every parameter's law, ξ = 0), which uqflight "
        f"runs first to learn the outputs, the time grid and the cost of a run: {type(exc).__name__}: "
        f"{one_line(str(exc))}. "
        "Make the simulator succeed at these values (call simulator.function with them to see why), or move "
        "the parameters' intervals (lower and upper, or nominal with interval_pct) so that their centre is an "
        "input it accepts")
