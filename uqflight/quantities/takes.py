"""The kinds of `take`: one class each, registered by subclassing `Take` with its name (`REGISTRY`), and the
quantity a take is made of (`QuantitySpec`: what the campaign's `quantities:` states of it, checked by spec.py).

A take over the steps is a reduction fed once per integration step (or per time point of a Python model)
with the step's time and value. Every reduction sees the steps inside its window [after_s, before_s]
(ends included, within WINDOW_SLACK_S); one that sees no step, or whose condition never holds, is
undefined (NaN). A mode of the linearised model (`Mode`) is read once at the level-flight trim point
instead (modes.py). A new take is a class here and a line in docs/quantities.md.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

from ..text.labels import name_unit

NAN = float("nan")
WINDOW_SLACK_S = 1e-9  # a step's time and a window's end written in decimal differ by rounding only
WINDOW = ("after_s", "before_s")

REGISTRY: dict[str, type[Take]] = {}  # every take by its name, in the order the classes are defined


@dataclass(frozen=True)
class When:
    """The event of a quantity's `when:`: the first step where `of` is above (or below) `threshold`.

    Parameters
    ----------
    of : str
        The output or property whose crossing is the event.
    side : str
        "above" or "below", the key the threshold was written under.
    threshold : float
        The value `of` crosses.

    Examples
    --------
    >>> When("alpha_deg", "above", 3.0).side
    'above'
    """

    of: str
    side: str
    threshold: float


@dataclass(frozen=True)
class QuantitySpec:
    """One quantity of the campaign's `quantities:` as the validator (spec.py) checked it: the keys it was
    written with (an absent key is None), which its take's reduction reads.

    Parameters
    ----------
    name : str
        The quantity's name, its key under `quantities:` (stored in /quantities/NAME).
    take : str
        The take's kind (`entry` is its class).
    of : str or None
        The output or property taken.
    at_s : float or None
        `at`'s time [s].
    when : When or None
        `at_first`'s and `time_of_first`'s event.
    after_s, before_s : float or None
        The window's ends [s]; None: the flight's.

    Examples
    --------
    >>> spec = QuantitySpec("touchdown", "at_first", of="h_ft", when=When("alpha_deg", "below", 2.0))
    >>> spec.entry.name, spec.entry.required, spec.at_s
    ('at_first', ('of', 'when'), None)
    >>> spec.unit({"h_ft": "ft"}), QuantitySpec("t", "time_of_first", when=spec.when).unit({})
    ('ft', 's')
    """

    name: str
    take: str
    of: str | None = None
    at_s: float | None = None
    when: When | None = None
    after_s: float | None = None
    before_s: float | None = None

    @property
    def entry(self) -> type[Take]:
        """The take's class (`REGISTRY[take]`): its keys, its unit and its reduction over the steps."""
        return REGISTRY[self.take]

    def unit(self, output_units: dict[str, str]) -> str:
        """The quantity's unit: its take's own (`Take.unit`: time_of_first s, a damping -, a frequency rad/s),
        else its `of`'s.

        Parameters
        ----------
        output_units : dict of str to str
            The units of the outputs by name; an `of` not among them: the unit its name ends in.

        Returns
        -------
        str
            The unit, "" when unknown.
        """
        if self.entry.unit is not None:
            return self.entry.unit
        if self.of is None:
            return ""
        return output_units.get(self.of) or name_unit(self.of)


class Take:
    """A `take`: what one quantity of interest takes of a flight.

    A subclass registers itself under its name, `class Max(Take, name="max")`, and says which keys it
    requires (`required`), whether it takes the window keys (`windowed`), its own unit where it is not
    its `of`'s (`unit`) and a small `example` (tests); its docstring's first paragraph describes it in
    the campaign-key reference. A reduction is made of the quantity's `QuantitySpec` and reads its keys
    as the spec's attributes.

    Examples
    --------
    >>> REGISTRY["max"].required, REGISTRY["max"].windowed, REGISTRY["max"].mode
    (('of',), True, False)
    >>> reduction = REGISTRY["max"](QuantitySpec("peak_h", "max", of="h_ft", after_s=1.0))
    >>> for t, x in [(0.0, 9.0), (1.0, 2.0), (2.0, 5.0)]:
    ...     reduction.step(t, x, NAN)
    >>> reduction.result()
    5.0
    """

    name: ClassVar[str]
    required: ClassVar[tuple[str, ...]] = ("of",)
    windowed: ClassVar[bool] = True  # takes after_s and before_s
    mode: ClassVar[bool] = False  # a mode of the linearised model at the trim point, not a reduction
    unit: ClassVar[str | None] = None  # its own unit; None: its `of`'s (QuantitySpec.unit)
    example: ClassVar[dict]

    def __init_subclass__(cls, name: str | None = None, **kwargs):
        super().__init_subclass__(**kwargs)
        if name is not None:
            cls.name = name
            REGISTRY[name] = cls

    def __init__(self, spec: QuantitySpec):
        self.after = (-math.inf if spec.after_s is None else spec.after_s) - WINDOW_SLACK_S
        self.before = (math.inf if spec.before_s is None else spec.before_s) + WINDOW_SLACK_S
        self.reset()

    def reset(self) -> None:
        self.value = NAN

    def step(self, t: float, x: float, y: float) -> None:
        """`x`: the value of `of`; `y`: the value of `when.of` (NaN without a condition)."""
        if self.after <= t <= self.before:
            self.update(t, x, y)

    def update(self, t: float, x: float, y: float) -> None:
        raise NotImplementedError

    def result(self) -> float:
        return self.value


class Max(Take, name="max"):
    """The largest value over the steps in the window.

    Examples
    --------
    The window ends at before_s = 2: the 9.0 at t = 3 is not seen.

    >>> reduction = REGISTRY["max"](QuantitySpec("peak_h", "max", of="h_ft", before_s=2.0))
    >>> for t, x in [(0.0, 1.0), (1.0, 7.0), (2.0, 4.0), (3.0, 9.0)]:
    ...     reduction.step(t, x, NAN)
    >>> reduction.result()
    7.0
    """

    example = {"of": "h_ft", "take": "max"}

    def update(self, t, x, y):
        if not x <= self.value:  # NaN at first
            self.value = x


class Min(Take, name="min"):
    """The smallest value over the steps in the window.

    Examples
    --------
    The window starts at after_s = 1: the −5.0 at t = 0 is not seen.

    >>> reduction = REGISTRY["min"](QuantitySpec("lowest_h", "min", of="h_ft", after_s=1.0))
    >>> for t, x in [(0.0, -5.0), (1.0, 3.0), (2.0, 1.0), (3.0, 2.0)]:
    ...     reduction.step(t, x, NAN)
    >>> reduction.result()
    1.0
    """

    example = {"of": "h_ft", "take": "min"}

    def update(self, t, x, y):
        if not x >= self.value:
            self.value = x


class Final(Take, name="final"):
    """The last step's value.

    Examples
    --------
    The last step inside the window (before_s = 1.5), not the run's last:

    >>> reduction = REGISTRY["final"](QuantitySpec("final_h", "final", of="h_ft", before_s=1.5))
    >>> for t, x in [(0.0, 1.0), (1.0, 2.0), (2.0, 3.0)]:
    ...     reduction.step(t, x, NAN)
    >>> reduction.result()
    2.0
    """

    example = {"of": "h_ft", "take": "final"}

    def update(self, t, x, y):
        self.value = x


class Drop(Take, name="drop"):
    """How far `of` falls below its value at the window's first step (first − min, 0 if it never falls):
    `{of: h_ft, take: drop}` is an altitude loss.

    Examples
    --------
    From 100 at the window's first step (after_s = 1) down to 85 at the lowest: 15; the 120 at t = 0 is
    outside the window.

    >>> reduction = REGISTRY["drop"](QuantitySpec("altitude_loss", "drop", of="h_ft", after_s=1.0))
    >>> for t, x in [(0.0, 120.0), (1.0, 100.0), (2.0, 85.0), (3.0, 95.0)]:
    ...     reduction.step(t, x, NAN)
    >>> reduction.result()
    15.0
    """

    example = {"of": "h_ft", "take": "drop"}

    def reset(self):
        self.value = self.first = NAN

    def update(self, t, x, y):
        if self.first != self.first:  # the window's first step
            self.first, self.value = x, 0.0
        elif self.first - x > self.value:
            self.value = self.first - x


class Change(Take, name="change"):
    """The last step's value minus the window's first (last − first): `{of: attitude/psi-deg, take: change}`
    is the heading change of a turn, continuous across 360° (an angle `of` is unwrapped along the run).

    Examples
    --------
    A heading from 350° to 370° as the recorder feeds it, unwrapped (recorder.py), for the 350° → 10° it
    reads: a change of +20, not −340.

    >>> reduction = REGISTRY["change"](QuantitySpec("heading_change", "change", of="attitude/psi-deg"))
    >>> for t, x in [(0.0, 350.0), (1.0, 362.0), (2.0, 370.0)]:
    ...     reduction.step(t, x, NAN)
    >>> reduction.result()
    20.0
    """

    example = {"of": "h_ft", "take": "change"}

    def reset(self):
        self.value = self.first = NAN

    def update(self, t, x, y):
        if self.first != self.first:
            self.first = x
        self.value = x - self.first


class Mean(Take, name="mean"):
    """Time average of `of` by the trapezoid rule over the window, ∫of dt / (t_last − t_first) (a window holding
    one step: that step's value).

    Examples
    --------
    Steps 0, 4, 4 at t = 0, 2, 4: the trapezoids 0.5·2·(0 + 4) + 0.5·2·(4 + 4) = 12 over 4 s give 3.0
    (the mean of the samples would be 8/3).

    >>> reduction = REGISTRY["mean"](QuantitySpec("mean_h", "mean", of="h_ft"))
    >>> for t, x in [(0.0, 0.0), (2.0, 4.0), (4.0, 4.0)]:
    ...     reduction.step(t, x, NAN)
    >>> reduction.result()
    3.0
    """

    example = {"of": "h_ft", "take": "mean", "after_s": 10.0}

    def reset(self):
        self.first = self.last = self.previous = NAN
        self.area = 0.0

    def update(self, t, x, y):
        if self.last == self.last:  # not the first step
            self.area += 0.5 * (t - self.last) * (x + self.previous)
        else:
            self.first = t
        self.last, self.previous = t, x

    def result(self):
        if self.last != self.last:
            return NAN
        span = self.last - self.first
        return self.previous if span == 0 else self.area / span


class At(Take, name="at"):
    """Linear interpolation at `at_s` between the two steps around it (exact at a step's time).

    Examples
    --------
    at_s = 1.5 lies halfway between the steps (1, 10) and (2, 30): 10 + 0.5·(30 − 10) = 20, not the
    nearest step's value.

    >>> reduction = REGISTRY["at"](QuantitySpec("h_at", "at", of="h_ft", at_s=1.5))
    >>> for t, x in [(0.0, 0.0), (1.0, 10.0), (2.0, 30.0), (3.0, 100.0)]:
    ...     reduction.step(t, x, NAN)
    >>> reduction.result()
    20.0
    """

    required = ("of", "at_s")
    windowed = False
    example = {"of": "h_ft", "take": "at", "at_s": 20.0}

    def __init__(self, spec: QuantitySpec):
        self.at = spec.at_s
        super().__init__(spec)

    def reset(self):
        self.value, self.last, self.previous = NAN, NAN, NAN

    def update(self, t, x, y):
        if self.value == self.value:
            return
        if abs(t - self.at) <= WINDOW_SLACK_S:
            self.value = x
        elif t > self.at and self.last == self.last:
            share = (self.at - self.last) / (t - self.last)
            self.value = self.previous + share * (x - self.previous)
        self.last, self.previous = t, x


class AtFirst(Take, name="at_first"):
    """The value of `of` at the first step meeting `when`, no interpolation: the touchdown sink rate `{of:
    velocities/h-dot-fps, take: at_first, when: {of: "gear/unit[1]/WOW", above: 0.5}}`.

    Examples
    --------
    `when.of` (the third argument of `step`) first exceeds 3.0 at t = 1, where `of` is 90:

    >>> spec = QuantitySpec("h_at_stall", "at_first", of="h_ft", when=When("alpha_deg", "above", 3.0))
    >>> reduction = REGISTRY["at_first"](spec)
    >>> for t, x, y in [(0.0, 100.0, 1.0), (1.0, 90.0, 4.0), (2.0, 80.0, 5.0)]:
    ...     reduction.step(t, x, y)
    >>> reduction.result()
    90.0
    """

    required = ("of", "when")
    example = {"of": "h_ft", "take": "at_first", "when": {"of": "alpha_deg", "above": 3.0}}

    def __init__(self, spec: QuantitySpec, time: bool = False):
        self.above = spec.when.side == "above"
        self.threshold = spec.when.threshold
        self.time = time
        super().__init__(spec)

    def update(self, t, x, y):
        if self.value == self.value:
            return
        if (y > self.threshold) if self.above else (y < self.threshold):
            self.value = t if self.time else x


class TimeOfFirst(AtFirst, name="time_of_first"):
    """The time of the first step meeting `when`.

    Examples
    --------
    `when.of` first falls below 2.0 at the step t = 2 (the step's time, not an interpolated crossing):

    >>> spec = QuantitySpec("t_low_alpha", "time_of_first", when=When("alpha_deg", "below", 2.0))
    >>> reduction = REGISTRY["time_of_first"](spec)
    >>> for t, y in [(0.0, 5.0), (1.0, 3.0), (2.0, 1.5), (3.0, 1.0)]:
    ...     reduction.step(t, NAN, y)
    >>> reduction.result()
    2.0
    """

    required = ("when",)
    unit = "s"
    example = {"take": "time_of_first", "when": {"of": "alpha_deg", "below": 2.0}}

    def __init__(self, spec: QuantitySpec):
        super().__init__(spec, time=True)


class Mode(Take):
    """A mode of JSBSim's linearised model at the level-flight trim point (modes.py), read once per run
    by the recorder: no reduction over the steps, no key but `take`.

    Examples
    --------
    `classified_modes` (modes.py: the recorder's `eigen_modes` applies it to JSBSim's linearisation) on a
    block-diagonal matrix: −0.03 ± 0.04i on (Vt, Theta) is a phugoid (ζ = 0.03/0.05 = 0.6, period
    2π/0.04 s), −4 ± 3i on (Alpha, Q) a short period (ω = |λ| = 5 rad/s, ζ = 4/5 = 0.8).

    >>> import numpy as np
    >>> from uqflight.quantities.modes import classified_modes
    >>> system = np.array([[-0.03, 0.04, 0, 0], [-0.04, -0.03, 0, 0], [0, 0, -4, 3], [0, 0, -3, -4]])
    >>> modes = classified_modes(["Vt", "Theta", "Alpha", "Q"], system, np.array([100.0, 0, 0, 0]))
    >>> round(modes["phugoid_period_s"], 6), round(2 * math.pi / 0.04, 6)
    (157.079633, 157.079633)
    >>> round(modes["phugoid_damping"], 6), round(modes["short_period_frequency_rad_s"], 6)
    (0.6, 5.0)
    >>> round(modes["short_period_damping"], 6)
    0.8
    """

    required = ()
    windowed = False
    mode = True

    def __init_subclass__(cls, name: str | None = None, **kwargs):
        super().__init_subclass__(name=name, **kwargs)
        cls.example = {"take": name}  # a mode takes no key but its name


class PhugoidPeriod(Mode, name="phugoid_period_s"):
    """The phugoid's damped period 2π/Im λ [s] of JSBSim's linearised model at the level-flight trim.

    Examples
    --------
    Its value on a known matrix is in `Mode`'s example.

    >>> PhugoidPeriod.mode, PhugoidPeriod.required, PhugoidPeriod.unit
    (True, (), 's')
    """

    unit = "s"


class PhugoidDamping(Mode, name="phugoid_damping"):
    """The phugoid's damping ratio −Re λ/|λ| at the level-flight trim.

    Examples
    --------
    Its value on a known matrix is in `Mode`'s example.

    >>> PhugoidDamping.mode, PhugoidDamping.required, PhugoidDamping.unit
    (True, (), '-')
    """

    unit = "-"


class ShortPeriodFrequency(Mode, name="short_period_frequency_rad_s"):
    """The short period's natural frequency |λ| [rad/s] at the level-flight trim.

    Examples
    --------
    Its value on a known matrix is in `Mode`'s example.

    >>> ShortPeriodFrequency.mode, ShortPeriodFrequency.required, ShortPeriodFrequency.unit
    (True, (), 'rad/s')
    """

    unit = "rad/s"


class ShortPeriodDamping(Mode, name="short_period_damping"):
    """The short period's damping ratio at the level-flight trim.

    Examples
    --------
    Its value on a known matrix is in `Mode`'s example.

    >>> ShortPeriodDamping.mode, ShortPeriodDamping.required, ShortPeriodDamping.unit
    (True, (), '-')
    """

    unit = "-"
