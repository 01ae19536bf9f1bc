"""Quantities of interest: every `take` exact on a closed-form model at its time points, their statistics
exact on a grid with pseudo-Galerkin, missing runs counted (conditional statistics for sampled designs,
null with a note on grids), the store bit-identical whatever the workers, the refusals at plan, and a
JSBSim quantity taken at every integration step."""
import json
import math

import numpy as np
import pytest
from conftest import DATA, assert_same_results, cli_in_process

from uqflight.campaign import parse_campaign
from uqflight.campaign.schema import Checker
from uqflight.running.runner import run_campaign
from uqflight.quantities import REGISTRY, QuantitySpec
from uqflight.quantities.recorder import QuantityRecorder
from uqflight.quantities.spec import check_quantities
from uqflight.simulators.aircraft_properties import AircraftProperties
from uqflight.analysis.statistics import analyse, summary_json
from uqflight.store import ResultStore
from uqflight.running.worker import WorkerSpec, run_chunk
from uqflight.simulators.spec import SimulatorSpec

MODEL = f"{DATA / 'quantity_model.py'}:ramp"  # y = a + b t, z = a t², w = a − b t, t = 0, 0.25, ..., 4

# a = 0.5, b = 1: y = 0.5 + t, z = 0.5 t². Each value by hand, at the model's 17 time points.
TRAPEZOID_Z = 0.5 * (0.25 * 1496 / 16 - 0.25 * 16 / 2) / 4  # trapezoid of 0.5 t² over the grid, / 4 s
CASES = {
    "max": ({"of": "z", "take": "max", "before_s": 2}, 2.0),
    "min": ({"of": "y", "take": "min", "after_s": 1}, 1.5),
    "final": ({"of": "y", "take": "final", "before_s": 3}, 3.5),
    "drop": ({"of": "w", "take": "drop", "after_s": 1, "before_s": 3}, 2.0),  # w(1) = -0.5, min w(3) = -2.5
    "drop_rising": ({"of": "y", "take": "drop"}, 0.0),
    "change": ({"of": "w", "take": "change", "after_s": 1, "before_s": 3}, -2.0),  # w(3) - w(1) = -2.5 + 0.5
    "mean": ({"of": "z", "take": "mean"}, TRAPEZOID_Z),
    "mean_window": ({"of": "y", "take": "mean", "after_s": 1, "before_s": 3}, 2.5),
    "at": ({"of": "z", "take": "at", "at_s": 1.25}, 0.78125),
    "at_between": ({"of": "z", "take": "at", "at_s": 1.3}, 0.78125 + 0.2 * (1.125 - 0.78125)),
    "at_first": ({"of": "z", "take": "at_first", "when": {"of": "y", "above": 2.1}}, 0.5 * 1.75**2),
    "time_of_first": ({"take": "time_of_first", "when": {"of": "y", "above": 2.1}}, 1.75),
    "time_of_first_window": ({"take": "time_of_first", "when": {"of": "y", "above": 2.1}, "after_s": 2}, 2.0),
    "never": ({"take": "time_of_first", "when": {"of": "y", "below": 0.5}}, math.nan),  # y >= 0.5, strictly
}


def python_campaign(tmp_path, quantities: str, design: str, method: str = "{kind: monte_carlo}",
                    analysis: str = "{band_samples: 20000}", name: str = "q") -> str:
    text = f"""
name: {name}
seed: 3
simulator: {{kind: python, function: "{MODEL}"}}
parameters:
  a: {{distribution: uniform, lower: -1, upper: 1}}
  b: {{distribution: uniform, lower: 0.5, upper: 1.5}}
design: {design}
method: {method}
quantities: {quantities}
analysis: {analysis}
execution: {{workers: 2, chunk: 16}}
"""
    (tmp_path / f"{name}.yaml").write_text(text)
    return text


def test_every_take_is_exact_at_the_models_time_points():
    # through the worker's own path (run_chunk), at a = 0.5, b = 1; exact to rounding (1e-12)
    assert {spec["take"] for spec, _ in CASES.values()} == {t for t, e in REGISTRY.items() if not e.mode}
    simulator = SimulatorSpec("python", {"function": MODEL})
    quantities = check_quantities(Checker("cases"), {k: s for k, (s, _) in CASES.items()}, simulator)
    spec = WorkerSpec(simulator=simulator, parameter_names=("a", "b"), properties=("a", "b"), base=str(DATA),
                      quantities=quantities)
    _, status, reasons, values = run_chunk(spec, np.arange(1), np.array([[0.5, 1.0]]), 17, ["y", "z"])
    assert status.tolist() == [0], reasons
    for name, (_, expected) in CASES.items():
        found = values[("quantity", name)][0]
        assert (math.isnan(found) and math.isnan(expected)) or found == pytest.approx(expected, abs=1e-12), name


def test_statistics_of_quantities_are_exact_on_a_grid_with_pseudo_galerkin(tmp_path):
    # final y = a + 4b, windowed mean y = a + 2b, mean z = 2c·a (c the trapezoid above, at a = 0.5): polynomials of
    # degree 1, which an order-2 projection on a level-2 Gauss-Legendre grid integrates exactly (1e-12).
    # t_up (y ever above 4 <=> a + 4b > 4) is undefined at the grid's centre: null, with a note.
    text = python_campaign(tmp_path, """
  final_y: {of: y, take: final}
  mean_y: {of: y, take: mean, after_s: 1, before_s: 3}
  mean_z: {of: z, take: mean}
  t_up: {take: time_of_first, when: {of: y, above: 4}}""",
                           "{kind: sparse_grid, rule: gauss_legendre, level: 2}", "{kind: pseudo_galerkin, order: 2}")
    out = tmp_path / "grid.h5"
    run_campaign(parse_campaign(text, str(tmp_path / "q.yaml")), out=out)
    summary = json.loads(json.dumps(summary_json(analyse(out)), allow_nan=False))
    expected = {"final_y": (4.0, 1 / 3 + 16 / 12, {"a": 0.2, "b": 0.8}),
                "mean_y": (2.0, 1 / 3 + 4 / 12, {"a": 0.5, "b": 0.5}),
                "mean_z": (0.0, (2 * TRAPEZOID_Z)**2 / 3, {"a": 1.0, "b": 0.0})}
    for name, (mean, variance, first) in expected.items():
        q = summary["quantities"][name]
        assert q["mean"] == pytest.approx(mean, abs=1e-12) and q["variance"] == pytest.approx(variance, rel=1e-12)
        assert q["std"] == pytest.approx(math.sqrt(variance), rel=1e-12) and q["missing"] == 0
        for p, index in first.items():
            assert q["sobol_first"][p] == pytest.approx(index, abs=1e-12)
            assert q["sobol_total"][p] == pytest.approx(index, abs=1e-12)
        assert isinstance(q["skewness"], float) and q["band99"]["lower"] < mean < q["band99"]["upper"]
    with ResultStore.open(out) as store:
        kappa, t_up = store.kappa, store.quantity("t_up")
    undefined = kappa[:, 0] + 4 * kappa[:, 1] <= 4
    assert undefined.any() and np.array_equal(np.isnan(t_up), undefined)
    nulled = summary["quantities"]["t_up"]
    assert nulled["missing"] == int(undefined.sum()) and nulled["mean"] is None and nulled["sobol_first"] == {}
    assert any("t_up" in note and "needs every run" in note for note in summary["notes"])
    assert summary["outputs"]["y"]["mean"][-1] == pytest.approx(4.0, abs=1e-12)  # the rest of the report stands


@pytest.mark.slow
def test_a_quantity_undefined_in_some_runs_of_a_sampled_design_is_conditional_and_counted(tmp_path):
    # t_up = the first time point with a + b t > 4: closed form on the runs where a + 4b > 4
    text = python_campaign(tmp_path, "{t_up: {take: time_of_first, when: {of: y, above: 4}}, "
                                     "peak: {of: y, take: max}}", "{kind: monte_carlo, samples: 400}")
    out = tmp_path / "mc.h5"
    run_campaign(parse_campaign(text, str(tmp_path / "q.yaml")), out=out)
    stats = analyse(out)
    with ResultStore.open(out) as store:
        a, b = store.kappa.T
    defined = a + 4 * b > 4
    time = np.linspace(0.0, 4.0, 17)
    first = np.array([time[np.argmax(ai + bi * time > 4)] for ai, bi in zip(a[defined], b[defined])])
    q = stats.quantities["t_up"]
    assert q.missing == int((~defined).sum()) > 0
    assert q.output.mean[0] == pytest.approx(first.mean(), rel=1e-12)
    assert stats.quantities["peak"].output.mean[0] == pytest.approx(np.mean(a + 4 * b), rel=1e-12)
    assert any("t_up" in note and "conditional" in note for note in stats.notes)


@pytest.mark.slow
def test_quantities_are_bit_identical_whatever_the_workers(tmp_path):
    text = python_campaign(tmp_path, "{peak: {of: z, take: max}, t_up: {take: time_of_first, when: {of: y, above: 4}}}",
                           "{kind: monte_carlo, samples: 100}")
    files = []
    for workers in (1, 2):
        files.append(tmp_path / f"w{workers}.h5")
        run_campaign(parse_campaign(text, str(tmp_path / "q.yaml")), out=files[-1], workers=workers)
    assert_same_results(*files)
    with ResultStore.open(files[0]) as store:
        assert store.quantity_names == ["peak", "t_up"] and store.quantity("peak").shape == (100,)


BACM = """
name: refused
simulator: {{kind: jsbsim, aircraft: bacm, duration_s: 20}}
parameters:
  CL0: {{property: aero/uq/CL0, distribution: normal, interval_pct: 10}}
design: {{kind: monte_carlo, samples: 4}}
quantities: {{q: {quantity}}}
"""


@pytest.mark.parametrize("quantity, field", [
    ("{of: h_ft, take: biggest}", "quantities.q.take"),
    ("{of: h_ft, take: at, at_s: 25}", "quantities.q.at_s"),
    ("{of: h_ft, take: max, after_s: -1}", "quantities.q.after_s"),
    ("{of: h_ft, take: at_first, when: {of: 'gear/unit[0]/WOWW', above: 0.5}}", "quantities.q.when.of"),
    ("{of: position/h-sl-fts, take: max}", "quantities.q.of"),
    ("{of: h_ft, take: at_first}", "quantities.q.when"),
    ("{of: h_ft, take: phugoid_damping}", "quantities.q.of"),
])
def test_plan_refuses_a_bad_quantity_naming_the_field(tmp_path, quantity, field):
    path = tmp_path / "refused.yaml"
    path.write_text(BACM.format(quantity=quantity))
    result = cli_in_process("plan", path)
    assert result.returncode == 2 and f"{field}:" in result.stderr + result.stdout, result.stderr


def test_every_take_is_a_registered_class_whose_example_a_level_flight_campaign_accepts(tmp_path):
    # the bacm's level flight records h_ft and alpha_deg and trims level: every take's example holds
    assert list(REGISTRY) == ["max", "min", "final", "drop", "change", "mean", "at", "at_first", "time_of_first",
                              "phugoid_period_s", "phugoid_damping", "short_period_frequency_rad_s",
                              "short_period_damping"]
    for name, take in REGISTRY.items():
        assert take.name == name and take.example["take"] == name and set(take.required) <= set(take.example)
        assert take.__doc__ and not (take.mode and take.windowed)
    quantities = ", ".join(f"q_{name}: {json.dumps(take.example)}" for name, take in REGISTRY.items())
    campaign = parse_campaign(BACM.format(quantity="{of: h_ft, take: max}").replace(
        "quantities: {q: {of: h_ft, take: max}}", f"quantities: {{{quantities}}}"), str(tmp_path / "q.yaml"),
        AircraftProperties)
    assert set(campaign.quantities) == {f"q_{name}" for name in REGISTRY}


def test_plan_refuses_modes_where_there_is_no_level_flight_trim(tmp_path):
    python_campaign(tmp_path, "{p: {take: phugoid_period_s}}", "{kind: monte_carlo, samples: 4}")
    result = cli_in_process("plan", tmp_path / "q.yaml")
    assert result.returncode == 2 and "quantities.p.take:" in result.stderr and "level_flight" in result.stderr


def test_a_jsbsim_quantity_is_taken_at_every_integration_step():
    # the recorder's max of altitude and min of q over the flight equal a plain JSBSim loop's over
    # every 120 Hz step (exactly: the same values), which the 20 Hz recorded times can miss
    from uqflight.simulators import JSBSimSimulator

    simulator = JSBSimSimulator(SimulatorSpec("jsbsim", {"duration_s": 10.0}), [])
    recorder = QuantityRecorder({"h": QuantitySpec("h", "max", of="h_ft"),
                                 "q": QuantitySpec("q", "min", of="q_degps")}, simulator.source)
    recorded = simulator.evaluate(np.zeros(0), (recorder,))
    found = recorder.result()

    # the plain loop, on a freshly loaded aircraft (a reused one differs in the 15th digit: engine state):
    # the same trim, excitation and steps
    flight = JSBSimSimulator(SimulatorSpec("jsbsim", {"duration_s": 10.0}), []).flight
    flight.trim({})
    fdm, setup = flight.fdm, flight.setup
    node, base, per_deg = flight._excitation_input()
    steps = int(round(setup.duration_s * setup.rate_hz))
    heights, rates = [fdm["position/h-sl-ft"]], [fdm["velocities/q-rad_sec"]]
    for i, value in enumerate(setup.excitation.values(np.arange(steps) / setup.rate_hz)):
        node.set_double_value(base + per_deg * value)
        fdm.run()
        heights.append(fdm["position/h-sl-ft"])
        rates.append(fdm["velocities/q-rad_sec"])
    assert found["h"] == max(heights)
    assert found["q"] == min(rates) * (180.0 / math.pi)  # the named output q_degps, scaled as recorded
    assert found["q"] <= recorded["q_degps"].min() and found["h"] >= recorded["h_ft"].max()


@pytest.mark.slow
def test_the_report_shows_the_quantities_table_pdfs_and_sobol_bars(tmp_path):
    from uqflight.report import write_report

    text = python_campaign(tmp_path, "{final_y: {of: y, take: final}, t_up: {take: time_of_first, when: "
                                     "{of: y, above: 4}}}", "{kind: sparse_grid, rule: gauss_legendre, level: 2}",
                           "{kind: pseudo_galerkin, order: 2}",
                           analysis="{band_samples: 2000, exceedance: {final_y: [{above: 5}]}}")
    out = tmp_path / "grid.h5"
    run_campaign(parse_campaign(text, str(tmp_path / "q.yaml")), out=out)
    report = tmp_path / "report"
    write_report([out], report)
    page = (report / "report.html").read_text()
    assert 'id="quantities"' in page and "Exceedance probabilities" in page
    assert (report / "plots" / "quantity_pdfs_grid.png").stat().st_size > 0
    assert (report / "plots" / "quantity_sobol_grid.png").stat().st_size > 0
    import csv

    rows = list(csv.reader((report / "tables" / "quantities.csv").open()))
    assert [row[1:3] for row in rows[1:]] == [["final_y", "0"], ["t_up", "7"]] and rows[2][3] == ""


def test_quantities_written_in_two_sessions_equal_one_and_a_damaged_layout_is_refused(tmp_path):
    import h5py

    from uqflight.quantities import quantity_key
    from uqflight.store import CorruptFile

    def create(path):
        return ResultStore.create(path, campaign_text="x", xi=np.zeros((4, 1)), kappa=np.zeros((4, 1)),
                                  weights=np.full(4, 0.25), parameter_names=["a"], outputs=["y"],
                                  time=np.arange(3.0), quantities=["q"])

    def batch(rows):
        return (rows, np.zeros(len(rows), np.int8), [""] * len(rows),
                {"y": np.ones((len(rows), 3)), quantity_key("q"): np.array([1.5, np.nan, 2.5, 3.5])[rows]})

    with create(tmp_path / "one.h5") as store:
        store.write_batch(*batch(np.arange(4)))
    with create(tmp_path / "two.h5") as store:
        store.write_batch(*batch(np.array([2, 0])))
    with ResultStore.open(tmp_path / "two.h5", "a") as store:  # a resume
        assert store.pending().tolist() == [1, 3]
        store.write_batch(*batch(np.array([3, 1])))
    assert_same_results(tmp_path / "one.h5", tmp_path / "two.h5")
    with ResultStore.open(tmp_path / "one.h5") as store:
        np.testing.assert_array_equal(store.quantity("q"), [1.5, np.nan, 2.5, 3.5])
        with pytest.raises(ValueError, match="quantities"):  # an ok run without its quantities
            store._split_quantities(np.arange(1), np.zeros(1), {"y": np.ones((1, 3))})
    with h5py.File(tmp_path / "one.h5", "a") as f:
        del f["quantities/q"]
        f["quantities/q"] = np.zeros(3)
    with pytest.raises(CorruptFile, match="/quantities/q has shape"):
        ResultStore.open(tmp_path / "one.h5")


def test_every_take_has_a_docstring_example_and_the_examples_hold():
    # each take's Examples feed it a few steps and check the value worked out by hand from its definition; the
    # modes' values on a system matrix of known eigenvalues are Mode's example, each mode shows its attributes
    import doctest

    from uqflight.quantities import takes

    result = doctest.testmod(takes)
    assert result.attempted >= 3 * len(REGISTRY) and result.failed == 0
    assert "classified_modes" in takes.Mode.__doc__
    assert [name for name, take in REGISTRY.items() if ">>>" not in (take.__doc__ or "")] == []
