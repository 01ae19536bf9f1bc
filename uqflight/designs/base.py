"""The design kind's base class: a kind is a subclass with a `kind` name, registered by subclassing."""
from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Integral
from typing import Callable, ClassVar

import numpy as np

from ..analysis.proportions import Independent
from ..text import FieldError

REQUIRED = object()  # a key's default: none, the key must be given


def is_integer(value) -> bool:
    return isinstance(value, Integral) and not isinstance(value, bool)


@dataclass(frozen=True)
class Key:
    """A design key: what it expects (for the refusal), its default (REQUIRED: none; None: absent), its test of
    a given value (None: the kind checks it, an event in its `settings`, a rule against the germs) and its
    meaning for this kind (the campaign-key reference, `campaign.keys`)."""

    expects: str = ""
    default: object = None
    test: Callable | None = None
    description: str = ""


def count(minimum: int, maximum: int | None = None, default=REQUIRED, description: str = "") -> Key:
    """An integer key >= minimum (and <= maximum when given)."""
    top = math.inf if maximum is None else maximum
    return Key(f"an integer >= {minimum}" if maximum is None else f"an integer from {minimum} to {maximum}",
               default, lambda value: is_integer(value) and minimum <= value <= top, description)


def number(expects: str, test: Callable, default=REQUIRED, description: str = "") -> Key:
    """A real-number key that `test` accepts."""
    return Key(expects, default, lambda value: isinstance(value, (int, float)) and not isinstance(value, bool)
               and test(value), description)


def flag(default, description: str = "") -> Key:
    return Key("true or false", default, lambda value: isinstance(value, bool), description)


def choice(choices: tuple[str, ...], default, description: str = "") -> Key:
    return Key(f"one of {', '.join(choices)}", default, lambda value: value in choices, description)


REGISTRY: dict[str, DesignKind] = {}  # kind name -> the kind (its class's one instance)


class DesignKind:
    """A design kind: where the runs are (ξ_j in standard variables) and how each weighs, from a campaign's
    `design:` mapping, and how the runs count for the analysis.

    A kind is a subclass that sets `kind` (its name under `design.kind`, registered in `REGISTRY` on
    subclassing), declares its `keys`, gives an `example` and implements `points`; the class docstring's first
    paragraph is the kind's line in the key reference.

    Attributes
    ----------
    kind : str
        The name a campaign gives.
    keys : dict of str to Key
        Its keys besides `kind`: what each expects, its default, its test and its meaning for this kind.
        `settings` checks a spec on them (once, into a `DesignSpec`) and the key reference lists them with
        their meanings.
    example : dict
        A small `design:` mapping of this kind (help text and tests).
    sampling : analysis.proportions.Independent or None
        How its points were sampled, which says how they count as draws for a proportion's interval; None for
        a grid (its weights hold only all together) and for a rare-event design.
    sampled : bool
        `sampling` is not None: its moments are sample averages, valid on any subset of runs.
    sobol_from_runs : bool
        Its runs give Sobol' indices themselves (pick-freeze estimators), without a PCE.
    adaptive : bool
        `build` gives the first round only; the runner adds the others from the results, up to `size` runs.
    rare : bool
        It estimates the probability of its `event`: its runs are not draws of the input law.
    not_draws : str or None
        The note of a design whose points are not draws of the law.

    Examples
    --------
    >>> from uqflight.designs import REGISTRY, DesignSpec, build_design
    >>> kind = REGISTRY["monte_carlo"]
    >>> kind.settings({"kind": "monte_carlo", "samples": 8})
    {'samples': 8}
    >>> kind.size(DesignSpec.checked({"kind": "monte_carlo", "samples": 8}), ["normal", "uniform"]), kind.sampled
    (8, True)
    >>> build_design(kind.example, ["normal"], seed=1).xi.shape
    (64, 1)
    """

    kind: ClassVar[str]
    keys: ClassVar[dict[str, Key]] = {}
    example: ClassVar[dict]
    sampling: ClassVar[Independent | None] = Independent()
    sampled: ClassVar[bool] = True
    sobol_from_runs: ClassVar[bool] = False
    adaptive: ClassVar[bool] = False
    rare: ClassVar[bool] = False
    not_draws: ClassVar[str | None] = None

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        cls.sampled = cls.sampling is not None
        if "kind" in vars(cls):
            REGISTRY[cls.kind] = cls()

    def settings(self, spec: dict) -> dict:
        """The spec's values of `keys`, checked, defaults filled in: what `DesignSpec.checked` holds. A kind
        with checks across its keys extends it.

        Parameters
        ----------
        spec : dict
            A `design:` mapping of this kind.

        Returns
        -------
        dict
            {key: value} for every declared key.

        Raises
        ------
        FieldError
            Naming `design.KEY` and what was expected.
        """
        for key in spec:
            if key != "kind" and key not in self.keys:
                raise FieldError(f"design.{key}", f"unknown key for kind {self.kind}; accepted keys: "
                                 f"{', '.join(('kind', *self.keys))}")
        found = {}
        for key, declared in self.keys.items():
            if key not in spec and declared.default is REQUIRED:
                raise FieldError(f"design.{key}", f"missing; kind {self.kind} expects {declared.expects}")
            value = spec.get(key, declared.default)
            if key in spec and declared.test is not None and not declared.test(value):
                raise FieldError(f"design.{key}", f"expected {declared.expects}, got {value!r}")
            found[key] = value
        return found

    def size(self, spec, germs: list[str]) -> float:
        """The runs `spec` (a `DesignSpec` of this kind) builds over `germs`, from the spec alone and without
        building anything (for the campaign's limits). Here `samples`."""
        return spec["samples"]

    def build(self, spec, germs: list[str], seed: int, redrawn: tuple[int, ...] = ()) -> tuple:
        """(ξ (N, d), weights (N,), info) of `spec` (a `DesignSpec` of this kind) over `germs`; `redrawn`: the
        columns that are random-stream seeds (a rare-event design's)."""
        return self.points(spec, germs, seed)

    def points(self, spec, germs: list[str], seed: int) -> tuple:
        """(ξ, weights, info) of `spec`."""
        raise NotImplementedError(f"design kind {self.kind} gives no points")

    def info_problem(self, info: dict, runs: int, d: int) -> tuple[str, str] | None:
        """(the key of `info`, what it expects) when a results file's recorded design `info` does not fit its
        `runs` of `d` parameters, for what the analysis reads of it; None when it fits."""
        return None

    # a design whose runs measure each input's importance themselves (Morris): (xi, Y, ok, info, bootstrap, seed,
    # names) -> ({input name: its measures}, note); the measures' name in summary.json and the report
    screening: ClassVar[Callable | None] = None
    screening_name: ClassVar[str | None] = None


def equal_weights(n: int) -> np.ndarray:
    return np.full(n, 1.0 / n)
