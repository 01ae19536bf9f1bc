"""The campaign schema: the keys a campaign file may hold, and the typed checks that raise
CampaignError naming the file, the field and what was expected."""
from __future__ import annotations

import difflib
import math
import re
from collections.abc import Hashable
from pathlib import Path

import numpy as np
import yaml

from ..designs import Design, is_sampled
from ..methods import METHOD_KINDS, method_entry
from ..methods.exactness import exact_total_degree, max_projection_order
from ..methods.validity import MAX_TERMS, method_problem
from ..parameters import DISTRIBUTIONS, Parameter, make_parameter
from ..simulators.jsbsim import Excitation, FlightSetup
from ..simulators.python import PluginError, load_function

SIMULATOR_KINDS = ("jsbsim", "python")
EXECUTORS = ("local", "dask")
TOP_KEYS = ("name", "description", "seed", "simulator", "parameters", "design", "method",
            "execution", "storage", "analysis", "limits", "quantities")
JSBSIM_KEYS = ("kind", "aircraft", "flight", "excitation", "duration_s", "output_rate_hz", "outputs", "trim")
PYTHON_KEYS = ("kind", "function", "outputs")
PARAMETER_KEYS = ("property", "function", "perturbation", "distribution", "nominal", "interval_pct", "lower", "upper")
PERTURBATIONS = ("scale", "offset")
METHOD_KEYS = ("kind", "order", "split", "allow_aliasing")
EXECUTION_KEYS = ("workers", "executor", "scheduler", "chunk", "timeout_s")
STORAGE_KEYS = ("path", "raw", "tsvd")
TSVD_KEYS = ("tol", "batch")
DEFAULT_ORDER = 2
ANALYSIS_KEYS = ("band_samples", "bootstrap", "quantiles", "exceedance")
# Refused before anything is built (see `check_size`); a campaign raises them under `limits:`.
WORKER_BYTES = 60e6  # memory of one local worker process: Python, numpy, JSBSim, the aircraft (52 MB measured)
DEFAULT_LIMITS = {"max_runs": 1_000_000, "max_memory_gb": 8.0, "max_disk_gb": 100.0, "max_pce_terms": MAX_TERMS}
LIMIT_KEYS = tuple(DEFAULT_LIMITS)
MAX_FILE_BYTES = 1 << 20  # a campaign file is at most 1 MiB
MAX_LEVEL = 1000          # sparse grid levels beyond this are refused before any estimate
NAME_PATTERN = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]{0,99}")


class CampaignError(ValueError):
    """A campaign file that cannot be run: names the file, the field and what was expected."""

    def __init__(self, source: str, field_path: str, message: str):
        self.source, self.field = source, field_path
        if len(field_path) > 200:
            field_path = field_path[:197] + "..."
        if len(message) > 2000:  # never quote a huge value back
            message = message[:1997] + "..."
        where = f"{source}: {field_path}: " if field_path else f"{source}: "
        super().__init__(where + message)


def shown(value) -> str:
    """A value as an error message quotes it: short, and readable for people who wrote YAML."""
    if value is None:
        return "nothing"
    if isinstance(value, dict):
        return "a mapping"
    if isinstance(value, list):
        return "a list"
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


class Checker:
    """Typed access to a YAML mapping that raises CampaignError with the field's path."""

    def __init__(self, source: str):
        self.source = source

    def fail(self, path: str, message: str):
        raise CampaignError(self.source, path, message)

    def mapping(self, value, path: str, allowed: tuple[str, ...], required=()) -> dict:
        if not isinstance(value, dict):
            self.fail(path, f"expected a mapping with the keys {', '.join(allowed)}, got {shown(value)}")
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
            self.fail(path, f"expected a finite number, got {shown(value)}")
        if minimum is not None and (value <= minimum if strict else value < minimum):
            self.fail(path, f"expected a number {'>' if strict else '>='} {minimum:g}, got {value!r}")
        return float(value)

    def integer(self, value, path: str, minimum: int) -> int:
        if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
            self.fail(path, f"expected an integer >= {minimum}, got {shown(value)}")
        return value

    def string(self, value, path: str, choices: tuple[str, ...] | None = None) -> str:
        expected = f"one of {', '.join(choices)}" if choices else "a non-empty string"
        if not isinstance(value, str) or not value or (choices and value not in choices):
            self.fail(path, f"expected {expected}, got {shown(value)}")
        return value

    def boolean(self, value, path: str) -> bool:
        if not isinstance(value, bool):
            self.fail(path, f"expected true or false, got {shown(value)}")
        return value


class CampaignLoader(yaml.SafeLoader):
    """YAML's safe loader, except that a key given twice in one mapping is an error (plain YAML
    keeps the last one silently, so a parameter pasted twice would vanish), and that aliases
    (`*name`) are refused: nested aliases expand exponentially (a "billion laughs" bomb)."""

    def compose_node(self, parent, index):
        if self.check_event(yaml.events.AliasEvent):
            event = self.peek_event()
            raise yaml.composer.ComposerError(
                None, None, "YAML aliases (*name) are not accepted in campaign files; write the value out",
                event.start_mark)
        return super().compose_node(parent, index)

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


def check_method_fits_design(check: Checker, method: dict, design: Design, germs: list[str]) -> None:
    """Refuse, before anything runs, a method the design's points cannot carry (methods.validity).
    Without `order`, the order is 2, or the largest a grid's projection allows when that is lower."""
    sampled = is_sampled(design.kind)
    if "order" not in method:
        method["order"] = DEFAULT_ORDER
        if method_entry(method["kind"]).rule == "projection" and not sampled:
            degree = exact_total_degree(design.xi, design.weights, germs, max_degree=2 * DEFAULT_ORDER)
            method["order"] = max(0, min(DEFAULT_ORDER, max_projection_order(degree)))
    problem = method_problem(method["kind"], method["order"], design.xi, design.weights, germs, sampled,
                             allow_aliasing=method.get("allow_aliasing", False))
    if problem:
        check.fail("method.order" if method["kind"] != "monte_carlo" else "method.kind", problem)


def simulator(check: Checker, value, source: str) -> dict:
    if not isinstance(value, dict):
        check.fail("simulator", f"expected a mapping with a kind key, got {shown(value)}")
    if "kind" not in value:
        check.fail("simulator.kind", f"is required; expected one of {', '.join(SIMULATOR_KINDS)}")
    kind = check.string(value["kind"], "simulator.kind", SIMULATOR_KINDS)
    if kind == "python":
        sim = check.mapping(value, "simulator", PYTHON_KEYS, required=("function",))
        try:
            load_function(sim["function"], Path(source).parent)
        except PluginError as exc:
            check.fail("simulator.function", str(exc))
        if "outputs" in sim:
            outputs(check, sim["outputs"])
        return dict(sim)
    sim = dict(check.mapping(value, "simulator", JSBSIM_KEYS))
    sim.setdefault("aircraft", "bacm")
    check.string(sim["aircraft"], "simulator.aircraft")
    from ..simulators.aircraft import AircraftNotFound, locate

    try:  # a path is relative to the campaign file; the resolved folder travels with the simulator
        sim["aircraft_path"] = str(locate(sim["aircraft"], Path(source).resolve().parent).folder)
    except AircraftNotFound as exc:
        check.fail("simulator.aircraft", str(exc))
    if "trim" in sim:
        check.string(sim["trim"], "simulator.trim", FlightSetup.TRIMS)
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
        outputs(check, sim["outputs"])
    return sim


def outputs(check: Checker, value) -> list[str]:
    if not isinstance(value, list) or not value:
        check.fail("simulator.outputs", f"expected a non-empty list of output names, got {shown(value)}")
    for i, item in enumerate(value):
        check.string(item, f"simulator.outputs[{i}]")
    if len(set(value)) != len(value):
        check.fail("simulator.outputs", "names must be unique")
    return value


def parameters(check: Checker, value, kind: str, aircraft) -> list[Parameter]:
    if not isinstance(value, dict) or not value:
        check.fail("parameters", f"expected a mapping of parameter names to their definitions, got {shown(value)}")
    parameters = []
    owners: dict[str, str] = {}  # property -> the parameter that sets it
    for name, spec in value.items():
        path = f"parameters.{name}"
        spec = check.mapping(spec, path, PARAMETER_KEYS, required=("distribution",))
        distribution = check.string(spec["distribution"], f"{path}.distribution", DISTRIBUTIONS)
        function = None
        if "function" in spec or "perturbation" in spec:
            function = function_property(check, spec, path, kind, aircraft)
        if kind == "jsbsim" and "property" not in spec and function is None:
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


def function_property(check: Checker, spec: dict, path: str, kind: str, aircraft) -> str:
    """The property that scales or offsets `spec["function"]` (aero/uq/scale/NAME), checked
    against the aircraft's aerodynamic functions when the aircraft is known."""
    from ..simulators.patch import PatchError, patch_property, resolve_function

    if kind != "jsbsim":
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
    if "interval_pct" in spec and perturbation == "offset":
        check.fail(f"{path}.interval_pct", "has no meaning for an offset (nominal 0): give lower and upper")
    functions = getattr(aircraft, "functions", None)
    if functions is None:
        return patch_property(function, perturbation)
    try:
        full = resolve_function(function, functions)
    except PatchError as exc:
        check.fail(f"{path}.function", f"{exc} (aircraft {aircraft.aircraft!r})")
    return patch_property(full, perturbation, functions)


def method(check: Checker, value) -> dict:
    method = dict(check.mapping(value, "method", METHOD_KEYS, required=("kind",)))
    check.string(method["kind"], "method.kind", METHOD_KINDS)
    if "order" in method:
        check.integer(method["order"], "method.order", 0)
    method["split"] = check.boolean(method.get("split", False), "method.split")
    if "allow_aliasing" in method:  # kept only when given, so that files of older campaigns stay identical
        check.boolean(method["allow_aliasing"], "method.allow_aliasing")
    return method


def execution(check: Checker, value) -> dict:
    execution = dict(check.mapping(value, "execution", EXECUTION_KEYS))
    execution["workers"] = check.integer(execution.get("workers", 1), "execution.workers", 1)
    execution["executor"] = check.string(execution.get("executor", "local"), "execution.executor", EXECUTORS)
    execution["chunk"] = check.integer(execution.get("chunk", 16), "execution.chunk", 1)
    if execution.get("scheduler") is not None:
        check.string(execution["scheduler"], "execution.scheduler")
    if execution.get("timeout_s") is not None:  # default: derived from a measured nominal flight
        execution["timeout_s"] = check.number(execution["timeout_s"], "execution.timeout_s", 0.0, strict=True)
    return execution


def storage(check: Checker, value, name: str) -> dict:
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


def analysis(check: Checker, value, quantities: dict | None = None) -> dict:
    """`quantities`: the campaign's checked quantities, which `exceedance:` must name."""
    analysis = dict(check.mapping(value, "analysis", ANALYSIS_KEYS))
    if "exceedance" in analysis:
        from ..quantities.spec import check_exceedance

        analysis["exceedance"] = check_exceedance(check, analysis["exceedance"], quantities or {})
    analysis["band_samples"] = check.integer(analysis.get("band_samples", 20000), "analysis.band_samples", 100)
    analysis["bootstrap"] = check.integer(analysis.get("bootstrap", 200), "analysis.bootstrap", 0)
    if "quantiles" in analysis:  # kept only when given (default: statistics.DEFAULT_QUANTILES)
        value = analysis["quantiles"]
        if not isinstance(value, list) or not value or len(value) > 20:
            check.fail("analysis.quantiles", f"expected a list of 1 to 20 probabilities, got {shown(value)}")
        for i, probability in enumerate(value):
            check.number(probability, f"analysis.quantiles[{i}]")
            if not 0.0 < probability < 1.0:
                check.fail(f"analysis.quantiles[{i}]", f"expected a probability in (0, 1), got {probability!r}")
    return analysis


def campaign_name(check: Checker, value) -> str:
    """A name that is safe in a path (the default results file is results/NAME.h5)."""
    name = check.string(value, "name")
    if not NAME_PATTERN.fullmatch(name):
        check.fail("name", f"expected 1-100 characters among A-Z a-z 0-9 _ . - (not starting with . or -), "
                           f"got {shown(name)}")
    return name


def limits(check: Checker, value) -> dict:
    """The campaign's size limits (`limits:`), defaults in DEFAULT_LIMITS."""
    given = dict(check.mapping(value, "limits", LIMIT_KEYS))
    found = dict(DEFAULT_LIMITS)
    for key, default in DEFAULT_LIMITS.items():
        if key in given:
            if isinstance(default, int):
                found[key] = check.integer(given[key], f"limits.{key}", 1)
            else:
                found[key] = check.number(given[key], f"limits.{key}", 0.0, strict=True)
    return found


def _points_bound(check: Checker, design: dict, germs: list[str]) -> float | None:
    """The number of points the design builds (for a sparse grid: before merging the tensor rules'
    shared points, an upper bound on the runs and the size of the arrays built), computed without
    building anything; None when the design's own checks should speak first."""
    from ..designs import rules as rule_catalog

    kind, d = design.get("kind"), len(germs)

    def count(key):
        value = design.get(key)
        return value if isinstance(value, int) and not isinstance(value, bool) and value >= 1 else None

    if kind in ("monte_carlo", "sobol", "halton", "latin_hypercube"):
        return count("samples")
    if kind == "pick_freeze":
        n = count("samples")
        return None if n is None else float(n) * (d + 2)
    if kind == "tensor_grid":
        n = count("points")
        return None if n is None else float(n) ** d
    if kind == "sparse_grid":
        level = design.get("level")
        if not isinstance(level, int) or isinstance(level, bool) or level < 0:
            return None
        if level > MAX_LEVEL:
            check.fail("design.level", f"expected at most {MAX_LEVEL}, got {level}")
        try:
            rules = rule_catalog.rules_by_dimension(design.get("rule"), germs, design.get("nested"))
            growth = design.get("growth") or "linear"
            sizes = {}
            for rule in dict.fromkeys(rules):
                top = rule_catalog.max_level(rule, growth)
                if top is not None and level + 1 > top:
                    return None
                sizes[rule] = np.array(rule_catalog.level_sizes(rule, growth, level + 1), dtype=float)
        except (ValueError, KeyError, TypeError):
            return None
        # polynomial product over dimensions: coefficient s = sum over |j| = s of prod sizes[j_k]
        total = np.array([1.0])
        for rule in rules:
            total = np.convolve(total, sizes[rule])[: level + 1]
        return float(total[max(0, level - d + 1): level + 1].sum())
    return None


def check_size(check: Checker, data: dict, simulator: dict, parameters: list, method: dict, execution: dict,
               storage: dict, limits: dict) -> dict:
    """The design's size, its memory and disk estimate and the PCE size, from the campaign alone
    (nothing built): refused beyond `limits` (CampaignError naming the figure and the limit).
    Returns the figures {"runs", "memory_gb", "disk_gb", "pce_terms"}."""
    d = len(parameters)
    points = _points_bound(check, data["design"], [p.germ for p in parameters])
    figures = {"runs": points}
    if points is not None and points > limits["max_runs"]:
        check.fail("design", f"{points:.4g} runs (points built), more than limits.max_runs = {limits['max_runs']}; "
                             "choose a smaller design or raise limits.max_runs")
    order = method.get("order", DEFAULT_ORDER)  # without it, at most DEFAULT_ORDER (check_method_fits_design)
    terms = math.comb(d + order, order) if order <= 10**6 else math.inf
    figures["pce_terms"] = terms
    if terms > limits["max_pce_terms"]:
        check.fail("method.order", f"a PCE of order {order} in {d} dimensions has {float(terms):.4g} "
                                   f"terms, more than limits.max_pce_terms = {limits['max_pce_terms']}")
    if simulator["kind"] == "jsbsim":
        times = math.floor(float(simulator.get("duration_s", 50.0)) * float(simulator.get("output_rate_hz", 20.0))) + 1
        n_outputs = len(simulator.get("outputs", ())) or 5
    else:
        times, n_outputs = 1, len(simulator.get("outputs", ())) or 1  # known only once a sample has run
    n = points or 0
    rank = min(times, n, 1000)
    memory = 8.0 * (n * (3 * d + 6)                                    # the design, status, merging
                    + execution["workers"] * execution["chunk"] * times * n_outputs * 3  # chunks in flight
                    + n_outputs * times * execution["chunk"] * 4)      # results being written
    on_this_machine = execution.get("executor", "local") == "local" or not execution.get("scheduler")
    processes = execution["workers"] if on_this_machine else 0  # dask without a scheduler: a LocalCluster
    memory += processes * WORKER_BYTES
    tsvd = storage.get("tsvd")
    if tsvd:
        memory += 8.0 * 4 * times * (tsvd["batch"] + rank) + 8.0 * n * rank
    disk = 8.0 * n * times * n_outputs if storage["raw"] else 0.0
    if tsvd:
        disk += 8.0 * n_outputs * (times + n) * rank * 2
    figures["memory_gb"], figures["disk_gb"] = memory / 1e9, disk / 1e9
    if memory / 1e9 > limits["max_memory_gb"]:
        check.fail("design", f"the campaign needs about {memory / 1e9:.3g} GB of memory ({n:.4g} runs of "
                             f"{times:.4g} times x {n_outputs} outputs, {processes} worker processes of "
                             f"{WORKER_BYTES / 1e6:.0f} MB), more than limits.max_memory_gb = "
                             f"{limits['max_memory_gb']:g}")
    if disk / 1e9 > limits["max_disk_gb"]:
        check.fail("storage", f"the results file would take about {disk / 1e9:.3g} GB ({n:.4g} runs of "
                              f"{times:.4g} times x {n_outputs} outputs), more than limits.max_disk_gb = "
                              f"{limits['max_disk_gb']:g}")
    return figures
