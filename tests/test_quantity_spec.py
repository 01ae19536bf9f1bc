"""The campaign's `quantities:` as typed, frozen QuantitySpecs: built once by the validator (check_quantities) when
the campaign is parsed, pickled to the workers as they are (never checked there again), equal when read back from
a results file's record, and refused with the messages they always had."""
import dataclasses
import pickle

import numpy as np
import pytest
from conftest import DATA

import uqflight.campaign
import uqflight.quantities.spec
from uqflight.campaign import parse_campaign
from uqflight.campaign.record import read_record, record_text
from uqflight.campaign.schema import CampaignError
from uqflight.quantities import QuantitySpec, When
from uqflight.running.runner import worker_spec
from uqflight.running.worker import run_chunk

MODEL = f"{DATA / 'quantity_model.py'}:ramp"  # y = a + b t, z = a t², w = a − b t, t = 0, 0.25, ..., 4
TEMPLATE = """
name: spec
simulator: {{kind: python, function: "{model}", outputs: [y, z, w]}}
parameters:
  a: {{distribution: uniform, lower: -1, upper: 1}}
  b: {{distribution: uniform, lower: 0.5, upper: 1.5}}
design: {{kind: monte_carlo, samples: 4}}
quantities: {quantities}
"""
QUANTITIES = """
  peak_y: {of: y, take: max, after_s: 1, before_s: 3.5}
  z_at: {of: z, take: at, at_s: 1.25}
  t_up: {take: time_of_first, when: {of: y, above: 2.1}}"""


def campaign(quantities: str = QUANTITIES):
    return parse_campaign(TEMPLATE.format(model=MODEL, quantities=quantities), str(DATA / "spec.yaml"))


def test_the_campaigns_quantities_are_frozen_specs_by_name_with_absent_keys_none():
    quantities = campaign().quantities
    assert quantities == {"peak_y": QuantitySpec("peak_y", "max", of="y", after_s=1.0, before_s=3.5),
                          "z_at": QuantitySpec("z_at", "at", of="z", at_s=1.25),
                          "t_up": QuantitySpec("t_up", "time_of_first", when=When("y", "above", 2.1))}
    assert [type(quantities["peak_y"].after_s), type(quantities["t_up"].when.threshold)] == [float, float]
    assert quantities["t_up"].entry.unit == "s" and quantities["z_at"].entry.required == ("of", "at_s")
    with pytest.raises(dataclasses.FrozenInstanceError):
        quantities["peak_y"].of = "z"
    with pytest.raises(dataclasses.FrozenInstanceError):
        quantities["t_up"].when.threshold = 3.0


def test_the_mapping_is_validated_once_per_parse_and_never_in_a_worker(monkeypatch):
    calls = []
    check_quantities = uqflight.quantities.spec.check_quantities

    def counted(*args, **kwargs):
        calls.append(args[1])
        return check_quantities(*args, **kwargs)

    monkeypatch.setattr(uqflight.campaign, "check_quantities", counted)
    monkeypatch.setattr(uqflight.quantities.spec, "check_quantities", counted)
    parsed = campaign()
    assert len(calls) == 1
    # what a worker is sent (pickled) and flies at a = 0.5, b = 1: the specs as they are, no check
    spec = pickle.loads(pickle.dumps(worker_spec(parsed)))
    assert spec.quantities == parsed.quantities
    _, status, reasons, values = run_chunk(spec, np.arange(1), np.array([[0.5, 1.0]]), 17, ["y"])
    assert status.tolist() == [0], reasons
    assert values[("quantity", "peak_y")][0] == 4.0  # y(3.5) = 0.5 + 3.5
    assert values[("quantity", "z_at")][0] == 0.78125  # 0.5 · 1.25², a time point
    assert values[("quantity", "t_up")][0] == 1.75  # the first time point with 0.5 + t > 2.1
    assert len(calls) == 1


def test_a_spec_round_trips_through_the_record_and_the_record_is_unchanged():
    written = campaign()
    text = record_text(written, "monte_carlo", {}, {})
    read = read_record({"record": text, "campaign": written.text}, "spec.h5").campaign
    assert read.quantities == written.quantities
    assert all(isinstance(spec, QuantitySpec) for spec in read.quantities.values())
    assert record_text(read, "monte_carlo", {}, {}) == text


@pytest.mark.parametrize("quantity, message", [
    ("{of: y, take: max, after_s: 3, before_s: 2.5}",
     "quantities.q.after_s: expected after_s < before_s, got 3 >= 2.5"),
    ("{of: y, take: at, at_s: -1}", "quantities.q.at_s: -1 s is outside the flight (t >= 0)"),
    ("{of: y, take: at_first, when: {of: z, above: 1, below: 2}}",
     "quantities.q.when: expected exactly one of above or below (the threshold)"),
    ("{take: time_of_first, when: {of: z, above: yes}}", "quantities.q.when.above: expected a finite number, got True"),
    ("{of: y, take: max, at_s: 1}", "quantities.q.at_s: has no meaning for take: max (it takes after_s, before_s, of)"),
    ("{of: y, take: at}", "quantities.q.at_s: is required for take: at"),
    ("{take: time_of_first, when: {of: v, below: 1}}",
     "quantities.q.when.of: expected one of the model's outputs (y, z, w), got 'v'"),
    ("{take: phugoid_damping}", "quantities.q.take: phugoid_damping is a mode of the linearised model at a "
                                "level-flight trim: it needs a JSBSim simulator with scenario kind level_flight"),
])
def test_a_bad_quantity_is_refused_with_its_message_naming_the_file(quantity, message):
    with pytest.raises(CampaignError) as refused:
        campaign(f"{{q: {quantity}}}")
    assert str(refused.value) == f"{DATA / 'spec.yaml'}: {message}"

