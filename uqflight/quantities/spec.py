"""The campaign's `quantities:` and `analysis.exceedance:` mappings, checked before anything runs.

Each problem is raised through the campaign's checker (`Checker.fail`), so it names the file and the
field, e.g. `quantities.peak.take: expected one of max, min, ...`.
"""
from __future__ import annotations

import math
import re

from ..simulators.kinds import simulator_entry
from . import REGISTRY, TAKES, WINDOW

KEYS = ("of", "take", "at_s", "when", "after_s", "before_s")
WHEN_KEYS = ("of", "above", "below")
BOUNDS = ("above", "below")
NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]{0,99}")


def flight_span(simulator: dict) -> float | None:
    """The flight's last time [s] when the campaign fixes it (a level flight's duration, a script's end_s or,
    once the script is resolved at plan, its own end), else None (a Python model's time grid: known once a
    run is made)."""
    return simulator_entry(simulator).span(simulator)


def is_level_flight(simulator: dict) -> bool:
    """A JSBSim aircraft trimmed in level flight (its modes are those of that trim)."""
    return simulator_entry(simulator).trims_level(simulator)


def check_quantities(check, value, simulator: dict, aircraft=None) -> dict[str, dict]:
    """The checked `quantities:` mapping {name: spec}; `aircraft` (the `AircraftProperties` of a JSBSim
    aircraft, or None) checks the names in `of:` and `when.of:`."""
    if value is None:
        return {}
    if not isinstance(value, dict) or not value:
        check.fail("quantities", f"expected a mapping of quantity names to {{of, take, ...}}, got {value!r:.60}")
    found = {}
    for name, spec in value.items():
        path = f"quantities.{name}"
        if not isinstance(name, str) or not NAME.fullmatch(name):
            check.fail(path, "expected a name of 1-100 characters among A-Z a-z 0-9 _ . - "
                             "(not starting with . or -)")
        spec = dict(check.mapping(spec, path, KEYS, required=("take",)))
        take = check.string(spec["take"], f"{path}.take", TAKES)
        entry = REGISTRY[take]
        allowed = set(entry.required) | (set(WINDOW) if entry.windowed else set())
        for key in spec:
            if key != "take" and key not in allowed:
                check.fail(f"{path}.{key}", f"has no meaning for take: {take} (it takes "
                                            f"{', '.join(sorted(allowed)) or 'no other key'})")
        for key in entry.required:
            if key not in spec:
                check.fail(f"{path}.{key}", f"is required for take: {take}")
        if entry.mode and not is_level_flight(simulator):
            check.fail(f"{path}.take", f"{take} is a mode of the linearised model at a level-flight trim: it needs "
                                       "a JSBSim simulator with scenario kind level_flight")
        if "of" in spec:
            _source(check, spec["of"], f"{path}.of", simulator, aircraft)
        if "when" in spec:
            when = spec["when"] = dict(check.mapping(spec["when"], f"{path}.when", WHEN_KEYS, required=("of",)))
            _source(check, when["of"], f"{path}.when.of", simulator, aircraft)
            bounds = [key for key in BOUNDS if key in when]
            if len(bounds) != 1:
                check.fail(f"{path}.when", "expected exactly one of above or below (the threshold)")
            check.number(when[bounds[0]], f"{path}.when.{bounds[0]}")
        _times(check, spec, path, flight_span(simulator))
        found[name] = spec
    return found


def _source(check, name, path: str, simulator: dict, aircraft) -> None:
    """An output or property a quantity reads, as the simulator kind knows its names."""
    simulator_entry(simulator).check_source(check, name, path, simulator, aircraft)


def _times(check, spec: dict, path: str, span: float | None) -> None:
    """at_s within the flight, and a window that holds part of it."""
    for key in ("at_s", *WINDOW):
        if key in spec:
            spec[key] = check.number(spec[key], f"{path}.{key}")
            if spec[key] < 0 or (span is not None and spec[key] > span):
                flight = f"[0, {span:g}] s" if span is not None else "t >= 0"
                check.fail(f"{path}.{key}", f"{spec[key]:g} s is outside the flight ({flight})")
    if spec.get("after_s", -math.inf) >= spec.get("before_s", math.inf):
        check.fail(f"{path}.after_s", f"expected after_s < before_s, got {spec['after_s']:g} >= {spec['before_s']:g}")


def check_exceedance(check, value, quantities: dict) -> dict[str, list[dict]]:
    """The checked `analysis.exceedance` mapping {quantity: [{above: X} | {below: Y}, ...]}."""
    if not isinstance(value, dict) or not value:
        check.fail("analysis.exceedance", "expected a mapping of quantity names to lists of {above: X} or "
                                          "{below: Y}")
    found = {}
    for name, thresholds in value.items():
        path = f"analysis.exceedance.{name}"
        if name not in quantities:
            known = ", ".join(quantities) or "none: the campaign has no quantities: mapping"
            check.fail(path, f"expected a quantity of the campaign's quantities: ({known})")
        if not isinstance(thresholds, list) or not thresholds:
            check.fail(path, "expected a list of {above: X} or {below: Y}")
        found[name] = []
        for i, item in enumerate(thresholds):
            item = check.mapping(item, f"{path}[{i}]", BOUNDS)
            if len(item) != 1:
                check.fail(f"{path}[{i}]", "expected exactly one of above or below")
            (bound, threshold), = item.items()
            found[name].append({bound: check.number(threshold, f"{path}[{i}].{bound}")})
    return found


def parse_exceedance_option(texts: list[str]) -> dict[str, list[dict]]:
    """`report --exceedance` values, "NAME>X" (P(NAME > X)) or "NAME<X", into {NAME: [{above: X} | {below: X}]}
    in the order given; ValueError naming the text and what is expected (X a finite number)."""
    import math
    import re

    found: dict[str, list[dict]] = {}
    for text in texts:
        match = re.fullmatch(r"\s*([^<>\s]+)\s*([<>])\s*(\S+)\s*", text)
        try:
            threshold = float(match.group(3)) if match else math.nan
        except ValueError:
            threshold = math.nan
        if match is None or not math.isfinite(threshold):
            raise ValueError(f"expected NAME>X or NAME<X with X a finite number, e.g. peak_nz>3.5, got {text!r}")
        bound = "above" if match.group(2) == ">" else "below"
        found.setdefault(match.group(1), []).append({bound: threshold})
    return found
