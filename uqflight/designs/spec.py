"""Reading a campaign's `design:` mapping: typed values with errors that name the key."""
from __future__ import annotations

from numbers import Integral


def check_keys(spec: dict, kind: str, accepted: tuple[str, ...]) -> None:
    """Reject keys that the kind does not know (typos would otherwise be silently ignored)."""
    allowed = ("kind", *accepted)
    for key in spec:
        if key not in allowed:
            raise ValueError(
                f"design.{key}: unknown key for kind {kind}; accepted keys: {', '.join(allowed)}"
            )


def is_integer(value) -> bool:
    return isinstance(value, Integral) and not isinstance(value, bool)


def integer(spec: dict, key: str, kind: str, minimum: int) -> int:
    """The required integer spec[key] >= minimum."""
    expected = f"an integer >= {minimum}"
    if key not in spec:
        raise ValueError(f"design.{key}: missing; kind {kind} expects {expected}")
    value = spec[key]
    if not is_integer(value) or value < minimum:
        raise ValueError(f"design.{key}: expected {expected}, got {value!r}")
    return int(value)


def given_count(spec: dict, key: str) -> int | None:
    """spec[key] when it is an integer >= 1, else None (the builder's own checks then speak)."""
    value = spec.get(key)
    return value if is_integer(value) and value >= 1 else None


def optional_boolean(spec: dict, key: str, default: bool | None) -> bool | None:
    if key not in spec:
        return default
    value = spec[key]
    if not isinstance(value, bool):
        raise ValueError(f"design.{key}: expected true or false, got {value!r}")
    return value


def optional_choice(spec: dict, key: str, choices: tuple[str, ...]) -> str | None:
    if key not in spec:
        return None
    value = spec[key]
    if value not in choices:
        raise ValueError(f"design.{key}: expected one of {', '.join(choices)}, got {value!r}")
    return value
