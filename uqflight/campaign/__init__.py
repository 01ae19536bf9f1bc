"""Campaign files (YAML): read, validate (against `schema`), and turn into parameters, a design and settings.

Validation happens before anything runs. Every problem is a `CampaignError` whose message
names the file, the field and what was expected, e.g.
`campaigns/x.yaml: parameters.CL0.interval_pct: expected a number > 0, got -3`.
"""
from __future__ import annotations

import copy
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable

import numpy as np
import yaml

from ..designs import Design, DesignSpec
from ..methods import Method, MethodSpec
from ..parameters import Parameter, germs_of, seed_names, to_physical
from ..parameters.dependence import GaussianCopula
from ..quantities import QuantitySpec
from ..quantities.spec import check_quantities
from ..simulators.jsbsim import NAMED_OUTPUTS
from ..simulators.spec import SimulatorSpec
from . import schema
from ..text import FieldError
from .schema import TOP_KEYS, CampaignError, CampaignLoader, Checker, yaml_error
from .sections import Analysis, Execution, Limits, Storage

AircraftReader = Callable[[SimulatorSpec], object]  # simulator -> its aircraft's properties (see AircraftProperties)

@dataclass(frozen=True)
class Campaign:
    """A validated campaign, frozen. `text` is the file's exact text (its hash identifies results)."""

    source: str
    text: str
    name: str
    seed: int
    simulator: SimulatorSpec  # `simulator:` checked, located when the campaign is to run
    parameters: list[Parameter]
    design_spec: DesignSpec
    method: MethodSpec
    execution: Execution
    storage: Storage
    analysis: Analysis = field(default_factory=Analysis)
    limits: Limits = field(default_factory=Limits)
    runs: int | None = None  # the design's size, known once validated
    quantities: dict[str, QuantitySpec] = field(default_factory=dict)  # `quantities:` by name, checked
    dependence: GaussianCopula | None = None  # `dependence:` (parameters.dependence), None: independent
    mapping: dict = field(default_factory=dict, repr=False)  # the file's mapping as written (YAML), never changed

    @property
    def germs(self) -> list[str]:
        return germs_of(self.parameters, self.dependence)

    def to_physical(self, xi: np.ndarray) -> np.ndarray:
        """κ (N, d) = T(ξ) of the design's ξ (N, d): what the simulator is given."""
        return to_physical(self.parameters, xi, self.dependence)

    @property
    def redrawn(self) -> tuple[int, ...]:
        """The columns of the parameters that are random streams' seeds (`distribution: seed`)."""
        return tuple(k for k, p in enumerate(self.parameters) if not p.law.polynomial)

    def design(self) -> Design:
        """The design of `design_spec` over the parameters' germs (DesignSpec.build)."""
        return self.design_spec.build(self.germs, self.seed, self.redrawn)


def load_campaign(path: str | Path, read_aircraft: AircraftReader | None = None) -> Campaign:
    """Read and validate a campaign file.

    `read_aircraft(simulator)` gives the aircraft's properties
    (`uqflight.simulators.aircraft_properties.AircraftProperties`); it is used for
    JSBSim campaigns to check property and output names and to read nominal values from the
    aircraft. Without it, those checks are skipped and nominal values must be given.
    """
    source = str(path)
    try:
        with open(path, "rb") as fh:
            raw = fh.read(schema.MAX_FILE_BYTES + 1)
        if len(raw) > schema.MAX_FILE_BYTES:
            raise CampaignError(source, "", f"the file is larger than {schema.MAX_FILE_BYTES // 1024} KiB; "
                                            "a campaign file is a few lines of YAML")
        text = raw.decode("utf-8")
    except OSError as exc:
        raise CampaignError(source, "", f"cannot read the file ({exc.strerror})") from exc
    except UnicodeDecodeError as exc:
        raise CampaignError(source, "", f"expected UTF-8 text, got byte {exc.object[exc.start]:#04x} "
                                        f"at position {exc.start}") from exc
    return parse_campaign(text, source, read_aircraft)


def parse_campaign(text: str, source: str = "<campaign>", read_aircraft: AircraftReader | None = None) -> Campaign:
    """Validate campaign text; see `load_campaign`. A python simulator's module is imported (its code
    runs): this is for campaigns about to be planned or run; a results file's campaign is read by
    `campaign.record.read_record`, which never resolves the simulator."""
    written = campaign_yaml(text, source)
    check, data, simulator = check_settings(Checker(source), written)
    simulator = schema.resolve_simulator(check, simulator, source)
    aircraft = None
    if read_aircraft and simulator.entry.aircraft:
        try:
            aircraft = read_aircraft(simulator)
        except (FileNotFoundError, RuntimeError) as exc:  # no such aircraft, or JSBSim cannot load it
            check.fail("simulator.aircraft", str(exc))
        for i, output in enumerate(simulator.get("outputs", ())):
            if output not in NAMED_OUTPUTS and aircraft.value(output) is None:
                check.fail(f"simulator.outputs[{i}]", f"expected one of {', '.join(NAMED_OUTPUTS)} or a JSBSim "
                           f"property of aircraft {aircraft.aircraft!r}, got {output!r}{aircraft.hint(output)}")
    parameters = schema.parameters(check, data["parameters"], simulator.kind, aircraft)
    schema.check_fixed_properties(check, simulator, parameters, aircraft)
    quantities = check_quantities(check, data.get("quantities"), simulator, aircraft)
    campaign = build_campaign(check, data, simulator, parameters, text, quantities, written)
    schema.check_dependence_design(check, campaign.design_spec, campaign.dependence, parameters)
    schema.check_size(check, campaign.design_spec, simulator, parameters, campaign.method, campaign.execution,
                      campaign.storage, campaign.limits, campaign.germs)  # from the campaign alone, nothing built
    try:  # what the spec asks of the parameters' germs (their rules, their number)
        design = campaign.design()
    except FieldError as exc:
        raise CampaignError(source, exc.field, exc.message) from exc
    except ValueError as exc:
        raise CampaignError(source, "design", str(exc)) from exc
    design_kind = campaign.design_spec.entry
    if design_kind.rare:  # its rounds are made from the results; it estimates its event only
        from ..designs.rare import check_rare_campaign

        check_rare_campaign(check, campaign)
        return replace(campaign, runs=int(campaign.design_spec.size(campaign.germs)))
    if design_kind.adaptive:  # its grid is made from the results: its points are checked on analysis
        entry = campaign.method.entry
        if entry.sampled_only:
            check.fail("method.kind", f"{campaign.method.kind} needs a sampled design; an adaptive grid needs "
                                      "its weights: use integration, pseudo_galerkin or interpolation")
        method = campaign.method  # its order given or its default, the mapping's first key
        method = replace(method, order=entry.keys[entry.order_key].default if method.order is None else method.order,
                         written=(entry.order_key, *(key for key in method.written if key != entry.order_key)))
        return replace(campaign, method=method, runs=int(campaign.design_spec.size(campaign.germs)))
    method = schema.method_for_design(check, campaign.method, design, campaign.germs)
    return replace(campaign, method=method, runs=len(design.weights))


def campaign_yaml(text: str, source: str):
    """The value campaign text holds (YAML, as written): CampaignError naming `source` when the text is too
    long or not YAML."""
    if len(text) > schema.MAX_FILE_BYTES:
        raise CampaignError(source, "", f"the text is longer than {schema.MAX_FILE_BYTES // 1024} KiB; a campaign "
                                        "is a few lines of YAML")
    try:
        return yaml.load(text, Loader=CampaignLoader)
    except yaml.YAMLError as exc:
        raise CampaignError(source, "", yaml_error(exc)) from exc


def check_settings(check: Checker, written) -> tuple[Checker, dict, SimulatorSpec]:
    """(checker, the mapping, the checked `simulator:`) of a campaign's value as written (`written`, left
    unchanged: the mapping returned is a copy that the later checks fill): the name, seed and simulator
    checked as written; nothing imported, located or built."""
    data = check.mapping(copy.deepcopy(written), "", TOP_KEYS, required=("name", "simulator", "parameters", "design"))
    schema.campaign_name(check, data["name"])
    check.integer(data.get("seed", 0), "seed", 0)
    return check, data, schema.simulator(check, data["simulator"])


def build_campaign(check: Checker, data: dict, simulator: SimulatorSpec, parameters: list[Parameter], text: str,
                   quantities: dict[str, QuantitySpec] | None = None, mapping: dict | None = None) -> Campaign:
    """The Campaign of a checked mapping (`check_settings`) and its parameters, its other sections checked
    (the design checked into its spec, not built: `runs` stays None); `mapping`: the mapping as written (`data`
    before it was checked)."""
    name = data["name"]
    design = schema.design(check, data["design"])
    default_method = Method.of_runs(design.entry.sampled or design.entry.rare).kind
    method = schema.method(check, data.get("method", {"kind": default_method}))
    schema.check_seeds(check, parameters, design, method)
    seeds = seed_names(parameters)
    execution = Execution.checked(check, data.get("execution", {}))
    storage = Storage.checked(check, data.get("storage", {}), name)
    if quantities is None:  # read from a results file: checked as written, no aircraft to name properties
        quantities = check_quantities(check, data.get("quantities"), simulator)
    analysis = Analysis.checked(check, data.get("analysis", {}), quantities)
    limits = Limits.checked(check, data.get("limits", {}))
    dependence = schema.dependence(check, data.get("dependence"), [p.name for p in parameters], seeds,
                                   simulator.get("properties", {}))
    return Campaign(check.source, text, name, data.get("seed", 0), simulator, parameters, design, method,
                    execution, storage, analysis, limits, quantities=quantities, dependence=dependence,
                    mapping=mapping if mapping is not None else {})
