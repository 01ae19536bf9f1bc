"""The reductions a quantity of interest takes over one flight, one class per `take`, fed once per
integration step (or per time point of a Python model) with the step's time and value.

Every reduction sees the steps inside its window [after_s, before_s] (ends included, within
WINDOW_SLACK_S); one that sees no step, or whose condition never holds, is undefined (NaN):
* max, min: over the steps; final: the value at the last step; drop: how far the value falls below
  its value at the window's first step, first − min (0 when it never falls; an altitude loss);
  change: the value at the last step minus that at the first, last − first (a heading change);
* mean: the time average by the trapezoid rule over the steps, ∫y dt / (t_last − t_first); a window
  holding one step gives that step's value;
* at: linear interpolation between the two steps around at_s (exact at a step's time);
* at_first: the value of `of` at the first step where `when.of` is above (>) or below (<) the threshold;
  time_of_first: that step's time. No interpolation between steps: exact at a model's time points.
"""
from __future__ import annotations

import math

NAN = float("nan")
WINDOW_SLACK_S = 1e-9  # a step's time and a window's end written in decimal differ by rounding only


class Reduction:
    """Window handling shared by every reduction: `update` sees only the steps inside it."""

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

    def result(self) -> float:
        return self.value


class Max(Reduction):
    def update(self, t, x, y):
        if not x <= self.value:  # NaN at first
            self.value = x


class Min(Reduction):
    def update(self, t, x, y):
        if not x >= self.value:
            self.value = x


class Drop(Reduction):
    def reset(self):
        self.value = self.first = NAN

    def update(self, t, x, y):
        if self.first != self.first:  # the window's first step
            self.first, self.value = x, 0.0
        elif self.first - x > self.value:
            self.value = self.first - x


class Change(Reduction):
    def reset(self):
        self.value = self.first = NAN

    def update(self, t, x, y):
        if self.first != self.first:
            self.first = x
        self.value = x - self.first


class Final(Reduction):
    def update(self, t, x, y):
        self.value = x


class Mean(Reduction):
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


class At(Reduction):
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


class AtFirst(Reduction):
    """The value of `of` (or, for time_of_first, the time) at the first step meeting `when`."""

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


class TimeOfFirst(AtFirst):
    def __init__(self, spec: dict):
        super().__init__(spec, time=True)
