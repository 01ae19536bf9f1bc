"""Dimension-adaptive sparse grids (designs.adaptive, refinement): the combination rule against closed
forms, the refinement on an anisotropic closed form against the isotropic grid, the rounds in one
results file, and a SIGKILLed campaign resumed to the same bits."""
import csv
import math
import os
import signal
import subprocess
from itertools import product

import h5py
import numpy as np
import pytest

from uqflight.campaign import parse_campaign
from uqflight.designs import build_design
from uqflight.designs import rules as rule_catalog
from uqflight.designs.adaptive import Grid, IndexSet, combination_weights, grid_points, refine
from uqflight.running.runner import run_campaign
from uqflight.report import write_report
from uqflight.simulators import models
from uqflight.analysis.statistics import analyse, summary_json
from uqflight.store import CorruptFile, ResultStore

from conftest import UQFLIGHT, assert_same_results, cli_in_process

RULES = ["genz_keister", "gauss_patterson", "clenshaw_curtis"]
# downward closed, anisotropic, with a mixed index
INDEX_SET = [(0, 0, 0), (1, 0, 0), (2, 0, 0), (0, 1, 0), (1, 1, 0), (0, 0, 1), (0, 0, 2), (0, 0, 3)]


def monomial_mean(rule: str, power: int) -> float:
    """E[ξ^power] under the rule's germ: N(0, 1) moments (power − 1)!!, U(−1, 1) moments 1/(power + 1)."""
    if power % 2:
        return 0.0
    if rule_catalog.rule(rule).germ == "normal":
        return float(math.prod(range(power - 1, 0, -2)))
    return 1.0 / (power + 1)


def degrees(rule: str, level: int) -> int:
    return rule_catalog.degree(rule, rule_catalog.level_sizes(rule, "exponential", level + 1)[level])


def classic_combination(indices):
    """Σ_j c_j Q_j with c_j = Σ_{e ∈ {0,1}^d, j + e ∈ I} (−1)^|e| over full tensor rules: {point: weight}."""
    rule = {}
    for j in indices:
        c = sum((-1) ** sum(e) for e in product((0, 1), repeat=len(j))
                if tuple(a + b for a, b in zip(j, e)) in indices)
        if not c:
            continue
        sets = [rule_catalog.nodes_weights(r, rule_catalog.level_sizes(r, "exponential", level + 1)[level])
                for r, level in zip(RULES, j)]
        for combo in product(*[list(zip(*s)) for s in sets]):
            key = tuple(round(float(node), 12) for node, _ in combo)
            rule[key] = rule.get(key, 0.0) + c * math.prod(w for _, w in combo)
    return rule


def test_the_combination_rule_is_exact_on_its_index_sets_polynomials_and_is_the_combination_technique():
    grid = Grid(RULES)
    state = IndexSet(INDEX_SET, [False] * len(INDEX_SET), [0] * len(INDEX_SET), [math.nan] * len(INDEX_SET))
    points = grid_points(grid, state)
    weights = combination_weights(grid, points, INDEX_SET)
    classic = classic_combination(INDEX_SET)
    ours = {tuple(round(float(v), 12) for v in x): w for x, w in zip(points.xi, weights)}
    # The same rule by the textbook formula: rounding of sums of a few signed products (1e-14).
    assert set(k for k, w in classic.items() if abs(w) > 1e-14) <= set(ours)
    for key, w in ours.items():
        assert w == pytest.approx(classic.get(key, 0.0), abs=1e-14)
    covered = {alpha for j in INDEX_SET
               for alpha in product(*[range(degrees(r, level) + 1) for r, level in zip(RULES, j)])}
    for alpha in covered:  # exact to rounding: 1e-12 of the sum's scale Σ|w| |ξ^α|
        values = np.prod(points.xi ** np.array(alpha), axis=1)
        exact = math.prod(monomial_mean(r, a) for r, a in zip(RULES, alpha))
        assert abs(weights @ values - exact) <= 1e-12 * (np.abs(weights) @ np.abs(values) + 1), alpha
    # and not beyond: ξ1² ξ3² needs levels (1, 0, 1), which the set lacks
    values = points.xi[:, 0] ** 2 * points.xi[:, 2] ** 2
    assert abs(weights @ values - monomial_mean(RULES[0], 2) * monomial_mean(RULES[2], 2)) > 1e-3


def anisotropic_moments(d: int) -> tuple[float, float]:
    a, b, c = models.ANISOTROPIC_A, models.ANISOTROPIC_B, models.ANISOTROPIC_C
    return math.exp(a * a / 2), math.exp(2 * a * a) - math.exp(a * a) + (d - 1) * b * b * (1 - math.exp(-2)) / 2 + c * c


def model(xi: np.ndarray) -> np.ndarray:
    return np.array([models.anisotropic(dict(enumerate(x)))["y"] for x in xi])


def eps_v(weights, y, variance) -> float:
    mean = weights @ y
    return abs(weights @ (y - mean) ** 2 - variance) / variance


def test_on_one_dominant_input_among_10_the_adaptive_grid_needs_5x_fewer_runs_than_the_isotropic_one():
    d = 10
    _, variance = anisotropic_moments(d)
    isotropic = None
    for level in range(5):  # the isotropic grid on the same nested members (Genz–Keister, exponential growth)
        design = build_design({"kind": "sparse_grid", "level": level, "rule": "genz_keister",
                               "growth": "exponential"}, ["normal"] * d, 0)
        if eps_v(design.weights, model(design.xi), variance) <= 1e-6:
            isotropic = len(design.weights)
            break
    grid, state = Grid(["genz_keister"] * d), IndexSet.initial(d)
    while not state.stopped:
        points = grid_points(grid, state)
        state = refine(grid, state, points, [model(points.xi)[:, None]], budget=2000, tolerance=1e-7)
    weights = combination_weights(grid, points, state.indices)
    assert state.stopped == "tolerance"
    assert eps_v(weights, model(points.xi), variance) <= 1e-6
    assert isotropic is not None and 5 * len(points.ids) <= isotropic, (len(points.ids), isotropic)
    top = np.max(np.array(state.indices), axis=0)
    assert top[0] == max(grid.levels[0] - 1, top.max()) and np.all(top[1:] < top[0])  # x1 refined most


ADAPTIVE = """
name: adaptive-{budget}
seed: 1
simulator: {{kind: python, function: "uqflight.simulators.models:anisotropic"}}
parameters:
{parameters}
design: {{kind: adaptive_sparse_grid, rule: genz_keister, budget: {budget}, tolerance: 1.0e-7}}
method: {{kind: integration, order: 1}}
execution: {{workers: 1, chunk: 8}}
"""


def adaptive_text(budget: int, d: int = 3) -> str:
    parameters = "\n".join(f"  x{k}: {{distribution: normal, lower: -3, upper: 3}}" for k in range(1, d + 1))
    return ADAPTIVE.format(budget=budget, parameters=parameters)


@pytest.mark.slow
def test_rounds_grow_one_results_file_whose_statistics_are_the_combination_quadrature(tmp_path):
    campaign = parse_campaign(adaptive_text(budget=200), str(tmp_path / "a.yaml"))
    assert campaign.runs == campaign.design_spec.size(campaign.germs) == 200  # limits.max_runs' figure
    run_campaign(campaign, out=tmp_path / "a.h5")
    with ResultStore.open(tmp_path / "a.h5") as store:
        state, n, weights = store.index_set(), store.status.size, store.weights
    assert state.stopped == "tolerance" and state.rounds >= 2 and n <= 200
    assert weights.sum() == pytest.approx(1.0, abs=1e-13)
    stats = analyse(tmp_path / "a.h5")
    mean, variance = anisotropic_moments(3)
    out = stats.outputs["y"]  # stopped at tolerance 1e-7 of the indicators: 1e-6 holds with margin
    assert out.mean[0] == pytest.approx(mean, rel=1e-6) and out.variance[0] == pytest.approx(variance, rel=1e-6)
    recorded = summary_json(stats)["index_set"]
    assert recorded["stopped"] == "tolerance" and recorded["rounds"] == state.rounds
    assert recorded["max_level"]["x1"] == max(index[0] for index in state.indices)
    assert recorded["indices"] == [list(index) for index in state.indices]
    rerun = run_campaign(parse_campaign(adaptive_text(budget=200), str(tmp_path / "a.yaml")), out=tmp_path / "a.h5")
    assert rerun.ran == 0  # a finished adaptive campaign resumes to nothing
    with h5py.File(tmp_path / "a.h5", "r+") as f:  # a damaged index set is refused, not read
        del f["design/old"]
    with pytest.raises(CorruptFile, match="/design/old is missing"):
        ResultStore.open(tmp_path / "a.h5")


@pytest.mark.parametrize("damage", ["rounds", "eta", "indicator", "index_set"])
def test_a_damaged_index_set_is_refused_by_every_reader_naming_design(tmp_path, damage):
    run_campaign(parse_campaign(adaptive_text(budget=30), str(tmp_path / "a.yaml")), out=tmp_path / "a.h5")
    with h5py.File(tmp_path / "a.h5", "r+") as f:  # present, as the layout check wants, but not a state
        group = f["design"]
        if damage in ("rounds", "eta"):
            group.attrs[damage] = "many"
        else:
            size = group[damage].shape[0]
            del group[damage]
            group.create_dataset(damage, data=np.zeros((size + 1, 3) if damage == "index_set" else size + 1))
    for command in (["report", tmp_path / "a.h5", "--out", tmp_path / "report"], ["info", tmp_path / "a.h5"],
                    ["surrogate", "export", tmp_path / "a.h5", "--out", tmp_path / "s.json"]):
        done = cli_in_process(*command)
        assert done.returncode == 2, (command, done.stdout, done.stderr)
        assert f"{tmp_path / 'a.h5'}: /design" in done.stderr and "the file is damaged" in done.stderr
        assert len(done.stderr.strip().splitlines()) == 1 and "Traceback" not in done.stderr


@pytest.mark.slow  # a whole report (the default suite checks the index set it draws, above)
def test_the_report_shows_the_refined_inputs_most_refined_first(tmp_path):
    run_campaign(parse_campaign(adaptive_text(budget=200), str(tmp_path / "a.yaml")), out=tmp_path / "a.h5")
    write_report([tmp_path / "a.h5"], tmp_path / "report")
    html = (tmp_path / "report" / "report.html").read_text()
    assert "Adaptive grid: the refined inputs" in html and (tmp_path / "report/plots/index_set_a.png").is_file()
    with open(tmp_path / "report/tables/index_set.csv") as table:
        first = next(csv.DictReader(table))
    assert first["input"] == "x1"  # the dominant input is the most refined


def test_the_refinement_stops_before_the_budget():
    grid, state = Grid(["genz_keister"] * 3), IndexSet.initial(3)
    while not state.stopped:
        points = grid_points(grid, state)
        state = refine(grid, state, points, [model(points.xi)[:, None]], budget=30, tolerance=0.0)
    assert state.stopped == "budget" and len(grid_points(grid, state).ids) <= 30 and state.rounds >= 2


@pytest.mark.slow
def test_a_sigkilled_adaptive_campaign_resumes_to_the_same_bits(tmp_path):
    (tmp_path / "c.yaml").write_text(adaptive_text(budget=500, d=10))
    killed = tmp_path / "killed.h5"
    proc = subprocess.Popen([UQFLIGHT, "run", str(tmp_path / "c.yaml"), "--out", str(killed)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, start_new_session=True)
    rounds = 0
    for line in proc.stderr:  # one "N/N runs (100 %)" line per finished round
        rounds += "(100 %)" in line
        if rounds >= 8:
            break
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    with h5py.File(killed, "r") as f:
        assert f["design"].attrs["stopped"] == "", "the kill should land mid-refinement"
    resumed = subprocess.run([UQFLIGHT, "run", str(tmp_path / "c.yaml"), "--out", str(killed)],
                             capture_output=True, text=True)
    assert resumed.returncode == 0, resumed.stderr
    whole = tmp_path / "whole.h5"
    subprocess.run([UQFLIGHT, "run", str(tmp_path / "c.yaml"), "--out", str(whole)], check=True,
                   capture_output=True)
    assert_same_results(killed, whole)
    with h5py.File(killed, "r") as a, h5py.File(whole, "r") as b:
        assert dict(a["design"].attrs) == dict(b["design"].attrs) and a["design"].attrs["stopped"] == "tolerance"


@pytest.mark.parametrize("spec, message", [
    ({"budget": 10}, "design.tolerance: missing"),
    ({"budget": 10, "tolerance": -1}, "design.tolerance: expected a number >= 0"),
    ({"tolerance": 1e-3}, "design.budget: missing"),
    ({"budget": 10, "tolerance": 1e-3, "rule": "gauss_hermite"}, "design.rule: an adaptive grid needs nested rules"),
    ({"budget": 10, "tolerance": 1e-3, "level": 2}, "design.level: unknown key"),
])
def test_bad_adaptive_specs_name_the_key(spec, message):
    with pytest.raises(ValueError, match=message):
        build_design({"kind": "adaptive_sparse_grid", **spec}, ["normal"], seed=0)


def test_an_adaptive_grid_refuses_monte_carlo_before_anything_runs(tmp_path):
    from uqflight.campaign import CampaignError

    with pytest.raises(CampaignError, match="method.kind: monte_carlo needs a sampled design"):
        parse_campaign(adaptive_text(budget=30).replace("kind: integration, order: 1", "kind: monte_carlo"),
                       str(tmp_path / "m.yaml"))


@pytest.mark.slow
def test_on_bacm_the_adaptive_grid_refines_k2_most(tmp_path):
    """campaigns/bacm-adaptive.yaml as shipped (300 runs at most, real JSBSim). k2 carries most of h's and
    V_TAS's variance and is only C⁰ there (the engine tables' kinks): it is refined most; CLalpha (q) and
    CL0 (α, θ) follow, the inputs that carry the other outputs' variance."""
    from uqflight.campaign import load_campaign
    from uqflight.simulators.aircraft_properties import AircraftProperties

    from conftest import ROOT

    campaign = load_campaign(ROOT / "campaigns" / "bacm-adaptive.yaml", read_aircraft=AircraftProperties)
    run_campaign(campaign, out=tmp_path / "bacm.h5")
    with ResultStore.open(tmp_path / "bacm.h5") as store:
        state, names, n = store.index_set(), store.parameter_names, store.status.size
    levels = np.array(state.indices)
    refined = dict(zip(names, np.count_nonzero(levels[np.array(state.old)] > 0, axis=0)))
    ranked = sorted(refined, key=refined.get, reverse=True)
    assert n <= 300 and state.stopped in ("budget", "tolerance")
    assert ranked[0] == "k2" and set(ranked[:3]) == {"k2", "CLalpha", "CL0"}, refined
