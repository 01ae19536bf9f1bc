"""What every simulator shares: the run status codes, the errors of a failed sample, the refusal of a
simulator's setting, and the base classes
of the simulator and scenario kinds (registered by subclassing) with the fields their keys are.

The status codes are stored per run in `/samples/status` of a results file; they are defined here
once, and each error class carries its own code.
"""
from __future__ import annotations

import enum
from abc import ABC, abstractmethod
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

from ..text import Refusal
from ..text.console import one_line, quoted_name


class Status(enum.IntEnum):
    """Outcome of one run, as stored in /samples/status."""

    PENDING = -1
    OK = 0
    TRIM_FAILURE = 1
    DIVERGED = 2
    SIMULATOR_ERROR = 3
    WORKER_DIED = 4  # the sample killed its worker process (exit, signal, out of memory)
    TIMEOUT = 5  # the sample ran past execution.timeout_s; its worker was replaced


class FlightError(RuntimeError):
    """A sample that could not be flown; `status` is its code in the results file."""

    status = Status.SIMULATOR_ERROR


class TrimError(FlightError):
    """The trim did not converge or converged to a state outside the aircraft's envelope."""

    status = Status.TRIM_FAILURE


class DivergenceError(FlightError):
    """The flight left the envelope or produced NaN after the trim."""

    status = Status.DIVERGED


class SimulatorSettingError(Refusal):
    """A simulator's setting that cannot be used: an aerodynamic function or perturbation to patch, a JSBSim
    script, a python model (`simulator.function`); the message says what was expected. A campaign's checks
    raise it again as a CampaignError naming the file and the field."""


class NominalFailed(RuntimeError):
    """The nominal sample, which `layout` runs before any other to learn the outputs, failed: the
    message names it, gives its values and says what to do; `run` stops there (exit 2)."""


def nominal_failed(names, kappa, exc: Exception) -> NominalFailed:
    """The NominalFailed that says sample `kappa` of the parameters `names` failed with `exc`."""
    values = ", ".join(f"{quoted_name(name)} = {float(value):.10g}" for name, value in zip(names, kappa))
    return NominalFailed(
        f"the nominal sample failed ({values}: the centre of every parameter's law, ξ = 0), which uqflight "
        f"runs first to learn the outputs, the time grid and the cost of a run: {type(exc).__name__}: "
        f"{one_line(str(exc))}. "
        "Make the simulator succeed at these values (call simulator.function with them to see why), or move "
        "the parameters' intervals (lower and upper, or nominal with interval_pct) so that their centre is an "
        "input it accepts")


@dataclass(frozen=True)
class Field:
    """A campaign key a simulator or scenario kind owns: its meaning (the key reference) and what its
    check accepts. `number`: a number, at least `minimum` (above it when `strict`); `choices`: one of these
    strings; `keys`: a mapping of these keys, each checked as its field says. A field with none of them is
    checked by its kind's own code."""

    description: str
    number: bool = False
    minimum: float | None = None
    strict: bool = False
    choices: tuple[str, ...] = ()
    keys: dict | None = None


def check_fields(check, mapping: dict, path: str, fields: dict[str, Field]) -> None:
    """Check the keys of `mapping` (at `path`) that `fields` declare a number, choice or mapping of."""
    for name, spec in fields.items():
        at = f"{path}.{name}"
        if spec.keys is not None:
            check_fields(check, check.mapping(mapping.get(name, {}), at, tuple(spec.keys)), at, spec.keys)
        elif name not in mapping:
            continue
        elif spec.number:
            check.number(mapping[name], at, spec.minimum, strict=spec.strict)
        elif spec.choices:
            check.string(mapping[name], at, spec.choices)


def field_descriptions(prefix: str, fields: dict[str, Field]) -> dict[str, str]:
    """{path: description} of `fields` under `prefix`, each mapping's own keys after every key of its level."""
    found = {f"{prefix}.{name}": spec.description for name, spec in fields.items()}
    for name, spec in fields.items():
        if spec.keys:
            found.update(field_descriptions(f"{prefix}.{name}", spec.keys))
    return found


class Kind(ABC):
    """What simulator and scenario kinds share: a `kind` name, its keys as `fields`, and registration: a
    subclass of SimulatorKind or ScenarioKind (the classes that hold a `registry`) registers one instance
    of itself under its `kind` when it is defined."""

    registry: ClassVar[dict]
    kind: ClassVar[str]
    fields: ClassVar[dict[str, Field]]

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if "registry" not in cls.__dict__:
            cls.registry[cls.kind] = cls()

    @property
    def keys(self) -> tuple[str, ...]:
        return tuple(self.fields)


class SimulatorKind(Kind):
    """A simulator kind (`simulator.kind`): what runs a sample. Defining a subclass with `kind = "NAME"`
    registers one instance of it in `SimulatorKind.registry`.

    A kind owns its `simulator:` keys (`fields`; a JSBSim scenario adds its own) and their checks, finds
    what it runs, builds the simulator a worker uses, names the files that travel to workers and the
    provenance the results file keeps, and counts what a run records from the campaign alone (for
    `limits`). Beside `check`, which checks the mapping as written, and `relocated`, which rewrites it, its
    methods take the campaign's `SimulatorSpec` (simulators/spec.py), `config` or `sim`.

    Attributes
    ----------
    kind : str
        The name campaigns give in `simulator.kind`.
    fields : dict of str to Field
        Its `simulator:` keys.
    aircraft : bool
        Parameters set properties of an aircraft (`property` or `function` required, checked against the
        probed aircraft).
    integer_seeds : bool
        A seed parameter reaches the model as an int (JSBSim properties are doubles).
    example : tuple of dict
        A small `simulator:` mapping of this kind and the `parameters:` of a campaign on it (tests).

    Examples
    --------
    >>> from uqflight.simulators.kinds import REGISTRY
    >>> from uqflight.simulators.spec import SimulatorSpec
    >>> sorted(REGISTRY)
    ['jsbsim', 'python']
    >>> REGISTRY["python"].recorded(SimulatorSpec("python", {"function": "m:f", "outputs": ["y", "z"]}))
    (1, 2)
    """

    registry: ClassVar[dict[str, "SimulatorKind"]] = {}
    aircraft: ClassVar[bool] = False
    integer_seeds: ClassVar[bool] = False
    example: ClassVar[tuple[dict, dict]]

    @abstractmethod
    def check(self, check, value: dict) -> dict:
        """The mapping checked as written (`check` is the campaign's Checker); nothing imported or located."""

    @abstractmethod
    def resolve(self, check, sim, source: str):
        """`sim` with what it runs found relative to the campaign file `source` (a python module is imported,
        an aircraft located); only for campaigns about to be planned or run."""

    @abstractmethod
    def make(self, config, parameter_names: list[str], properties: list[str], base: Path):
        """The simulator a worker flies."""

    def bundle(self, config, properties, base) -> dict | None:
        """The files a worker that shares no disk with the client needs, or None."""
        return None

    def provenance(self, config, base: Path | None = None, properties=()) -> dict:
        """Results-file attributes naming what it runs."""
        return {}

    def relocated(self, config: dict, folder: Path) -> dict:
        """The mapping as written with the files it names relative to `folder` made absolute (a campaign
        written elsewhere, e.g. calibrate's calibrated.yaml, reads the same files)."""
        return dict(config)

    @abstractmethod
    def recorded(self, config) -> tuple[int, int]:
        """(times, outputs) a run records, from the campaign alone (1 where known only once a sample has run)."""

    def span(self, config) -> float | None:
        """The flight's last time [s] when the campaign fixes it, else None."""
        return None

    def trims_level(self, config) -> bool:
        """A JSBSim aircraft trimmed in level flight (its modes are those of that trim)."""
        return False

    @abstractmethod
    def check_source(self, check, name, path: str, config, aircraft) -> None:
        """Refuse (check.fail at `path`) a name a quantity reads that the simulator does not record."""

    def flight_summary(self, config) -> dict[str, str]:
        """{"flight": text, "excitation": text}: what is flown, defaults resolved (the report; {} for a model)."""
        return {}


class ScenarioKind(Kind):
    """How a JSBSim run is flown (`simulator.scenario.kind`). Defining a subclass with `kind = "NAME"`
    registers one instance of it in `ScenarioKind.registry`.

    A scenario owns its keys and their checks, builds the setup and the flight of a campaign's
    `simulator:` mapping, counts its recorded times from the campaign alone, names the files beyond the
    aircraft's that travel to workers, and states its provenance and resolution. Beside `relocated`, which
    rewrites the mapping as written, its methods take the campaign's `SimulatorSpec` (simulators/spec.py).

    Attributes
    ----------
    kind : str
        The name campaigns give in `simulator.scenario.kind`.
    fields : dict of str to Field
        The `simulator:` keys it owns (beside kind, aircraft, scenario, outputs and properties).
    scenario_fields : dict of str to Field
        The keys of `simulator.scenario` beside kind.
    default_aircraft : str or None
        The aircraft flown when the campaign names none (None: the scenario names its own).
    level_trim : bool
        It flies from a level-flight trim (the modes of that trim are quantities of it).
    example : dict
        A small `simulator:` mapping of this kind (tests).

    Examples
    --------
    >>> from uqflight.simulators.scenarios import REGISTRY, scenario_entry
    >>> from uqflight.simulators.spec import SimulatorSpec
    >>> sorted(REGISTRY)
    ['level_flight', 'script']
    >>> spec = SimulatorSpec("jsbsim", {"duration_s": 1.0})
    >>> scenario_entry(spec).kind, scenario_entry(spec).times(spec)
    ('level_flight', 21)
    """

    registry: ClassVar[dict[str, "ScenarioKind"]] = {}
    scenario_fields: ClassVar[dict[str, Field]] = {}
    default_aircraft: ClassVar[str | None] = None
    level_trim: ClassVar[bool] = False
    example: ClassVar[dict]

    @property
    def scenario_keys(self) -> tuple[str, ...]:
        return tuple(self.scenario_fields)

    @abstractmethod
    def check(self, check, sim, folder: Path):
        """`sim` checked (`check.fail(field, message)` refuses), its files resolved against `folder`."""

    @abstractmethod
    def setup(self, config, root: Path | None = None, base: Path | None = None, properties=()):
        """The setup (aircraft, root, aircraft_file, time, outputs) of a checked `simulator:` mapping."""

    @abstractmethod
    def flight(self, setup, preflight: bool = True):
        """The flight: `fly(settings, observers=()) -> FlightResult`."""

    @abstractmethod
    def times(self, config) -> int:
        """The number of recorded times, from the campaign alone."""

    @abstractmethod
    def span(self, config) -> float | None:
        """The flight's last time [s] from the campaign alone, or None."""

    def files(self, config) -> dict[str, bytes]:
        """{name: bytes}: files beyond the aircraft's that a worker needs."""
        return {}

    def localize(self, config, folder: Path):
        """The spec reading the files of `files` from `folder`, where a worker wrote them."""
        return config

    def relocated(self, config: dict, folder: Path) -> dict:
        """The mapping with the files it names relative to the campaign's `folder` made absolute."""
        return config

    def provenance(self, config) -> dict:
        """Results-file attributes beyond the aircraft's hash."""
        return {}

    def resolution(self, setup, settings: dict[str, float], ours=None):
        """{output: (T,)}: the simulator's own resolution at `settings`, or None."""
        return None

    @abstractmethod
    def flight_summary(self, config) -> dict[str, str]:
        """{"flight": text, "excitation": text}: what is flown, defaults resolved (the report)."""
