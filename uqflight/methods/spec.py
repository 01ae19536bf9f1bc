"""A campaign's `method:` as a typed, frozen value (`MethodSpec`): built by the campaign's validator
(`campaign.schema.method`), by `--method KIND[:ORDER]` (`methods.parsing`) and from a results file's record."""
from __future__ import annotations

from dataclasses import dataclass, field

from .kind import DEFAULT_ORDER, Method


@dataclass(frozen=True)
class MethodSpec:
    """A method and its keys of `method:`, checked.

    Parameters
    ----------
    kind : str
        The method kind (`Method.of(kind)` is its class: `entry`).
    order : int or None
        The PCE's total degree, whatever the kind's order key is called in YAML (sparse: `max_order`); None
        until the design resolves it (`plan`: the largest a grid's projection allows).
    split : bool
        The split form x = x0 + S of the projections.
    allow_aliasing : bool
        A projection's order may exceed what the grid integrates exactly.
    settings : tuple of (str, object)
        The kind's own keys as written (`Method.settings`, e.g. sparse's selection and q), in its keys' order;
        the others take their defaults at the fit.
    written : tuple of str
        The keys the `method:` mapping holds, in its order (those `as_mapping` states; a resolved order
        follows them). Not compared: two specs are equal when they mean the same method.

    Examples
    --------
    >>> spec = MethodSpec.from_checked({"kind": "sparse", "max_order": 4, "q": 0.75})
    >>> spec.order, spec.settings, spec.entry.order_key, spec.label
    (4, (('q', 0.75),), 'max_order', 'sparse order 4')
    >>> spec.as_mapping()  # the kind's own order key, as the campaign writes it
    {'kind': 'sparse', 'max_order': 4, 'q': 0.75}
    >>> spec.summary()  # "order" first, as summary.json states it
    {'order': 4, 'kind': 'sparse', 'q': 0.75}
    >>> MethodSpec("least_squares", 2).analysed(spec).label  # the campaign's least_squares, analysed as sparse
    'sparse order 4'
    """

    kind: str
    order: int | None = None
    split: bool = False
    allow_aliasing: bool = False
    settings: tuple[tuple[str, object], ...] = ()
    written: tuple[str, ...] = field(default=("kind",), compare=False)

    @classmethod
    def from_checked(cls, mapping: dict) -> MethodSpec:
        """The spec of a `method:` mapping whose keys and values are checked against its kind's `Key`s.

        Parameters
        ----------
        mapping : dict
            `kind` and the kind's keys (`Method.keys`), as `campaign.schema.method` or `--method` checked them.

        Returns
        -------
        MethodSpec
            Its keys as fields, `written` the mapping's keys in order.
        """
        entry = Method.of(mapping["kind"])
        return cls(mapping["kind"], mapping.get(entry.order_key), mapping.get("split", False),
                   mapping.get("allow_aliasing", False),
                   tuple((key, mapping[key]) for key in entry.settings if key in mapping), tuple(mapping))

    @property
    def entry(self) -> Method:
        """The kind's class (`Method.of`): its facts and its fit."""
        return Method.of(self.kind)

    @property
    def label(self) -> str:
        """The method as in the paper's legends, e.g. "PG order 2", "PG order 2 split", "MC"."""
        entry = self.entry
        if not entry.expands:
            return entry.label
        return f"{entry.label} order {self.order}" + (" split" if self.split else "")

    def _value(self, key: str):
        """The value of the `method:` key `key` (the kind's order key: the order)."""
        if key == "kind":
            return self.kind
        if key == self.entry.order_key:
            return self.order
        if key in ("split", "allow_aliasing"):
            return getattr(self, key)
        return dict(self.settings)[key]

    def as_mapping(self) -> dict:
        """The `method:` mapping: its written keys in order, then a resolved order under the kind's order key.

        Returns
        -------
        dict
            What a results file's record stores, e.g. {"kind": "pseudo_galerkin", "split": False, "order": 2}.
        """
        keys = list(self.written)
        if self.order is not None and self.entry.order_key not in keys:
            keys.append(self.entry.order_key)
        return {key: self._value(key) for key in keys}

    def summary(self) -> dict:
        """The method as summary.json, a baseline and a calibration state it: "order" first (whatever the kind's
        order key), then its other keys as `as_mapping` has them.

        Returns
        -------
        dict
            e.g. {"order": 2, "kind": "pseudo_galerkin", "split": False}.
        """
        mapping = self.as_mapping()
        return {"order": mapping.pop(self.entry.order_key, self.order), **mapping}

    def analysed(self, override: MethodSpec | None = None) -> MethodSpec:
        """The method the statistics apply: `override`'s kind, order and written keys over this one's (the
        runs of one campaign serve every method), the keys its kind lacks left out, and an order (DEFAULT_ORDER
        when neither gives one).

        Parameters
        ----------
        override : MethodSpec, optional
            The method asked for instead (`--method`); None: this one.

        Returns
        -------
        MethodSpec
            With an order, and `written` this one's keys that the kind has, then `override`'s.
        """
        override = override or MethodSpec(self.kind)
        keys = override.entry.keys

        def value(key: str):
            for spec in (override, self):
                if key in spec.written:
                    return spec._value(key)
            return keys[key].default

        written = tuple(dict.fromkeys(key for key in (*self.written, *override.written)
                                      if key == "kind" or key in keys))
        order = next((o for o in (override.order, self.order) if o is not None), DEFAULT_ORDER)
        return MethodSpec(override.kind, order, value("split") if "split" in keys else False,
                          value("allow_aliasing") if "allow_aliasing" in keys else False,
                          tuple((key, value(key)) for key in override.entry.settings if key in written), written)
