"""Quantities of interest: one number per run (a peak, a final value, a value at an event, a mode of
the linearised model), from a campaign's top-level `quantities:` mapping, computed in the worker at
every integration step and stored in /quantities/<NAME> (NaN where undefined in a run).

Kinds of `take` (keys in braces; every one but the modes takes `after_s`/`before_s` too):
- max, min, final, mean, drop, change {of}; at {of, at_s}: see takes.py for exactly what each computes;
- at_first {of, when: {of, above | below}}; time_of_first {when};
- phugoid_period_s, phugoid_damping, short_period_frequency_rad_s, short_period_damping {}: the modes
  of JSBSim's linearised model at the level-flight trim point (modes.py).
"""
from __future__ import annotations

from dataclasses import dataclass

from . import takes


@dataclass(frozen=True)
class TakeKind:
    """A registered `take`: its reduction over the steps (None for a mode of the linearised model,
    read once at the trim point), the keys it requires, and a small example (help text and tests)."""

    reduction: type | None
    required: tuple[str, ...]
    example: dict

    @property
    def mode(self) -> bool:
        return self.reduction is None


WINDOW = ("after_s", "before_s")
REGISTRY: dict[str, TakeKind] = {
    "max": TakeKind(takes.Max, ("of",), {"of": "h_ft", "take": "max"}),
    "min": TakeKind(takes.Min, ("of",), {"of": "h_ft", "take": "min"}),
    "final": TakeKind(takes.Final, ("of",), {"of": "h_ft", "take": "final"}),
    "drop": TakeKind(takes.Drop, ("of",), {"of": "h_ft", "take": "drop"}),
    "change": TakeKind(takes.Change, ("of",), {"of": "h_ft", "take": "change"}),
    "mean": TakeKind(takes.Mean, ("of",), {"of": "h_ft", "take": "mean", "after_s": 10.0}),
    "at": TakeKind(takes.At, ("of", "at_s"), {"of": "h_ft", "take": "at", "at_s": 20.0}),
    "at_first": TakeKind(takes.AtFirst, ("of", "when"),
                         {"of": "h_ft", "take": "at_first", "when": {"of": "alpha_deg", "above": 3.0}}),
    "time_of_first": TakeKind(takes.TimeOfFirst, ("when",),
                              {"take": "time_of_first", "when": {"of": "alpha_deg", "below": 2.0}}),
    "phugoid_period_s": TakeKind(None, (), {"take": "phugoid_period_s"}),
    "phugoid_damping": TakeKind(None, (), {"take": "phugoid_damping"}),
    "short_period_frequency_rad_s": TakeKind(None, (), {"take": "short_period_frequency_rad_s"}),
    "short_period_damping": TakeKind(None, (), {"take": "short_period_damping"}),
}
TAKES = tuple(REGISTRY)


def take_entry(take: str) -> TakeKind:
    return REGISTRY[take]


def quantity_key(name: str) -> tuple[str, str]:
    """The key of a quantity among a chunk's values (output names are strings: no clash)."""
    return ("quantity", name)


def is_quantity_key(key) -> bool:
    return isinstance(key, tuple) and len(key) == 2 and key[0] == "quantity"


__all__ = ["REGISTRY", "TAKES", "TakeKind", "is_quantity_key", "quantity_key", "take_entry"]
