"""`simulator: {kind: python, function: MODULE:CALLABLE | FILE.py:CALLABLE, outputs: [...]}`."""
from __future__ import annotations

from pathlib import Path

from ..base import Field, SimulatorKind, SimulatorSettingError
from ..bundle import python_bundle
from ..python import PythonSimulator, load_function, split_spec
from ..spec import SimulatorSpec
from .outputs import KIND, OUTPUTS, check_outputs


class Python(SimulatorKind):
    """A Python function (see `simulator.function`); it is code: see [security](../security.md).

    Examples
    --------
    >>> Python().relocated({"kind": "python", "function": "models.py:ramp"}, Path("/x"))
    {'kind': 'python', 'function': '/x/models.py:ramp'}
    """

    kind = "python"
    integer_seeds = True
    fields = {
        "kind": KIND,
        "function": Field("python only, required. `package.module:callable` or `file.py:callable` (relative to the "
                          "campaign file); called with {parameter: value}, returns {output: array or scalar} and "
                          "optionally `time`. `function: \"uqflight.simulators.models:linear\"`"),
        "outputs": OUTPUTS,
    }
    example = ({"kind": "python", "function": "uqflight.simulators.models:exp_decay"},
               {"a": {"distribution": "normal", "nominal": 1.0, "lower": 0.9, "upper": 1.1}})

    def check(self, check, value: dict) -> dict:
        sim = check.mapping(value, "simulator", self.keys, required=("function",))
        try:
            split_spec(sim["function"])
        except SimulatorSettingError as exc:
            check.fail("simulator.function", str(exc))
        if "outputs" in sim:
            check_outputs(check, sim["outputs"])
        return dict(sim)

    def resolve(self, check, sim: SimulatorSpec, source: str) -> SimulatorSpec:
        """Import the function (its module's code runs), relative to the campaign file's folder."""
        try:
            load_function(sim["function"], Path(source).parent)
        except SimulatorSettingError as exc:
            check.fail("simulator.function", str(exc))
        return sim

    def make(self, config: SimulatorSpec, parameter_names: list[str], properties: list[str],
             base: Path) -> PythonSimulator:
        return PythonSimulator(config, parameter_names, base)

    def bundle(self, config: SimulatorSpec, properties, base) -> dict | None:
        """A `file.py` model's file; None for an installed module."""
        return python_bundle(config, base)

    def relocated(self, config: dict, folder: Path) -> dict:
        """A `file.py:callable` relative to `folder` made absolute; an installed module as it is."""
        module, attribute = split_spec(config["function"])
        if not module.endswith(".py") or Path(module).is_absolute():
            return dict(config)
        return {**config, "function": f"{(Path(folder) / module).resolve()}:{attribute}"}

    def recorded(self, config: SimulatorSpec) -> tuple[int, int]:
        """The time grid is the model's: known once a sample has run (1 until then)."""
        return 1, len(config.get("outputs", ())) or 1

    def check_source(self, check, name, path: str, config: SimulatorSpec, aircraft) -> None:
        """One of the model's outputs, when the campaign lists them."""
        check.string(name, path)
        outputs = config.get("outputs")
        if outputs and name not in outputs:
            check.fail(path, f"expected one of the model's outputs ({', '.join(outputs)}), got {name!r}")
