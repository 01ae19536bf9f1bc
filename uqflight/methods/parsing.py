"""`KIND[:ORDER[:KEY=VALUE,...]]`, the one way a method is written on the command line (report, surrogate
export, calibrate)."""
from __future__ import annotations

from . import METHOD_KINDS, method_entry


def parse_methods(methods: list[str], order: int | None = None) -> list[dict]:
    """`KIND[:ORDER[:KEY=VALUE,...]]` strings into method overrides (KEY one of the kind's settings,
    e.g. `sparse:4:selection=omp,q=0.75`); a bare KIND takes `order` (when given). ValueError naming
    the bad item."""
    parsed = []
    for text in methods:
        kind, sep, rest = text.partition(":")
        number, more, pairs = rest.partition(":")
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
        if more:
            method.update(_settings(kind, pairs, text))
        parsed.append(method)
    return parsed


def _settings(kind: str, pairs: str, text: str) -> dict:
    """The KEY=VALUE,... after KIND:ORDER: as settings of `kind` (numbers where they parse)."""
    entry = method_entry(kind)
    known = [key for key, _ in entry.settings]
    settings = {}
    for pair in pairs.split(","):
        key, equals, value = (part.strip() for part in pair.partition("="))
        if not equals or key not in known:
            raise ValueError(f"expected KIND:ORDER:KEY=VALUE,... with KEY one of {', '.join(known) or '(none)'} "
                             f"for {kind}, got {text!r}")
        try:
            settings[key] = float(value)
        except ValueError:
            settings[key] = value
    problem = entry.settings_problem(settings) if entry.settings_problem else None
    if problem:
        raise ValueError(f"{text!r}: {problem[0]}: {problem[1]}")
    return settings
