"""`uqflight check` against a baseline: the exact baseline passes, a moved mean drifts (exit 1), a bad,
missing or other campaign's baseline is refused (exit 2, one line); quantities of interest sit beside the
outputs (a moved or one-sided quantity drifts, an older baseline without them is compared on its outputs);
baselines that are no baselines and tolerances that let anything through are refused."""
import json
from pathlib import Path

import h5py
import pytest
from conftest import cli_in_process
from test_quantities import python_campaign
from test_report import pg  # noqa: F401 - the closed-form campaign the baseline is of

from uqflight.campaign import parse_campaign
from uqflight.analysis.check import compare, write_baseline
from uqflight.running.runner import run_campaign
from uqflight.analysis.statistics import analyse, read_statistics


@pytest.fixture(scope="module")
def quantity_files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("check")
    text = python_campaign(folder, "{final_y: {of: y, take: final}, peak_z: {of: z, take: max}}",
                           "{kind: sobol, samples: 64}")
    results, baseline = folder / "q.h5", folder / "baseline.json"
    run_campaign(parse_campaign(text, str(folder / "q.yaml")), out=results, workers=1)
    with h5py.File(results, "r") as f:
        campaign_hash = str(f.attrs["campaign_hash"])
    write_baseline(analyse(results), campaign_hash, baseline)  # what `report --write-baseline` writes
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


def test_a_baseline_without_quantities_is_refused_naming_the_field_and_the_fix(quantity_files, tmp_path):
    from uqflight.analysis.check import BadInput, load_baseline

    _, baseline = quantity_files
    data = json.loads(baseline.read_text())
    path = tmp_path / "b.json"
    path.write_text(json.dumps({key: value for key, value in data.items() if key != "quantities"}))
    with pytest.raises(BadInput) as refused:
        load_baseline(path)
    assert str(refused.value) == (f"{path}: quantities: expected a mapping of quantity names to statistics ({{}} "
                                  "without quantities), got nothing; write one with `uqflight report RESULTS.h5 --out "
                                  "DIR --write-baseline FILE`")


# -- baselines that are no baselines, and tolerances that let anything through
HASH = "0" * 64


def baseline_text(mean, version="1", campaign_hash=f'"{HASH}"'):
    return ('{"kind": "uqflight-baseline", "version": %s, "campaign_hash": %s, "outputs": {"y": {"time": [0, 1], '
            '"mean": %s, "variance": [1, 1], "band99": {"lower": [0, 0], "upper": [1, 1]}, "sobol_first": {}, '
            '"sobol_total": {}}}, "quantities": {}}' % (version, campaign_hash, mean))


@pytest.mark.parametrize("mean", ["[Infinity, 1]", "[-Infinity, 1]", "[1e999, 1]", f"[{10 ** 400}, 1]"])
def test_check_refuses_infinite_baseline_values(tmp_path, mean):
    from uqflight.analysis.check import BadInput, load_baseline

    path = tmp_path / "b.json"
    path.write_text(baseline_text(mean))
    with pytest.raises(BadInput, match="infinite|Infinity"):
        load_baseline(path)


def test_check_accepts_nan_and_null_baseline_values(tmp_path):
    from uqflight.analysis.check import load_baseline

    path = tmp_path / "b.json"
    path.write_text(baseline_text("[NaN, null]"))
    assert load_baseline(path)["outputs"]["y"]["mean"][1] is None


@pytest.mark.parametrize("version, campaign_hash, field", [
    ("999", f'"{HASH}"', "version"), ("null", f'"{HASH}"', "version"), ("1", '""', "campaign_hash"),
    ("1", "null", "campaign_hash"), ("1", '"abc"', "campaign_hash")])
def test_check_refuses_a_baseline_of_another_version_or_without_its_campaign(tmp_path, version, campaign_hash, field):
    # a baseline without its campaign's hash would let a file of another campaign pass its check
    from uqflight.analysis.check import BadInput, load_baseline

    path = tmp_path / "b.json"
    path.write_text(baseline_text("[1, 1]", version, campaign_hash))
    with pytest.raises(BadInput, match=f"b.json: {field}: expected .*--write-baseline"):
        load_baseline(path)


def test_check_refuses_deeply_nested_json(tmp_path):
    from uqflight.analysis.check import BadInput, load_baseline

    path = tmp_path / "b.json"
    path.write_text("[" * 100000 + "]" * 100000)
    with pytest.raises(BadInput, match="nested too deeply"):
        load_baseline(path)


@pytest.mark.parametrize("rtol, atol", [(1e-6, float("inf")), (float("nan"), 1e-9), (float("inf"), 0.0)])
def test_check_refuses_non_finite_tolerances(rtol, atol):
    from uqflight.analysis.check import BadInput, compare

    with pytest.raises(BadInput, match="expected a finite number >= 0"):
        compare(None, {"outputs": {}}, rtol, atol)


# -- check against a baseline of the outputs of a closed-form campaign
@pytest.fixture(scope="module")
def baseline(pg, tmp_path_factory) -> Path:
    """What `report --write-baseline` writes for pg (test_report.py checks the report writes these bytes)."""
    stats, attrs = read_statistics(pg)
    return write_baseline(stats, attrs["campaign_hash"], tmp_path_factory.mktemp("baseline") / "baseline.json")


def test_check_passes_on_the_exact_baseline(pg, baseline):
    result = cli_in_process("check", pg, "--baseline", baseline)
    assert result.returncode == 0, result.stdout + result.stderr
    n = 51 * 6  # mean, variance, two band bounds, first and total index of a
    assert result.stdout.strip() == f"no drift: {n} values within rtol=1e-06/atol=1e-09"


def test_check_reports_a_moved_mean_with_exit_1(pg, baseline, tmp_path):
    data = json.loads(baseline.read_text())
    data["outputs"]["x"]["mean"][20] += 1e-3
    moved = tmp_path / "moved.json"
    moved.write_text(json.dumps(data))
    result = cli_in_process("check", pg, "--baseline", moved)
    assert result.returncode == 1, result.stdout + result.stderr
    assert result.stdout.startswith("drift: 1 of 306 values outside rtol=1e-06, atol=1e-09")
    row = next(line.split() for line in result.stdout.splitlines() if line.startswith("x "))
    assert row[:3] == ["x", "mean", "2"]
    assert float(row[4]) == pytest.approx(data["outputs"]["x"]["mean"][20])
    assert cli_in_process("check", pg, "--baseline", moved, "--atol", "0.01").returncode == 0


def edited(data: dict, edit) -> str:
    """The baseline `data` as JSON text after `edit(copy)` changed a copy."""
    copy = json.loads(json.dumps(data))
    edit(copy)
    return json.dumps(copy)


def drop_last_time(data: dict) -> None:
    entry = data["outputs"]["x"]
    for key in ("time", "mean", "variance"):
        entry[key].pop()
    for key in ("band99", "sobol_first", "sobol_total"):
        for values in entry[key].values():
            values.pop()


def bad_baselines(data: dict) -> dict[str, tuple[str, str]]:
    """Name: (file text, expected message fragment)."""
    x = "outputs.x"

    def shift_time(d):
        d["outputs"]["x"]["time"] = [t + 1 for t in d["outputs"]["x"]["time"]]

    def add_parameter(d):
        d["outputs"]["x"]["sobol_first"]["b"] = d["outputs"]["x"]["time"]

    return {
        "bad json": ('{"kind": "uqflight-baseline", "outputs": {', "not a JSON baseline"),
        "not a baseline": ('{"outputs": {}}', "not a uqflight baseline"),
        "missing key": (edited(data, lambda d: d["outputs"]["x"].pop("variance")), f"{x}.variance: missing"),
        "wrong length": (edited(data, lambda d: d["outputs"]["x"]["mean"].append(1.0)),
                         f"{x}.mean: expected 51 values (one per time), got 52"),
        "not numbers": (edited(data, lambda d: d["outputs"]["x"]["band99"].update(lower="low")),
                        f"{x}.band99.lower: expected a list of numbers"),
        "shorter time grid": (edited(data, drop_last_time), "the baseline's time grid (50 times, 0 to 4.9 s) differs"),
        "shifted time grid": (edited(data, shift_time), "the baseline's time grid (51 times, 1 to 6 s) differs"),
        "other outputs": (edited(data, lambda d: d.update(outputs={"y": d["outputs"]["x"]})),
                          "the baseline is for outputs y; the results have x"),
        "other parameters": (edited(data, add_parameter),
                             "the baseline has statistics sobol_first[b] that the results lack"),
    }


def test_check_refuses_bad_input_with_exit_2_and_one_line(pg, baseline, tmp_path):
    cases = bad_baselines(json.loads(baseline.read_text()))
    for name, (text, message) in cases.items():
        path = tmp_path / f"{name.replace(' ', '_')}.json"
        path.write_text(text)
        result = cli_in_process("check", pg, "--baseline", path)
        assert result.returncode == 2, (name, result.stdout, result.stderr)
        assert message in result.stderr, (name, result.stderr)
        assert "Traceback" not in result.stderr and len(result.stderr.strip().splitlines()) == 1, (name, result.stderr)
    for args, message in (((pg, "--baseline", tmp_path / "missing.json"), "cannot read the baseline"),
                          ((tmp_path / "missing.h5", "--baseline", baseline), "no such results file"),
                          ((baseline, "--baseline", baseline), "baseline.json is not a results file (a results file is HDF5")):
        result = cli_in_process("check", *args)
        assert result.returncode == 2 and message in result.stderr and "Traceback" not in result.stderr, result.stderr


def test_check_against_another_campaigns_baseline_exits_2(decay_results, tmp_path):
    baseline = write_baseline(analyse(decay_results), "", tmp_path / "baseline.json")
    data = json.loads(baseline.read_text())
    data["campaign_hash"] = "0" * 64
    baseline.write_text(json.dumps(data))
    checked = cli_in_process("check", decay_results, "--baseline", baseline)
    assert checked.returncode == 2 and "comes from another campaign" in checked.stderr
