"""The campaign's `method:` as a typed, frozen MethodSpec: built by the validator, by `--method` and from the
record, and stated in JSON exactly as the mapping it was written as."""
import dataclasses
import json

import pytest

import uqflight.methods.spec
from uqflight.campaign import parse_campaign, schema
from uqflight.campaign.record import read_record, record_text
from uqflight.campaign.schema import Checker
from uqflight.methods import MethodSpec
from uqflight.methods.parsing import parse_methods

TEMPLATE = """
name: spec
simulator: {{kind: python, function: "uqflight.simulators.models:exp_decay"}}
parameters:
  a: {{distribution: normal, lower: 0.5, upper: 1.5}}
  b: {{distribution: uniform, lower: 1.0, upper: 2.0, nominal: 1.4}}
design: {design}
method: {method}
"""
GRID, SAMPLED = "{kind: sparse_grid, level: 3}", "{kind: monte_carlo, samples: 40}"
ADAPTIVE = "{kind: adaptive_sparse_grid, budget: 60, tolerance: 1.0e-7}"

# (method as written, design, the record's mapping, summary.json's), the JSON text as uqflight wrote it
KINDS = [
    ("{kind: monte_carlo}", SAMPLED,
     '{"kind": "monte_carlo", "split": false, "order": 2}', '{"order": 2, "kind": "monte_carlo", "split": false}'),
    ("{kind: integration}", GRID,
     '{"kind": "integration", "split": false, "order": 2}', '{"order": 2, "kind": "integration", "split": false}'),
    ("{kind: integration}", ADAPTIVE,
     '{"order": 2, "kind": "integration", "split": false}', '{"order": 2, "kind": "integration", "split": false}'),
    ("{kind: integration, order: 1}", ADAPTIVE,  # an adaptive grid's record puts the order first, given or not
     '{"order": 1, "kind": "integration", "split": false}', '{"order": 1, "kind": "integration", "split": false}'),
    ("{kind: pseudo_galerkin, order: 1, split: true}", GRID,
     '{"kind": "pseudo_galerkin", "order": 1, "split": true}',
     '{"order": 1, "kind": "pseudo_galerkin", "split": true}'),
    ("{kind: interpolation, allow_aliasing: false}", GRID,
     '{"kind": "interpolation", "allow_aliasing": false, "split": false, "order": 2}',
     '{"order": 2, "kind": "interpolation", "allow_aliasing": false, "split": false}'),
    ("{kind: regression, order: 1}", SAMPLED,
     '{"kind": "regression", "order": 1, "split": false}', '{"order": 1, "kind": "regression", "split": false}'),
    ("{kind: least_squares}", SAMPLED,
     '{"kind": "least_squares", "split": false, "order": 2}', '{"order": 2, "kind": "least_squares", "split": false}'),
    ("{kind: sparse, q: 0.75, selection: omp}", SAMPLED,
     '{"kind": "sparse", "q": 0.75, "selection": "omp", "max_order": 2}',
     '{"order": 2, "kind": "sparse", "q": 0.75, "selection": "omp"}'),
    ("{order: 1, kind: auto}", SAMPLED,
     '{"order": 1, "kind": "auto", "split": false}', '{"order": 1, "kind": "auto", "split": false}'),
]


def campaign(method: str, design: str = SAMPLED):
    return parse_campaign(TEMPLATE.format(method=method, design=design), "spec.yaml")


@pytest.mark.parametrize("method, design, record, summary", KINDS, ids=[f"{m} on {d}" for m, d, _, _ in KINDS])
def test_each_kind_states_the_mapping_it_was_written_as(method, design, record, summary):
    spec = campaign(method, design).method
    assert isinstance(spec, MethodSpec)
    assert json.dumps(spec.as_mapping()) == record
    assert json.dumps(spec.analysed().summary()) == summary


def test_the_spec_is_frozen():
    spec = campaign("{kind: sparse, max_order: 3, q: 0.5}").method
    with pytest.raises(dataclasses.FrozenInstanceError):
        spec.order = 4
    with pytest.raises(dataclasses.FrozenInstanceError):
        spec.settings = ()
    assert spec.settings == (("q", 0.5),) and isinstance(spec.settings, tuple)


def test_the_validator_builds_it_once(monkeypatch):
    built = []
    real = MethodSpec.from_checked.__func__
    monkeypatch.setattr(uqflight.methods.spec.MethodSpec, "from_checked",
                        classmethod(lambda cls, mapping: built.append(dict(mapping)) or real(cls, mapping)))
    spec = campaign("{kind: least_squares, order: 1}").method
    assert built == [{"kind": "least_squares", "order": 1, "split": False}]
    assert spec == MethodSpec("least_squares", 1)


@pytest.mark.parametrize("method, design", [(m, d) for m, d, _, _ in KINDS])
def test_the_spec_round_trips_through_the_record(method, design):
    written = campaign(method, design)
    attrs = {"record": record_text(written, "monte_carlo", {}, {}), "campaign": written.text}
    read = read_record(attrs, "spec.h5").campaign.method
    assert read == written.method
    assert json.dumps(read.as_mapping()) == json.dumps(written.method.as_mapping())


@pytest.mark.parametrize("flag, mapping", [
    ("sparse:4:selection=omp,q=0.75", {"kind": "sparse", "max_order": 4, "selection": "omp", "q": 0.75}),
    ("least_squares:2", {"kind": "least_squares", "order": 2}),
    ("monte_carlo", {"kind": "monte_carlo"}),
])
def test_the_spec_round_trips_through_the_method_flag(flag, mapping):
    parsed = parse_methods([flag])[0]
    assert parsed.as_mapping() == mapping
    assert parsed == schema.method(Checker("spec.yaml"), mapping)
    assert parse_methods([flag.split(":")[0]], parsed.order)[0] == MethodSpec(parsed.kind, parsed.order)


def test_an_override_keeps_the_campaigns_keys_its_kind_has():
    grid = campaign("{kind: pseudo_galerkin, order: 1, split: true, allow_aliasing: true}", GRID).method
    projected = grid.analysed(parse_methods(["pseudo_galerkin:2"])[0])
    assert (projected.order, projected.split, projected.allow_aliasing) == (2, True, True)
    assert projected.label == "PG order 2 split"
    assert projected.summary() == {"order": 2, "kind": "pseudo_galerkin", "split": True, "allow_aliasing": True}
    fitted = grid.analysed(MethodSpec.from_checked({"kind": "least_squares", "split": False}))
    assert (fitted.order, fitted.split, fitted.label) == (1, False, "least squares order 1")
    sparse = grid.analysed(parse_methods(["sparse:3:q=0.5"])[0])
    assert sparse.summary() == {"order": 3, "kind": "sparse", "q": 0.5}
    assert sparse.settings == (("q", 0.5),) and not sparse.split


def test_the_spec_example_runs():
    import doctest

    result = doctest.testmod(uqflight.methods.spec)
    assert result.attempted >= 5 and result.failed == 0
