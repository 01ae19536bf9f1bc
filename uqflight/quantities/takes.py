"""The kinds of `take`: one class each, registered by subclassing `Take` with its name (`REGISTRY`).

A take over the steps is a reduction fed once per integration step (or per time point of a Python model)
with the step's time and value. Every reduction sees the steps inside its window [after_s, before_s]
(ends included, within WINDOW_SLACK_S); one that sees no step, or whose condition never holds, is
undefined (NaN). A mode of the linearised model (`Mode`) is read once at the level-flight trim point
instead (modes.py). A new take is a class here and a line in docs/quantities.md.
"""
from __future__ import annotations

import math
from typing import ClassVar

NAN = float("nan")
WINDOW_SLACK_S = 1e-9  # a step's time and a window's end written in decimal differ by rounding only
WINDOW = ("after_s", "before_s")

REGISTRY: dict[str, type[Take]] = {}  # every take by its name, in the order the classes are defined


class Take:
    """A `take`: what one quantity of interest takes of a flight.

    A subclass registers itself under its name, `class Max(Take, name="max")`, and says which keys it
    requires (`required`), whether it takes the window keys (`windowed`), its own unit where it is not
    its `of`'s (`unit`) and a small `example` (tests); its docstring's first paragraph describes it in
    the campaign-key reference.

    Examples
    --------
    >>> REGISTRY["max"].required, REGISTRY["max"].windowed, REGISTRY["max"].mode
    (('of',), True, False)
    >>> reduction = REGISTRY["max"]({"of": "h_ft", "take": "max", "after_s": 1.0})
    >>> for t, x in [(0.0, 9.0), (1.0, 2.0), (2.0, 5.0)]:
    ...     reduction.step(t, x, NAN)
    >>> reduction.result()
    5.0
    """

    name: ClassVar[str]
    required: ClassVar[tuple[str, ...]] = ("of",)
    windowed: ClassVar[bool] = True  # takes after_s and before_s
    mode: ClassVar[bool] = False  # a mode of the linearised model at the trim point, not a reduction
    unit: ClassVar[str | None] = None  # its own unit; None: its `of`'s (quantity_unit)
    example: ClassVar[dict]

    def __init_subclass__(cls, name: str | None = None, **kwargs):
        super().__init_subclass__(**kwargs)
        if name is not None:
            cls.name = name
            REGISTRY[name] = cls

    def __init__(self, spec: dict):
        self.after = float(spec.get("after_s", -math.inf)) - WINDOW_SLACK_S
        self.before = float(spec.get("before_s", math.inf)) + WINDOW_SLACK_S
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
    """The largest value over the steps in the window."""

    example = {"of": "h_ft", "take": "max"}

    def update(self, t, x, y):
        if not x <= self.value:  # NaN at first
            self.value = x


class Min(Take, name="min"):
    """The smallest value over the steps in the window."""

    example = {"of": "h_ft", "take": "min"}

    def update(self, t, x, y):
        if not x >= self.value:
            self.value = x


class Final(Take, name="final"):
    """The last step's value."""

    example = {"of": "h_ft", "take": "final"}

    def update(self, t, x, y):
        self.value = x


class Drop(Take, name="drop"):
    """How far `of` falls below its value at the window's first step (first − min, 0 if it never falls):
    `{of: h_ft, take: drop}` is an altitude loss."""

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
    is the heading change of a turn, continuous across 360° (an angle `of` is unwrapped along the run)."""

    example = {"of": "h_ft", "take": "change"}

    def reset(self):
        self.value = self.first = NAN

    def update(self, t, x, y):
        if self.first != self.first:
            self.first = x
        self.value = x - self.first


class Mean(Take, name="mean"):
    """Time average by the trapezoid rule over the window, ∫y dt / (t_last − t_first) (a window holding one
    step: that step's value)."""

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
    """Linear interpolation at `at_s` between the two steps around it (exact at a step's time)."""

    required = ("of", "at_s")
    windowed = False
    example = {"of": "h_ft", "take": "at", "at_s": 20.0}

    def __init__(self, spec: dict):
        self.at = float(spec["at_s"])
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
    velocities/h-dot-fps, take: at_first, when: {of: "gear/unit[1]/WOW", above: 0.5}}`."""

    required = ("of", "when")
    example = {"of": "h_ft", "take": "at_first", "when": {"of": "alpha_deg", "above": 3.0}}

    def __init__(self, spec: dict, time: bool = False):
        when = spec["when"]
        self.above = "above" in when
        self.threshold = float(when["above"] if self.above else when["below"])
        self.time = time
        super().__init__(spec)

    def update(self, t, x, y):
        if self.value == self.value:
            return
        if (y > self.threshold) if self.above else (y < self.threshold):
            self.value = t if self.time else x


class TimeOfFirst(AtFirst, name="time_of_first"):
    """The time of the first step meeting `when`."""

    required = ("when",)
    unit = "s"
    example = {"take": "time_of_first", "when": {"of": "alpha_deg", "below": 2.0}}

    def __init__(self, spec: dict):
        super().__init__(spec, time=True)


class Mode(Take):
    """A mode of JSBSim's linearised model at the level-flight trim point (modes.py), read once per run
    by the recorder: no reduction over the steps, no key but `take`."""

    required = ()
    windowed = False
    mode = True

    def __init_subclass__(cls, name: str | None = None, **kwargs):
        super().__init_subclass__(name=name, **kwargs)
        cls.example = {"take": name}  # a mode takes no key but its name


class PhugoidPeriod(Mode, name="phugoid_period_s"):
    """The phugoid's damped period 2π/Im λ [s] of JSBSim's linearised model at the level-flight trim."""

    unit = "s"


class PhugoidDamping(Mode, name="phugoid_damping"):
    """The phugoid's damping ratio −Re λ/|λ| at the level-flight trim."""

    unit = "-"


class ShortPeriodFrequency(Mode, name="short_period_frequency_rad_s"):
    """The short period's natural frequency |λ| [rad/s] at the level-flight trim."""

    unit = "rad/s"


class ShortPeriodDamping(Mode, name="short_period_damping"):
    """The short period's damping ratio at the level-flight trim."""

    unit = "-"
