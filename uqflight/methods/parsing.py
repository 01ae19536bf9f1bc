"""`KIND[:ORDER[:KEY=VALUE,...]]`, the one way a method is written on the command line (report, surrogate
export, calibrate), with `--order N` as the ORDER of a bare KIND."""
from __future__ import annotations

from . import METHOD_KINDS, Method


def parse_methods(methods: list[str], order: int | None = None) -> list[dict]:
    """`KIND[:ORDER[:KEY=VALUE,...]]` strings into method overrides (KEY one of the kind's settings,
    e.g. `sparse:4:selection=omp,q=0.75`); a bare KIND takes `order` (when given). ValueError naming
    the bad item: an ORDER, written or given, is refused in one sentence."""
    parsed = []
    for text in methods:
        kind, sep, rest = text.partition(":")
        number, more, pairs = rest.partition(":")
        kind = kind.strip()
        if kind not in METHOD_KINDS:
            raise ValueError(f"expected KIND[:ORDER] with KIND one of {', '.join(METHOD_KINDS)}, got {text!r}")
        method = {"kind": kind}
        if sep or order is not None:
            given = repr(text) if sep else f"--order {order}"
            try:
                method["order"] = int(number if sep else order)
            except ValueError:
                method["order"] = -1
            if method["order"] < 0:
                raise ValueError(f"expected an integer ORDER >= 0 after {kind}:, got {given}")
        if more:
            method.update(_settings(Method.of(kind), pairs, text))
        parsed.append(method)
    return parsed


def _settings(entry: Method, pairs: str, text: str) -> dict:
    """The KEY=VALUE,... after KIND:ORDER: as settings of the method (numbers where they parse)."""
    settings = {}
    for pair in pairs.split(","):
        key, equals, value = (part.strip() for part in pair.partition("="))
        if not equals or key not in entry.settings:
            raise ValueError(f"expected KIND:ORDER:KEY=VALUE,... with KEY one of {', '.join(entry.settings) or '(none)'} "
                             f"for {entry.kind}, got {text!r}")
        try:
            settings[key] = float(value)
        except ValueError:
            settings[key] = value
    problem = entry.problem(settings)
    if problem:
        raise ValueError(f"{text!r}: {problem[0]}: {problem[1]}")
    return settings
