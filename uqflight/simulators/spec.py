"""A campaign's `simulator:` as a typed, frozen value (`SimulatorSpec`): built once by the campaign's
validator (`campaign.schema.simulator`), its locations set by its resolution, and sent to the workers as it is."""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from types import MappingProxyType

from .base import SimulatorKind


def frozen(value):
    """`value` read-only all the way down: mappings as MappingProxyType, lists as tuples."""
    if isinstance(value, Mapping):
        return MappingProxyType({key: frozen(item) for key, item in value.items()})
    if isinstance(value, (list, tuple)):
        return tuple(frozen(item) for item in value)
    return value


def thawed(value):
    """The plain data of a `frozen` value: dicts and lists."""
    if isinstance(value, Mapping):
        return {key: thawed(item) for key, item in value.items()}
    if isinstance(value, tuple):
        return [thawed(item) for item in value]
    return value


@dataclass(frozen=True)
class SimulatorSpec:
    """A simulator and its keys of `simulator:`, checked, and where its files were found.

    Parameters
    ----------
    kind : str
        The simulator kind (`entry` is its SimulatorKind).
    settings : mapping
        Its other keys as checked (the scenario's included), read-only all the way down: read them with
        `spec[key]`, `spec.get(key, default)` and `key in spec`.
    script_path : str or None
        A script scenario's run script, once resolved (on a worker: its copy there).
    aircraft_path : str or None
        The folder of a JSBSim aircraft, once located.
    root : str or None
        The JSBSim root a worker flies the aircraft from (its unpacked copy of the client's files).
    seed_parameters : tuple of str
        The parameters a python model is given as Python ints (random streams' seeds).

    Examples
    --------
    >>> spec = SimulatorSpec("python", {"function": "m:f", "outputs": ["y"]})
    >>> spec["outputs"], spec.get("seed", 0), "function" in spec, spec.entry.kind
    (('y',), 0, True, 'python')
    >>> spec.with_settings(function="n:g").as_mapping()
    {'kind': 'python', 'function': 'n:g', 'outputs': ['y']}
    """

    kind: str
    settings: Mapping
    script_path: str | None = None
    aircraft_path: str | None = None
    root: str | None = None
    seed_parameters: tuple[str, ...] = ()

    def __post_init__(self):
        object.__setattr__(self, "settings", frozen(self.settings))

    @classmethod
    def from_checked(cls, mapping: dict) -> SimulatorSpec:
        """The spec of a `simulator:` mapping its kind has checked (`kind` and that kind's keys)."""
        return cls(mapping["kind"], {key: value for key, value in mapping.items() if key != "kind"})

    def __reduce__(self):
        return (SimulatorSpec, (self.kind, thawed(self.settings), self.script_path, self.aircraft_path, self.root,
                                self.seed_parameters))

    def __getitem__(self, key: str):
        return self.settings[key]

    def __contains__(self, key: str) -> bool:
        return key in self.settings

    def get(self, key: str, default=None):
        """The setting `key`, or `default` when the campaign gives none."""
        return self.settings.get(key, default)

    @property
    def entry(self) -> SimulatorKind:
        """The kind's SimulatorKind (simulators/kinds): its checks, its simulator, its files."""
        return SimulatorKind.registry[self.kind]

    def with_settings(self, **changes) -> SimulatorSpec:
        """This spec with the settings `changes` given (a located aircraft's name, a worker's model file)."""
        return replace(self, settings={**self.settings, **changes})

    def as_mapping(self) -> dict:
        """The spec as plain data: `kind`, the settings, then the locations and seeds that are set.

        Returns
        -------
        dict
            e.g. {"kind": "jsbsim", "aircraft": "bacm", "aircraft_path": "/.../bacm"}: what identifies a
            worker's simulator.
        """
        located = {"script_path": self.script_path, "aircraft_path": self.aircraft_path, "root": self.root}
        return {"kind": self.kind, **thawed(self.settings), **{k: v for k, v in located.items() if v is not None},
                **({"seed_parameters": list(self.seed_parameters)} if self.seed_parameters else {})}
