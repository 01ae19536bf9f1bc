"""The observer that computes a run's quantities while it flies.

A flight loop calls `step(t, values)` once at t = 0 and after every integration step, `values` being
the current values of `properties` in that order, and, on a level-flight trim, `at_trim(fdm)` before
the excitation. `reset()` starts a run, `result()` gives {name: value} (NaN where undefined).

An `of` that is an angle (its name ends in deg or rad: `attitude/psi-deg`, `alpha_deg`) is unwrapped
along the run before any take sees it: a step that jumps by more than half a turn is taken as the
angle crossing the end of its range (a heading from 359° to 1°), so the values stay continuous
(361°) and `final`, `change`, `max` of a heading are those of the flown turn.
"""
from __future__ import annotations

from collections.abc import Callable, Sequence

from ..text.labels import ANGLE_PERIODS, name_unit
from .modes import eigen_modes
from . import QuantitySpec

Resolve = Callable[[str], tuple[str, float]]  # a name in `of:` -> (the property recorded, its scale)


class QuantityRecorder:
    """`specs`: the campaign's quantities by name; `resolve`: the simulator's `source` (a named output's
    property and scale for JSBSim, the output itself for a Python model)."""

    def __init__(self, specs: dict[str, QuantitySpec], resolve: Resolve):
        self.specs = dict(specs)
        self.reductions, self.modes = {}, []
        sources: dict[str, int] = {}
        self._wiring = []  # (reduction, index of `of`, scale, index of `when.of`, its scale)

        def index(name):
            prop, scale = resolve(name)
            return sources.setdefault(prop, len(sources)), scale

        for name, spec in self.specs.items():
            take = spec.entry
            if take.mode:
                self.modes.append(name)
                continue
            reduction = self.reductions[name] = take(spec)
            of, of_scale = index(spec.of) if spec.of is not None else (None, 1.0)
            when, when_scale = index(spec.when.of) if spec.when is not None else (None, 1.0)
            period = ANGLE_PERIODS.get(name_unit(spec.of)) if spec.of is not None else None
            self._wiring.append((reduction, of, of_scale, when, when_scale, period and Unwrapped(period)))
        self.properties: tuple[str, ...] = tuple(sources)
        self._modes: dict[str, float] = {}

    def reset(self) -> None:
        for reduction in self.reductions.values():
            reduction.reset()
        for *_, unwrapped in self._wiring:
            if unwrapped:
                unwrapped.reset()
        self._modes = {}

    def at_trim(self, fdm) -> None:
        if self.modes:
            self._modes = eigen_modes(fdm)

    def step(self, t: float, values: Sequence[float]) -> None:
        nan = float("nan")
        for reduction, of, of_scale, when, when_scale, unwrapped in self._wiring:
            x = values[of] * of_scale if of is not None else nan
            if unwrapped:
                x = unwrapped(x)
            y = values[when] * when_scale if when is not None else nan
            reduction.step(t, x, y)

    def result(self) -> dict[str, float]:
        found = {name: reduction.result() for name, reduction in self.reductions.items()}
        for name in self.modes:
            found[name] = self._modes.get(self.specs[name].take, float("nan"))
        return {name: float(found[name]) for name in self.specs}


class Unwrapped:
    """An angle made continuous along a run: each value moved by the whole turns (`period`) that bring it
    within half a turn of the value before (numpy.unwrap, one step at a time)."""

    def __init__(self, period: float):
        self.period = period
        self.reset()

    def reset(self) -> None:
        self.previous, self.turns = float("nan"), 0.0

    def __call__(self, x: float) -> float:
        if x != x:  # NaN: passed on, the history kept
            return x
        if self.previous == self.previous:
            self.turns -= self.period * round((x + self.turns - self.previous) / self.period)
        self.previous = x + self.turns
        return self.previous
