"""Probabilities that a quantity of interest exceeds a threshold (`analysis.exceedance`).

* From runs (sampled designs): the proportion of the runs where the quantity is defined, with the 95 %
  interval that holds for how the design drew them (analysis.proportions): `method: "wilson"` (the
  Wilson score interval), "replicates" (randomised QMC) or "points" (unscrambled QMC, no interval).
* From a PCE: the fraction of the expansion's draws beyond the threshold, `method: "pce"`. Its bounds
  are null: a PCE's error is known in the mean square (leave-one-out, lower-order difference), not on
  the individual values a threshold sorts, so no interval would hold.
Fewer than RARE_COUNT runs beyond the threshold (p < RARE_COUNT/n for a PCE) is flagged (the entry's
`flags`, and its note): the estimate then rests on the tail of a few runs, a rare-event extrapolation. A
threshold beyond the runs' range by more than the range's own width (`unit_slip`) is flagged instead as a
probable unit slip: more runs would not reach it.
"""
from __future__ import annotations

import numpy as np

from .proportions import Independent

RARE_COUNT = 10
CONFIDENCE = 0.95


def _beyond(values: np.ndarray, bound: str, threshold: float) -> np.ndarray:
    return values > threshold if bound == "above" else values < threshold


def unit_slip(runs: np.ndarray, threshold: float, units: str = "") -> str | None:
    """The flag of a threshold farther from the runs' values `runs` (those where the quantity is defined)
    than their range is wide: more likely a threshold in another unit than an event more runs would
    show; None when it lies within that reach."""
    runs = np.asarray(runs, dtype=float)
    runs = runs[np.isfinite(runs)]
    if not runs.size:
        return None
    low, high = float(runs.min()), float(runs.max())
    width = high - low
    if low - width <= threshold <= high + width:
        return None
    unit = f" {units}" if units else ""
    return (f"threshold {threshold:g}{unit} lies beyond the runs' range [{low:.4g}, {high:.4g}]{unit} by more than "
            "its width: a probable unit slip (check the threshold's unit against the quantity's), not an event "
            "more runs would resolve")


def exceedance_entry(bound: str, threshold: float, probability, lower, upper, method, sentence: str,
                     flag: str | None) -> dict:
    """One exceedance entry: its probability, 95 % interval and method, and the flag that bears on it (None:
    none) as its `flags` and after the sentence of its note."""
    return {bound: threshold, "probability": probability, "lower": lower, "upper": upper, "method": method,
            "flags": [flag] if flag else [], "note": sentence + (f"; {flag}" if flag else "")}


def exceedance_from_runs(values: np.ndarray, defined: np.ndarray, thresholds: list[dict],
                         sampling: Independent = Independent(), info: dict | None = None,
                         units: str = "") -> list[dict]:
    """[{above|below, probability, lower, upper, method, flags, note}] over the runs where `defined` (bool (N,),
    design order) holds; `sampling`, `info`: how the design drew its points (analysis.proportions); `units`:
    the quantity's, for the unit-slip flag (`unit_slip`)."""
    found = []
    for item in thresholds:
        (bound, threshold), = item.items()
        beyond = _beyond(values, bound, threshold) & defined
        p = sampling.proportion(beyond, defined, info or {}, CONFIDENCE, event=f"{bound} {threshold:g}")
        slip = unit_slip(values[defined], threshold, units)
        flag = slip or (f"fewer than {RARE_COUNT} runs exceed: a rare-event extrapolation from the runs, run more "
                        "to resolve it (or a rare-event design)" if int(beyond.sum()) < RARE_COUNT else None)
        found.append(exceedance_entry(bound, threshold, p["estimate"], p["lower"], p["upper"], p["method"],
                                      p["sentence"], flag))
    return found


def exceedance_from_pce(draws: np.ndarray, runs: int, thresholds: list[dict], run_values: np.ndarray | None = None,
                        units: str = "") -> list[dict]:
    """[{above|below, probability, lower: None, upper: None, method: "pce", flags, note}] from the PCE's draws;
    `runs`: the runs the expansion was made from (the rare-event flag compares p with 10/runs);
    `run_values`, `units`: those runs' values and unit, for the unit-slip flag (`unit_slip`)."""
    found = []
    for item in thresholds:
        (bound, threshold), = item.items()
        p = float(_beyond(draws, bound, threshold).mean())
        note = (f"fraction of {draws.size} draws of the PCE {bound} {threshold:g}; no interval: the expansion's "
                "error is known in the mean square, not on the individual values a threshold sorts")
        slip = None if run_values is None else unit_slip(run_values, threshold, units)
        flag = slip or (f"p < {RARE_COUNT}/{runs} (fewer than {RARE_COUNT} of the runs' worth): a rare-event "
                        "extrapolation of the expansion's tail" if p < RARE_COUNT / runs else None)
        found.append(exceedance_entry(bound, threshold, p, None, None, "pce", note, flag))
    return found
