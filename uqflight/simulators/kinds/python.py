"""`simulator: {kind: python, function: MODULE:CALLABLE | FILE.py:CALLABLE, outputs: [...]}`."""
from __future__ import annotations

from pathlib import Path

from ..python import PluginError, PythonSimulator, load_function, split_spec
from .outputs import check_outputs

KEYS = ("kind", "function", "outputs")


def check(check, value: dict) -> dict:
    sim = check.mapping(value, "simulator", KEYS, required=("function",))
    try:
        split_spec(sim["function"])
    except PluginError as exc:
        check.fail("simulator.function", str(exc))
    if "outputs" in sim:
        check_outputs(check, sim["outputs"])
    return dict(sim)


def resolve(check, sim: dict, source: str) -> None:
    """Import the function (its module's code runs), relative to the campaign file's folder."""
    try:
        load_function(sim["function"], Path(source).parent)
    except PluginError as exc:
        check.fail("simulator.function", str(exc))


def make(config: dict, parameter_names: list[str], properties: list[str], base: Path) -> PythonSimulator:
    return PythonSimulator(config, parameter_names, base)


def bundle(config: dict, properties, base) -> dict | None:
    from ..bundle import python_bundle

    return python_bundle(config, base)


def provenance(config: dict, base: Path | None = None, properties=()) -> dict:
    return {}


def relocated(config: dict, folder: Path) -> dict:
    """A `file.py:callable` relative to `folder` made absolute; an installed module as it is."""
    module, attribute = split_spec(config["function"])
    if not module.endswith(".py") or Path(module).is_absolute():
        return dict(config)
    return {**config, "function": f"{(Path(folder) / module).resolve()}:{attribute}"}


def recorded(config: dict) -> tuple[int, int]:
    """The time grid is the model's: known once a sample has run (1 until then)."""
    return 1, len(config.get("outputs", ())) or 1


def span(config: dict) -> None:
    return None


def facts(config: dict) -> dict:
    """A model has no flight condition or excitation."""
    return {}


def check_source(check, name, path: str, config: dict, aircraft) -> None:
    """One of the model's outputs, when the campaign lists them."""
    check.string(name, path)
    outputs = config.get("outputs")
    if outputs and name not in outputs:
        check.fail(path, f"expected one of the model's outputs ({', '.join(outputs)}), got {name!r}")
