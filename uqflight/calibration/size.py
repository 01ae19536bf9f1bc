"""The memory a calibration needs, estimated before any work from the data file's rows and the
options, and refused beyond the campaign's memory limit (limits.max_memory_gb, as `plan` and `run`).

Per data row and calibrated output, the arrays that grow with the data: the posterior-predictive
band (predictive draws x noise draws, and the copy its quantiles sort), the simulator runs and the
surrogate at the draws, and the walkers' residuals in every log-posterior evaluation. The chain
adds walkers x steps x parameters. The file is a regular file of at most MAX_DATA_BYTES (a device or
a FIFO, which may never end, is refused before a byte is read); its rows are counted without parsing,
and only up to the most that fit: a file of 10^6 rows is refused after reading the first few hundred
thousand lines.
"""
from __future__ import annotations

from pathlib import Path

from ..text.bounded import OutsideBounds, open_bounded
from ..text import Refusal
from .likelihood import DATA_FORM, MAX_DATA_BYTES

DEFAULT_WALKERS = 32  # the fewest `calibrate` uses when --walkers is not given
MAX_STEPS = 6000  # the longest an adaptive chain (no --steps) runs (calibration.sampler)
PREDICTIVE_NOISE_DRAWS = 40  # noise draws per simulator run for the 95 % predictive band


def row_bytes(predictive_draws: int, walkers: int, noise_draws: int = PREDICTIVE_NOISE_DRAWS) -> float:
    """Bytes per data row and output: the predictive band (twice: its quantiles sort a copy), the runs,
    the surrogate and its error at the draws, and the walkers' residuals (float64)."""
    return 8.0 * (predictive_draws * (2 * noise_draws + 3) + 4 * walkers)


def check_size(data, outputs: list[str] | None, walkers: int | None, steps: int | None, predictive_draws: int,
               max_memory_gb: float) -> None:
    """Refusal when the calibration of `data` would need more than `max_memory_gb`; reads the
    header and counts lines, nothing more."""
    path = Path(data)
    walkers, steps = walkers or DEFAULT_WALKERS, steps or MAX_STEPS  # an adaptive chain may take MAX_STEPS
    budget = max_memory_gb * 1e9
    chain = 8.0 * walkers * steps * 3  # the chain (and emcee's copy) of at least one parameter, its log-probability
    if chain > budget:
        raise Refusal(f"--walkers {walkers} x --steps {steps} keep a chain of about {chain / 1e9:.3g} GB, more than "
                      f"the {max_memory_gb:g} GB memory limit (limits.max_memory_gb): run fewer --steps")
    try:
        with open_bounded(path, MAX_DATA_BYTES, "flight data") as fh:
            header = fh.readline(1 << 20).decode("utf-8-sig", "replace")
            columns = max(len(header.split(",")) - 1, 1)  # every column but time_s may be calibrated
            count = len(outputs) if outputs else columns
            per_row = count * row_bytes(predictive_draws, walkers)
            most = int((budget - chain) // per_row)
            rows = 0
            while rows <= most:
                block = fh.read(1 << 20)
                if not block:
                    return
                rows += block.count(b"\n")
    except OutsideBounds as exc:
        raise Refusal(f"{path}: {exc}: {DATA_FORM}") from exc
    except OSError as exc:
        raise Refusal(f"{path}: cannot read the file ({exc.strerror or exc})") from exc
    raise Refusal(f"{path}: more than {most} rows of data: calibrating {count} output(s) with {walkers} walkers "
                  f"and {predictive_draws} predictive draws takes about {per_row / 1e3:.0f} kB a row, more than the "
                  f"{max_memory_gb:g} GB memory limit (limits.max_memory_gb) allows; thin the data to fewer "
                  "times, calibrate fewer --output or take fewer --predictive-draws")
