"""Rare-event designs as campaigns (designs.rare, rare_rounds, rare_statistics, report.rare_event): each
kind end to end through `run` and `report` on closed-form limit states (python models), the refusals of
their keys, and reproducibility (a SIGKILLed run resumed, 1 worker against 2, another seed). The algorithms
themselves are tested on their own in tests/test_rare_algorithms.py."""
import math
import os
import signal
import subprocess

import h5py
import numpy as np
import pytest
from scipy.special import ndtr, ndtri

from uqflight.campaign import CampaignError, parse_campaign
from uqflight.running.runner import run_campaign
from uqflight.analysis.statistics import analyse, summary_json

from conftest import UQFLIGHT, assert_same_results, cli_in_process, read_summary

THRESHOLD = 3.0  # y ~ N(0, 1) in both models: P(y > 3) = Φ(−3) = 1.35e-3
EXACT = float(ndtr(-THRESHOLD))

LINEAR = """
name: rare-{kind}
seed: {seed}
simulator: {{kind: python, function: "uqflight.simulators.models:normal_sum"}}
parameters:
  x1: {{distribution: normal, lower: -3, upper: 3}}
  x2: {{distribution: normal, lower: -3, upper: 3}}
quantities:
  peak: {{of: y, take: max}}
  low: {{of: y, take: min}}
design: {{kind: {kind}, event: {{of: peak, above: {threshold}}}{settings}}}
execution: {{workers: 1, chunk: 25}}
"""
SETTINGS = {"subset_simulation": ", samples_per_level: 200, p0: 0.1, budget: 1000",
            "importance_sampling": ", samples: 200, budget: 1000",
            "active_learning": ", budget: 500"}

SEEDED = """
name: rare-seeded
seed: {seed}
simulator: {{kind: python, function: "uqflight.simulators.models:seeded_sum"}}
parameters:
  x: {{distribution: normal, lower: -3, upper: 3}}
  seed: {{distribution: seed}}
quantities:
  peak: {{of: y, take: max}}
design: {{kind: subset_simulation, event: {{of: peak, above: {threshold}}}, samples_per_level: 200, p0: 0.1,
          budget: 1000}}
execution: {{workers: 1, chunk: 25}}
"""


QUICK = ", samples_per_level: 200, p0: 0.1, budget: 1000"  # P(y > 2.5) = 6.2e-3: three levels, 560 runs


def linear_text(kind: str, seed: int = 1, threshold: float = THRESHOLD, settings: str | None = None) -> str:
    return LINEAR.format(kind=kind, seed=seed, threshold=threshold,
                         settings=SETTINGS[kind] if settings is None else settings)


def fly(tmp_path, text: str, name: str = "r", workers: int = 1):
    source = tmp_path / f"{name}.yaml"
    source.write_text(text)
    out = tmp_path / f"{name}.h5"
    run_campaign(parse_campaign(text, str(source)), out=out, workers=workers)
    return out


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    """A quick subset simulation flown once: (its folder, campaign text, results file)."""
    folder = tmp_path_factory.mktemp("quick")
    text = linear_text("subset_simulation", threshold=2.5, settings=QUICK)
    return folder, text, fly(folder, text)


def copied(quick, tmp_path):
    """The quick campaign and a copy of its results file in tmp_path: (campaign file, results file)."""
    folder, text, out = quick
    (tmp_path / "r.yaml").write_text(text)
    (tmp_path / "r.h5").write_bytes(out.read_bytes())
    return tmp_path / "r.yaml", tmp_path / "r.h5"


def check_entry(entry: dict, kind: str, names: list[str], runs_at_most: int) -> None:
    """The summary.json exceedance entry of a rare-event design: every field, strict types, the exact value
    inside the algorithm's 95 % interval (a fixed seed: the check is deterministic)."""
    assert entry["above"] == THRESHOLD and entry["method"] == kind
    assert {"probability", "lower", "upper", "cov", "runs", "beta", "design_point", "importance"} <= set(entry)
    assert 0 <= entry["lower"] <= entry["probability"] <= entry["upper"] <= 1
    assert entry["lower"] <= EXACT <= entry["upper"], entry
    assert 0 < entry["runs"] <= runs_at_most
    assert entry["beta"] == pytest.approx(-float(ndtri(entry["probability"])), rel=1e-12)  # its definition
    assert set(entry["design_point"]) == set(names) and set(entry["importance"]) == set(names)
    assert sum(entry["importance"].values()) == pytest.approx(1.0, abs=1e-12)
    # the design point is a run in the event: y = Σ x/√d > 3 there
    point = np.array([entry["design_point"][n] for n in names])
    assert point.sum() / math.sqrt(len(names)) > THRESHOLD


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["subset_simulation", "importance_sampling", "active_learning"])
def test_each_kind_estimates_its_event_end_to_end_through_run_and_report(tmp_path, kind):
    (tmp_path / "r.yaml").write_text(linear_text(kind))
    done = cli_in_process("run", tmp_path / "r.yaml", "--out", tmp_path / "r.h5")
    assert done.returncode == 0, done.stderr
    done = cli_in_process("report", tmp_path / "r.h5", "--out", tmp_path / "report")
    assert done.returncode == 0, done.stderr
    summary = read_summary(tmp_path / "report" / "summary.json")
    entry, = summary["quantities"]["peak"]["exceedance"]
    check_entry(entry, kind, ["x1", "x2"], runs_at_most=int(SETTINGS[kind].rsplit("budget: ", 1)[1]))
    assert entry["runs"] == summary["runs"] == summary["rare_event"]["runs"]
    rounds = summary["rare_event"]["rounds"]
    assert rounds and rounds[-1]["runs"] <= entry["runs"] and [r["runs"] for r in rounds] == sorted(
        r["runs"] for r in rounds)
    # the other statistics are not the input law's: null, and said so
    assert summary["quantities"]["peak"]["mean"] is None and summary["quantities"]["low"]["exceedance"] == []
    assert summary["outputs"] == {} and summary["failure_probability"]["estimate"] is None
    assert any("not draws of the input law" in note for note in summary["notes"])
    html = (tmp_path / "report" / "report.html").read_text()
    assert "Rare event: the probability" in html and f"P(peak &gt; {THRESHOLD:g})" in html
    for figure in ("rare_convergence_r.png", "rare_runs_r.png"):
        assert (tmp_path / "report" / "plots" / figure).stat().st_size > 10_000
    with h5py.File(tmp_path / "r.h5", "r") as f:  # the file holds the estimate and every run it used
        assert f["rare_event"].attrs["probability"] == entry["probability"]
        assert f["samples/status"].shape[0] == entry["runs"] and (f["samples/status"][()] == 0).all()


@pytest.mark.slow
def test_a_seed_parameter_is_redrawn_by_subset_simulation(tmp_path):
    out = fly(tmp_path, SEEDED.format(seed=2, threshold=THRESHOLD))
    entry, = summary_json(analyse(out))["quantities"]["peak"]["exceedance"]
    assert entry["lower"] <= EXACT <= entry["upper"], entry
    with h5py.File(out, "r") as f:
        seeds = f["samples/kappa"][:, 1]
    assert np.unique(seeds).size > 0.9 * seeds.size  # fresh seeds in the chains, not copies of their starts


@pytest.mark.parametrize("change, field, message", [
    ("event: {of: peak, above: 3.0}", "design.event.of", "expected one of the campaign's quantities (peak, low)"),
    ("", "design.event", "missing"),
    ("event: {of: peak, above: 3.0, below: 1.0}", "design.event", "exactly one of above or below"),
    ("event: {of: peak, above: .nan}", "design.event.above", "a finite number"),
    ("event: {of: peak, over: 3.0}", "design.event.over", "unknown key"),
    ("event: {of: peak, above: 3.0}, p0: 0.7", "design.p0", "in (0, 0.5]"),
    ("event: {of: peak, above: 3.0}, p0: 0", "design.p0", "in (0, 0.5]"),
    ("event: {of: peak, above: 3.0}, samples_per_level: 5, p0: 0.1", "design.samples_per_level",
     "at least one chain"),
    ("event: {of: peak, above: 3.0}, samples_per_level: 1", "design.samples_per_level", "from 2"),
    ("event: {of: peak, above: 3.0}, budget: 0", "design.budget", "from 1"),
    ("event: {of: peak, above: 3.0}, samples: 100", "design.samples", "unknown key for kind subset_simulation"),
])
def test_bad_rare_event_designs_are_refused_naming_the_key(tmp_path, change, field, message):
    text = linear_text("subset_simulation", settings="").replace("event: {of: peak, above: 3.0}", change)
    if field == "design.event.of":
        text = text.replace("{of: peak,", "{of: y,")
    with pytest.raises(CampaignError) as refused:
        parse_campaign(text, str(tmp_path / "r.yaml"))
    assert f"{field}: " in str(refused.value) and message in str(refused.value), str(refused.value)


def test_the_command_line_refuses_an_event_of_no_quantity_in_one_line(tmp_path):
    (tmp_path / "r.yaml").write_text(linear_text("subset_simulation").replace("{of: peak,", "{of: y,"))
    done = cli_in_process("run", tmp_path / "r.yaml", "--out", tmp_path / "r.h5")
    assert done.returncode == 2 and "design.event.of: expected one of the campaign's quantities" in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1 and not (tmp_path / "r.h5").exists()


def test_an_active_learning_budget_too_small_for_its_rounds_is_refused_by_run_naming_design_budget(tmp_path):
    # first design 4k + 12 = 20 and one enrichment of 5 within 40 % of the budget, two importance-sampling
    # rounds of 100 in the rest: 332 runs at least (smallest_budget), so 331 is refused before a run
    (tmp_path / "r.yaml").write_text(linear_text("active_learning", settings=", budget: 331"))
    done = cli_in_process("run", tmp_path / "r.yaml", "--out", tmp_path / "r.h5")
    assert done.returncode == 2 and "r.yaml: design.budget: 331 runs are too few for active learning on 2 inputs" \
        in done.stderr  # the field once, right after the file
    assert "at least 332" in done.stderr and len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert not (tmp_path / "r.h5").exists()
    parse_campaign(linear_text("active_learning", settings=", budget: 332"), str(tmp_path / "r.yaml"))


def test_active_learning_on_seed_parameters_alone_is_refused_naming_the_kind(tmp_path):
    text = SEEDED.format(seed=1, threshold=THRESHOLD).replace("kind: subset_simulation", "kind: active_learning")
    text = text.replace(", samples_per_level: 200, p0: 0.1,", ",").replace("  x: {distribution: normal, lower: -3, upper: 3}\n", "")
    with pytest.raises(CampaignError, match="design.kind: active_learning learns a surrogate of the inputs that are not"):
        parse_campaign(text, str(tmp_path / "r.yaml"))


def test_analysis_exceedance_is_refused_beside_a_rare_event_design(tmp_path):
    text = linear_text("subset_simulation") + "analysis: {exceedance: {peak: [{above: 2.0}]}}\n"
    with pytest.raises(CampaignError, match="analysis.exceedance: a subset_simulation design's runs are not draws"):
        parse_campaign(text, str(tmp_path / "r.yaml"))


def test_an_unfinished_rare_event_file_is_refused_by_the_report(quick, tmp_path):
    _, out = copied(quick, tmp_path)
    with h5py.File(out, "r+") as f:
        del f["rare_event"]
    done = cli_in_process("report", out, "--out", tmp_path / "report")
    assert done.returncode == 2 and "has not finished" in done.stderr and "uqflight run" in done.stderr


@pytest.mark.slow
def test_one_worker_and_two_give_the_same_bits_and_another_seed_another_estimate(quick, tmp_path):
    folder, text, one = quick
    two = fly(tmp_path, text, "two", workers=2)
    assert_same_results(one, two)
    with h5py.File(one, "r") as a, h5py.File(two, "r") as b:
        assert dict(a["rare_event"].attrs) == dict(b["rare_event"].attrs)
    other = fly(tmp_path, text.replace("seed: 1", "seed: 2"), "other")
    with h5py.File(one, "r") as a, h5py.File(other, "r") as b:
        assert a["rare_event"].attrs["probability"] != b["rare_event"].attrs["probability"]


def test_a_finished_rare_event_campaign_resumes_to_nothing(quick, tmp_path):
    source, out = copied(quick, tmp_path)
    assert run_campaign(parse_campaign(source.read_text(), str(source)), out=out).ran == 0


KILLED = {"subset_simulation": QUICK, "importance_sampling": ", samples: 200, budget: 1000",
          "active_learning": ", budget: 500"}


@pytest.mark.parametrize("kind", ["subset_simulation"] + [  # three campaigns through the command line each
    pytest.param(kind, marks=pytest.mark.slow) for kind in ("importance_sampling", "active_learning")])
@pytest.mark.slow
def test_a_sigkilled_rare_event_campaign_resumes_to_the_same_bits(tmp_path, kind):
    (tmp_path / "c.yaml").write_text(linear_text(kind, threshold=2.5, settings=KILLED[kind]))
    killed = tmp_path / "killed.h5"
    proc = subprocess.Popen([UQFLIGHT, "run", str(tmp_path / "c.yaml"), "--out", str(killed)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, start_new_session=True)
    rounds = 0
    for line in proc.stderr:  # one "N/N runs (100 %)" line per finished round
        rounds += "(100 %)" in line
        if rounds >= 2:
            break
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    with h5py.File(killed, "r") as f:
        assert "rare_event" not in f, "the kill should land before the estimate"
        flown = int((f["samples/status"][()] >= 0).sum())
    resumed = subprocess.run([UQFLIGHT, "run", str(tmp_path / "c.yaml"), "--out", str(killed)],
                             capture_output=True, text=True)
    assert resumed.returncode == 0, resumed.stderr
    whole = tmp_path / "whole.h5"
    subprocess.run([UQFLIGHT, "run", str(tmp_path / "c.yaml"), "--out", str(whole)], check=True, capture_output=True)
    assert_same_results(killed, whole)
    with h5py.File(killed, "r") as a, h5py.File(whole, "r") as b:
        assert dict(a["rare_event"].attrs) == dict(b["rare_event"].attrs)
        assert flown < a["samples/status"].shape[0]  # the resume flew the rest


def test_a_file_whose_runs_are_not_the_replay_is_refused(quick, tmp_path):
    source, out = copied(quick, tmp_path)
    with h5py.File(out, "r+") as f:
        del f["rare_event"]
        f["samples/xi"][0, 0] += 1e-12
    done = cli_in_process("run", source, "--out", out)
    assert done.returncode == 2 and "are not the points this campaign's subset_simulation asks for" in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1


def test_no_surrogate_is_exported_from_a_rare_event_design(quick, tmp_path):
    _, out = copied(quick, tmp_path)
    done = cli_in_process("surrogate", "export", out, "--out", tmp_path / "s.json")
    assert done.returncode == 2 and "not draws of the input law" in done.stderr, done.stderr
    assert len(done.stderr.strip().splitlines()) == 1 and not (tmp_path / "s.json").exists()
    done = cli_in_process("info", out)
    assert done.returncode == 0 and "rare event: P(peak > 2.5) = " in done.stdout, done.stderr


@pytest.mark.parametrize("damage", ["probability", "round_cov", "notes"])
def test_a_damaged_rare_event_record_is_refused_naming_it(quick, tmp_path, damage):
    _, out = copied(quick, tmp_path)
    with h5py.File(out, "r+") as f:
        group = f["rare_event"]
        if damage == "round_cov":  # a length that differs from the other rounds'
            del group[damage]
            group.create_dataset(damage, data=np.zeros(1000))
        else:
            group.attrs[damage] = "many" if damage == "probability" else "[1, 2"
    for command in (["report", out, "--out", tmp_path / "report"], ["info", out]):
        done = cli_in_process(*command)
        assert done.returncode == 2 and f"{out}: /rare_event" in done.stderr and "damaged" in done.stderr, done.stderr
        assert len(done.stderr.strip().splitlines()) == 1


FAILING_MODEL = '''
import numpy as np


def f(p):
    if p["x1"] < -2.0:  # far from the event (y > 2.5): the estimate keeps its closed form
        raise RuntimeError("stalled on the approach")
    return {"y": (p["x1"] + p["x2"]) / np.sqrt(2.0)}
'''


@pytest.mark.slow
def test_failed_runs_are_recorded_counted_outside_the_event_and_the_campaign_goes_on(tmp_path):
    (tmp_path / "model.py").write_text(FAILING_MODEL)
    text = linear_text("subset_simulation", threshold=2.5, settings=QUICK).replace(
        '"uqflight.simulators.models:normal_sum"', '"model.py:f"')
    summary = summary_json(analyse(fly(tmp_path, text)))
    assert summary["failed"] > 0 and summary["failures"][0]["reason"].endswith("stalled on the approach")
    assert all(run["parameters"]["x1"] < -2.0 for run in summary["failures"])
    entry, = summary["quantities"]["peak"]["exceedance"]
    assert entry["failed"] == summary["failed"] and entry["runs"] == summary["runs"]
    exact = float(ndtr(-2.5))  # P(y > 2.5): the failed runs (x1 < -2) are all outside it
    assert entry["lower"] <= exact <= entry["upper"], entry
    assert any("counts them as outside the event" in note for note in summary["notes"])


def test_the_shipped_hard_landing_campaign_loads_against_the_c172p():
    from conftest import ROOT
    from uqflight.campaign import load_campaign
    from uqflight.designs.rare import Event
    from uqflight.simulators.aircraft_properties import AircraftProperties

    campaign = load_campaign(ROOT / "campaigns" / "c172p-landing-rare.yaml", read_aircraft=AircraftProperties)
    design = campaign.design()
    assert design.kind == "subset_simulation" and campaign.runs == campaign.design_spec["budget"]
    assert campaign.design_spec["event"] == Event("touchdown_sink_rate_fps", "below", -8.5)
    assert [campaign.parameters[k].name for k in campaign.redrawn] == ["turbulence"]
    assert design.xi.shape == (campaign.design_spec["samples_per_level"], 5)


def test_a_rare_event_file_is_reported_alone(quick, tmp_path):
    _, out = copied(quick, tmp_path)
    for extra in (["--reference", out], [out]):  # another file or a reference: nothing to compare
        done = cli_in_process("report", out, *extra, "--out", tmp_path / "report")
        assert done.returncode == 2 and "is reported alone" in done.stderr, done.stderr
        assert len(done.stderr.strip().splitlines()) == 1 and not (tmp_path / "report").exists()


def test_no_baseline_is_written_of_a_rare_event_file(quick, tmp_path):
    _, out = copied(quick, tmp_path)
    done = cli_in_process("report", out, "--out", tmp_path / "report", "--write-baseline", tmp_path / "b.json")
    assert done.returncode == 2 and "--write-baseline" in done.stderr, done.stderr
    assert not (tmp_path / "b.json").exists() and not (tmp_path / "report").exists()


def test_report_exceedance_is_refused_for_a_rare_event_file(quick, tmp_path):
    _, out = copied(quick, tmp_path)
    done = cli_in_process("report", out, "--out", tmp_path / "report", "--exceedance", "peak>2")
    assert done.returncode == 2 and "--exceedance" in done.stderr, done.stderr
    assert not (tmp_path / "report").exists()


@pytest.mark.slow  # a Dask LocalCluster starts for each round's runs
def test_dask_gives_the_bits_of_the_local_workers(quick, tmp_path):
    folder, text, local = quick
    source = tmp_path / "r.yaml"
    source.write_text(text)
    run_campaign(parse_campaign(text, str(source)), out=tmp_path / "dask.h5", executor="dask", workers=2)
    assert_same_results(local, tmp_path / "dask.h5")
