"""`KIND[:ORDER[:KEY=VALUE,...]]`, the one way a method is written on the command line (report, surrogate
export, calibrate), with `--order N` as the ORDER of a bare KIND."""
from __future__ import annotations

from . import METHOD_KINDS, Method, MethodSpec


def parse_methods(methods: list[str], order: int | None = None) -> list[MethodSpec]:
    """`KIND[:ORDER[:KEY=VALUE,...]]` strings into method overrides (KEY one of the kind's settings,
    e.g. `sparse:4:selection=omp,q=0.75`); a bare KIND takes `order` (when given).

    Parameters
    ----------
    methods : list of str
        The `--method` values.
    order : int, optional
        `--order`: the ORDER of a bare KIND.

    Returns
    -------
    list of MethodSpec
        One per item, its written keys those the item gives (the order under the kind's order key).

    Raises
    ------
    ValueError
        Naming the bad item: an ORDER, written or given, is refused in one sentence.
    """
    parsed = []
    for text in methods:
        kind, sep, rest = text.partition(":")
        number, more, pairs = rest.partition(":")
        kind = kind.strip()
        if kind not in METHOD_KINDS:
            raise ValueError(f"expected KIND[:ORDER] with KIND one of {', '.join(METHOD_KINDS)}, got {text!r}")
        method = {"kind": kind}
        entry = Method.of(kind)
        if sep or order is not None:
            method[entry.order_key] = checked_order(number if sep else order, entry, repr(text) if sep else None)
        if more:
            method.update(_settings(entry, pairs, text))
        parsed.append(MethodSpec.from_checked(method))
    return parsed


def checked_order(value, entry: Method | None = None, text: str | None = None) -> int:
    """An ORDER, written after KIND: (`text`) or given by --order (`value`), as an integer within the order key's
    own bound (sparse's max_order: >= 1; any kind: >= 0); the one ValueError for a bad order otherwise."""
    least = (entry or Method).keys[(entry or Method).order_key].minimum
    try:
        order = int(value)
    except ValueError:
        order = least - 1
    if order < least:
        after = f" after {entry.kind}:" if entry else ""
        raise ValueError(f"expected an integer ORDER >= {least}{after}, got {text or f'--order {value}'}")
    return order


def _settings(entry: Method, pairs: str, text: str) -> dict:
    """The KEY=VALUE,... after KIND:ORDER: as settings of the method (numbers where they parse)."""
    settings = {}
    for pair in pairs.split(","):
        key, equals, value = (part.strip() for part in pair.partition("="))
        if not equals or key not in entry.settings:
            raise ValueError("expected KIND:ORDER:KEY=VALUE,... with KEY one of "
                             f"{', '.join(entry.settings) or '(none)'} for {entry.kind}, got {text!r}")
        try:
            settings[key] = float(value)
        except ValueError:
            settings[key] = value
    problem = entry.problem(settings)
    if problem:
        raise ValueError(f"{text!r}: {problem[0]}: {problem[1]}")
    return settings
