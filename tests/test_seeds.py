"""A random stream's seed as an uncertain input (`distribution: seed`): integers drawn from the campaign's
seed and each run's design index, flown as given, refused where a polynomial would have to represent them,
and the share of the variance they cause, against a closed form."""
import json

import h5py
import numpy as np
import pytest
from conftest import DATA, assert_same_results, cli_in_process

from uqflight.campaign import CampaignError, load_campaign, parse_campaign
from uqflight.running.runner import run_campaign
from uqflight.parameters.distributions import SEED_COUNT
from uqflight.analysis.statistics import analyse, summary_json

MODEL = DATA / "seed_models.py"
PARAMETERS = ("  x: {distribution: normal, lower: -3, upper: 3}\n"
              "  seed: {distribution: seed}\n")


def campaign(design="{kind: pick_freeze, samples: 512}", method="", parameters=PARAMETERS, seed=11,
             bootstrap=300):
    return (f"name: seeds\nseed: {seed}\nsimulator: {{kind: python, function: \"{MODEL}:x_plus_noise\"}}\n"
            f"parameters:\n{parameters}design: {design}\n{method}"
            f"analysis: {{band_samples: 2000, bootstrap: {bootstrap}}}\n")


def run(folder, text, name="s", workers=1, executor="local"):
    source = folder / f"{name}.yaml"
    source.write_text(text)
    out = folder / f"{name}.h5"
    run_campaign(load_campaign(source), out=out, workers=workers, executor=executor)
    return out


@pytest.fixture(scope="module")
def pick_freeze(tmp_path_factory):
    return run(tmp_path_factory.mktemp("seeds"), campaign())


def test_seeds_are_integers_flown_as_given_and_stored_exactly(pick_freeze):
    with h5py.File(pick_freeze) as f:
        seeds, status = f["samples/kappa"][:, 1], f["samples/status"][:]
        assert json.loads(f.attrs["record"])["parameters"][1]["distribution"] == "seed"
    assert np.all(status == 0)  # the model refuses a seed that is not an int: every run got one
    assert np.all(seeds == np.floor(seeds)) and seeds.min() >= 0 and seeds.max() < SEED_COUNT
    n = 512  # pick-freeze: A, B, then A with B's column k; the seed column is frozen or swapped like x's
    a, b, ab_x, ab_seed = seeds[:n], seeds[n:2 * n], seeds[2 * n:3 * n], seeds[3 * n:]
    np.testing.assert_array_equal(ab_x, a)
    np.testing.assert_array_equal(ab_seed, b)
    assert len(np.unique(a)) == n


def test_the_seeds_share_of_the_variance_is_the_closed_form(pick_freeze):
    """y(t) = t·x + 0.5·e(seed): the seed's share is 0.25 / (t² + 0.25), first-order and total alike
    (0.2 at t = 1, 1/17 at t = 2), and the other inputs' the rest. Each estimate's 95 % bootstrap interval
    (300 resamples of 512 base rows) must hold the closed form; at t = 0 the seed has no share."""
    summary = summary_json(analyse(pick_freeze))
    split = summary["outputs"]["y"]["variance_split"]
    assert split["seed"] == "seed"
    share = np.array([0.0, 0.25 / 1.25, 0.25 / 4.25])
    for t in (1, 2):
        for kind in ("first", "total"):
            seeds = split["seeds"]
            assert seeds[f"{kind}_ci"]["lower"][t] <= share[t] <= seeds[f"{kind}_ci"]["upper"][t], (t, kind, seeds)
            others = split["other_parameters"]
            assert others[f"{kind}_ci"]["lower"][t] <= 1 - share[t] <= others[f"{kind}_ci"]["upper"][t]
    assert abs(summary["outputs"]["y"]["sobol_total"]["seed"][0]) < 0.02  # y(0) = x: the seed plays no part


@pytest.mark.slow
def test_seeds_depend_on_the_campaign_seed_and_design_index_only(tmp_path, pick_freeze):
    small = campaign(design="{kind: monte_carlo, samples: 40}", bootstrap=0)
    one = run(tmp_path, small, "one", workers=1)
    two = run(tmp_path, small, "two", workers=2)
    assert_same_results(one, two)
    other = run(tmp_path, campaign(design="{kind: monte_carlo, samples: 40}", bootstrap=0, seed=12), "other")
    with h5py.File(one) as f, h5py.File(other) as g:
        assert not np.array_equal(f["samples/kappa"][:, 1], g["samples/kappa"][:, 1])
        assert not np.array_equal(f["outputs/y"][:, 1], g["outputs/y"][:, 1])


@pytest.mark.parametrize("design, method, field", [
    ("{kind: sparse_grid, level: 2}", "", "parameters.seed.distribution"),
    ("{kind: tensor_grid, points: 3}", "method: {kind: integration}\n", "parameters.seed.distribution"),
    ("{kind: monte_carlo, samples: 40}", "method: {kind: least_squares, order: 1}\n", "parameters.seed.distribution"),
    ("{kind: sobol, samples: 32}", "method: {kind: pseudo_galerkin, order: 1}\n", "parameters.seed.distribution"),
])
def test_grids_and_pce_over_a_seed_are_refused_naming_it(design, method, field):
    with pytest.raises(CampaignError, match=field.replace(".", r"\.")) as info:
        parse_campaign(campaign(design=design, method=method), "c.yaml")
    assert "seed" in str(info.value)


@pytest.mark.parametrize("parameters, field", [
    (PARAMETERS + "  other: {distribution: seed}\n", "parameters.other.distribution"),
    ("  x: {distribution: normal, lower: -3, upper: 3}\n  seed: {distribution: seed, lower: 0, upper: 9}\n",
     "parameters.seed.lower"),
])
def test_two_seeds_or_a_seed_interval_are_refused(parameters, field):
    with pytest.raises(CampaignError, match=field.replace(".", r"\.")):
        parse_campaign(campaign(parameters=parameters), "c.yaml")


def test_plan_refuses_a_sparse_grid_over_a_seed_with_exit_2(tmp_path):
    path = tmp_path / "grid.yaml"
    path.write_text(campaign(design="{kind: sparse_grid, level: 2}"))
    done = cli_in_process("plan", path)
    assert done.returncode == 2 and "parameters.seed.distribution" in done.stderr, done.stderr


def test_report_refuses_a_pce_method_over_a_seed(tmp_path):
    results = run(tmp_path, campaign(design="{kind: monte_carlo, samples: 40}", bootstrap=0))
    done = cli_in_process("report", results, "--method", "least_squares:1", "--out", tmp_path / "r")
    assert done.returncode == 2 and "seed" in done.stderr and "polynomials" in done.stderr, done.stderr
    summary = summary_json(analyse(results))  # monte_carlo on a Monte Carlo design: sample moments
    assert summary["outputs"]["y"]["variance"][1] == pytest.approx(1.25, rel=0.5)
    assert "variance_split" not in summary["outputs"]["y"]  # Sobol' shares need a pick_freeze design


def test_a_jsbsim_seed_must_be_a_property_of_the_aircraft(tmp_path):
    text = ("name: s\nsimulator: {kind: jsbsim, aircraft: bacm, duration_s: 5}\nparameters:\n"
            "  turbulence: {property: atmosphere/randomseedx, distribution: seed}\n"
            "design: {kind: monte_carlo, samples: 4}\n")
    (tmp_path / "s.yaml").write_text(text)
    done = cli_in_process("plan", tmp_path / "s.yaml")
    assert done.returncode == 2, done.stderr
    assert "parameters.turbulence.property" in done.stderr and "did you mean atmosphere/randomseed" in done.stderr


@pytest.mark.slow
def test_the_report_shows_the_variance_split_with_its_intervals(tmp_path):
    import csv

    results = run(tmp_path, campaign(design="{kind: pick_freeze, samples: 128}", bootstrap=100))
    done = cli_in_process("report", results, "--out", tmp_path / "r", "--times", "1,2")
    assert done.returncode == 0, done.stderr
    with open(tmp_path / "r" / "tables" / "variance_split.csv", newline="") as fh:
        rows = {row["quantity or output"]: row for row in csv.DictReader(fh)}
    at_1 = rows["y at 1 s"]  # closed form: the seed's share 0.2, the others' 0.8
    assert float(at_1["seed total lower"]) <= 0.2 <= float(at_1["seed total upper"])
    assert float(at_1["others first lower"]) <= 0.8 <= float(at_1["others first upper"])
    assert "Variance split" in (tmp_path / "r" / "report.md").read_text()
