"""The `simulator:` keys every simulator kind has: `kind` and `outputs`."""
from __future__ import annotations

from ..base import Field

KIND = Field("Required. `jsbsim` (a JSBSim flight) or `python` (a Python function).")
OUTPUTS = Field("The recorded outputs. JSBSim: named outputs (`alpha_deg`, `theta_deg`, `h_ft`, `q_degps`, `vtas_kt`, "
                "the default) and/or any JSBSim property; python: the names of the function's outputs (default: all "
                "it returns). `outputs: [alpha_deg, h_ft]`")


def check_outputs(check, value) -> list[str]:
    """A non-empty list of unique names (`check` is the campaign's Checker)."""
    if not isinstance(value, list) or not value:
        check.fail("simulator.outputs", f"expected a non-empty list of output names, got {check.quoted(value)}")
    for i, item in enumerate(value):
        check.string(item, f"simulator.outputs[{i}]")
    if len(set(value)) != len(value):
        check.fail("simulator.outputs", "names must be unique")
    return value
