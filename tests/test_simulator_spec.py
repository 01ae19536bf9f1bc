"""The campaign's `simulator:` as a typed, frozen SimulatorSpec: built once by the validator when the campaign is
parsed, located by its resolution (explicit fields, never a rewritten mapping), pickled to the workers as it is
(never checked there again), and equal when read back from a results file's record."""
import dataclasses
import pickle

import numpy as np
import pytest
from conftest import DATA

from uqflight.campaign import parse_campaign
from uqflight.campaign.record import read_record, record_text
from uqflight.running.runner import worker_spec
from uqflight.running.worker import run_chunk
from uqflight.simulators.kinds import REGISTRY
from uqflight.simulators.spec import SimulatorSpec

MODEL = f"{DATA / 'quantity_model.py'}:ramp"  # y = a + b t, z = a t², w = a − b t, t = 0, 0.25, ..., 4
PYTHON = f'{{kind: python, function: "{MODEL}", outputs: [y, z]}}'
JSBSIM = "{kind: jsbsim, duration_s: 1.0, output_rate_hz: 10.0, excitation: {kind: doublet}, outputs: [h_ft]}"
TEMPLATE = """
name: spec
simulator: {simulator}
parameters:
  {parameters}
design: {{kind: monte_carlo, samples: 4}}
"""
PARAMETERS = {"python": "a: {distribution: uniform, lower: -1, upper: 1}\n  b: {distribution: uniform, lower: 0.5, "
                        "upper: 1.5}",
              "jsbsim": "CL0: {property: aero/uq/CL0, distribution: normal, nominal: 0.1, interval_pct: 20}"}
SIMULATORS = {"python": PYTHON, "jsbsim": JSBSIM}


def campaign(kind: str = "python"):
    text = TEMPLATE.format(simulator=SIMULATORS[kind], parameters=PARAMETERS[kind])
    return parse_campaign(text, str(DATA / "spec.yaml"))


def test_the_simulator_is_a_frozen_spec_read_by_attribute_and_key():
    spec = campaign("jsbsim").simulator
    assert isinstance(spec, SimulatorSpec) and spec.kind == "jsbsim" and spec.entry is REGISTRY["jsbsim"]
    assert spec["duration_s"] == 1.0 and spec["outputs"] == ("h_ft",) and spec["excitation"]["kind"] == "doublet"
    assert spec.get("trim", "newton") == "newton" and "trim" not in spec and spec["aircraft"] == "bacm"
    assert spec.aircraft_path.endswith("bacm") and spec.script_path is None and spec.root is None
    with pytest.raises(dataclasses.FrozenInstanceError):
        spec.aircraft_path = "/elsewhere"
    with pytest.raises(TypeError):
        spec.settings["duration_s"] = 2.0
    with pytest.raises(TypeError):
        spec["excitation"]["kind"] = "step"
    assert dataclasses.replace(spec, root="/r").root == "/r" and spec.root is None


@pytest.mark.parametrize("kind", ["python", "jsbsim"])
def test_the_mapping_is_validated_once_per_parse_and_never_in_a_worker(kind, monkeypatch):
    calls = []
    entry = REGISTRY[kind]
    check = entry.check

    def counted(*args):
        calls.append(args)
        return check(*args)

    monkeypatch.setattr(entry, "check", counted)
    parsed = campaign(kind)
    assert len(calls) == 1
    if kind == "jsbsim":
        return  # a worker's flight is in the slow tests (test_distributed_aircraft, test_scenarios)
    # what a worker is sent (pickled) and flies at a = 0.5, b = 1: the spec as it is, no check
    spec = pickle.loads(pickle.dumps(worker_spec(parsed)))
    assert spec.simulator == parsed.simulator and isinstance(spec.simulator, SimulatorSpec)
    _, status, reasons, values = run_chunk(spec, np.arange(1), np.array([[0.5, 1.0]]), 17, ["y"])
    assert status.tolist() == [0], reasons
    assert values["y"][0][4] == 1.5  # y(1) = 0.5 + 1
    assert len(calls) == 1


def test_a_spec_pickles_to_an_equal_frozen_spec():
    spec = SimulatorSpec("python", {"function": "m:f", "outputs": ["y"]}, seed_parameters=("s",))
    copy = pickle.loads(pickle.dumps(spec))
    assert copy == spec and copy.as_mapping() == {"kind": "python", "function": "m:f", "outputs": ["y"],
                                                 "seed_parameters": ["s"]}
    with pytest.raises(TypeError):
        copy.settings["function"] = "n:g"


@pytest.mark.parametrize("kind", ["python", "jsbsim"])
def test_a_spec_round_trips_through_the_record_and_the_record_is_unchanged(kind):
    written = campaign(kind)
    text = record_text(written, "monte_carlo", {}, {})
    read = read_record({"record": text, "campaign": written.text}, "spec.h5").campaign
    assert read.simulator == dataclasses.replace(written.simulator, aircraft_path=None)  # never located from a record
    assert record_text(read, "monte_carlo", {}, {}) == text
