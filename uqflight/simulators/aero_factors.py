"""What an aerodynamic function's value is, and what turns a coefficient increment into it.

JSBSim adds every function of an `<axis>` of `<aerodynamics>` into that axis' force (lbf) or
moment (lbf·ft), whatever the function's form. A coefficient increment ΔC on it is therefore
ΔC times the axis' reference factor, from the aircraft's own properties:

    forces  DRAG, SIDE, LIFT (wind); X, Y, Z (any frame); AXIAL, NORMAL (body)   qbar·S
    moments PITCH                                                                 qbar·S·c̄
            ROLL, YAW (any frame)                                                 qbar·S·b

with qbar `aero/qbar-psf` (the free-stream dynamic pressure), S `metrics/Sw-sqft`, c̄
`metrics/cbarw-ft` and b `metrics/bw-ft`. A frame (BODY, STABILITY, WIND) turns the axis but
not its reference. A function outside the axes (a helper others use: a ground-effect factor,
an induced velocity) has a unit of its own and no reference factor; so has a moment when the
aircraft's `<metrics>` leave its length out (JSBSim then holds 0 for it).
"""
from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass

from .aircraft import aero_functions
from .directives import jsbsim_tree

QBAR, AREA, CHORD, SPAN = "aero/qbar-psf", "metrics/Sw-sqft", "metrics/cbarw-ft", "metrics/bw-ft"
FORCE_AXES = ("DRAG", "SIDE", "LIFT", "X", "Y", "Z", "AXIAL", "NORMAL")
MOMENT_LENGTH = {"PITCH": CHORD, "ROLL": SPAN, "YAW": SPAN}
SYMBOLS = {QBAR: "qbar", AREA: "S", CHORD: "c̄", SPAN: "b"}
METRICS = {AREA: "wingarea", CHORD: "chord", SPAN: "wingspan"}  # the <metrics> element defining each


@dataclass(frozen=True)
class AeroFactor:
    """A function's unit and the properties whose product multiplies a coefficient increment on
    it; `refusal` says why there is none ("" when there is)."""

    axis: str
    unit: str         # "lbf", "lbf·ft", or "" for a unit of the function's own
    factor: tuple[str, ...] = ()
    refusal: str = ""

    @property
    def symbol(self) -> str:
        """The factor as a formula (`qbar·S·c̄`), or "" without one."""
        return "·".join(SYMBOLS[p] for p in self.factor)


def _stated(metrics: ET.Element | None, prop: str) -> bool:
    """True when the aircraft's <metrics> gives the length or area behind `prop`, not 0."""
    text = metrics.findtext(METRICS[prop]) if metrics is not None else None
    try:
        return float(text) != 0.0
    except (TypeError, ValueError):
        return False


def axis_factor(axis: str, metrics: ET.Element | None) -> AeroFactor:
    """The reference of a function in `<axis name="AXIS">` ("" for one outside the axes)."""
    if not axis:
        return AeroFactor(axis, "", refusal="it lies outside the <axis> elements of <aerodynamics> "
                                                  "(a helper other functions use), so its unit is its own")
    if axis in FORCE_AXES:
        factor, unit = (QBAR, AREA), "lbf"
    elif axis in MOMENT_LENGTH:
        factor, unit = (QBAR, AREA, MOMENT_LENGTH[axis]), "lbf·ft"
    else:
        return AeroFactor(axis, "", refusal=f"its axis {axis!r} is none of JSBSim's "
                                                  f"({', '.join(FORCE_AXES + tuple(MOMENT_LENGTH))})")
    missing = [METRICS[p] for p in factor[1:] if not _stated(metrics, p)]
    if missing:
        return AeroFactor(axis, unit, factor, refusal=f"the aircraft's <metrics> state no {' or '.join(missing)}, "
                                                     f"so {'·'.join(SYMBOLS[p] for p in factor)} is 0")
    return AeroFactor(axis, unit, factor)


def aero_factors(xml: bytes) -> dict[str, AeroFactor]:
    """Each named function of the aircraft's <aerodynamics> and its reference."""
    metrics = jsbsim_tree(xml).find("metrics")
    return {f.name: axis_factor(f.axis, metrics) for f in aero_functions(xml)}


def factor_values(value) -> list[tuple[str, float, str]]:
    """(formula, value, unit) of the three reference factors, `value(property)` reading the
    aircraft's properties at a state (e.g. a trimmed flight's `property_value`)."""
    force = value(QBAR) * value(AREA)
    return [("qbar·S", force, "lbf"), ("qbar·S·c̄", force * value(CHORD), "lbf·ft"),
            ("qbar·S·b", force * value(SPAN), "lbf·ft")]
