"""Quantities of interest: one number per run (a peak, a final value, a value at an event, a mode of
the linearised model), from a campaign's top-level `quantities:` mapping, computed in the worker at
every integration step and stored in /quantities/<NAME> (NaN where undefined in a run).

Kinds of `take` (keys in braces; every one but the modes takes `after_s`/`before_s` too):
- max, min, final, mean, drop, change {of}; at {of, at_s}: see takes.py for exactly what each computes;
- at_first {of, when: {of, above | below}}; time_of_first {when};
- phugoid_period_s, phugoid_damping, short_period_frequency_rad_s, short_period_damping {}: the modes
  of JSBSim's linearised model at the level-flight trim point (modes.py).
Each kind is a class in takes.py, registered by subclassing `Take`; a quantity as the campaign states it is
a typed, frozen `QuantitySpec` (takes.py), built by the validator alone (spec.py) and read by its take.
"""
from __future__ import annotations

from .takes import REGISTRY, WINDOW, QuantitySpec, Take, When

TAKES = tuple(REGISTRY)


def quantity_key(name: str) -> tuple[str, str]:
    """The key of a quantity among a chunk's values (output names are strings: no clash)."""
    return ("quantity", name)


def is_quantity_key(key) -> bool:
    return isinstance(key, tuple) and len(key) == 2 and key[0] == "quantity"


__all__ = ["REGISTRY", "TAKES", "WINDOW", "QuantitySpec", "Take", "When", "is_quantity_key", "quantity_key"]
