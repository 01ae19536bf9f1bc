"""Exceedance probabilities of quantities: the Monte Carlo interval holds the true probability, the PCE
estimate samples the expansion (no interval, with a note), rare events are flagged, and bad
`analysis.exceedance` entries are refused at plan."""
import json

import numpy as np
import pytest
from conftest import cli_in_process
from test_quantities import python_campaign

from uqflight.analysis.exceedance import exceedance_from_runs
from uqflight.campaign import parse_campaign
from uqflight.running.runner import run_campaign
from uqflight.analysis.statistics import analyse, summary_json
from uqflight.store import ResultStore

# final y = a + 4b with a ~ U(-1, 1), b ~ U(0.5, 1.5): a trapezoidal law on [1, 7], flat on [3, 5];
# P(> 5) = 1/4, P(> 6) = 1/16, P(< 1.1) = 0.1²/16
TRUE = {("above", 5.0): 0.25, ("above", 6.0): 1 / 16, ("below", 1.1): 0.01 / 16}
EXCEEDANCE = "{exceedance: {final_y: [{above: 5}, {above: 6}, {below: 1.1}]}}"


@pytest.mark.slow
def test_the_monte_carlo_interval_holds_the_true_probability(tmp_path):
    text = python_campaign(tmp_path, "{final_y: {of: y, take: final}}", "{kind: monte_carlo, samples: 2000}",
                           analysis=EXCEEDANCE)
    out = tmp_path / "mc.h5"
    run_campaign(parse_campaign(text, str(tmp_path / "q.yaml")), out=out)
    summary = json.loads(json.dumps(summary_json(analyse(out)), allow_nan=False))
    with ResultStore.open(out) as store:
        final = store.quantity("final_y")
    np.testing.assert_allclose(final, store_kappa_sum(out), rtol=1e-12)
    for item in summary["quantities"]["final_y"]["exceedance"]:
        bound = "above" if "above" in item else "below"
        threshold = item[bound]
        beyond = final > threshold if bound == "above" else final < threshold
        assert item["probability"] == beyond.mean() and item["method"] == "wilson"
        assert item["lower"] <= TRUE[bound, threshold] <= item["upper"], item
        assert ("rare-event" in item["note"]) == (beyond.sum() < 10)
    assert "rare-event" in summary["quantities"]["final_y"]["exceedance"][2]["note"]


def store_kappa_sum(path):
    with ResultStore.open(path) as store:
        a, b = store.kappa.T
    return a + 4 * b


def test_the_wilson_interval_covers_the_true_probability_about_95_percent_of_the_time():
    # 400 independent sets of 200 runs: the coverage is a binomial mean with s.d. 0.011 around ~0.95;
    # [0.90, 0.99] is 4 s.d. either side
    rng = np.random.default_rng(5)
    covered = []
    for _ in range(400):
        final = rng.uniform(-1, 1, 200) + 4 * rng.uniform(0.5, 1.5, 200)
        item, = exceedance_from_runs(final, np.ones(final.size, bool), [{"above": 5.0}])
        covered.append(item["lower"] <= 0.25 <= item["upper"])
    assert 0.90 <= np.mean(covered) <= 0.99


def test_a_pce_gives_the_probability_from_its_draws_without_an_interval(tmp_path):
    # the order-2 projection on the grid is the exact a + 4b: the fraction of 20000 draws above 5
    # has a s.d. of 0.003 around 1/4; 0.015 is 5 of them
    text = python_campaign(tmp_path, "{final_y: {of: y, take: final}}",
                           "{kind: sparse_grid, rule: gauss_legendre, level: 2}", "{kind: pseudo_galerkin, order: 2}",
                           analysis="{band_samples: 20000, exceedance: {final_y: [{above: 5}, {above: 6.9}]}}")
    out = tmp_path / "pce.h5"
    run_campaign(parse_campaign(text, str(tmp_path / "q.yaml")), out=out)
    summary = json.loads(json.dumps(summary_json(analyse(out)), allow_nan=False))
    above5, above69 = summary["quantities"]["final_y"]["exceedance"]
    assert above5["probability"] == pytest.approx(0.25, abs=0.015)
    assert above5["method"] == "pce" and above5["lower"] is None and above5["upper"] is None
    assert "no interval" in above5["note"]
    assert above69["probability"] < 0.005 and "rare-event" in above69["note"]


@pytest.mark.parametrize("analysis, field", [
    ("{exceedance: {nothing: [{above: 1}]}}", "analysis.exceedance.nothing"),
    ("{exceedance: {final_y: [{above: 1, below: 2}]}}", "analysis.exceedance.final_y[0]"),
    ("{exceedance: {final_y: [{over: 1}]}}", "analysis.exceedance.final_y[0].over"),
    ("{exceedance: {final_y: {above: 1}}}", "analysis.exceedance.final_y"),
])
def test_plan_refuses_a_bad_exceedance_naming_the_field(tmp_path, analysis, field):
    python_campaign(tmp_path, "{final_y: {of: y, take: final}}", "{kind: monte_carlo, samples: 8}", analysis=analysis)
    result = cli_in_process("plan", tmp_path / "q.yaml")
    assert result.returncode == 2 and f"{field}:" in result.stderr, result.stderr
