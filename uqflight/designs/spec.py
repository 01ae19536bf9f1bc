"""A campaign's `design:` as a typed, frozen value (`DesignSpec`), checked once by its kind's `settings`, and the
`Design` it builds over the parameters' germs."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..parameters.germs import check_germs
from ..text import FieldError
from .base import REGISTRY, DesignKind, is_integer


@dataclass
class Design:
    """Where to run the model and how to weigh each run."""

    kind: str
    xi: np.ndarray  # (N, d) standard variables, in the order the runs are made
    weights: np.ndarray  # (N,), summing to 1 for the input distribution; may be negative
    info: dict = field(default_factory=dict)  # facts for people: level, rule, degree, n_base, ...


@dataclass(frozen=True)
class DesignSpec:
    """A design kind and its keys of `design:`, checked by the kind (`DesignKind.settings`).

    Parameters
    ----------
    kind : str
        The design kind (`entry` is its `DesignKind`).
    settings : tuple of (str, object)
        Every key the kind declares, in its keys' order, with its checked value or its default (a rare-event
        kind's `event` parsed into an `Event`); `spec[key]` reads one.

    Examples
    --------
    >>> spec = DesignSpec.checked({"kind": "sobol", "samples": 8})
    >>> spec.settings, spec["replicates"], spec.entry.sampled
    ((('samples', 8), ('scramble', True), ('replicates', 1)), 1, True)
    >>> spec.size(["uniform", "normal"]), spec.build(["uniform", "normal"], seed=0).xi.shape
    (8, (8, 2))
    >>> DesignSpec.checked({"kind": "sobol", "samples": 0})
    Traceback (most recent call last):
    ...
    uqflight.text.FieldError: design.samples: expected an integer >= 1, got 0
    """

    kind: str
    settings: tuple[tuple[str, object], ...]

    @classmethod
    def checked(cls, mapping) -> DesignSpec:
        """The spec of a `design:` mapping as written: the one validator of a design.

        Parameters
        ----------
        mapping : object
            The `design:` value: a mapping with a `kind` and that kind's keys.

        Returns
        -------
        DesignSpec
            Its kind and its kind's `settings`.

        Raises
        ------
        FieldError
            Naming `design`, `design.kind` or `design.KEY` and what was expected.
        """
        if not isinstance(mapping, dict):
            raise FieldError("design", f"expected a mapping with a kind key, got {mapping!r}")
        kind = mapping.get("kind")
        if not isinstance(kind, str) or kind not in REGISTRY:
            raise FieldError("design.kind", f"expected one of {', '.join(REGISTRY)}, got {kind!r}")
        return cls(kind, tuple(REGISTRY[kind].settings(mapping).items()))

    @property
    def entry(self) -> DesignKind:
        """The kind (its class's instance in `REGISTRY`): its facts, its size and its points."""
        return REGISTRY[self.kind]

    def __getitem__(self, key: str):
        return dict(self.settings)[key]

    def get(self, key: str, default=None):
        """The value of `key`, or `default` for a key the kind does not have."""
        return dict(self.settings).get(key, default)

    def size(self, germs: list[str]) -> float:
        """The runs the design builds over `germs`, from the spec alone (`DesignKind.size`).

        Parameters
        ----------
        germs : list of str
            The germ of each dimension.

        Returns
        -------
        float
            The runs, or for an adaptive or rare-event design the most it makes (a grid's may pass any integer).

        Raises
        ------
        FieldError
            Naming `design.KEY` when the spec goes beyond its kind's limit over these germs.
        """
        return self.entry.size(self, germs)

    def build(self, germs: list[str], seed: int, redrawn: tuple[int, ...] = ()) -> Design:
        """The design over `germs`.

        Parameters
        ----------
        germs : list of str
            The germ of each dimension.
        seed : int
            The campaign's seed (>= 0).
        redrawn : tuple of int
            The columns that are random-stream seeds (a rare-event design treats them apart, see designs.rare).

        Returns
        -------
        Design
            Its points ξ (N, d), weights and facts.

        Raises
        ------
        ValueError
            Naming `seed`, `germs` or `design.KEY` (a `FieldError` but for the germs) when the seed or the germs
            are not a campaign's, or the spec does not fit these germs.
        """
        if not is_integer(seed) or seed < 0:
            raise FieldError("seed", f"expected an integer >= 0, got {seed!r}")
        xi, weights, info = self.entry.build(self, check_germs(germs), int(seed), tuple(redrawn))
        return Design(self.kind, xi, weights, info)
