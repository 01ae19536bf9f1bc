"""Campaign validation: every bad file gets one clear message (file, field, what was expected),
`uqflight plan` and `uqflight run` exit with code 2 and no traceback, and nothing is written; YAML that breaks
Python's parser limits is one message too."""
from pathlib import Path

import pytest

from conftest import ROOT, cli, cli_in_process
from uqflight.campaign import CampaignError, load_campaign, parse_campaign
from uqflight.simulators.aircraft_properties import AircraftProperties

DATA = Path(__file__).parent / "data" / "campaigns"

# file -> (field the message names, "" for the file as a whole; words that say what was expected)
BAD = {
    "bad_yaml_syntax.yaml": ("", "YAML syntax error at line 5"),
    "bad_yaml_tab.yaml": ("", "YAML syntax error at line 3"),
    "bad_duplicate_key.yaml": ("", "line 5, column 3: found the key 'CL0' twice"),
    "bad_not_utf8.yaml": ("", "expected UTF-8 text"),
    "bad_empty.yaml": ("", "expected a mapping with the keys name"),
    "bad_not_a_mapping.yaml": ("", "expected a mapping with the keys name"),
    "bad_top_key_typo.yaml": ("desing", "did you mean design?"),
    "bad_missing_name.yaml": ("name", "is required"),
    "bad_missing_simulator.yaml": ("simulator", "is required"),
    "bad_missing_parameters.yaml": ("parameters", "is required"),
    "bad_missing_design.yaml": ("design", "is required"),
    "bad_seed.yaml": ("seed", "expected an integer >= 0, got -1"),
    "bad_simulator_kind.yaml": ("simulator.kind", "expected one of jsbsim, python, got 'xplane'"),
    "bad_missing_simulator_kind.yaml": ("simulator.kind", "is required; expected one of jsbsim, python"),
    "bad_unknown_aircraft.yaml": ("simulator.aircraft", "no aircraft 'concorde'"),
    "bad_aircraft_number.yaml": ("simulator.aircraft", 'got 737 (YAML reads 737 as a number: quote it, "737")'),
    "bad_unknown_output.yaml": ("simulator.outputs[1]", "or a JSBSim property of aircraft 'bacm', got 'aero/not-a-property'"),
    "bad_excitation_kind.yaml": ("simulator.excitation.kind", "expected one of pulse, step, doublet, none"),
    "bad_duration.yaml": ("simulator.duration_s", "expected a number > 0, got -5"),
    "bad_output_rate.yaml": ("simulator.output_rate_hz", "expected a divisor of the 120 Hz integration rate"),
    "bad_python_import.yaml": ("simulator.function", "cannot import 'uqflight.simulators.no_such_module'"),
    "bad_python_attribute.yaml": ("simulator.function", "has no callable 'ishigamy'"),
    "bad_python_file.yaml": ("simulator.function", "expected an existing Python file"),
    "bad_python_module_error.yaml": ("simulator.function", "cannot import 'broken_model.py': ImportError"),
    "bad_unknown_property.yaml": ("parameters.CL0.property", "got 'aero/uq/CL00'; did you mean aero/uq/CL0"),
    "bad_read_only_property.yaml": ("parameters.alpha.property", "'aero/alpha-deg' is read-only"),
    "bad_missing_property.yaml": ("parameters.CL0.property", "is required: the JSBSim property"),
    "bad_duplicate_property.yaml": ("parameters.lift0.property", "already set by parameters.CL0"),
    "bad_parameter_key_typo.yaml": ("parameters.CL0.interval_pc", "did you mean interval_pct?"),
    "bad_negative_interval.yaml": ("parameters.CL0.interval_pct", "expected a number > 0, got -3"),
    "bad_string_for_number.yaml": ("parameters.CL0.interval_pct", "expected a finite number, got 'ten'"),
    "bad_lower_ge_upper.yaml": ("parameters.vt.lower", "expected lower < upper, got 210 >= 190"),
    "bad_interval_and_bounds.yaml": ("parameters.CL0", "either interval_pct or lower and upper, not both"),
    "bad_only_lower.yaml": ("parameters.CL0", "or both lower and upper"),
    "bad_unknown_distribution.yaml": ("parameters.CL0.distribution", "expected one of normal, uniform"),
    "bad_lognormal_straddles_zero.yaml": ("parameters.k2", "lognormal interval must lie entirely above or"),
    "bad_nominal_zero_pct.yaml": ("parameters.gamma", "percentage of the nominal, which is 0"),
    "bad_design_kind.yaml": ("design.kind", "expected one of monte_carlo"),
    "bad_rule.yaml": ("design.rule", "expected one of gauss_hermite"),
    "bad_negative_level.yaml": ("design.level", "expected an integer >= 0, got -1"),
    "bad_samples_zero.yaml": ("design.samples", "expected an integer >= 1, got 0"),
    "bad_samples_string.yaml": ("design.samples", "expected an integer >= 1, got '100'"),
    "bad_method_kind.yaml": ("method.kind", "expected one of integration, pseudo_galerkin"),
    "bad_method_for_design.yaml": ("method.kind", "monte_carlo needs a sampled design"),
    "bad_regression_order.yaml": ("method.order", "the largest order with full rank is 1"),
    "bad_workers_zero.yaml": ("execution.workers", "expected an integer >= 1, got 0"),
    "bad_executor.yaml": ("execution.executor", "expected one of local, dask, got 'slurm'"),
    "bad_tsvd_tol.yaml": ("storage.tsvd.tol", "expected a relative tolerance in (0, 1), got 1.5"),
    "bad_raw_false_without_tsvd.yaml": ("storage.raw", "false needs storage.tsvd"),
    "bad_band_samples.yaml": ("analysis.band_samples", "expected at most 1000000 draws (a million draws of an output"),
    "bad_take_typo.yaml": ("quantities.peak.take", "got 'maximum'; did you mean max?"),
    "bad_bootstrap.yaml": ("analysis.bootstrap", "expected at most 10000 resamplings (10^4 of a pick-freeze design"),
}
# A representative handful through the command line (each start costs about a second).
CLI_BAD = ["bad_yaml_syntax.yaml", "bad_top_key_typo.yaml", "bad_unknown_property.yaml",
           "bad_negative_interval.yaml", "bad_rule.yaml", "bad_python_import.yaml"]


def expected_start(path: Path, field: str) -> str:
    return f"{path}: {field}: " if field else f"{path}: "


def test_the_corpus_is_listed_whole():
    assert sorted(p.name for p in DATA.glob("bad_*.yaml")) == sorted(BAD)


@pytest.mark.parametrize("name", sorted(BAD))
def test_a_bad_file_gets_one_message_naming_file_field_and_expectation(name):
    field, expected = BAD[name]
    path = DATA / name
    with pytest.raises(CampaignError) as caught:
        load_campaign(path, read_aircraft=AircraftProperties)
    message = str(caught.value)
    assert message.startswith(expected_start(path, field)), message
    assert expected in message
    assert "\n" not in message
    assert (caught.value.source, caught.value.field) == (str(path), field)


def uqflight(*args, cwd):
    return cli_in_process(*args, cwd=cwd)


@pytest.mark.parametrize("name", CLI_BAD)
def test_plan_and_run_refuse_a_bad_file_with_exit_code_2_and_write_nothing(name, tmp_path):
    field, expected = BAD[name]
    path = DATA / name
    out = tmp_path / "x.h5"
    for args in (("plan", path), ("run", path, "--out", out)):
        result = uqflight(*args, cwd=tmp_path)
        assert result.returncode == 2, (args, result.stdout, result.stderr)
        assert result.stderr.startswith("error: " + expected_start(path, field)), result.stderr
        assert expected in result.stderr
        assert "Traceback" not in result.stdout + result.stderr
    assert list(tmp_path.iterdir()) == [], "no results file (--out or storage.path) may be created"


def test_a_refused_run_leaves_an_existing_file_untouched(tmp_path):
    existing = tmp_path / "existing.h5"
    existing.write_bytes(b"not results, and not to be touched")
    before = existing.stat().st_mtime_ns
    result = uqflight("run", DATA / "bad_unknown_aircraft.yaml", "--out", existing, "--force", cwd=tmp_path)
    assert result.returncode == 2 and "simulator.aircraft" in result.stderr
    assert existing.read_bytes() == b"not results, and not to be touched"
    assert existing.stat().st_mtime_ns == before
    assert [p.name for p in tmp_path.iterdir()] == ["existing.h5"]


def test_a_missing_file_is_named():
    with pytest.raises(CampaignError, match=r"no_such\.yaml: cannot read the file \(No such file"):
        load_campaign(DATA / "no_such.yaml")


# -- good files ---------------------------------------------------------------------------

def test_the_shipped_campaign_validates():
    campaign = load_campaign(ROOT / "campaigns" / "paper-pg2-l2.yaml", read_aircraft=AircraftProperties)
    assert [p.name for p in campaign.parameters] == ["CL0", "CLalpha", "CD0", "k1", "k2", "Cm0", "Cmq"]
    assert campaign.parameters[0].nominal == pytest.approx(0.2)  # from the aircraft
    assert len(campaign.design().xi) == 113


def test_initial_conditions_are_uncertain_parameters_with_the_flight_condition_as_nominal():
    campaign = load_campaign(DATA / "good_jsbsim_ic.yaml", read_aircraft=AircraftProperties)
    speed, altitude, lift = campaign.parameters
    assert (speed.property, speed.lower, speed.upper) == ("ic/vt-kts", 185.0, 195.0)
    assert speed.nominal == pytest.approx(190.0)  # the campaign's airspeed, not the aircraft's 0
    assert (altitude.lower, altitude.upper) == pytest.approx((11400.0, 12600.0))  # 5 % of 12000 ft
    assert lift.distribution == "lognormal"
    assert campaign.storage.tsvd.tol == 1e-6


def test_calibrated_airspeed_takes_its_nominal_from_the_flight_condition():
    text = """
name: vc
simulator: {kind: jsbsim, flight: {altitude_ft: 15000, airspeed_ktas: 200}}
parameters:
  Vc: {property: ic/vc-kts, distribution: normal, interval_pct: 2}
design: {kind: monte_carlo, samples: 4}
"""
    (vc,) = parse_campaign(text, "vc.yaml", AircraftProperties).parameters
    assert 150 < vc.nominal < 170  # 200 KTAS at 15000 ft is about 160 KCAS


def test_a_python_model_from_the_package_validates():
    campaign = load_campaign(DATA / "good_python_ishigami.yaml", read_aircraft=AircraftProperties)
    assert campaign.simulator["function"] == "uqflight.simulators.models:ishigami"
    assert [p.property for p in campaign.parameters] == ["x1", "x2", "x3"]
    assert campaign.method.as_mapping() == {"kind": "regression", "order": 6, "split": False}


@pytest.mark.slow
def test_a_python_file_is_found_relative_to_the_campaign_not_the_working_directory(tmp_path):
    result = cli("run", DATA / "good_python_file.yaml", "--out", tmp_path / "r.h5", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "r.h5").is_file()


def test_without_a_validation_view_interval_pct_needs_a_nominal():
    text = """
name: no-view
simulator: {kind: jsbsim}
parameters:
  CL0: {property: aero/uq/CL0, distribution: normal, interval_pct: 10}
design: {kind: monte_carlo, samples: 4}
"""
    with pytest.raises(CampaignError, match=r"^x\.yaml: parameters\.CL0\.nominal: is required with interval_pct"):
        parse_campaign(text, "x.yaml")
    campaign = parse_campaign(text.replace("interval_pct: 10", "interval_pct: 10, nominal: 0.2"), "x.yaml")
    assert (campaign.parameters[0].lower, campaign.parameters[0].upper) == pytest.approx((0.18, 0.22))


def test_exponents_without_a_dot_are_numbers():
    text = (DATA / "good_python_ishigami.yaml").read_text() + "storage: {raw: false, tsvd: {tol: 1e-8}}\n"
    assert parse_campaign(text, "x.yaml").storage.tsvd.tol == 1e-8


HOSTILE_YAML = {  # name: (the value of `seed:`, what the one line says)
    "nested 200,000 deep": ("[" * 200_000 + "]" * 200_000, "nested deeper than 64 levels"),
    "an integer of 4,400 digits": ("9" * 4400, "an integer of 4400 characters; no field takes more than 100"),
    "a month 13": ("2001-13-45", "cannot read this value (month must be in 1..12)"),
    "a float tag on a word": ("!!float abc", "cannot read this value (could not convert string to float"),
    "a set tag on a list": ("!!set [1]", "expected a mapping node, but found sequence"),
}


@pytest.mark.parametrize("name", HOSTILE_YAML)
def test_hostile_campaign_yaml_is_one_message_with_exit_2(tmp_path, name):
    value, message = HOSTILE_YAML[name]
    path = tmp_path / "hostile.yaml"
    path.write_text(f"name: hostile\nseed: {value}\n")
    result = cli_in_process("plan", path)
    assert result.returncode == 2, result.stderr[-2000:]
    assert result.stderr.startswith(f"error: {path}: YAML error at line 2") and message in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1 and "Traceback" not in result.stderr



LIST_AS_NAME = {  # name: (the campaign's last lines, the field, what the message says)
    "a method kind": ("method: {kind: [pseudo_galerkin]}\n", "method.kind", "expected one of integration"),
    "a correlated parameter": ("dependence: {kind: gaussian_copula, parameters: [[a], b], correlation: [[1, 0], "
                               "[0, 1]]}\n", "dependence.parameters[0]", "expected one of the campaign's parameters"),
}


@pytest.mark.parametrize("name", LIST_AS_NAME)
def test_a_list_where_a_name_is_expected_is_refused_naming_the_field(name):
    lines, field, message = LIST_AS_NAME[name]
    text = ("name: lists\nsimulator: {kind: python, function: \"uqflight.simulators.models:exp_decay\"}\n"
            "parameters:\n  a: {distribution: normal, lower: 0.5, upper: 1.5}\n"
            "  b: {distribution: normal, lower: 1.0, upper: 2.0}\ndesign: {kind: monte_carlo, samples: 10}\n" + lines)
    with pytest.raises(CampaignError) as caught:
        parse_campaign(text, "lists.yaml")
    assert caught.value.field == field and message in str(caught.value)


def test_the_sections_are_typed_frozen_and_their_examples_run():
    import dataclasses
    import doctest

    import uqflight.campaign.sections as sections

    assert doctest.testmod(sections).failed == 0
    campaign = parse_campaign((DATA / "good_python_ishigami.yaml").read_text(), "x.yaml")
    assert isinstance(campaign.execution, sections.Execution) and campaign.limits == sections.Limits()
    with pytest.raises(dataclasses.FrozenInstanceError):
        campaign.execution.workers = 4
