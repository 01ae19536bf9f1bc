"""A campaign's design as a typed, frozen spec (designs.spec.DesignSpec): checked once by its kind when the campaign
is, then sized, built and flown round by round without checking the mapping again; its refusals name the file
and the key as they always have."""
import dataclasses
from collections import Counter

import pytest

from uqflight.campaign import CampaignError, parse_campaign
from uqflight.designs import REGISTRY, DesignSpec, build_design, design_size
from uqflight.designs.rare import Event
from uqflight.running.runner import run_campaign

from conftest import cli_in_process

CAMPAIGN = """
name: spec
seed: 1
simulator: {{kind: python, function: "uqflight.simulators.models:normal_sum"}}
parameters:
  x1: {{distribution: normal, lower: -3, upper: 3}}
  x2: {{distribution: normal, lower: -3, upper: 3}}
quantities:
  peak: {{of: y, take: max}}
design: {design}
execution: {{workers: 1, chunk: 25}}
"""
DESIGNS = {
    "sparse_grid": "{kind: sparse_grid, level: 2}",
    "sobol": "{kind: sobol, samples: 16, replicates: 2}",
    "morris": "{kind: morris, trajectories: 4}",
    "adaptive_sparse_grid": "{kind: adaptive_sparse_grid, budget: 30, tolerance: 1.0e-6}",
    "subset_simulation": "{kind: subset_simulation, event: {of: peak, above: 2.5}, samples_per_level: 200, p0: 0.1, "
                         "budget: 1000}",
}


def counting_checks(monkeypatch, kind: str) -> Counter:
    """Counts the calls of `kind`'s validator (its class's `settings`, whatever class defines it)."""
    calls = Counter()
    cls = type(REGISTRY[kind])
    original = cls.settings

    def counted(self, spec):
        calls[kind] += 1
        return original(self, spec)

    monkeypatch.setattr(cls, "settings", counted)
    return calls


def test_the_spec_is_frozen_and_holds_every_key_of_its_kind_checked():
    spec = DesignSpec.checked({"kind": "sparse_grid", "level": 2})
    assert spec.kind == "sparse_grid" and spec.entry is REGISTRY["sparse_grid"]
    assert spec.settings == (("level", 2), ("rule", None), ("nested", None), ("growth", "linear"))
    with pytest.raises(dataclasses.FrozenInstanceError):
        spec.kind = "tensor_grid"
    with pytest.raises(dataclasses.FrozenInstanceError):
        spec.settings = ()
    rare = DesignSpec.checked({"kind": "subset_simulation", "event": {"of": "peak", "below": -2}, "p0": 0.25})
    assert rare["event"] == Event("peak", "below", -2.0) and rare["budget"] == 12000  # the kind's default budget
    assert rare["p0"] == 0.25 and isinstance(rare["p0"], float) and rare["samples_per_level"] is None


def test_the_campaign_holds_the_spec_and_the_public_functions_agree_with_it():
    campaign = parse_campaign(CAMPAIGN.format(design=DESIGNS["sobol"]), "c.yaml")
    spec = campaign.design_spec
    assert spec == DesignSpec("sobol", (("samples", 16), ("scramble", True), ("replicates", 2)))
    assert campaign.runs == spec.size(campaign.germs) == design_size({"kind": "sobol", "samples": 16,
                                                                      "replicates": 2}, campaign.germs) == 32
    built = build_design({"kind": "sobol", "samples": 16, "replicates": 2}, campaign.germs, campaign.seed)
    assert (campaign.design().xi == built.xi).all() and (campaign.design().weights == built.weights).all()


@pytest.mark.parametrize("kind", list(DESIGNS))
def test_a_campaign_checks_its_design_mapping_once(monkeypatch, kind):
    calls = counting_checks(monkeypatch, kind)
    campaign = parse_campaign(CAMPAIGN.format(design=DESIGNS[kind]), "c.yaml")
    assert calls == {kind: 1}
    campaign.design()
    assert campaign.design_spec.size(campaign.germs) >= campaign.runs  # a sparse grid's: before merging
    assert calls == {kind: 1}  # sized and built from the spec


@pytest.mark.parametrize("kind", ["sparse_grid", "adaptive_sparse_grid", "subset_simulation"])
def test_a_run_and_its_rounds_do_not_check_the_design_again(tmp_path, monkeypatch, kind):
    calls = counting_checks(monkeypatch, kind)
    campaign = parse_campaign(CAMPAIGN.format(design=DESIGNS[kind]), str(tmp_path / "c.yaml"))
    summary = run_campaign(campaign, out=tmp_path / "c.h5", workers=1)
    assert summary.ran > 0 and calls == {kind: 1}


@pytest.mark.parametrize("design, message", [
    ("{kind: sparse_grid, level: -1}", "c.yaml: design.level: expected an integer >= 0, got -1"),
    ("{kind: sparse_grid}", "c.yaml: design.level: missing; kind sparse_grid expects an integer >= 0"),
    ("{kind: monte_carlo, sample: 10}",
     "c.yaml: design.sample: unknown key for kind monte_carlo; accepted keys: kind, samples"),
    ("{kind: spiral}", "c.yaml: design.kind: expected one of monte_carlo, sobol, halton, latin_hypercube, "
                       "sparse_grid, tensor_grid, pick_freeze, morris, adaptive_sparse_grid, subset_simulation, "
                       "importance_sampling, active_learning, got 'spiral'"),
    ("sparse_grid", "c.yaml: design: expected a mapping with a kind key, got 'sparse_grid'"),
    ("{kind: sobol, samples: 8, scramble: false, replicates: 2}",
     "c.yaml: design.replicates: replicates need scramble: true (unscrambled copies are identical)"),
    ("{kind: morris, trajectories: 4, levels: 3}",
     "c.yaml: design.levels: expected an even number of levels (the jump Δ = p/(2(p−1)) is then p/2 grid steps), "
     "got 3"),
    ("{kind: sparse_grid, level: 1, rule: gauss_legendre}",
     "c.yaml: design.rule: rule gauss_legendre is for uniform germs, but dimension 1 has a normal germ"),
    ("{kind: sparse_grid, level: 5, rule: genz_keister, growth: exponential}",
     "c.yaml: design.level: rule genz_keister with exponential growth reaches level 4 at most, got 5"),
    ("{kind: subset_simulation, event: {of: peak, above: 3}, samples_per_level: 200, budget: 100}",
     "c.yaml: design.budget: 100 runs cannot hold one level of samples_per_level = 200"),
    ("{kind: importance_sampling, event: {of: peak}}",
     "c.yaml: design.event: expected exactly one of above or below (the threshold), got neither"),
    ("{kind: tensor_grid, points: 12, rule: genz_keister}",
     "c.yaml: design.points: rule genz_keister comes in 1, 3, 9, 19, 43 points, got 12"),
    ("{kind: active_learning, event: {of: peak, above: 3}, budget: 10}",
     "c.yaml: design.budget: 10 runs are too few for active learning on 2 inputs: its first design, one "
     "enrichment and two importance-sampling rounds need at least 332"),
])
def test_a_malformed_design_is_refused_naming_the_file_and_the_key(design, message):
    with pytest.raises(CampaignError) as refused:
        parse_campaign(CAMPAIGN.format(design=design), "c.yaml")
    assert str(refused.value) == message


def test_plan_refuses_a_malformed_design_with_exit_2_naming_the_field(tmp_path):
    (tmp_path / "c.yaml").write_text(CAMPAIGN.format(design="{kind: tensor_grid, rule: gauss_hermite}"))
    done = cli_in_process("plan", tmp_path / "c.yaml")
    assert done.returncode == 2
    assert done.stderr.strip() == (f"error: {tmp_path / 'c.yaml'}: design.points: missing; kind tensor_grid "
                                   "expects an integer >= 1")
