"""Campaign files (YAML): read, validate, and turn into parameters, a design and settings.

Validation happens before anything runs. Every problem is a `CampaignError` whose message
names the file, the field and what was expected, e.g.
`campaigns/x.yaml: parameters.CL0.interval_pct: expected a number > 0, got -3`.
"""
from __future__ import annotations

import difflib
import hashlib
import importlib
import importlib.util
import math
import re
import sys
from collections.abc import Hashable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import jsbsim
import yaml

from .designs import Design, build_design
from .methods import METHOD_KINDS
from .parameters import DISTRIBUTIONS, Parameter, make_parameter
from .simulators.jsbsim import NAMED_OUTPUTS, Excitation, JSBSimFlight, flight_setup_from

SIMULATOR_KINDS = ("jsbsim", "python")
EXECUTORS = ("local", "dask")
TOP_KEYS = ("name", "description", "seed", "simulator", "parameters", "design", "method",
            "execution", "storage", "analysis")
JSBSIM_KEYS = ("kind", "aircraft", "flight", "excitation", "duration_s", "output_rate_hz", "outputs")
PYTHON_KEYS = ("kind", "function", "outputs")
PARAMETER_KEYS = ("property", "distribution", "nominal", "interval_pct", "lower", "upper")
METHOD_KEYS = ("kind", "order", "split")
EXECUTION_KEYS = ("workers", "executor", "scheduler", "chunk")
STORAGE_KEYS = ("path", "raw", "tsvd")
TSVD_KEYS = ("tol", "batch")
SAMPLED_DESIGNS = ("monte_carlo", "sobol", "halton", "latin_hypercube", "pick_freeze")
ANALYSIS_KEYS = ("band_samples", "bootstrap")


class CampaignError(ValueError):
    """A campaign file that cannot be run: names the file, the field and what was expected."""

    def __init__(self, source: str, field_path: str, message: str):
        self.source, self.field = source, field_path
        where = f"{source}: {field_path}: " if field_path else f"{source}: "
        super().__init__(where + message)


@dataclass
class Campaign:
    """A validated campaign. `text` is the file's exact text (its hash identifies results)."""

    source: str
    text: str
    name: str
    seed: int
    simulator: dict
    parameters: list[Parameter]
    design_spec: dict
    method: dict
    execution: dict
    storage: dict
    analysis: dict = field(default_factory=dict)

    @property
    def germs(self) -> list[str]:
        return [p.germ for p in self.parameters]

    def design(self) -> Design:
        return build_design(self.design_spec, self.germs, self.seed)


def _shown(value) -> str:
    """A value as an error message quotes it: short, and readable for people who wrote YAML."""
    if value is None:
        return "nothing"
    if isinstance(value, dict):
        return "a mapping"
    if isinstance(value, list):
        return "a list"
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


class _Checker:
    """Typed access to a YAML mapping that raises CampaignError with the field's path."""

    def __init__(self, source: str):
        self.source = source

    def fail(self, path: str, message: str):
        raise CampaignError(self.source, path, message)

    def mapping(self, value, path: str, allowed: tuple[str, ...], required=()) -> dict:
        if not isinstance(value, dict):
            self.fail(path, f"expected a mapping with the keys {', '.join(allowed)}, got {_shown(value)}")
        for key in value:
            if key not in allowed:
                close = difflib.get_close_matches(str(key), allowed, n=1)
                hint = f"did you mean {close[0]}? " if close else ""
                self.fail(f"{path}.{key}" if path else str(key),
                          f"unknown key; {hint}expected one of {', '.join(allowed)}")
        for key in required:
            if key not in value:
                self.fail(f"{path}.{key}" if path else key, "is required")
        return value

    def number(self, value, path: str, minimum: float | None = None, strict=False) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            self.fail(path, f"expected a finite number, got {_shown(value)}")
        if minimum is not None and (value <= minimum if strict else value < minimum):
            self.fail(path, f"expected a number {'>' if strict else '>='} {minimum:g}, got {value!r}")
        return float(value)

    def integer(self, value, path: str, minimum: int) -> int:
        if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
            self.fail(path, f"expected an integer >= {minimum}, got {_shown(value)}")
        return value

    def string(self, value, path: str, choices: tuple[str, ...] | None = None) -> str:
        expected = f"one of {', '.join(choices)}" if choices else "a non-empty string"
        if not isinstance(value, str) or not value or (choices and value not in choices):
            self.fail(path, f"expected {expected}, got {_shown(value)}")
        return value

    def boolean(self, value, path: str) -> bool:
        if not isinstance(value, bool):
            self.fail(path, f"expected true or false, got {_shown(value)}")
        return value


class _CampaignLoader(yaml.SafeLoader):
    """YAML's safe loader, except that a key given twice in one mapping is an error (plain YAML
    keeps the last one silently, so a parameter pasted twice would vanish)."""

    def construct_mapping(self, node, deep=False):
        seen = set()
        for key_node, _ in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge":
                continue
            key = self.construct_object(key_node, deep=deep)
            if isinstance(key, Hashable):
                if key in seen:
                    raise yaml.constructor.ConstructorError(
                        "while reading the mapping", node.start_mark, f"found the key {key!r} twice",
                        key_node.start_mark)
                seen.add(key)
        return super().construct_mapping(node, deep)


# YAML 1.1 (PyYAML) reads 1e-8 as a string: accept exponents without a dot, as YAML 1.2 does.
_CampaignLoader.yaml_implicit_resolvers = {
    key: list(value) for key, value in yaml.SafeLoader.yaml_implicit_resolvers.items()}
_CampaignLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
                  |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
                  |\.[0-9_]+(?:[eE][-+]?[0-9]+)?
                  |[-+]?\.(?:inf|Inf|INF)
                  |\.(?:nan|NaN|NAN))$""", re.X),
    list("-+0123456789."))


def _yaml_error(exc: yaml.YAMLError) -> str:
    """'YAML syntax error at line L, column C: problem (context at line L', column C')'."""
    def at(mark) -> str:
        return f"line {mark.line + 1}, column {mark.column + 1}"

    mark = getattr(exc, "problem_mark", None)
    message = f"YAML syntax error at {at(mark)}: " if mark else "YAML syntax error: "
    message += getattr(exc, "problem", None) or str(exc)
    context, context_mark = getattr(exc, "context", None), getattr(exc, "context_mark", None)
    if context and context_mark:
        message += f" ({context} that starts at {at(context_mark)})"
    return message


class AircraftProperties:
    """The campaign's aircraft as a sample finds it before the trim: loaded, with the flight
    condition's initial conditions set (so `ic/vt-kts` reads the campaign's airspeed and
    `ic/vc-kts` the matching calibrated airspeed). Validation reads nominal values here."""

    def __init__(self, simulator: dict):
        setup = flight_setup_from({**simulator, "outputs": []})
        if not setup.aircraft_file.is_file():
            folder = Path(setup.root) / "aircraft"
            known = sorted(p.parent.name for p in folder.glob("*/*.xml") if p.stem == p.parent.name)
            raise FileNotFoundError(f"expected one of {', '.join(known)} (the aircraft in {folder}), "
                                    f"got {setup.aircraft!r}")
        self.aircraft = setup.aircraft
        self._flight = JSBSimFlight(setup)
        fdm = self._flight.fdm
        fdm["ic/h-sl-ft"] = setup.altitude_ft  # as JSBSimFlight.trim sets them
        fdm["ic/vt-kts"] = setup.airspeed_ktas
        names = [line.rsplit(" (", 1)[0] for line in fdm.query_property_catalog("").splitlines()]  # "name (RW)"
        self._names = {name.lower(): name for name in names}  # for hints, whatever the case typed

    def value(self, name: str) -> float | None:
        """The property's value (None when the aircraft has no such property)."""
        return self._flight.property_value(name)

    def writable(self, name: str) -> bool:
        return self._flight.node(name).get_attribute(jsbsim.Attribute.WRITE)

    def hint(self, name: str) -> str:
        """'; did you mean ...?' with the aircraft's properties closest to `name`, or ''."""
        close = difflib.get_close_matches(name.lower(), self._names, n=3, cutoff=0.8)
        return f"; did you mean {' or '.join(self._names[c] for c in close)}?" if close else ""


def jsbsim_probe(simulator: dict) -> AircraftProperties:
    """The campaign aircraft's properties, for `load_campaign(..., probe=jsbsim_probe)`."""
    return AircraftProperties(simulator)


PropertyProbe = Callable[[dict], AircraftProperties]


def load_campaign(path: str | Path, probe: PropertyProbe | None = None) -> Campaign:
    """Read and validate a campaign file.

    `probe(simulator_config)` gives the aircraft's properties (`jsbsim_probe`); it is used for
    JSBSim campaigns to check property and output names and to read nominal values from the
    aircraft. Without it, those checks are skipped and nominal values must be given.
    """
    source = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise CampaignError(source, "", f"cannot read the file ({exc.strerror})") from exc
    except UnicodeDecodeError as exc:
        raise CampaignError(source, "", f"expected UTF-8 text, got byte {exc.object[exc.start]:#04x} "
                                        f"at position {exc.start}") from exc
    return parse_campaign(text, source, probe)


def parse_campaign(text: str, source: str = "<campaign>", probe: PropertyProbe | None = None) -> Campaign:
    """Validate campaign text; see `load_campaign`."""
    check = _Checker(source)
    try:
        data = yaml.load(text, Loader=_CampaignLoader)
    except yaml.YAMLError as exc:
        raise CampaignError(source, "", _yaml_error(exc)) from exc
    data = check.mapping(data, "", TOP_KEYS, required=("name", "simulator", "parameters", "design"))
    name = check.string(data["name"], "name")
    seed = check.integer(data.get("seed", 0), "seed", 0)
    simulator = _simulator(check, data["simulator"], source)
    aircraft = None
    if probe and simulator["kind"] == "jsbsim":
        try:
            aircraft = probe(simulator)
        except (FileNotFoundError, RuntimeError) as exc:  # no such aircraft, or JSBSim cannot load it
            check.fail("simulator.aircraft", str(exc))
        for i, output in enumerate(simulator.get("outputs", ())):
            if output not in NAMED_OUTPUTS and aircraft.value(output) is None:
                check.fail(f"simulator.outputs[{i}]", f"expected one of {', '.join(NAMED_OUTPUTS)} or a JSBSim "
                           f"property of aircraft {aircraft.aircraft!r}, got {output!r}{aircraft.hint(output)}")
    parameters = _parameters(check, data["parameters"], simulator["kind"], aircraft)
    design_kind = data["design"].get("kind") if isinstance(data["design"], dict) else None
    default_method = "monte_carlo" if design_kind in SAMPLED_DESIGNS else "integration"
    method = _method(check, data.get("method", {"kind": default_method}))
    execution = _execution(check, data.get("execution", {}))
    storage = _storage(check, data.get("storage", {}), name)
    analysis = _analysis(check, data.get("analysis", {}))
    campaign = Campaign(source, text, name, seed, simulator, parameters, data["design"], method,
                        execution, storage, analysis)
    try:
        design = campaign.design()
    except ValueError as exc:
        message = str(exc)
        field_path, sep, rest = message.partition(": ")
        if sep and (field_path.startswith("design") or field_path == "seed"):
            raise CampaignError(source, field_path, rest) from exc
        raise CampaignError(source, "design", message) from exc
    _check_method_fits_design(check, method, design, len(parameters))
    return campaign


def _check_method_fits_design(check: _Checker, method: dict, design: Design, dimensions: int) -> None:
    if method["kind"] == "monte_carlo" and design.kind not in SAMPLED_DESIGNS:
        check.fail("method.kind", f"monte_carlo needs a sampled design ({', '.join(SAMPLED_DESIGNS)}); "
                   f"a {design.kind} needs its weights: use integration, pseudo_galerkin, interpolation, "
                   "regression or least_squares")
    if method["kind"] in ("regression", "least_squares"):
        order, points = method["order"], len(design.xi)
        terms = math.comb(dimensions + order, order)
        if points < terms:
            fitting = max((o for o in range(order) if math.comb(dimensions + o, o) <= points), default=0)
            check.fail("method.order", f"expected at most {fitting} for this design: {method['kind']} of "
                       f"order {order} in {dimensions} dimensions fits {terms} terms, but the design has "
                       f"only {points} points")


def _simulator(check: _Checker, value, source: str) -> dict:
    if not isinstance(value, dict):
        check.fail("simulator", f"expected a mapping with a kind key, got {_shown(value)}")
    if "kind" not in value:
        check.fail("simulator.kind", f"is required; expected one of {', '.join(SIMULATOR_KINDS)}")
    kind = check.string(value["kind"], "simulator.kind", SIMULATOR_KINDS)
    if kind == "python":
        sim = check.mapping(value, "simulator", PYTHON_KEYS, required=("function",))
        load_function(sim["function"], Path(source).parent, check)
        if "outputs" in sim:
            _outputs(check, sim["outputs"])
        return dict(sim)
    sim = dict(check.mapping(value, "simulator", JSBSIM_KEYS))
    sim.setdefault("aircraft", "bacm")
    check.string(sim["aircraft"], "simulator.aircraft")
    flight = check.mapping(sim.get("flight", {}), "simulator.flight", ("altitude_ft", "airspeed_ktas"))
    if "altitude_ft" in flight:
        check.number(flight["altitude_ft"], "simulator.flight.altitude_ft", 0.0)
    if "airspeed_ktas" in flight:
        check.number(flight["airspeed_ktas"], "simulator.flight.airspeed_ktas", 0.0, strict=True)
    excitation = check.mapping(sim.get("excitation", {}), "simulator.excitation",
                               ("kind", "amplitude_deg", "start_s", "duration_s"))
    if "kind" in excitation:
        check.string(excitation["kind"], "simulator.excitation.kind", Excitation.KINDS)
    if "amplitude_deg" in excitation:
        check.number(excitation["amplitude_deg"], "simulator.excitation.amplitude_deg")
    for key in ("start_s", "duration_s"):
        if key in excitation:
            check.number(excitation[key], f"simulator.excitation.{key}", 0.0)
    if "duration_s" in sim:
        check.number(sim["duration_s"], "simulator.duration_s", 0.0, strict=True)
    if "output_rate_hz" in sim:
        rate = check.number(sim["output_rate_hz"], "simulator.output_rate_hz", 0.0, strict=True)
        if abs(120.0 / rate - round(120.0 / rate)) > 1e-9:
            check.fail("simulator.output_rate_hz",
                       f"expected a divisor of the 120 Hz integration rate (120, 60, 40, 30, 24, 20, ...), got {rate:g}")
    if "outputs" in sim:
        _outputs(check, sim["outputs"])
    return sim


def _outputs(check: _Checker, value) -> list[str]:
    if not isinstance(value, list) or not value:
        check.fail("simulator.outputs", f"expected a non-empty list of output names, got {_shown(value)}")
    for i, item in enumerate(value):
        check.string(item, f"simulator.outputs[{i}]")
    if len(set(value)) != len(value):
        check.fail("simulator.outputs", "names must be unique")
    return value


def load_function(spec: str, base: Path, check: _Checker | None = None) -> Callable:
    """The callable named `module:attribute` or `path/to/file.py:attribute` (relative to base)."""
    check = check or _Checker("<campaign>")
    if not isinstance(spec, str) or spec.count(":") != 1:
        check.fail("simulator.function",
                   f"expected 'package.module:callable' or 'file.py:callable', got {_shown(spec)}")
    module_name, attribute = spec.split(":")
    try:
        if module_name.endswith(".py"):
            file = (base / module_name) if not Path(module_name).is_absolute() else Path(module_name)
            if not file.is_file():
                check.fail("simulator.function", f"expected an existing Python file, got {str(file)!r} "
                                                 "(a relative path is read from the campaign's folder)")
            unique = "uqflight_user_" + hashlib.sha256(str(file.resolve()).encode()).hexdigest()[:12]
            module = sys.modules.get(unique)
            if module is None:
                module_spec = importlib.util.spec_from_file_location(unique, file)
                module = importlib.util.module_from_spec(module_spec)
                module_spec.loader.exec_module(module)
                sys.modules[unique] = module
        else:
            module = importlib.import_module(module_name)
    except CampaignError:
        raise
    except Exception as exc:  # the user's module failed to import: say which and why
        check.fail("simulator.function", f"cannot import {module_name!r}: {type(exc).__name__}: {exc}")
    function = getattr(module, attribute, None)
    if not callable(function):
        check.fail("simulator.function", f"{module_name!r} has no callable {attribute!r}")
    return function


def _parameters(check: _Checker, value, kind: str, aircraft: AircraftProperties | None) -> list[Parameter]:
    if not isinstance(value, dict) or not value:
        check.fail("parameters", f"expected a mapping of parameter names to their definitions, got {_shown(value)}")
    parameters = []
    owners: dict[str, str] = {}  # property -> the parameter that sets it
    for name, spec in value.items():
        path = f"parameters.{name}"
        spec = check.mapping(spec, path, PARAMETER_KEYS, required=("distribution",))
        distribution = check.string(spec["distribution"], f"{path}.distribution", DISTRIBUTIONS)
        if kind == "jsbsim" and "property" not in spec:
            check.fail(f"{path}.property", "is required: the JSBSim property the parameter sets, e.g. aero/uq/CL0")
        prop = check.string(spec.get("property", str(name)), f"{path}.property")
        if prop in owners:
            check.fail(f"{path}.property", f"expected each property once, but {prop!r} is already set by "
                                           f"parameters.{owners[prop]}")
        owners[prop] = str(name)
        for key in ("interval_pct", "lower", "upper", "nominal"):
            if key in spec:
                check.number(spec[key], f"{path}.{key}")
        if "interval_pct" in spec and ("lower" in spec or "upper" in spec):
            check.fail(path, "give either interval_pct or lower and upper, not both")
        if "interval_pct" not in spec and ("lower" not in spec or "upper" not in spec):
            check.fail(path, "give interval_pct (percent of the nominal) or both lower and upper")
        if "interval_pct" in spec and not spec["interval_pct"] > 0:
            check.fail(f"{path}.interval_pct", f"expected a number > 0, got {spec['interval_pct']!r}")
        if "lower" in spec and not spec["lower"] < spec["upper"]:
            check.fail(f"{path}.lower", f"expected lower < upper, got {spec['lower']!r} >= {spec['upper']!r}")
        nominal = spec.get("nominal")
        if aircraft is not None:
            known = aircraft.value(prop)
            if known is None:
                check.fail(f"{path}.property", f"expected a JSBSim property of aircraft {aircraft.aircraft!r}, "
                                               f"got {prop!r}{aircraft.hint(prop)}")
            if not aircraft.writable(prop):
                check.fail(f"{path}.property", f"expected a property the simulator can set, but {prop!r} is "
                                               f"read-only in aircraft {aircraft.aircraft!r}")
            nominal = known if nominal is None else nominal
        if nominal is None:
            if "interval_pct" in spec:
                check.fail(f"{path}.nominal", "is required with interval_pct when the simulator cannot supply it")
            nominal = 0.5 * (spec["lower"] + spec["upper"])
        try:
            parameters.append(make_parameter(str(name), prop, distribution, float(nominal),
                                             spec.get("interval_pct"), spec.get("lower"), spec.get("upper")))
        except ValueError as exc:
            check.fail(path, str(exc).removeprefix(f"parameter {str(name)!r}: "))
    return parameters


def _method(check: _Checker, value) -> dict:
    method = dict(check.mapping(value, "method", METHOD_KEYS, required=("kind",)))
    check.string(method["kind"], "method.kind", METHOD_KINDS)
    method["order"] = check.integer(method.get("order", 2), "method.order", 0)
    method["split"] = check.boolean(method.get("split", False), "method.split")
    return method


def _execution(check: _Checker, value) -> dict:
    execution = dict(check.mapping(value, "execution", EXECUTION_KEYS))
    execution["workers"] = check.integer(execution.get("workers", 1), "execution.workers", 1)
    execution["executor"] = check.string(execution.get("executor", "local"), "execution.executor", EXECUTORS)
    execution["chunk"] = check.integer(execution.get("chunk", 16), "execution.chunk", 1)
    if execution.get("scheduler") is not None:
        check.string(execution["scheduler"], "execution.scheduler")
    return execution


def _storage(check: _Checker, value, name: str) -> dict:
    storage = dict(check.mapping(value, "storage", STORAGE_KEYS))
    storage["path"] = check.string(storage.get("path", f"results/{name}.h5"), "storage.path")
    storage["raw"] = check.boolean(storage.get("raw", True), "storage.raw")
    tsvd = storage.get("tsvd")
    if tsvd is not None:
        tsvd = dict(check.mapping(tsvd, "storage.tsvd", TSVD_KEYS))
        tsvd["tol"] = check.number(tsvd.get("tol", 1e-8), "storage.tsvd.tol", 0.0, strict=True)
        if tsvd["tol"] >= 1:
            check.fail("storage.tsvd.tol", f"expected a relative tolerance in (0, 1), got {tsvd['tol']!r}")
        tsvd["batch"] = check.integer(tsvd.get("batch", 1000), "storage.tsvd.batch", 1)
        storage["tsvd"] = tsvd
    if not storage["raw"] and tsvd is None:
        check.fail("storage.raw", "false needs storage.tsvd: otherwise nothing of the outputs would be kept")
    return storage


def _analysis(check: _Checker, value) -> dict:
    analysis = dict(check.mapping(value, "analysis", ANALYSIS_KEYS))
    analysis["band_samples"] = check.integer(analysis.get("band_samples", 20000), "analysis.band_samples", 100)
    analysis["bootstrap"] = check.integer(analysis.get("bootstrap", 200), "analysis.bootstrap", 0)
    return analysis
