"""Quantities of interest: one number per run (a peak, a final value, a value at an event, a mode of
the linearised model), from a campaign's top-level `quantities:` mapping, computed in the worker at
every integration step and stored in /quantities/<NAME> (NaN where undefined in a run).

Kinds of `take` (keys in braces; every one but the modes takes `after_s`/`before_s` too):
- max, min, final, mean, drop, change {of}; at {of, at_s}: see takes.py for exactly what each computes;
- at_first {of, when: {of, above | below}}; time_of_first {when};
- phugoid_period_s, phugoid_damping, short_period_frequency_rad_s, short_period_damping {}: the modes
  of JSBSim's linearised model at the level-flight trim point (modes.py).
Each kind is a class in takes.py, registered by subclassing `Take`.
"""
from __future__ import annotations

from ..text.labels import name_unit
from .takes import REGISTRY, WINDOW, Take

TAKES = tuple(REGISTRY)


def quantity_unit(spec, output_units: dict[str, str]) -> str:
    """The unit of a quantity whose campaign spec is `spec` ({take, of, ...}): its take's own (`Take.unit`:
    time_of_first s, a damping -, a frequency rad/s), else its `of`'s (`output_units`, else from the name);
    "" unknown."""
    if not isinstance(spec, dict) or not isinstance(spec.get("take"), str):
        return ""
    take = REGISTRY.get(spec["take"])
    if take is not None and take.unit is not None:
        return take.unit
    of = spec.get("of")
    if not isinstance(of, str):
        return ""
    return output_units.get(of) or name_unit(of)


def quantity_key(name: str) -> tuple[str, str]:
    """The key of a quantity among a chunk's values (output names are strings: no clash)."""
    return ("quantity", name)


def is_quantity_key(key) -> bool:
    return isinstance(key, tuple) and len(key) == 2 and key[0] == "quantity"


__all__ = ["REGISTRY", "TAKES", "WINDOW", "Take", "is_quantity_key", "quantity_key", "quantity_unit"]
