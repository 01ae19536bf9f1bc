"""The campaign schema: the keys a campaign file may hold, and the typed checks that raise
CampaignError naming the file, the field and what was expected."""
from __future__ import annotations

import difflib
import math
import re
from collections.abc import Hashable
from dataclasses import replace

import numpy as np
import yaml

from ..designs import REGISTRY as DESIGNS
from ..designs import Design, DesignSpec
from ..methods import DEFAULT_ORDER, METHOD_KINDS, METHODS, Method, MethodSpec
from ..methods.exactness import exact_total_degree, max_projection_order
from ..methods.validity import method_problem
from ..parameters import DISTRIBUTIONS, Parameter, make_parameter, seed_names
from ..parameters.dependence import KINDS as DEPENDENCE_KINDS
from ..parameters.dependence import GaussianCopula, correlation_problem
from ..parameters.distributions import SEED_REFUSAL
from ..simulators.patch import patch_kind
from ..simulators.kinds import REGISTRY as SIMULATORS
from ..simulators.kinds import SIMULATOR_KINDS
from ..simulators.spec import SimulatorSpec
from ..text import FieldError
from ..text.console import quoted_value
from .sections import Execution, Limits, Storage

TOP_KEYS = ("name", "description", "seed", "simulator", "parameters", "design", "method",
            "execution", "storage", "analysis", "limits", "quantities", "dependence")
PARAMETER_KEYS = ("property", "function", "perturbation", "distribution", "nominal", "interval_pct", "lower", "upper")
LAW_KEYS = ("distribution", "nominal", "interval_pct", "lower", "upper")  # a parameter's law; the rest say what it sets
PERTURBATIONS = ("scale", "offset", "offset_value")
DEPENDENCE_KEYS = ("kind", "parameters", "correlation")
# Refused before anything is built (see `check_size`); a campaign raises them under `limits:`.
WORKER_BYTES = 60e6  # memory of one local worker process: Python, numpy, JSBSim, the aircraft (52 MB measured)
MAX_FILE_BYTES = 1 << 20  # a campaign file is at most 1 MiB
NAME_PATTERN = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]{0,99}")


class CampaignError(FieldError):
    """A campaign file that cannot be run: names the file (`source`), the field and what was expected."""

    def __init__(self, source: str, field_path: str, message: str):
        if len(field_path) > 200:
            field_path = field_path[:197] + "..."
        if len(message) > 2000:  # never quote a huge value back
            message = message[:1997] + "..."
        super().__init__(field_path, message)
        self.source = source
        where = f"{source}: {field_path}: " if field_path else f"{source}: "
        self.args = (where + message,)


class Checker:
    """Typed access to a YAML mapping that raises CampaignError with the field's path."""

    quoted = staticmethod(quoted_value)

    def __init__(self, source: str):
        self.source = source

    def fail(self, path: str, message: str):
        raise CampaignError(self.source, path, message)

    def mapping(self, value, path: str, allowed: tuple[str, ...], required=()) -> dict:
        if not isinstance(value, dict):
            self.fail(path, f"expected a mapping with the keys {', '.join(allowed)}, got {quoted_value(value)}")
        for key in value:
            if key not in allowed:
                close = difflib.get_close_matches(str(key), allowed, n=1)
                hint = f"did you mean {close[0]}? " if close else ""
                key = str(key) if len(str(key)) <= 60 else str(key)[:57] + "..."
                self.fail(f"{path}.{key}" if path else key,
                          f"unknown key; {hint}expected one of {', '.join(allowed)}")
        for key in required:
            if key not in value:
                self.fail(f"{path}.{key}" if path else key, "is required")
        return value

    def number(self, value, path: str, minimum: float | None = None, strict=False) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            self.fail(path, f"expected a finite number, got {quoted_value(value)}")
        if minimum is not None and (value <= minimum if strict else value < minimum):
            self.fail(path, f"expected a number {'>' if strict else '>='} {minimum:g}, got {value!r}")
        return float(value)

    def integer(self, value, path: str, minimum: int) -> int:
        if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
            self.fail(path, f"expected an integer >= {minimum}, got {quoted_value(value)}")
        return value

    def string(self, value, path: str, choices: tuple[str, ...] | None = None) -> str:
        expected = f"one of {', '.join(choices)}" if choices else "a non-empty string"
        if not isinstance(value, str) or not value or (choices and value not in choices):
            number = isinstance(value, (int, float)) and not isinstance(value, bool)
            close = difflib.get_close_matches(value, choices, n=1) if choices and isinstance(value, str) else []
            hint = (f" (YAML reads {value} as a number: quote it, \"{value}\")" if number and not choices else
                    f"; did you mean {close[0]}?" if close else "")
            self.fail(path, f"expected {expected}, got {quoted_value(value)}{hint}")
        return value

    def boolean(self, value, path: str) -> bool:
        if not isinstance(value, bool):
            self.fail(path, f"expected true or false, got {quoted_value(value)}")
        return value


MAX_DEPTH = 64           # YAML nesting deeper than this is refused (a campaign nests 4 levels)
MAX_INTEGER_CHARS = 100  # an integer written longer is refused (Python reads at most 4300 decimal digits)


class CampaignLoader(yaml.SafeLoader):
    """YAML's safe loader, except that a key given twice in one mapping is an error (plain YAML
    keeps the last one silently, so a parameter pasted twice would vanish), that aliases
    (`*name`) are refused: nested aliases expand exponentially (a "billion laughs" bomb), and that
    every other way a value can fail to be read is a YAML error at its line: nesting beyond
    MAX_DEPTH (Python's recursion limit otherwise), integers longer than MAX_INTEGER_CHARS, and
    values that YAML's own constructors reject with a Python error (`2001-13-45`, `!!float abc`)."""

    def __init__(self, stream):
        super().__init__(stream)
        self.depth = 0

    def compose_node(self, parent, index):
        event = self.peek_event()
        if isinstance(event, yaml.events.AliasEvent):
            raise yaml.composer.ComposerError(
                None, None, "YAML aliases (*name) are not accepted in campaign files; write the value out",
                event.start_mark)
        if self.depth >= MAX_DEPTH:
            raise yaml.composer.ComposerError(
                None, None, f"nested deeper than {MAX_DEPTH} levels; a campaign nests a few", event.start_mark)
        self.depth += 1
        try:
            return super().compose_node(parent, index)
        finally:
            self.depth -= 1

    def construct_document(self, node):
        return self._readable(super().construct_document, node)

    def construct_object(self, node, deep=False):
        return self._readable(super().construct_object, node, deep)

    @staticmethod
    def _readable(construct, node, *args):
        try:
            return construct(node, *args)
        except (ValueError, TypeError, ArithmeticError) as exc:
            raise yaml.constructor.ConstructorError(None, None, f"cannot read this value ({exc})",
                                                    node.start_mark) from None

    def construct_yaml_int(self, node):
        text = self.construct_scalar(node)
        if len(text) > MAX_INTEGER_CHARS:
            raise yaml.constructor.ConstructorError(
                None, None, f"an integer of {len(text)} characters; no field takes more than {MAX_INTEGER_CHARS}",
                node.start_mark)
        return super().construct_yaml_int(node)

    def construct_mapping(self, node, deep=False):
        seen = set()
        for key_node, _ in node.value if isinstance(node, yaml.MappingNode) else ():
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


CampaignLoader.add_constructor("tag:yaml.org,2002:int", CampaignLoader.construct_yaml_int)
# YAML 1.1 (PyYAML) reads 1e-8 as a string: accept exponents without a dot, as YAML 1.2 does.
CampaignLoader.yaml_implicit_resolvers = {
    key: list(value) for key, value in yaml.SafeLoader.yaml_implicit_resolvers.items()}
CampaignLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
                  |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
                  |\.[0-9_]+(?:[eE][-+]?[0-9]+)?
                  |[-+]?\.(?:inf|Inf|INF)
                  |\.(?:nan|NaN|NAN))$""", re.X),
    list("-+0123456789."))


def yaml_error(exc: yaml.YAMLError) -> str:
    """'YAML syntax error at line L, column C: problem (context at line L', column C')' ('YAML error'
    for a value that cannot be read)."""
    def at(mark) -> str:
        return f"line {mark.line + 1}, column {mark.column + 1}"

    mark = getattr(exc, "problem_mark", None)
    kind = "YAML syntax error" if isinstance(exc, (yaml.scanner.ScannerError, yaml.parser.ParserError)) else "YAML error"
    message = f"{kind} at {at(mark)}: " if mark else f"{kind}: "
    message += getattr(exc, "problem", None) or str(exc)
    context, context_mark = getattr(exc, "context", None), getattr(exc, "context_mark", None)
    if context and context_mark:
        message += f" ({context} that starts at {at(context_mark)})"
    return message


def method_for_design(check: Checker, method: MethodSpec, design: Design, germs: list[str]) -> MethodSpec:
    """The checked `method` with the order the design's points carry, refused before anything runs when they
    cannot carry it (methods.validity). Without `order`, the order is 2, or the largest a grid's projection
    allows when that is lower."""
    sampled = DESIGNS[design.kind].sampled
    entry = method.entry
    order = method.order
    if order is None:
        order = DEFAULT_ORDER
        if entry.projects and not sampled:
            degree = exact_total_degree(design.xi, design.weights, germs, max_degree=2 * DEFAULT_ORDER)
            order = max(0, min(DEFAULT_ORDER, max_projection_order(degree)))
    problem = method_problem(method.kind, order, design.xi, design.weights, germs, sampled,
                             allow_aliasing=method.allow_aliasing)
    if problem:
        check.fail(f"method.{entry.order_key}" if entry.expands else "method.kind", problem)
    return replace(method, order=order)


def simulator(check: Checker, value) -> SimulatorSpec:
    """The `simulator:` mapping checked as written by its kind's entry (simulators/kinds), as its spec:
    nothing is imported or located (`resolve_simulator`)."""
    if not isinstance(value, dict):
        check.fail("simulator", f"expected a mapping with a kind key, got {quoted_value(value)}")
    if "kind" not in value:
        check.fail("simulator.kind", f"is required; expected one of {', '.join(SIMULATOR_KINDS)}")
    kind = check.string(value["kind"], "simulator.kind", SIMULATOR_KINDS)
    return SimulatorSpec.from_checked(SIMULATORS[kind].check(check, value))


def check_fixed_properties(check: Checker, sim: SimulatorSpec, parameters: list[Parameter], aircraft) -> None:
    """Each fixed property is one the aircraft can set (when it is known), and no parameter sets it too."""
    by_parameter = {p.property: p.name for p in parameters}
    for name in sim.get("properties", {}):
        path = f"simulator.properties.{name}"
        if name in by_parameter:
            check.fail(path, f"is also set by parameters.{by_parameter[name]}: give it in one place")
        if aircraft is not None and (aircraft.value(name) is None or not aircraft.writable(name)):
            check.fail(path, f"expected a property the simulator can set in aircraft {aircraft.aircraft!r}, "
                             f"got {name!r}{aircraft.hint(name)}")


def resolve_simulator(check: Checker, sim: SimulatorSpec, source: str) -> SimulatorSpec:
    """`sim` (checked by `simulator`) with what it runs found, relative to the campaign file `source`: a
    python simulator's function is imported (its module's code runs); a JSBSim aircraft is located
    (`aircraft_path`, the folder that travels with the simulator). Only for campaigns about to be planned
    or run: reading results never calls this."""
    return sim.entry.resolve(check, sim, source)


def parameters(check: Checker, value, kind: str, aircraft) -> list[Parameter]:
    if not isinstance(value, dict) or not value:
        check.fail("parameters", f"expected a mapping of parameter names to their definitions, got {quoted_value(value)}")
    parameters = []
    owners: dict[str, str] = {}  # property -> the parameter that sets it
    for name, spec in value.items():
        path = f"parameters.{name}"
        spec = check.mapping(spec, path, PARAMETER_KEYS, required=("distribution",))
        distribution = check.string(spec["distribution"], f"{path}.distribution", DISTRIBUTIONS)
        if not DISTRIBUTIONS[distribution].polynomial:
            parameters.append(seed_parameter(check, spec, path, str(name), kind, owners, aircraft))
            continue
        function = None
        if "function" in spec or "perturbation" in spec:
            function = function_property(check, spec, path, kind, aircraft)
        if SIMULATORS[kind].aircraft and "property" not in spec and function is None:
            check.fail(f"{path}.property", "is required: the JSBSim property the parameter sets, e.g. aero/uq/CL0 "
                                           "(or function: and perturbation: to scale or offset an aerodynamic function)")
        prop = function or check.string(spec.get("property", str(name)), f"{path}.property")
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
        if function is not None:
            from ..simulators.patch import NOMINAL

            nominal = NOMINAL[spec["perturbation"]] if nominal is None else nominal
        elif aircraft is not None and aircraft.value(prop) is None and patch_kind(prop):
            nominal = patch_nominal(check, prop, f"{path}.property", aircraft) if nominal is None else nominal
        elif aircraft is not None:
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


def seed_parameter(check: Checker, spec: dict, path: str, name: str, kind: str, owners: dict,
                   aircraft) -> Parameter:
    """`distribution: seed`: the integer seed of a random stream (e.g. atmosphere/randomseed), over its
    fixed range; only `property` goes with it."""
    from ..parameters.distributions import SEED_COUNT

    for key in spec:
        if key not in ("property", "distribution"):
            check.fail(f"{path}.{key}", f"has no meaning for a seed (its seeds are 0 to {SEED_COUNT - 1}, drawn "
                                        "from the campaign's seed and each run's design index): give only property")
    if SIMULATORS[kind].aircraft and "property" not in spec:
        check.fail(f"{path}.property", "is required: the JSBSim property the seed sets, e.g. atmosphere/randomseed")
    prop = check.string(spec.get("property", name), f"{path}.property")
    if prop in owners:
        check.fail(f"{path}.property", f"expected each property once, but {prop!r} is already set by "
                                       f"parameters.{owners[prop]}")
    owners[prop] = name
    if aircraft is not None and (aircraft.value(prop) is None or not aircraft.writable(prop)):
        check.fail(f"{path}.property", f"expected a property the simulator can set in aircraft "
                                       f"{aircraft.aircraft!r}, got {prop!r}{aircraft.hint(prop)}")
    return make_parameter(name, prop, "seed", SEED_COUNT // 2, lower=0.0, upper=float(SEED_COUNT))  # nominal: κ(ξ = 0)


def check_seeds(check: Checker, parameters: list[Parameter], design: DesignSpec, method: MethodSpec) -> None:
    """A seed's random stream has no polynomial expansion: refuse grids and PCE methods over it, and more
    than one seed (the split of the variance between seeds and the other inputs needs them as one input)."""
    seeds = seed_names(parameters)
    if not seeds:
        return
    if len(seeds) > 1:
        check.fail(f"parameters.{seeds[1]}.distribution", f"one seed parameter per campaign, but "
                                                          f"{', '.join(seeds)} are seeds")
    where = f"parameters.{seeds[0]}.distribution"
    if not design.entry.sampled and not design.entry.rare:  # a rare-event design redraws a seed
        sampled = ", ".join(name for name, kind in DESIGNS.items() if kind.sampled)
        check.fail(where, f"a seed needs a sampled design ({sampled}), not {design.kind}: "
                          "a random stream has no polynomial expansion for a grid to integrate")
    if not method.entry.runs_on_sampled:  # it would fit a PCE in the seed's ξ
        check.fail(where, f"{SEED_REFUSAL} ({method.kind})")


def dependence(check: Checker, value, known: list[str], seeds: list[str], fixed=()) -> GaussianCopula | None:
    """`dependence: {kind: gaussian_copula, parameters: [...], correlation: [[...]]}`: the copula over
    the named parameters (`known`, the campaign's, default: every one but the `seeds`, in campaign order),
    or None. `fixed`: the simulator's fixed properties, which a name may not be."""
    if value is None:
        return None
    value = check.mapping(value, "dependence", DEPENDENCE_KEYS, required=("kind", "correlation"))
    check.string(value["kind"], "dependence.kind", DEPENDENCE_KINDS)
    names = value.get("parameters", [name for name in known if name not in seeds])
    if not isinstance(names, list) or len(names) < 2:
        check.fail("dependence.parameters", f"expected a list of at least two parameter names, got {quoted_value(names)}")
    for i, name in enumerate(names):
        path = f"dependence.parameters[{i}]"
        if not isinstance(name, str) or name not in known:
            what = (" is a fixed property (simulator.properties), not an uncertain parameter"
                    if isinstance(name, str) and name in fixed else "")
            check.fail(path, f"expected one of the campaign's parameters ({', '.join(known)}), got {quoted_value(name)}{what}")
        if name in seeds:
            check.fail(path, f"{name} is a seed: a random stream's seed cannot be correlated")
        if name in names[:i]:
            check.fail(path, f"{name} is listed twice")
    n = len(names)
    rows = value["correlation"]
    size = f"a {n} x {n} list of rows (one per parameter: {', '.join(names)})"
    if not isinstance(rows, list) or len(rows) != n:
        check.fail("dependence.correlation", f"expected {size}, got {quoted_value(rows)}"
                                             + (f" of {len(rows)} rows" if isinstance(rows, list) else ""))
    for i, row in enumerate(rows):
        if not isinstance(row, list) or len(row) != n:
            check.fail(f"dependence.correlation[{i}]", f"expected a row of {n} numbers ({size}), got {quoted_value(row)}"
                                                       + (f" of {len(row)}" if isinstance(row, list) else ""))
        for j, entry in enumerate(row):
            check.number(entry, f"dependence.correlation[{i}][{j}]")
    matrix = np.array(rows, dtype=float)
    problem = correlation_problem(matrix)
    if problem:
        check.fail(f"dependence.correlation{problem[0]}", problem[1])
    return GaussianCopula(tuple(names), matrix)


def check_dependence_design(check: Checker, design: DesignSpec, copula: GaussianCopula | None,
                            parameters: list[Parameter]) -> None:
    """A grid over correlated parameters integrates in their standard-normal germs: a uniform rule named
    for every dimension cannot serve them."""
    rule = design.get("rule")
    if copula is None or not isinstance(rule, str):
        return
    from ..designs.rules import RULE_TABLE

    entry = RULE_TABLE.get(rule)
    if entry is not None and entry.germ != "normal" and any(p.germ == entry.germ for p in parameters
                                                            if p.name in copula.names):
        check.fail("design.rule", f"rule {rule} is for {entry.germ} germs, but the parameters in dependence: "
                                  f"({', '.join(copula.names)}) are driven by standard-normal germs (the Nataf "
                                  "transform works in normal space): give a normal rule (gauss_hermite, "
                                  "genz_keister) or a mapping germ -> rule, e.g. {normal: gauss_hermite, "
                                  "uniform: gauss_legendre}")


def patch_nominal(check: Checker, prop: str, path: str, aircraft) -> float:
    """The nominal of a property that asks for a patch itself (`aero/uq/offset/CDo`), checked as
    `function:` with `perturbation:` is."""
    from ..simulators.base import SimulatorSettingError
    from ..simulators.patch import NOMINAL, check_perturbation, patch_request

    try:
        function, perturbation = patch_request(prop, aircraft.functions)
        check_perturbation(function, perturbation, getattr(aircraft, "aero_factors", {}))
    except SimulatorSettingError as exc:
        check.fail(path, f"{exc} (aircraft {aircraft.aircraft!r})")
    return NOMINAL[perturbation]


def function_property(check: Checker, spec: dict, path: str, kind: str, aircraft) -> str:
    """The property that scales or offsets `spec["function"]` (aero/uq/scale/NAME), checked
    against the aircraft's aerodynamic functions when the aircraft is known."""
    from ..simulators.base import SimulatorSettingError
    from ..simulators.patch import check_perturbation, patch_property, resolve_function

    if not SIMULATORS[kind].aircraft:
        check.fail(f"{path}.function", "is for JSBSim aircraft; a python simulator's parameters have no functions")
    if "property" in spec:
        check.fail(path, "give either property or function (with perturbation), not both")
    if "function" not in spec:
        check.fail(f"{path}.function", "is required with perturbation: the aerodynamic function to perturb, "
                                       "e.g. aero/coefficient/CLwbh")
    function = check.string(spec["function"], f"{path}.function")
    if "perturbation" not in spec:
        check.fail(f"{path}.perturbation", f"is required with function: expected one of {', '.join(PERTURBATIONS)}")
    perturbation = check.string(spec["perturbation"], f"{path}.perturbation", PERTURBATIONS)
    if "interval_pct" in spec and perturbation != "scale":
        check.fail(f"{path}.interval_pct", "has no meaning for an offset (nominal 0): give lower and upper")
    functions = getattr(aircraft, "functions", None)
    if functions is None:
        return patch_property(function, perturbation)
    try:
        full = resolve_function(function, functions)
    except SimulatorSettingError as exc:
        check.fail(f"{path}.function", f"{exc} (aircraft {aircraft.aircraft!r})")
    try:
        check_perturbation(full, perturbation, getattr(aircraft, "aero_factors", {}))
    except SimulatorSettingError as exc:
        check.fail(f"{path}.perturbation", f"{exc} (aircraft {aircraft.aircraft!r})")
    return patch_property(full, perturbation, functions)


def design(check: Checker, value) -> DesignSpec:
    """The `design:` mapping checked by its kind (`DesignSpec.checked`): the one validator of a campaign's design
    and of a results file's record of it.

    Parameters
    ----------
    check : Checker
        Names the file in its CampaignError.
    value : object
        The `design:` value as written.

    Returns
    -------
    DesignSpec
        Its kind and every key of the kind, checked, defaults filled in.

    Raises
    ------
    CampaignError
        Naming the key (`design`, `design.kind`, `design.KEY`) and what it expected.
    """
    try:
        return DesignSpec.checked(value)
    except FieldError as exc:
        check.fail(exc.field, exc.message)


def method(check: Checker, value) -> MethodSpec:
    """The `method:` mapping checked against its kind's keys (`Method.keys`: an unknown kind, the shared ones):
    the one validator of a campaign's method and of a results file's record of it.

    Parameters
    ----------
    check : Checker
        Names the file in its CampaignError.
    value : object
        The `method:` value as written.

    Returns
    -------
    MethodSpec
        Its keys as written, `split` filled in where the kind has it.

    Raises
    ------
    CampaignError
        Naming the key (`method.KEY`) and what it expected.
    """
    kind = value.get("kind") if isinstance(value, dict) else None
    entry = METHODS.get(kind) if isinstance(kind, str) else None
    keys = (entry or Method).keys
    method = dict(check.mapping(value, "method", ("kind", *keys), required=("kind",)))
    check.string(method["kind"], "method.kind", METHOD_KINDS)
    for key, spec in keys.items():
        if key not in method and spec.filled:
            method[key] = spec.default
        if key in method and isinstance(spec.default, bool):
            check.boolean(method[key], f"method.{key}")
        elif key in method and spec.minimum is not None:
            check.integer(method[key], f"method.{key}", spec.minimum)
    problem = entry.problem(method) if entry else None
    if problem:
        check.fail(f"method.{problem[0]}", problem[1])
    return MethodSpec.from_checked(method)


def campaign_name(check: Checker, value) -> str:
    """A name that is safe in a path (the default results file is results/NAME.h5)."""
    name = check.string(value, "name")
    if not NAME_PATTERN.fullmatch(name):
        check.fail("name", f"expected 1-100 characters among A-Z a-z 0-9 _ . - (not starting with . or -), "
                           f"got {quoted_value(name)}")
    return name


def check_size(check: Checker, design: DesignSpec, simulator: SimulatorSpec, parameters: list, method: MethodSpec,
               execution: Execution, storage: Storage, limits: Limits, germs: list[str] | None = None) -> dict:
    """The design's size, its memory and disk estimate and the PCE size, from the campaign alone
    (nothing built): refused beyond `limits` (CampaignError naming the figure and the limit).
    Returns the figures {"runs", "memory_gb", "disk_gb", "pce_terms"}."""
    d = len(parameters)
    try:  # the design kind's own size (designs.DesignKind.size)
        points = design.size(germs or [p.germ for p in parameters])
    except FieldError as exc:
        check.fail(exc.field, exc.message)
    figures = {"runs": points}
    if points > limits.max_runs:
        check.fail("design", f"{points:.4g} runs (points built), more than limits.max_runs = {limits.max_runs}; "
                             "choose a smaller design or raise limits.max_runs")
    order = DEFAULT_ORDER if method.order is None else method.order  # DEFAULT_ORDER at most
    terms = math.comb(d + order, order) if order <= 10**6 else math.inf
    figures["pce_terms"] = terms
    if terms > limits.max_pce_terms:
        check.fail("method.order", f"a PCE of order {order} in {d} dimensions has {float(terms):.4g} "
                                   f"terms, more than limits.max_pce_terms = {limits.max_pce_terms}")
    times, n_outputs = simulator.entry.recorded(simulator)  # 1 where known once a sample has run
    n = points
    rank = min(times, n, 1000)
    memory = 8.0 * (n * (3 * d + 6)                                    # the design, status, merging
                    + execution.workers * execution.chunk * times * n_outputs * 3  # chunks in flight
                    + n_outputs * times * execution.chunk * 4)      # results being written
    processes = execution.workers if execution.on_this_machine else 0  # dask without a scheduler: a LocalCluster
    memory += processes * WORKER_BYTES
    tsvd = storage.tsvd
    if tsvd:
        memory += 8.0 * 4 * times * (tsvd.batch + rank) + 8.0 * n * rank
    disk = 8.0 * n * times * n_outputs if storage.raw else 0.0
    if tsvd:
        disk += 8.0 * n_outputs * (times + n) * rank * 2
    figures["memory_gb"], figures["disk_gb"] = memory / 1e9, disk / 1e9
    if memory / 1e9 > limits.max_memory_gb:
        check.fail("design", f"the campaign needs about {memory / 1e9:.3g} GB of memory ({n:.4g} runs of "
                             f"{times:.4g} times x {n_outputs} outputs, {processes} worker processes of "
                             f"{WORKER_BYTES / 1e6:.0f} MB), more than limits.max_memory_gb = "
                             f"{limits.max_memory_gb:g}")
    if disk / 1e9 > limits.max_disk_gb:
        check.fail("storage", f"the results file would take about {disk / 1e9:.3g} GB ({n:.4g} runs of "
                              f"{times:.4g} times x {n_outputs} outputs), more than limits.max_disk_gb = "
                              f"{limits.max_disk_gb:g}")
    from ..store.layout import MAX_OUTPUT_VALUES  # what every reader of the results file holds

    if n * times > MAX_OUTPUT_VALUES:
        check.fail("design", f"{n:.4g} runs x {times:.4g} times = {n * times:.4g} values per output, more than the "
                             f"results file's readers hold ({MAX_OUTPUT_VALUES:.4g}): choose fewer runs, or record "
                             "fewer times (a lower output rate or a shorter flight)")
    return figures
