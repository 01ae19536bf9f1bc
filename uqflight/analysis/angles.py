"""Angles that wrap (a heading from 359° to 1°, or from 180° to −180°): made continuous before any statistic.

An output whose unit is deg or rad (labels.name_unit) is unwrapped along each run's history
(numpy.unwrap with the period of its unit: a step that jumps by more than half a turn is the angle
crossing the end of its range), then each run is moved by whole turns onto the branch of the first
run, when that closes a gap of more than half a turn between the runs (runs starting at 179° and at
−179° are 2° apart, not 358°). A quantity, one number per run, gets the second step alone. Nothing
moves when no run jumps and the runs lie within half a turn of each other: the statistics of an angle
that does not wrap are unchanged to the bit.
"""
from __future__ import annotations

import numpy as np

from ..text.labels import ANGLE_PERIODS


def angle_period(units: str) -> float | None:
    """A whole turn in `units` (360 for deg, 2π for rad), None for a unit that is no angle."""
    return ANGLE_PERIODS.get(units)


def branch_shifts(values: np.ndarray, period: float) -> np.ndarray:
    """(N,) the whole turns to add to `values` (N,) to put them on the first value's branch, zeros when the
    values are not spread over about a turn (moving them would not narrow their range by half a turn)."""
    values = np.asarray(values, dtype=float)
    shifts = np.zeros_like(values)
    finite = np.isfinite(values)
    if finite.sum() < 2:
        return shifts
    reference = values[finite][0]
    shifts[finite] = -period * np.round((values[finite] - reference) / period)
    moved = values[finite] + shifts[finite]
    if np.ptp(values[finite]) - np.ptp(moved) > 0.5 * period:
        return shifts
    return np.zeros_like(values)


def unwrapped_runs(histories: np.ndarray, period: float) -> tuple[np.ndarray, bool]:
    """(histories made continuous, whether anything moved): `histories` (N runs, T times) unwrapped along
    time, then moved run by run onto the first run's branch (`branch_shifts` of their first values)."""
    histories = np.asarray(histories, dtype=float)
    jumps = histories.shape[1] > 1 and bool((np.abs(np.diff(histories, axis=1)) > 0.5 * period).any())
    found = np.unwrap(histories, period=period, axis=1) if jumps else histories
    shifts = branch_shifts(found[:, 0], period)
    if not shifts.any():
        return found, jumps
    return found + shifts[:, None], True


def on_branch(histories: np.ndarray, start: float, period: float) -> np.ndarray:
    """Runs of an angle (N, T; a quantity's (N, 1)) drawn as their statistics see them: unwrapped along time
    and moved by whole turns to start within half a turn of `start` (the statistics' mean at the first time)."""
    histories = np.asarray(histories, dtype=float)
    found = np.unwrap(histories, period=period, axis=1) if histories.shape[1] > 1 else histories
    return found - period * np.round((found[:, :1] - start) / period)
