"""`uqflight check` of quantities of interest: a baseline holds them beside the outputs, a moved quantity
drifts (exit 1), a quantity defined on one side only drifts, and a baseline written before quantities
existed is still compared on its outputs."""
import json

import pytest
from conftest import cli_in_process
from test_quantities import python_campaign

from uqflight.campaign import parse_campaign
from uqflight.check import baseline_json, compare, write_baseline
from uqflight.execution import run_campaign
from uqflight.statistics import analyse


@pytest.fixture(scope="module")
def quantity_files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("check")
    text = python_campaign(folder, "{final_y: {of: y, take: final}, peak_z: {of: z, take: max}}",
                           "{kind: sobol, samples: 64}")
    results, baseline = folder / "q.h5", folder / "baseline.json"
    run_campaign(parse_campaign(text, str(folder / "q.yaml")), out=results, workers=1)
    write_baseline(analyse(results), "", baseline)  # what `report --write-baseline` writes
    return results, baseline


def test_a_baseline_holds_the_quantities_and_check_passes_on_it(quantity_files):
    results, baseline = quantity_files
    data = json.loads(baseline.read_text())
    assert set(data["quantities"]) == {"final_y", "peak_z"} and len(data["quantities"]["final_y"]["mean"]) == 1
    done = cli_in_process("check", results, "--baseline", baseline)
    assert done.returncode == 0, done.stdout + done.stderr


def test_a_moved_quantity_drifts_with_exit_1(quantity_files, tmp_path):
    results, baseline = quantity_files
    data = json.loads(baseline.read_text())
    data["quantities"]["final_y"]["mean"][0] += 1e-3
    moved = tmp_path / "moved.json"
    moved.write_text(json.dumps(data))
    done = cli_in_process("check", results, "--baseline", moved)
    assert done.returncode == 1, done.stdout + done.stderr
    assert "quantity final_y  mean" in done.stdout


def test_a_quantity_defined_on_one_side_only_drifts(quantity_files):
    results, baseline = quantity_files
    data = json.loads(baseline.read_text())
    data["quantities"]["peak_z"] = None  # undefined in every run when the baseline was written
    comparison = compare(analyse(results), data, 1e-6, 1e-9)
    assert [(d.output, d.statistic) for d in comparison.drifts] == [("quantity peak_z", "mean")]


def test_a_baseline_without_quantities_is_compared_on_its_outputs(quantity_files):
    results, baseline = quantity_files
    data = json.loads(baseline.read_text())
    stats = analyse(results)
    older = {key: value for key, value in data.items() if key != "quantities"}
    assert compare(stats, older, 1e-6, 1e-9).compared < compare(stats, data, 1e-6, 1e-9).compared
    assert not compare(stats, older, 1e-6, 1e-9).drifts
    assert baseline_json(stats, "")["quantities"].keys() == data["quantities"].keys()


# -- baselines that are no baselines, and tolerances that let anything through
def baseline_text(mean):
    return ('{"kind": "uqflight-baseline", "version": 1, "outputs": {"y": {"time": [0, 1], "mean": %s, '
            '"variance": [1, 1], "band99": {"lower": [0, 0], "upper": [1, 1]}, "sobol_first": {}, '
            '"sobol_total": {}}}}' % mean)


@pytest.mark.parametrize("mean", ["[Infinity, 1]", "[-Infinity, 1]", "[1e999, 1]"])
def test_check_refuses_infinite_baseline_values(tmp_path, mean):
    from uqflight.check import BadInput, load_baseline

    path = tmp_path / "b.json"
    path.write_text(baseline_text(mean))
    with pytest.raises(BadInput, match="infinite|Infinity"):
        load_baseline(path)


def test_check_accepts_nan_and_null_baseline_values(tmp_path):
    from uqflight.check import load_baseline

    path = tmp_path / "b.json"
    path.write_text(baseline_text("[NaN, null]"))
    assert load_baseline(path)["outputs"]["y"]["mean"][1] is None


def test_check_refuses_deeply_nested_json(tmp_path):
    from uqflight.check import BadInput, load_baseline

    path = tmp_path / "b.json"
    path.write_text("[" * 100000 + "]" * 100000)
    with pytest.raises(BadInput, match="nested too deeply"):
        load_baseline(path)


@pytest.mark.parametrize("rtol, atol", [(1e-6, float("inf")), (float("nan"), 1e-9), (float("inf"), 0.0)])
def test_check_refuses_non_finite_tolerances(rtol, atol):
    from uqflight.check import BadInput, compare

    with pytest.raises(BadInput, match="expected a finite number >= 0"):
        compare(None, {"outputs": {}}, rtol, atol)


def test_check_against_another_campaigns_baseline_exits_2(decay_results, tmp_path):
    baseline = write_baseline(analyse(decay_results), "", tmp_path / "baseline.json")
    data = json.loads(baseline.read_text())
    data["campaign_hash"] = "0" * 64
    baseline.write_text(json.dumps(data))
    checked = cli_in_process("check", decay_results, "--baseline", baseline)
    assert checked.returncode == 2 and "comes from another campaign" in checked.stderr
