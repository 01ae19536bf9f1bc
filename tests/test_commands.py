"""The small commands say what they do: plan's method line, design on standard output, report's times
inside the flight, one KIND[:ORDER] for every --method, the campaign table's resolved flight."""
import csv
import io

import numpy as np
import pytest
import yaml
from conftest import DECAY_TWO_INPUTS, NORMAL_2D, cli, cli_in_process, closed_form_campaign, run_python_campaign

import uqflight
from uqflight.calibration.command import _method
from uqflight.campaign import parse_campaign
from uqflight.cli.commands import _check_times
from uqflight.simulators.spec import SimulatorSpec

GRID = closed_form_campaign("sq", "sum_of_squares", NORMAL_2D, "{kind: tensor_grid, points: 3}",
                "method: {kind: pseudo_galerkin, order: 2}\n")  # 9 runs, times 0, 0.25, ..., 1 s
SAMPLED = closed_form_campaign("mc", "sum_of_squares", NORMAL_2D, "{kind: monte_carlo, samples: 8}", "method: {kind: monte_carlo}\n")


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    return run_python_campaign(tmp_path_factory.mktemp("commands"), GRID)


def test_report_refuses_a_time_outside_the_flight(results, tmp_path):
    refused = cli_in_process("report", results, "--times", "0.5,99", "--out", tmp_path / "r")
    assert refused.returncode == 2
    assert refused.stderr == (f"error: --times 0.5,99: 99 s outside the flight of {results}, which records 0 to 1 s; "
                              "choose times in that range or 'end'\n")
    assert not (tmp_path / "r").exists()
    # within half a recording step of the last time (0.25 s apart) is the last time, as before
    _check_times("1.1,end", [1.1, float("inf")], [results])


def test_plan_prints_an_order_only_for_a_method_that_has_one(tmp_path):
    for text, line in ((GRID, "method: pseudo_galerkin (order 2)\n"), (SAMPLED, "method: monte_carlo\n")):
        (tmp_path / "c.yaml").write_text(text)
        planned = cli_in_process("plan", tmp_path / "c.yaml")
        assert planned.returncode == 0, planned.stderr
        assert line in planned.stdout


def test_design_prints_csv_on_standard_output_without_csv_or_with_dash(results, tmp_path):
    yaml_path = results.with_suffix(".yaml")
    written = cli_in_process("design", yaml_path, "--csv", tmp_path / "d.csv")
    assert written.returncode == 0
    from_file = list(csv.reader(open(tmp_path / "d.csv", newline="")))
    assert len(from_file) == 10 and from_file[0] == ["run", "xi_x1", "xi_x2", "x1", "x2", "weight"]
    for args in ((), ("--csv", "-")):
        printed = cli_in_process("design", yaml_path, *args, cwd=tmp_path)
        assert printed.returncode == 0, printed.stderr
        assert list(csv.reader(io.StringIO(printed.stdout))) == from_file  # the CSV alone on stdout
        assert "wrote the design: 9 points" in printed.stderr
    assert not (tmp_path / "-").exists()


def test_calibrate_takes_kind_colon_order_as_report_does():
    assert _method("least_squares:2", None) == ("least_squares", 2)
    assert _method("least_squares", 3) == ("least_squares", 3)
    assert _method("least_squares:3", 3) == ("least_squares", 3)


@pytest.mark.parametrize("args, message", [
    (("--method", "least_squares:2", "--order", "3"), "error: --method least_squares:2 and --order 3 give two orders"),
    (("--method", "lsq:2"), "error: --method: expected KIND[:ORDER] with KIND one of"),
    (("--method", "least_squares:x"), "error: --method: expected an integer ORDER >= 0 after least_squares:"),
    (("--method", "least_squares", "--order", "-1"),
     "error: --method: expected an integer ORDER >= 0 after least_squares:, got --order -1"),
])
def test_calibrate_refuses_a_bad_method_before_any_work(results, tmp_path, args, message):
    data = tmp_path / "flight.csv"
    data.write_text("time_s,y\n0,15000\n1,15002\n")
    refused = cli_in_process("calibrate", results, "--data", data, "--out", tmp_path / "cal", *args)
    assert refused.returncode == 2 and refused.stderr.startswith(message), refused.stderr
    assert not (tmp_path / "cal").exists()


def flight_facts(simulator: dict) -> dict:
    """What the report's campaign table says a simulator flies (campaign.record.CampaignRecord.flight)."""
    spec = SimulatorSpec.from_checked(simulator)
    return spec.entry.flight_summary(spec)


def test_the_campaign_table_shows_the_flight_and_excitation_flown():
    paper = yaml.safe_load(open("campaigns/paper-pg2-l2.yaml"))["simulator"]
    assert flight_facts(paper) == {"flight": "level, 15000 ft, 200 KTAS, trim newton",
                                   "excitation": "elevator pulse 1 deg at 1 s for 1 s"}
    given = {"kind": "jsbsim", "aircraft": "c172p", "flight": {"airspeed_ktas": 90},
             "excitation": {"kind": "step", "amplitude_deg": -2}, "trim": "jsbsim"}
    assert flight_facts(given) == {"flight": "level, 4000 ft, 90 KTAS, trim jsbsim",
                                   "excitation": "elevator step -2 deg at 1 s"}
    script = yaml.safe_load(open("campaigns/c172p-landing.yaml"))["simulator"]
    assert flight_facts(script) == {"flight": "script scripts/c172p-landing.xml", "excitation": "the script's events"}
    cut = {"kind": "jsbsim", "scenario": {"kind": "script", "script": "c172_cruise_8K", "end_s": 2}}
    assert flight_facts(cut)["flight"] == "script c172_cruise_8K, cut at 2 s"
    assert flight_facts({"kind": "python", "function": "m.py:f"}) == {}


def test_version_and_short_help():
    result = cli("--version")
    assert result.returncode == 0 and result.stdout.strip() == f"uqflight {uqflight.__version__}"
    short, long = cli_in_process("-h"), cli_in_process("--help")
    assert short.returncode == 0 and short.stdout == long.stdout and "-h, --help" in short.stdout
    for command in ("report", "design", "simulate", "calibrate", "aircraft"):
        assert cli_in_process(command, "-h").returncode == 0
    assert "surrogate" in short.stdout and "design" in short.stdout


def test_design_csv(tmp_path):
    campaign = tmp_path / "decay.yaml"
    campaign.write_text(DECAY_TWO_INPUTS)
    out = tmp_path / "design.csv"
    result = cli_in_process("design", campaign, "--csv", out)
    assert result.returncode == 0, result.stderr
    rows = list(csv.DictReader(open(out)))
    design = parse_campaign(DECAY_TWO_INPUTS, str(campaign)).design()
    assert result.stdout.strip() == (f"wrote {out}: {len(design.xi)} points of a sparse_grid design in 2 "
                                     "parameters (a, b)")
    assert list(rows[0]) == ["run", "xi_a", "xi_b", "a", "b", "weight"] and len(rows) == len(design.xi)
    xi = np.array([[float(r["xi_a"]), float(r["xi_b"])] for r in rows])
    np.testing.assert_array_equal(xi, design.xi)
    np.testing.assert_array_equal([float(r["weight"]) for r in rows], design.weights)
    kappa = np.array([[float(r["a"]), float(r["b"])] for r in rows])
    np.testing.assert_allclose(kappa[:, 0], 1.0 + xi[:, 0] / 6, rtol=1e-14)  # normal: ±3σ on [0.5, 1.5]
    np.testing.assert_allclose(kappa[:, 1], 1.5 + 0.5 * xi[:, 1], rtol=1e-14)  # uniform on [1, 2]
    missing = cli_in_process("design", tmp_path / "missing.yaml", "--csv", out)
    assert missing.returncode == 2 and "Traceback" not in missing.stderr


@pytest.mark.parametrize("args", [("--method", "least_squares:-1"), ("--method", "least_squares", "--order", "-1")])
def test_report_refuses_a_bad_order_one_way_whichever_way_it_is_given(results, tmp_path, args):
    refused = cli_in_process("report", results, *args, "--out", tmp_path / "r")
    assert refused.returncode == 2 and "expected an integer ORDER >= 0 after least_squares:" in refused.stderr
    assert "Traceback" not in refused.stderr and not (tmp_path / "r").exists()


def test_a_sparse_order_is_refused_below_its_max_order_bound():
    from uqflight.methods import MethodSpec
    from uqflight.methods.parsing import parse_methods

    with pytest.raises(ValueError, match="expected an integer ORDER >= 1 after sparse:, got 'sparse:0'"):
        parse_methods(["sparse:0"])
    assert parse_methods(["sparse", "least_squares:1"], 3) == [MethodSpec("sparse", 3), MethodSpec("least_squares", 1)]
