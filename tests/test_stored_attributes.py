"""A results file's campaign facts are root attributes of JSON text (method, germs, analysis, seeds,
dependence, design_info, versions) or text (design_kind, campaign_name, campaign_hash, ...): every reading
command refuses a malformed one with exit 2 and one line naming the file, the attribute and the field, never
a traceback. A real file of `uqflight run`, then edited with h5py."""
import shutil

import h5py
import numpy as np
import pytest
from conftest import DATA, DECAY_TWO_INPUTS, cli_in_process

BASELINE = DATA.parent / "baselines" / "ci-small.json"  # any sound baseline: the results file is refused first
PG = '{"kind": "pseudo_galerkin", "order": %s}'
COPULA = '{"kind": "gaussian_copula", "parameters": ["a", "b"], "correlation": %s}'
MALFORMED = {  # name: (attribute, value, what the message says after "FILE: attribute ATTRIBUTE: ")
    "method a string": ("method", '"pseudo_galerkin"', "expected a mapping with the keys kind"),
    "method an integer": ("method", np.int64(5), "expected JSON text, got np.int64(5)"),
    "method nested 100,000 deep": ("method", "[" * 100_000 + "]" * 100_000, "is not JSON (maximum recursion depth"),
    "method order NaN": ("method", PG % "NaN", "order: expected an integer >= 0, got nan"),
    "method order 1e308": ("method", PG % "1e308", "order: expected an integer >= 0, got 1e+308"),
    "method order -3": ("method", PG % "-3", "order: expected an integer >= 0, got -3"),
    "method order true": ("method", PG % "true", "order: expected an integer >= 0, got True"),
    "band_samples 1e12": ("analysis", '{"band_samples": 1e12, "bootstrap": -1}',
                          "band_samples: expected an integer >= 100, got 1000000000000.0"),
    "band_samples a word": ("analysis", '{"band_samples": "many"}',
                            "band_samples: expected an integer >= 100, got 'many'"),
    "band_samples NaN": ("analysis", '{"band_samples": NaN}', "band_samples: expected an integer >= 100, got nan"),
    "band_samples 10^12": ("analysis", '{"band_samples": 1000000000000, "bootstrap": 0}',
                           "band_samples: expected at most 1000000 draws"),
    "bootstrap -1": ("analysis", '{"bootstrap": -1}', "bootstrap: expected an integer >= 0, got -1"),
    "bootstrap 10^9": ("analysis", '{"bootstrap": 1000000000}', "bootstrap: expected at most 10000 resamplings"),
    "seeds a number": ("seeds", "5", "expected a list of distinct parameter names (a, b), got 5"),
    "seeds an unknown name": ("seeds", '["c"]', "expected a list of distinct parameter names (a, b), got ['c']"),
    "dependence without kind": ("dependence", '{"parameters": 5}', "kind: is required"),
    "dependence a list": ("dependence", "[1]", "expected a mapping with the keys kind, parameters, correlation"),
    "dependence a correlation of 2": ("dependence", COPULA % "[[1, 2], [2, 1]]",
                                      "correlation[0][1]: expected a correlation in [-1, 1], got 2.0"),
    "germs too few": ("germs", '["normal"]', "expected a list of 2 germs (normal / uniform), one per parameter"),
    "germs unknown": ("germs", '["normal", "cauchy"]', "got ['normal', 'cauchy']"),
    "design_info 5": ("design_info", "5", "expected a mapping of the design's facts, got 5"),
    "design_info not JSON": ("design_info", "{level", "is not JSON (Expecting property name"),
    "design_info an array": ("design_info", np.array([1, 2]), "expected JSON text, got array([1, 2])"),
    "replicates 10^12": ("design_info", '{"replicates": 1000000000000}',
                         "replicates: expected an integer >= 1 dividing the 29 runs, got 1000000000000"),
    "replicates a word": ("design_info", '{"replicates": "x"}', "replicates: expected an integer >= 1 dividing"),
    "scramble a number": ("design_info", '{"scramble": 2}', "scramble: expected true or false, got 2"),
    "design_kind an array": ("design_kind", np.array([1, 2]), "expected one of monte_carlo, sobol, halton"),
    "design_kind unknown": ("design_kind", "spiral", "expected one of monte_carlo, sobol, halton"),
    "design_kind missing": ("design_kind", None, "expected one of monte_carlo, sobol, halton"),
    "versions 5": ("versions", "5", "expected a mapping of package versions, got 5"),
    "versions missing": ("versions", None, "is missing: the file is damaged or was not written by uqflight: fly its "
                                           "campaign again (`uqflight run CAMPAIGN --out FILE --restart`)"),
    "analysis missing": ("analysis", None, "is missing: the file is damaged or was not written by uqflight"),
    "campaign_name an array": ("campaign_name", np.array([1, 2]), "expected text, got array([1, 2])"),
    "campaign_name an integer": ("campaign_name", np.int64(5), "expected text, got np.int64(5)"),
    "campaign_hash an array": ("campaign_hash", np.array([1, 2]), "expected text, got array([1, 2])"),
    "created an array": ("created", np.array([1.0]), "expected text, got array([1.])"),
    "campaign seed a word": ("campaign", DECAY_TWO_INPUTS.replace("seed: 3", "seed: abc"),
                             "seed: expected an integer >= 0, got 'abc'"),  # it draws the report's runs
    "campaign seed a list": ("campaign", DECAY_TWO_INPUTS.replace("seed: 3", "seed: [1]"),
                             "seed: expected an integer >= 0, got a list"),
    "campaign seed a word, a key twice": ("campaign", DECAY_TWO_INPUTS.replace("seed: 3", "seed: abc") + "name: x\n",
                                          "seed: expected an integer >= 0, got 'abc'"),  # read as the report reads
}


@pytest.fixture(scope="module")
def sound(tmp_path_factory):
    """The DECAY_TWO_INPUTS campaign's results file, written by `uqflight run`."""
    root = tmp_path_factory.mktemp("attrs")
    (root / "c.yaml").write_text(DECAY_TWO_INPUTS)
    done = cli_in_process("run", root / "c.yaml", "--out", root / "r.h5")
    assert done.returncode == 0, done.stderr
    return root / "r.h5"


def malformed(sound, folder, attribute, value):
    """A copy of the sound file in `folder` with `attribute` set to `value` (None: deleted)."""
    path = folder / "r.h5"
    shutil.copy(sound, path)
    with h5py.File(path, "a") as f:
        if value is None:
            del f.attrs[attribute]
        else:
            f.attrs[attribute] = value
    return path


def refused(result, path, attribute: str, message: str) -> None:
    assert result.returncode == 2, (result.stdout, result.stderr)
    assert "Traceback" not in result.stdout + result.stderr
    line, = result.stderr.strip().splitlines()
    assert line.startswith(f"error: {path}: attribute {attribute}: ") and message in line, line


@pytest.mark.parametrize("name", MALFORMED)
def test_every_reader_refuses_a_malformed_attribute_naming_file_attribute_and_field(sound, tmp_path, name):
    attribute, value, message = MALFORMED[name]
    path = malformed(sound, tmp_path, attribute, value)
    for command in (["report", path, "--out", tmp_path / "report"], ["check", path, "--baseline", BASELINE],
                    ["surrogate", "export", path, "--out", tmp_path / "s.json"]):
        refused(cli_in_process(*command), path, attribute, message)
    assert not (tmp_path / "report").exists() and not (tmp_path / "s.json").exists()


@pytest.mark.parametrize("name", ["method a string", "germs too few"])
def test_calibrate_refuses_a_malformed_attribute(sound, tmp_path, name):
    attribute, value, message = MALFORMED[name]
    path = malformed(sound, tmp_path, attribute, value)
    data = tmp_path / "data.csv"
    data.write_text("time_s,x\n0,1.0\n1,0.37\n2,0.14\n")
    refused(cli_in_process("calibrate", path, "--data", data, "--out", tmp_path / "cal", "--steps", 100),
            path, attribute, message)


@pytest.mark.parametrize("n_base", ["3", '"16"', "null"])
def test_a_pick_freeze_file_needs_its_base_rows(tmp_path, n_base):
    """Its failure probability counts the rows A and B, 2 n_base of the n_base (d + 2) runs."""
    campaign = DECAY_TWO_INPUTS.replace("{kind: sparse_grid, level: 3}", "{kind: pick_freeze, samples: 16}")
    (tmp_path / "c.yaml").write_text(campaign.replace("pseudo_galerkin, order: 2", "monte_carlo"))
    path = tmp_path / "r.h5"
    assert cli_in_process("run", tmp_path / "c.yaml", "--out", path).returncode == 0
    with h5py.File(path, "a") as f:
        f.attrs["design_info"] = '{"n_base": %s}' % n_base
    refused(cli_in_process("report", path, "--out", tmp_path / "report"), path, "design_info",
            "n_base: expected the base rows n of the 64 runs, n (2 parameters + 2)")


@pytest.mark.parametrize("text", [
    DECAY_TWO_INPUTS.replace("simulator:", "simulator: 5\nwas:"), "{{{", "[1, 2]",
    DECAY_TWO_INPUTS.replace('exp_decay"}', 'exp_decay", excitation: {start_s: abc}}')])
def test_a_stored_campaign_text_that_is_no_campaign_is_shown_not_trusted(sound, tmp_path, text):
    # the report shows the stored text and reads the excitation's start from it (where the coefficient decay
    # is drawn from): a text whose simulator or start is no mapping or number was a traceback after the analysis
    path = malformed(sound, tmp_path, "campaign", text)
    done = cli_in_process("report", path, "--out", tmp_path / "report")
    assert done.returncode == 0, done.stdout + done.stderr
    assert (tmp_path / "report" / "report.html").is_file()


def test_the_export_names_the_file_and_the_field_of_a_stored_campaign_it_cannot_read(sound, tmp_path):
    path = malformed(sound, tmp_path, "campaign", DECAY_TWO_INPUTS.replace("name: decay-people", "name: [1]"))
    done = cli_in_process("surrogate", "export", path, "--out", tmp_path / "s.json")
    assert done.returncode == 2 and not (tmp_path / "s.json").exists()
    assert done.stderr == (f"error: {path}: cannot read the parameters' distributions from the campaign stored in "
                           "the file: name: expected a non-empty string, got a list\n")


SCRIPT_CAMPAIGN = """name: old-script
seed: 3
simulator:
  kind: jsbsim
  scenario: {kind: script, script: 737_cruise_steady_turn}
  outputs: [h_ft]
parameters:
  a: {property: fcs/elevator-cmd-norm, distribution: normal, interval_pct: 10}
  b: {property: fcs/aileron-cmd-norm, distribution: uniform, interval_pct: 10}
design: {kind: sparse_grid, level: 3}
method: {kind: pseudo_galerkin, order: 2}
analysis: {band_samples: 500, bootstrap: 0}
"""


def test_a_stored_script_campaign_without_its_parameters_names_field_and_fix(decay_results, tmp_path):
    """D11: a file without the parameters attribute whose stored campaign is a script's, which names no
    simulator.aircraft. The campaign reader refuses it naming the attribute and `run --restart`: surrogate export,
    which needs the parameters, in one line (exit 2); the report, whose numbers do not depend on them (it shows
    the stored text, test above), flags it in its notes."""
    import hashlib

    from conftest import read_summary

    out = tmp_path / "old.h5"
    shutil.copy(decay_results, out)
    with h5py.File(out, "a") as f:
        f.attrs["campaign"] = SCRIPT_CAMPAIGN
        f.attrs["campaign_hash"] = hashlib.sha256(SCRIPT_CAMPAIGN.encode()).hexdigest()
        del f.attrs["parameters"]
    said = ("parameters: the results file records no parameters attribute (the parameters' laws with the nominal "
            "values its run read): fly the campaign again (`uqflight run CAMPAIGN --out FILE --restart` starts this "
            "file over)")
    done = cli_in_process("surrogate", "export", out, "--out", tmp_path / "s.json")
    assert done.returncode == 2 and not (tmp_path / "s.json").exists(), done.stderr
    errors = [line for line in done.stderr.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and "Traceback" not in done.stderr and errors[0].startswith(f"error: {out}: "), done.stderr
    assert errors[0].endswith(said), errors[0]
    done = cli_in_process("report", out, "--out", tmp_path / "rep")
    assert done.returncode == 0, done.stderr
    notes = read_summary(tmp_path / "rep" / "summary.json")["notes"]
    assert any(note.endswith(said) and f"stored in {out} cannot be read" in note for note in notes), notes
