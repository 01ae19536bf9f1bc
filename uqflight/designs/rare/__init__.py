"""Rare-event designs: the probability of an event `design.event` (a quantity above or below a threshold),
estimated by an algorithm that adapts its runs to the event round by round.

Kinds (keys in braces; every kind takes `event: {of: QUANTITY, above: X}` or `{of, below: X}` and an
optional `budget`, the most runs):
- subset_simulation {samples_per_level, p0}: Au & Beck's subset simulation, conditional levels by
  Markov chains in standard-normal space (`subset`).
- importance_sampling {samples}: adaptive importance sampling, `samples` runs per round (`importance`).
- active_learning {}: a Gaussian-process surrogate learnt where the event's boundary lies, then an
  importance-sampling correction on true runs (`active`).

The algorithms (`subset`, `importance`, `active`, `estimate`) work in standard-normal space u and call
`evaluate(u)` once per round with the whole round's points; this module checks the `design:` mapping (its
kinds' `settings`, once, into the campaign's `DesignSpec`), maps u to the germs ξ (each germ's `from_normal`)
and gives the first round's points (the design the results file is created with). The runner
(`uqflight.running.rare_rounds`) replays the algorithm over the stored runs. The runs of such a design are
not draws of the input law: the analysis gives the event's probability and refuses every other statistic
(`uqflight.analysis.rare_statistics`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...parameters.germs import GERMS
from ..base import REQUIRED, DesignKind, Key, count, number
from ..spec import DesignSpec
from ...text import FieldError

SIDES = ("above", "below")
EVENT_KEYS = ("of", *SIDES)
SHARED_KEYS = ("event", "budget")  # every rare-event kind's keys; the others are its algorithm's
@dataclass(frozen=True)
class Event:
    """The event whose probability is estimated: quantity `of` above (or below) `threshold`."""

    of: str
    side: str  # "above" or "below"
    threshold: float

    def margin(self, values: np.ndarray) -> np.ndarray:
        """g = q − X (above) or X − q (below): the event is g > 0; NaN stays NaN (no value)."""
        values = np.asarray(values, dtype=float)
        return values - self.threshold if self.side == "above" else self.threshold - values

    def text(self) -> str:
        return f"{self.of} {'>' if self.side == 'above' else '<'} {self.threshold:g}"


def _event(value) -> Event:
    if not isinstance(value, dict):
        raise FieldError("design.event", f"expected a mapping {{of: QUANTITY, above: X}} or {{of: QUANTITY, below: X}}, "
                         f"got {value!r}")
    for key in value:
        if key not in EVENT_KEYS:
            raise FieldError(f"design.event.{key}", "unknown key; expected one of of, above, below")
    of = value.get("of")
    if not isinstance(of, str) or not of:
        raise FieldError("design.event.of", f"expected the name of one of the campaign's quantities, got {of!r}")
    sides = [side for side in SIDES if side in value]
    if len(sides) != 1:
        raise FieldError("design.event", "expected exactly one of above or below (the threshold), got "
                         f"{' and '.join(sides) or 'neither'}")
    threshold = value[sides[0]]
    if isinstance(threshold, bool) or not isinstance(threshold, (int, float)) or not math.isfinite(threshold):
        raise FieldError(f"design.event.{sides[0]}", f"expected a finite number, got {threshold!r}")
    return Event(of, sides[0], float(threshold))


def algorithm_settings(settings) -> dict:
    """The algorithm's own keys that a rare-event design gives, from its checked `settings` (`DesignSpec.settings`
    or what its kind's `settings` returns): every key but the event and the budget whose value is given (the
    algorithm's defaults hold for the others)."""
    return {key: value for key, value in dict(settings).items() if key not in SHARED_KEYS and value is not None}


def run_algorithm(spec: DesignSpec, evaluate, dimension: int, seed: int, redrawn=()):
    """The algorithm's RareEventEstimate of a rare-event design's `spec`: `evaluate(u)` (n, d) -> margins (n,)
    is called once per round."""
    return spec.entry.algorithm()(evaluate, dimension, seed=int(seed), budget=spec["budget"],
                                  redrawn=tuple(int(k) for k in redrawn), **algorithm_settings(spec.settings))


def germs_from_normal(u: np.ndarray, germs: list[str]) -> np.ndarray:
    """ξ (n, d) of standard normals u (n, d): column k through germ k's `from_normal` (the Nataf map)."""
    u = np.asarray(u, dtype=float)
    if u.ndim != 2 or u.shape[1] != len(germs):
        raise ValueError(f"expected points of shape (n, {len(germs)}), got {u.shape}")
    xi = np.empty_like(u)
    for k, germ in enumerate(germs):
        xi[:, k] = GERMS[germ].from_normal(u[:, k])
    return xi


class _FirstRound(BaseException):
    """Raised by the first `evaluate` call of `first_round` to stop the algorithm there (a BaseException so
    that no `except Exception` of an algorithm can take it for a failed run)."""

    def __init__(self, u):
        super().__init__("first round")
        self.u = np.array(u, dtype=float)


def first_round(spec: DesignSpec, germs: list[str], seed: int, redrawn=()) -> np.ndarray:
    """The points u (n, d) of the algorithm's first `evaluate` call: a function of the spec and the seed
    alone (the algorithm is stopped there, nothing is run)."""

    def stop(u):
        raise _FirstRound(u)

    try:
        run_algorithm(spec, stop, len(germs), seed, redrawn)
    except _FirstRound as first:
        return first.u
    raise RuntimeError(f"{spec.kind} asked for no run")


MAX_RUNS = 10**8  # a budget beyond this is no rare-event design's (and limits.max_runs bounds it first)
EVENT = Key("an event {of: QUANTITY, above: X} (or below: X) whose probability it estimates", REQUIRED,
            description="Required: the event whose probability is estimated, `{of: QUANTITY, above: X}` or "
                        "`{of: QUANTITY, below: X}`. `event: {of: sink_rate_fps, below: -10}`")


def budget(default: int) -> Key:
    """The most runs of a rare-event design, `default` when not given."""
    return count(1, MAX_RUNS, default, f"The most runs. Default {default} (see [rare events](../rare-events.md)). "
                                       f"`budget: {2 * default}`")


class RareDesign(DesignKind):
    """A rare-event design: the first round of the algorithm's points, mapped to the germs; the runner
    (`uqflight.running.rare_rounds`) adds the other rounds from the results, up to `budget` runs (its kind's default
    budget when not given: what each kind needs, with its other defaults, to come within a factor 2 of the
    exact probability on the issue's closed-form problems, issue 46). The weights are equal and mean nothing:
    the runs are not draws of the input law."""

    sampling = None
    adaptive = rare = True

    def settings(self, spec):
        """Its keys, the `event` parsed into an `Event`, `p0` a float; one round of the algorithm's settings
        within the `budget` (`check_round`)."""
        found = super().settings(spec)
        found["event"] = _event(found["event"])
        if found.get("p0") is not None:
            found["p0"] = float(found["p0"])
        self.check_round(algorithm_settings(found), found["budget"])
        return found

    def size(self, spec, germs):
        """At most `budget`."""
        return spec["budget"]

    def build(self, spec, germs, seed, redrawn=()):
        problem = self.input_problem(spec, len(germs), len(redrawn))
        if problem:
            raise FieldError(*problem)
        xi = germs_from_normal(first_round(spec, germs, seed, redrawn), germs)
        info = {"event": spec["event"].text(), "budget": spec["budget"], **algorithm_settings(spec.settings),
                "rounds": "adapted to the event from the results, up to the budget"}
        return xi, np.full(len(xi), 1.0 / len(xi)), info

    def check_round(self, settings: dict, budget: int) -> None:
        """FieldError naming design.KEY when one round of the algorithm's `settings` does not fit the `budget`."""
        if settings.get("samples", 0) > budget:
            raise FieldError("design.budget", f"{budget} runs cannot hold one round of samples = {settings['samples']}")

    def input_problem(self, spec: DesignSpec, inputs: int, redrawn: int) -> tuple[str, str] | None:
        """(field, message) when the design cannot work on `inputs` parameters of which `redrawn` are seeds
        (`build` raises it as a FieldError)."""
        return None


class SubsetSimulation(RareDesign):
    """Subset simulation (Au & Beck 2001): the event's probability as a product of conditional probabilities
    p0 of nested levels, each level's `samples_per_level` runs grown by Markov chains (adaptive conditional
    sampling) from the p0 share of the runs beyond the previous level, a seed parameter redrawn at each step (keys `event`, `budget`, `samples_per_level`, `p0`).

    Examples
    --------
    >>> import numpy as np
    >>> from uqflight.designs import build_design
    >>> spec = {"kind": "subset_simulation", "event": {"of": "y", "above": 3.0}, "samples_per_level": 100}
    >>> design = build_design(spec, ["normal", "normal"], seed=7)
    >>> design.xi.shape, design.info["event"], design.info["budget"]  # level 0; the default budget
    ((100, 2), 'y > 3', 12000)
    >>> bool((design.xi == np.random.default_rng(7).standard_normal((100, 2))).all())  # draws of N(0, I)
    True
    """

    kind = "subset_simulation"
    keys = {"event": EVENT, "budget": budget(12000),
            "samples_per_level": count(2, MAX_RUNS, None, "Runs per level, >= 2, times p0 at least 1 (the chains). "
                                                          "Default 1000. `samples_per_level: 2000`"),
            "p0": number("a number in (0, 0.5], the conditional probability of each level", lambda v: 0 < v <= 0.5,
                         None, "The conditional probability of each level, in (0, 0.5]. Default 0.1. `p0: 0.1`")}
    example = {"kind": "subset_simulation", "event": {"of": "y", "above": 3.0}, "samples_per_level": 100, "p0": 0.1,
               "budget": 1000}

    @staticmethod
    def algorithm():
        from .subset import subset_simulation
        return subset_simulation

    def check_round(self, settings, budget):
        samples = settings.get("samples_per_level", 1000)
        if math.floor(samples * settings.get("p0", 0.1)) < 1:
            raise FieldError("design.samples_per_level", f"times p0 must give at least one chain (samples_per_level "
                             f"{samples}, p0 {settings.get('p0', 0.1):g})")
        if samples > budget:
            raise FieldError("design.budget", f"{budget} runs cannot hold one level of samples_per_level "
                             f"= {samples}")


class ImportanceSampling(RareDesign):
    """Adaptive importance sampling: a sampling density moved towards the event round by round (`samples`
    runs each), the probability weighted by the input law over that density (keys `event`, `budget`,
    `samples`).

    Examples
    --------
    >>> import numpy as np
    >>> from uqflight.designs import build_design
    >>> spec = {"kind": "importance_sampling", "event": {"of": "y", "below": -2.5}, "samples": 50}
    >>> design = build_design(spec, ["normal", "normal"], seed=7)
    >>> design.xi.shape, design.info["event"], design.info["budget"]  # round 0; the default budget
    ((50, 2), 'y < -2.5', 5000)
    >>> bool((design.xi == np.random.default_rng(7).standard_normal((50, 2))).all())  # draws of N(0, I)
    True
    >>> build_design({**spec, "budget": 40}, ["normal"], seed=7)
    Traceback (most recent call last):
    ...
    uqflight.text.FieldError: design.budget: 40 runs cannot hold one round of samples = 50
    """

    kind = "importance_sampling"
    keys = {"event": EVENT, "budget": budget(5000),
            "samples": count(2, MAX_RUNS, None, "Runs per round, >= 2. Default 500. `samples: 500`")}
    example = {"kind": "importance_sampling", "event": {"of": "y", "above": 3.0}, "samples": 100, "budget": 1000}

    @staticmethod
    def algorithm():
        from .importance import importance_sampling
        return importance_sampling


class ActiveLearning(RareDesign):
    """Active learning: a Gaussian-process surrogate of the event's margin, enriched where the sign is least
    sure, then an importance-sampling correction on true runs that keeps the estimate unbiased where the
    surrogate is wrong (keys `event`, `budget`).

    Examples
    --------
    >>> import numpy as np
    >>> from uqflight.designs import build_design
    >>> spec = {"kind": "active_learning", "event": {"of": "y", "above": 3.0}, "budget": 500}
    >>> xi = build_design(spec, ["normal", "normal"], seed=7).xi
    >>> len(xi)  # the first design: 4k + 12 points for k = 2 inputs
    20
    >>> bool(np.allclose(np.linalg.norm(xi, axis=1), np.linspace(0, 5.5, 20)))  # on spheres of radii 0 … 5.5
    True
    """

    kind = "active_learning"
    keys = {"event": EVENT, "budget": budget(1500)}
    example = {"kind": "active_learning", "event": {"of": "y", "above": 3.0}, "budget": 500}

    @staticmethod
    def algorithm():
        from .active import active_learning
        return active_learning

    def input_problem(self, spec, inputs, redrawn):
        from .active import smallest_budget

        learned = inputs - redrawn
        if learned == 0:
            return ("design.kind", "active_learning learns a surrogate of the inputs that are not seeds, and every "
                                   "parameter here is a seed: use subset_simulation or importance_sampling")
        fewest = smallest_budget(learned)
        if spec["budget"] < fewest:
            return ("design.budget", f"{spec['budget']} runs are too few for active learning on {learned} "
                                     f"input{'s' if learned > 1 else ''}: its first design, one enrichment and two "
                                     f"importance-sampling rounds need at least {fewest}")
        return None


def check_rare_campaign(check, campaign) -> None:
    """What a rare-event design asks of the rest of its campaign (a `campaign.schema.Checker` refuses):
    its event's quantity is one of the campaign's quantities, and no `analysis.exceedance` (its runs are
    not draws of the input law: it estimates its own event only)."""
    spec = campaign.design_spec
    event = spec["event"]
    names = list(campaign.quantities)
    if event.of not in names:
        check.fail("design.event.of", f"expected one of the campaign's quantities ({', '.join(names) or 'none: add '}"
                                       f"{'' if names else 'one under quantities:'}), got {event.of!r}")
    if campaign.analysis.exceedance:
        check.fail("analysis.exceedance", f"a {spec.kind} design's runs are not draws of the input law: it "
                                          "estimates the probability of its design.event only; give the threshold "
                                          "there, one campaign per event")
