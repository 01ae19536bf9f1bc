"""`KIND[:ORDER]`, the one way a method is written on the command line (report, surrogate export, calibrate)."""
from __future__ import annotations

from . import METHOD_KINDS


def parse_methods(methods: list[str], order: int | None = None) -> list[dict]:
    """`KIND[:ORDER]` strings into method overrides; a bare KIND takes `order` (when given).
    ValueError naming the bad item."""
    parsed = []
    for text in methods:
        kind, sep, number = text.partition(":")
        kind = kind.strip()
        if kind not in METHOD_KINDS:
            raise ValueError(f"expected KIND[:ORDER] with KIND one of {', '.join(METHOD_KINDS)}, got {text!r}")
        method = {"kind": kind}
        if sep:
            try:
                method["order"] = int(number)
            except ValueError:
                raise ValueError(f"expected an integer ORDER >= 0 after {kind}:, got {text!r}") from None
            if method["order"] < 0:
                raise ValueError(f"expected an integer ORDER >= 0 after {kind}:, got {text!r}")
        elif order is not None:
            method["order"] = order
        parsed.append(method)
    return parsed
