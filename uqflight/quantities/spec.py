"""The campaign's `quantities:` and `analysis.exceedance:` mappings, checked before anything runs: each quantity
into the typed, frozen value its take reads (`QuantitySpec`), built here alone (`check_quantities`).

Each problem is raised through the campaign's checker (`Checker.fail`), so it names the file and the
field, e.g. `quantities.peak.take: expected one of max, min, ...`.
"""
from __future__ import annotations

import math
import re

from ..simulators.spec import SimulatorSpec
from . import REGISTRY, TAKES, WINDOW, QuantitySpec, When

KEYS = ("of", "take", "at_s", "when", "after_s", "before_s")
WHEN_KEYS = ("of", "above", "below")
BOUNDS = ("above", "below")
NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]{0,99}")


def flight_span(simulator: SimulatorSpec) -> float | None:
    """The flight's last time [s] when the campaign fixes it (a level flight's duration, a script's end_s or,
    once the script is resolved at plan, its own end), else None (a Python model's time grid: known once a
    run is made)."""
    return simulator.entry.span(simulator)


def is_level_flight(simulator: SimulatorSpec) -> bool:
    """A JSBSim aircraft trimmed in level flight (its modes are those of that trim)."""
    return simulator.entry.trims_level(simulator)


def check_quantities(check, value, simulator: SimulatorSpec, aircraft=None) -> dict[str, QuantitySpec]:
    """The campaign's quantities, from its `quantities:` mapping checked.

    Parameters
    ----------
    check : Checker
        The campaign's checker: its `fail` names the file and the field.
    value : object
        The `quantities:` mapping as written; None: the campaign has none.
    simulator : SimulatorSpec
        The checked `simulator:`: its kind knows the names `of:` and `when.of:` may give, and the flight's span.
    aircraft : AircraftProperties, optional
        A JSBSim aircraft's properties, which check the names in `of:` and `when.of:`; None: not checked.

    Returns
    -------
    dict of str to QuantitySpec
        Every quantity by name, in the mapping's order.

    Raises
    ------
    CampaignError
        Through `check.fail`: `quantities.NAME.KEY: ...`, naming the file.
    """
    if value is None:
        return {}
    if not isinstance(value, dict) or not value:
        check.fail("quantities", f"expected a mapping of quantity names to {{of, take, ...}}, got {value!r:.60}")
    found = {}
    for name, given in value.items():
        path = f"quantities.{name}"
        if not isinstance(name, str) or not NAME.fullmatch(name):
            check.fail(path, "expected a name of 1-100 characters among A-Z a-z 0-9 _ . - "
                             "(not starting with . or -)")
        given = check.mapping(given, path, KEYS, required=("take",))
        take = check.string(given["take"], f"{path}.take", TAKES)
        entry = REGISTRY[take]
        allowed = set(entry.required) | (set(WINDOW) if entry.windowed else set())
        for key in given:
            if key != "take" and key not in allowed:
                check.fail(f"{path}.{key}", f"has no meaning for take: {take} (it takes "
                                            f"{', '.join(sorted(allowed)) or 'no other key'})")
        for key in entry.required:
            if key not in given:
                check.fail(f"{path}.{key}", f"is required for take: {take}")
        if entry.mode and not is_level_flight(simulator):
            check.fail(f"{path}.take", f"{take} is a mode of the linearised model at a level-flight trim: it needs "
                                       "a JSBSim simulator with scenario kind level_flight")
        if "of" in given:
            _source(check, given["of"], f"{path}.of", simulator, aircraft)
        when = _when(check, given["when"], f"{path}.when", simulator, aircraft) if "when" in given else None
        times = _times(check, given, path, flight_span(simulator))
        found[name] = QuantitySpec(name, take, given.get("of"), when=when, **times)
    return found


def _source(check, name, path: str, simulator: dict, aircraft) -> None:
    """An output or property a quantity reads, as the simulator kind knows its names."""
    simulator.entry.check_source(check, name, path, simulator, aircraft)


def _when(check, given, path: str, simulator: dict, aircraft) -> When:
    """The event of a `when:` mapping as written: its `of` a name the simulator records, one threshold."""
    given = check.mapping(given, path, WHEN_KEYS, required=("of",))
    _source(check, given["of"], f"{path}.of", simulator, aircraft)
    bounds = [key for key in BOUNDS if key in given]
    if len(bounds) != 1:
        check.fail(path, "expected exactly one of above or below (the threshold)")
    return When(given["of"], bounds[0], check.number(given[bounds[0]], f"{path}.{bounds[0]}"))


def _times(check, given: dict, path: str, span: float | None) -> dict[str, float]:
    """The times a quantity's mapping gives ({at_s, after_s, before_s} as far as written), each within the
    flight, and a window that holds part of it."""
    times = {}
    for key in ("at_s", *WINDOW):
        if key in given:
            time = times[key] = check.number(given[key], f"{path}.{key}")
            if time < 0 or (span is not None and time > span):
                flight = f"[0, {span:g}] s" if span is not None else "t >= 0"
                check.fail(f"{path}.{key}", f"{time:g} s is outside the flight ({flight})")
    if times.get("after_s", -math.inf) >= times.get("before_s", math.inf):
        check.fail(f"{path}.after_s", f"expected after_s < before_s, got {times['after_s']:g} >= {times['before_s']:g}")
    return times


def check_exceedance(check, value, quantities: dict[str, QuantitySpec]) -> dict[str, list[dict]]:
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
