"""`simulator.outputs`, the same key for every simulator kind."""
from __future__ import annotations


def check_outputs(check, value) -> list[str]:
    """A non-empty list of unique names (`check` is the campaign's Checker)."""
    if not isinstance(value, list) or not value:
        check.fail("simulator.outputs", f"expected a non-empty list of output names, got {check.shown(value)}")
    for i, item in enumerate(value):
        check.string(item, f"simulator.outputs[{i}]")
    if len(set(value)) != len(value):
        check.fail("simulator.outputs", "names must be unique")
    return value
