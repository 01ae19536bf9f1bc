"""The campaign-key reference: every key the schema accepts, gathered from the code (the schema's key
lists and the registries of scenarios, designs, methods, distributions, rules and quantities), with
its description: a simulator's, scenario's, design's or method's key from its kind's class (a design key taken by
several kinds, by each of them), the others from KEYS; each kind's from VALUES or its registry entry's docstring.

`reference_page()` is docs/reference/campaign-keys.md (the MkDocs build generates it from here; the
committed copy is rewritten by `python -m uqflight.campaign.keys > docs/reference/campaign-keys.md`). A key or kind without a description is an error
(`missing_descriptions`, checked by tests/test_docs.py), so the reference cannot fall behind the code.
"""
from __future__ import annotations

import inspect
from dataclasses import dataclass

from ..analysis import BAND_SAMPLES, BOOTSTRAP, QUANTILES
from ..methods import METHODS, Method
from .sections import Analysis, Execution, Limits, Storage, Tsvd, keys_of

# The meaning of each key, its default and an example, by its path (NAME: a name the user chooses).
KEYS = {
    "name": "Required. 1-100 characters among `A-Za-z0-9_.-`, not starting with `.` or `-`; the default "
            "results file is `results/NAME.h5`. `name: paper-pg2-l2`",
    "description": "Free text for people; not read. `description: the paper's level-2 grid`",
    "seed": ("Seeds every random choice (designs, seed parameters, and the analysis's band, PDF, bootstrap, exceedance "
             "and KLD-floor draws). Default 0. `seed: 20261124`"),
    "simulator": "Required. What flies each run: `{kind: jsbsim, ...}` or `{kind: python, function: ...}`.",
    "parameters": "Required. One entry per uncertain input: `parameters: {CL0: {property: aero/uq/CL0, "
                  "distribution: normal, interval_pct: 23.05}}`",
    "design": "Required. Where the runs are: `design: {kind: sparse_grid, rule: gauss_hermite, level: 2}`",
    "method": "How the statistics are computed. Default `{kind: monte_carlo}` for sampled designs, "
              "`{kind: integration}` for grids. `method: {kind: pseudo_galerkin, order: 2}`",
    "execution": "How the runs are executed: `execution: {workers: 2, executor: local, chunk: 16}`",
    "storage": "Where and how the results are stored: `storage: {path: results/x.h5, raw: true}`",
    "analysis": f"Options of the statistics: `analysis: {{band_samples: {BAND_SAMPLES}, bootstrap: {BOOTSTRAP}}}`",
    "limits": "Size limits checked before anything is built (exit 2 beyond them): "
              "`limits: {max_runs: 1000000}`",
    "quantities": "Quantities of interest, one number per run, stored in `/quantities/NAME`: "
                  "`quantities: {peak_alpha: {of: alpha_deg, take: max}}` (see [quantities](../quantities.md))",
    "simulator.scenario.kind": "The scenario kind (below). Default `level_flight`.",
    # parameters
    "parameters.NAME.property": "The property the parameter sets (JSBSim: before the trim, `ic/...` too; "
                                "python: the function's argument). Default for python: NAME. "
                                "`property: aero/uq/CL0`",
    "parameters.NAME.function": "JSBSim: an aerodynamic function of the aircraft to perturb instead of a "
                                "`property` (full name, or its last component when unique). `function: CLwbh`",
    "parameters.NAME.perturbation": "With `function`: `scale` (multiplied, nominal 1), `offset` (a "
                                    "coefficient increment ΔC, nominal 0) or `offset_value` (in the function's "
                                    "own unit, nominal 0). `perturbation: scale`",
    "parameters.NAME.distribution": "Required. The parameter's law (kinds below). `distribution: normal`",
    "parameters.NAME.nominal": "The centre value. Default: the aircraft's value of the property (python: "
                               "required with `interval_pct`, else the interval's midpoint). `nominal: 0.2`",
    "parameters.NAME.interval_pct": "± percent of the nominal (the paper's Table 1), > 0; or give `lower` and "
                                    "`upper`. `interval_pct: 23.05`",
    "parameters.NAME.lower": "The interval's lower end (with `upper`, instead of `interval_pct`). `lower: 195`",
    "parameters.NAME.upper": "The interval's upper end, > `lower`. `upper: 205`",
    # design
    "design.kind": "Required. The design kind (below).",
    "design.event.of": "The quantity (a name under `quantities:`) the event is about.",
    "design.event.above": "The event is QUANTITY > above (give above or below, not both).",
    "design.event.below": "The event is QUANTITY < below.",
    # method
    "method.kind": "The method (below).",
    # execution
    "execution.workers": "Worker processes, >= 1. Default 1; `run --workers` overrides.",
    "execution.executor": "`local` (a pool of worker processes, the default) or `dask`.",
    "execution.scheduler": "A Dask scheduler address (`tcp://HOST:8786`, `tls://...`); without it `dask` "
                           "starts a LocalCluster.",
    "execution.chunk": "Samples per task, >= 1 (the design's last 4 × chunk in chunks of chunk/4). Default 16.",
    "execution.timeout_s": "Per-run time limit [s], > 0; a run past it is stopped and recorded as `timeout`. "
                           "Default max(60 s, 50 × one nominal flight).",
    # storage
    "storage.path": "The results file, relative to the working directory. Default `results/NAME.h5`.",
    "storage.raw": "Keep the N × T time histories in `/outputs/NAME`. Default true; false needs `tsvd`.",
    "storage.tsvd": "Compress the outputs on the fly by an incremental thin SVD into `/tsvd/NAME`. "
                    "`tsvd: {tol: 1e-8, batch: 1000}`",
    "storage.tsvd.tol": "Relative truncation tolerance in (0, 1). Default 1e-8.",
    "storage.tsvd.batch": "Runs per SVD update, >= 1. Default 1000.",
    # analysis
    "analysis.band_samples": "Draws of the PCE for the bands and PDFs, from 100 to 10^6 (a million draws of an "
                             f"output take about 1.6 GB to sort). Default {BAND_SAMPLES}: on the paper's "
                             "expansion the band's sampling error is about 3.5 % of the output's std, "
                             "and grows as 1/sqrt(draws) (`benchmarks/band_samples.py`).",
    "analysis.bootstrap": f"Resamplings for the pick-freeze Sobol' intervals, 0 (none) to 10^4. Default {BOOTSTRAP}. "
                          "Each costs time and memory in every output's every time: on 1024 base rows, 3 "
                          "inputs and 5 outputs of 1001 times, 10^4 add 45 s of CPU and 1 GB to the report. "
                          "A 95 % interval's ends are steady from about 2000 on; at 10^4 the error of "
                          "each 2.5 % tail is 0.16 % (its 6 %): more buys nothing.",
    "analysis.quantiles": "1-20 probabilities in (0, 1) reported over time in summary.json. Default "
                          f"{list(QUANTILES)}. `quantiles: [0.05, 0.5, 0.95]`",
    "analysis.exceedance": "`{QUANTITY: [{above: X}, {below: Y}]}`: P(QUANTITY > X) and P(QUANTITY < Y). "
                           "`exceedance: {peak_load_factor: [{above: 3}]}`",
    "analysis.exceedance.QUANTITY[i].above": "The threshold of P(QUANTITY > X).",
    "analysis.exceedance.QUANTITY[i].below": "The threshold of P(QUANTITY < Y).",
    # limits
    "dependence": "Dependent inputs: a Gaussian copula (Nataf) over named parameters; the design and PCE "
                  "stay in independent standard variables (see [dependence](../dependence.md)). "
                  "`dependence: {kind: gaussian_copula, parameters: [CD0, k1], correlation: [[1, 0.8], [0.8, 1]]}`",
    "dependence.kind": "Required. The kind (below).",
    "dependence.parameters": "The correlated parameters, in the order of the matrix rows (the Cholesky order "
                             "the Sobol' indices follow). Default: every non-seed parameter in campaign order.",
    "dependence.correlation": "Required. The copula's correlation matrix ρ0 (of the normal scores Φ⁻¹(F(κ))): "
                              "symmetric, unit diagonal, entries in [-1, 1], positive definite; for normal "
                              "marginals the Pearson correlation of the parameters.",
    "limits.max_runs": "The design's runs (sparse grids: points built before merging). Default 1000000.",
    "limits.max_memory_gb": "Memory of the run (60 MB per local worker process). Default 8.",
    "limits.max_disk_gb": "Size of the results file. Default 100.",
    "limits.max_pce_terms": "Terms of the PCE. Default 100000.",
    # quantities
    "quantities.NAME.of": "The output, JSBSim property or python output the quantity reads. `of: h_ft`",
    "quantities.NAME.take": "Required. What is taken of it (kinds below). `take: max`",
    "quantities.NAME.at_s": "With `take: at`: the time [s]. `at_s: 20`",
    "quantities.NAME.when": "With `at_first`, `time_of_first`: the event, `{of: Y, above: A}` or `{of: Y, "
                            "below: B}`.",
    "quantities.NAME.after_s": "Restricts the window to t >= after_s (not `at` or the modes).",
    "quantities.NAME.before_s": "Restricts the window to t <= before_s (not `at` or the modes).",
    "quantities.NAME.when.of": "The output or property whose crossing is the event.",
    "quantities.NAME.when.above": "The event: the first step where `of` > above.",
    "quantities.NAME.when.below": "The event: the first step where `of` < below.",
}
# a method's keys are described where they are declared, on its class (methods.Key)
KEYS.update({f"method.{key}": spec.description for entry in (Method, *METHODS.values())
             for key, spec in entry.keys.items()})

# The meaning of a kind, where its registry entry's docstring does not say it.
VALUES = {
    "dependence.kind": {"gaussian_copula": "The Nataf transform: correlated standard normals z = Lξ, then Φ, then "
                                           "each marginal's inverse CDF."},
    "design.rule": {
        "gauss_hermite": "Gauss–Hermite (normal inputs; nested: Genz–Keister).",
        "genz_keister": "Genz–Keister, nested (normal inputs).",
        "gauss_legendre": "Gauss–Legendre (uniform inputs).",
        "clenshaw_curtis": "Clenshaw–Curtis, nested (uniform inputs).",
        "gauss_patterson": "Gauss–Patterson, nested (uniform inputs)."},
}


@dataclass(frozen=True)
class Key:
    """A key the schema accepts: its path, the section of the reference it belongs to, for a key that
    names a kind, the kinds {name: registry object or None}, and the description a kind's field gives."""

    path: str
    section: str
    kinds: dict | None = None
    description: str | None = None  # a kind's field's own (else KEYS)

    @property
    def meaning(self) -> str | None:
        return self.description or KEYS.get(self.path)


def _by_kind(meanings: dict[str, str]) -> str:
    """A design key's meaning in the reference: the kinds that take it, grouped by what it means for them, e.g.
    "`sobol`, `halton`: Scramble ...", one line per meaning. A kind without a meaning for it leaves the whole
    meaning empty (the reference then refuses to build: `missing_descriptions`)."""
    if not all(meanings.values()):
        return ""
    groups: dict[str, list[str]] = {}
    for kind, meaning in meanings.items():
        groups.setdefault(meaning, []).append(f"`{kind}`")
    return "<br>".join(f"{', '.join(kinds)}: {meaning}" for meaning, kinds in groups.items())


def _paths(prefix: str, keys) -> list[str]:
    return [f"{prefix}.{k}" if prefix else k for k in keys]


def accepted_keys() -> list[Key]:
    """Every key the campaign schema accepts, in the order of the reference."""
    from ..designs import REGISTRY as DESIGNS
    from ..designs.rules import RULE_TABLE
    from ..parameters import DISTRIBUTIONS
    from ..quantities import REGISTRY as TAKES
    from ..quantities.spec import KEYS as QUANTITY_KEYS
    from ..quantities.spec import WHEN_KEYS
    from ..simulators.base import field_descriptions
    from ..simulators.kinds import REGISTRY as SIMULATORS
    from ..simulators.scenarios import REGISTRY as SCENARIOS
    from . import schema

    found = [Key(k, "Top level") for k in schema.TOP_KEYS]
    described = {p: d for kind in SIMULATORS.values() for p, d in field_descriptions("simulator", kind.fields).items()}
    found += [Key(p, "simulator", dict(SIMULATORS) if p == "simulator.kind" else None, d) for p, d in described.items()]
    found.append(Key("simulator.scenario.kind", "simulator", dict(SCENARIOS)))
    for name, scenario in SCENARIOS.items():
        found += [Key(p, f"simulator, scenario `{name}`", None, d) for p, d in {
            **field_descriptions("simulator", scenario.fields),
            **field_descriptions("simulator.scenario", scenario.scenario_fields)}.items()]
    found += [Key(p, "parameters", dict(DISTRIBUTIONS) if p.endswith(".distribution") else None)
              for p in _paths("parameters.NAME", schema.PARAMETER_KEYS)]
    found.append(Key("design.kind", "design", dict(DESIGNS)))
    meanings: dict[str, dict[str, str]] = {}  # key -> {kind: its meaning there}
    for kind, entry in DESIGNS.items():
        for key, declared in entry.keys.items():
            meanings.setdefault(key, {})[kind] = declared.description
    found += [Key(f"design.{k}", "design", dict(RULE_TABLE) if k == "rule" else None, _by_kind(by_kind))
              for k, by_kind in meanings.items()]
    from ..designs.rare import EVENT_KEYS

    found += [Key(p, "design") for p in _paths("design.event", EVENT_KEYS)]
    kinds = {kind: type(entry) for kind, entry in METHODS.items()}  # described by their classes' docstrings
    found += [Key(p, "method", kinds if p == "method.kind" else None)
              for p in _paths("method", ("kind", *dict.fromkeys(k for entry in (Method, *METHODS.values())
                                                                   for k in entry.keys)))]
    found += [Key(p, "execution") for p in _paths("execution", keys_of(Execution))]
    found += [Key(p, "storage") for p in _paths("storage", keys_of(Storage)) + _paths("storage.tsvd",
                                                                                         keys_of(Tsvd))]
    found += [Key(p, "analysis") for p in _paths("analysis", keys_of(Analysis))]
    from ..quantities.spec import BOUNDS

    found += [Key(p, "analysis") for p in _paths("analysis.exceedance.QUANTITY[i]", BOUNDS)]
    found += [Key(p, "limits") for p in _paths("limits", keys_of(Limits))]
    found += [Key(p, "dependence", {"gaussian_copula": None} if p == "dependence.kind" else None)
              for p in _paths("dependence", schema.DEPENDENCE_KEYS)]
    found += [Key(p, "quantities", dict(TAKES) if p.endswith(".take") else None)
              for p in _paths("quantities.NAME", QUANTITY_KEYS) + _paths("quantities.NAME.when", WHEN_KEYS)]
    return found


def kind_description(path: str, kind: str, entry) -> str | None:
    """A kind's meaning: VALUES, else the first paragraph of its registry entry's docstring (a design kind's,
    a distribution's, a simulator's or scenario's kind class, a take's class)."""
    if kind in VALUES.get(path, {}):
        return VALUES[path][kind]
    from ..designs import DesignKind
    from ..simulators.base import Kind

    target = (type(entry) if isinstance(entry, (DesignKind, Kind)) else getattr(entry, "build", None)
              or (entry if inspect.isclass(entry) else None))
    doc = inspect.getdoc(target) if target is not None else None
    return " ".join(doc.split("\n\n")[0].split()) if doc else None


def missing_descriptions() -> list[str]:
    """Keys and kinds the reference cannot describe, and descriptions of keys the schema no longer has."""
    keys = accepted_keys()
    missing = [k.path for k in keys if not k.meaning]
    missing += [f"{k.path}: {kind}" for k in keys for kind, entry in (k.kinds or {}).items()
                if not kind_description(k.path, kind, entry)]
    paths = {k.path for k in keys}
    missing += [f"{path} (described, but the schema has no such key)" for path in KEYS if path not in paths]
    missing += [f"{path}: {kind} (described, but no such kind)" for path, kinds in VALUES.items()
                for kind in kinds if kind not in next((k.kinds for k in keys if k.path == path), {})]
    return missing


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def reference_page() -> str:
    """The Markdown of docs/reference/campaign-keys.md; RuntimeError when a key has no description."""
    missing = missing_descriptions()
    if missing:
        raise RuntimeError("campaign keys without a description (in their kind's class, or uqflight/campaign/keys.py): "
                           + "; ".join(missing))
    lines = ["# Campaign keys", "",
             "Every key a campaign file accepts, generated from the code (`uqflight/campaign/schema.py` and the "
             "registries of scenarios, designs, methods, distributions, rules and quantities; a kind's keys described "
             "in its class, the others in `uqflight/campaign/keys.py`). `NAME` is a name you choose. "
             "An unknown key is refused (exit 2) "
             "with the closest known one. The guide is [campaign files](../campaigns.md)."]
    keys = accepted_keys()
    for section in dict.fromkeys(k.section for k in keys):
        inside = [k for k in keys if k.section == section]
        lines += ["", f"## {section}", "", "| key | meaning |", "|---|---|"]
        lines += [f"| `{k.path}` | {_cell(k.meaning)} |" for k in inside]
        for k in (k for k in inside if k.kinds):
            lines += ["", f"### `{k.path}`", "", "| kind | meaning |", "|---|---|"]
            lines += [f"| `{kind}` | {_cell(kind_description(k.path, kind, entry))} |"
                      for kind, entry in k.kinds.items()]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    print(reference_page(), end="")
