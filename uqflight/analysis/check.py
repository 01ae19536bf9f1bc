"""Baselines of a results file's statistics, and the drift of a recomputation against one.

A baseline (written by `uqflight report --write-baseline`) holds, per output and time and per quantity of
interest, the mean, variance, 99 % band and Sobol' indices of one results file, with that file's campaign
hash (a quantity undefined in every run is null).
`compare` recomputes nothing itself: it takes fresh `Statistics` and lists every value outside
|value − baseline| <= atol + rtol·|baseline| (NaN matches only NaN).
"""
from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..text.bounded import OutsideBounds, read_bounded
from ..text.console import listed
from ..text.console import quoted_name, quoted_value
from ..text.json_text import json_text
from .statistics import BadInput, Statistics, json_ready

BASELINE_KIND = "uqflight-baseline"
BASELINE_VERSION = 1
STATISTICS = ("mean", "variance", "band99.lower", "band99.upper", "sobol_first", "sobol_total")
TIME_ATOL = 1e-9  # seconds: time grids closer than this are the same grid
MAX_BASELINE_BYTES = 128 << 20  # refused before it is read (parsing takes several times as much memory)


@dataclass
class Drift:
    """One value outside its tolerance."""

    output: str
    statistic: str
    time: float
    value: float
    baseline: float
    tolerance: float

    @property
    def excess(self) -> float:
        """|value − baseline| in units of the tolerance (inf for a NaN on one side only)."""
        difference = abs(self.value - self.baseline)
        return difference / self.tolerance if math.isfinite(difference) and self.tolerance > 0 else math.inf


@dataclass
class Comparison:
    compared: int
    drifts: list[Drift]


def _series(entry) -> dict[str, list]:
    """The compared statistics of one output ({statistic: values}) from a baseline entry (dict)."""
    series = {"mean": entry["mean"], "variance": entry["variance"],
              "band99.lower": entry["band99"]["lower"], "band99.upper": entry["band99"]["upper"]}
    for kind in ("sobol_first", "sobol_total"):
        series.update({f"{kind}[{parameter}]": values for parameter, values in entry[kind].items()})
    return series


def _entry(out) -> dict | None:
    """An output's (or quantity's) time grid and compared statistics; None for an undefined quantity."""
    if out is None:
        return None
    return json_ready({"time": out.time, "mean": out.mean, "variance": out.variance,
                       "band99": {"lower": out.band99[0], "upper": out.band99[1]},
                       "sobol_first": out.sobol_first, "sobol_total": out.sobol_total})


def baseline_json(stats: Statistics, campaign_hash: str) -> dict:
    """The baseline of `stats`: per output and quantity its time grid and compared statistics, and the
    campaign hash."""
    return {"kind": BASELINE_KIND, "version": BASELINE_VERSION, "results": stats.path,
            "campaign": stats.campaign_name, "campaign_hash": campaign_hash, "method": stats.method.summary(),
            "outputs": {name: _entry(out) for name, out in stats.outputs.items()},
            "quantities": {name: _entry(quantity.output) for name, quantity in stats.quantities.items()}}


def write_baseline(stats: Statistics, campaign_hash: str, path: Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json_text(baseline_json(stats, campaign_hash)), encoding="utf-8")
    return path


def load_baseline(path: Path) -> dict:
    """A baseline file, checked for shape: BadInput naming the file and the first bad field."""
    path = Path(path)

    def refuse_constant(name):  # Infinity would match anything (|x - inf| <= rtol * inf); NaN matches only NaN
        if name == "NaN":
            return math.nan
        raise BadInput(f"{path}: {name} is not a value a baseline may hold (expected finite numbers, null or NaN)")

    try:
        data = json.loads(read_bounded(path, MAX_BASELINE_BYTES, "a baseline").decode("utf-8"),
                          parse_constant=refuse_constant)
    except OutsideBounds as exc:
        raise BadInput(f"{path}: {exc}; a baseline holds a results file's statistics: write one with "
                       "`uqflight report RESULTS.h5 --out DIR --write-baseline FILE`") from exc
    except OSError as exc:
        raise BadInput(f"{path}: cannot read the baseline ({exc.strerror or exc})") from exc
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise BadInput(f"{path}: not a JSON baseline ({' '.join(str(exc).split())[:200]})") from exc
    except RecursionError as exc:
        raise BadInput(f"{path}: not a baseline (JSON nested too deeply)") from exc
    if not isinstance(data, dict) or data.get("kind") != BASELINE_KIND:
        raise BadInput(f"{path}: not a uqflight baseline (expected a JSON object with \"kind\": \"{BASELINE_KIND}\"; "
                       "write one with `uqflight report RESULTS.h5 --out DIR --write-baseline FILE`)")
    rewrite = "write one with `uqflight report RESULTS.h5 --out DIR --write-baseline FILE`"
    if data.get("version") != BASELINE_VERSION:
        raise BadInput(f"{path}: version: expected {BASELINE_VERSION} (the baselines this uqflight writes), got "
                       f"{quoted_value(data.get('version'))}; {rewrite}")
    if not isinstance(data.get("campaign_hash"), str) or not re.fullmatch(r"[0-9a-f]{64}", data["campaign_hash"]):
        raise BadInput(f"{path}: campaign_hash: expected the sha256 of the campaign the baseline was written from "
                       f"(64 hex digits), got {quoted_value(data.get('campaign_hash'))}: without it, a file of "
                       f"another campaign could pass; {rewrite}")
    outputs = data.get("outputs")
    if not isinstance(outputs, dict) or not outputs:
        raise BadInput(f"{path}: outputs: expected a non-empty mapping of output names to statistics")
    for name, entry in outputs.items():
        _check_entry(f"{path}: outputs.{quoted_name(name)}", entry)
    quantities = data.get("quantities")
    if not isinstance(quantities, dict):
        raise BadInput(f"{path}: quantities: expected a mapping of quantity names to statistics ({{}} without "
                       f"quantities), got {quoted_value(quantities)}; {rewrite}")
    for name, entry in quantities.items():
        if entry is not None:  # undefined in every run
            _check_entry(f"{path}: quantities.{quoted_name(name)}", entry)
    return data


def _check_entry(where: str, entry) -> None:
    if not isinstance(entry, dict):
        raise BadInput(f"{where}: expected a mapping of statistics")
    for key in ("time", "mean", "variance", "band99", "sobol_first", "sobol_total"):
        if key not in entry:
            raise BadInput(f"{where}.{key}: missing")
    for key in ("band99", "sobol_first", "sobol_total"):
        if not isinstance(entry[key], dict):
            raise BadInput(f"{where}.{key}: expected a mapping")
    for key in ("lower", "upper"):
        if key not in entry["band99"]:
            raise BadInput(f"{where}.band99.{key}: missing")
    length = _numbers(f"{where}.time", entry["time"], None)
    for statistic, values in _series(entry).items():
        _numbers(f"{where}.{statistic}", values, length)


def _numbers(where: str, values, length: int | None) -> int:
    """The length of a list of numbers (null stands for NaN), which must be `length` when given."""
    if not isinstance(values, list) or not all(v is None or (isinstance(v, (int, float)) and not isinstance(v, bool))
                                               for v in values):
        raise BadInput(f"{where}: expected a list of numbers")
    if any(v is not None and _infinite(v) for v in values):  # 1e999 parses as inf: it would match anything
        raise BadInput(f"{where}: expected finite numbers (null for undefined), got an infinite value")
    if not values or (length is not None and len(values) != length):
        raise BadInput(f"{where}: expected {length or 'at least one'} values (one per time), got {len(values)}")
    return len(values)


def _infinite(value: int | float) -> bool:
    """Whether a JSON number is beyond every float: inf, or an integer of 400 digits (NaN is not)."""
    try:
        return math.isinf(value)
    except OverflowError:
        return True


def compare(stats: Statistics, baseline: dict, rtol: float, atol: float) -> Comparison:
    """Every value of `stats` against the baseline; BadInput when outputs, time grids or the Sobol'
    parameters differ (then the two describe different things and nothing is compared), or when a
    tolerance is negative or not finite (an infinite tolerance would let anything match)."""
    for label, tol in (("rtol", rtol), ("atol", atol)):
        if not isinstance(tol, (int, float)) or not math.isfinite(tol) or tol < 0:
            raise BadInput(f"{label}: expected a finite number >= 0, got {tol!r}")
    fresh = baseline_json(stats, "")
    compared, drifts = _compare_section("output", fresh["outputs"], baseline["outputs"], rtol, atol)
    counted, more = _compare_section("quantity", fresh["quantities"], baseline["quantities"], rtol, atol)
    return Comparison(compared + counted, drifts + more)


def _compare_section(what: str, fresh: dict, expected: dict, rtol: float, atol: float) -> tuple[int, list[Drift]]:
    """(values compared, drifts) of the outputs or the quantities; a quantity defined on one side only
    drifts in its mean."""
    if set(fresh) != set(expected):
        plural = {"output": "outputs", "quantity": "quantities"}[what]
        raise BadInput(f"the baseline is for {plural} {listed(expected) or '-'}; the results have "
                       f"{listed(fresh) or '-'}")
    label = quoted_name if what == "output" else (lambda name: f"quantity {quoted_name(name)}")
    compared, drifts = 0, []
    for name, entry in expected.items():
        if entry is None or fresh[name] is None:
            if (entry is None) != (fresh[name] is None):
                value, base = (math.nan, 0.0) if entry is not None else (0.0, math.nan)
                drifts.append(Drift(label(name), "mean", 0.0, value, base, 0.0))
            compared += 1
            continue
        time = np.asarray(fresh[name]["time"])
        _check_time_grid(f"{what} {quoted_name(name)}", time, np.asarray(entry["time"], dtype=float))
        values, reference = _series(fresh[name]), _series(entry)
        if set(values) != set(reference):
            only_baseline = listed(sorted(set(reference) - set(values))) or "-"
            only_results = listed(sorted(set(values) - set(reference))) or "-"
            raise BadInput(f"{what} {quoted_name(name)}: the baseline has statistics {only_baseline} that the results "
                           f"lack, the results {only_results} that the baseline lacks (another method or parameters?)")
        for statistic, baseline_values in reference.items():
            value = np.asarray(values[statistic], dtype=float)
            base = np.asarray(baseline_values, dtype=float)
            tolerance = atol + rtol * np.abs(base)
            ok = (np.abs(value - base) <= tolerance) | (np.isnan(value) & np.isnan(base))
            compared += value.size
            drifts += [Drift(label(name), statistic, float(time[i]), float(value[i]), float(base[i]), float(tolerance[i]))
                       for i in np.flatnonzero(~ok)]
    return compared, drifts


def _check_time_grid(name: str, time: np.ndarray, expected: np.ndarray) -> None:
    if time.shape != expected.shape or not np.allclose(time, expected, rtol=0.0, atol=TIME_ATOL):
        raise BadInput(f"{name}: the baseline's time grid ({expected.size} times, {expected[0]:g} to "
                       f"{expected[-1]:g} s) differs from the results' ({time.size} times, {time[0]:g} to "
                       f"{time[-1]:g} s)")


def drift_table(comparison: Comparison, worst: int = 5) -> str:
    """The `worst` drifts of each statistic (mean, variance, band99.lower, band99.upper, sobol_first,
    sobol_total; largest excess over the tolerance first) as a text table, with how many drifted of each."""
    by_statistic: dict[str, list[Drift]] = {statistic: [] for statistic in STATISTICS}
    for drift in comparison.drifts:
        by_statistic[drift.statistic.split("[")[0]].append(drift)
    by_statistic = {statistic: drifts for statistic, drifts in by_statistic.items() if drifts}
    header = ("output", "statistic", "time [s]", "value", "baseline", "|difference|", "tolerance")
    rows = []
    for statistic, drifts in by_statistic.items():
        drifts.sort(key=lambda d: d.excess, reverse=True)
        for d in drifts[:worst]:
            rows.append((d.output, d.statistic, f"{d.time:g}", f"{d.value:.10g}", f"{d.baseline:.10g}",
                         f"{abs(d.value - d.baseline):.3g}", f"{d.tolerance:.3g}"))
        if len(drifts) > worst:
            rows.append(("", f"... {len(drifts) - worst} more {statistic}", "", "", "", "", ""))
    widths = [max(len(row[i]) for row in (header, *rows)) for i in range(len(header))]
    lines = ["  ".join(cell.ljust(width) for cell, width in zip(row, widths)).rstrip() for row in (header, *rows)]
    counts = ", ".join(f"{statistic} {len(drifts)}" for statistic, drifts in by_statistic.items())
    return "\n".join([*lines, f"drifted per statistic: {counts}"])
