"""A results file records its campaign once, in the root attribute `record` (versioned JSON: the campaign as
written, the parameters' laws and the method as its run resolved them, the design's kind and facts, the
versions), beside text attributes of provenance (campaign_hash, created, ...): every reading command refuses a
malformed one with exit 2 and one line naming the file, the attribute and the field, never a traceback. A
real file of `uqflight run`, then edited with h5py."""
import json
import shutil

import h5py
import numpy as np
import pytest
from conftest import DATA, DECAY_TWO_INPUTS, cli_in_process

BASELINE = DATA.parent / "baselines" / "ci-small.json"  # any sound baseline: the results file is refused first
DEPENDENT = {"kind": "gaussian_copula", "parameters": ["a", "b"], "correlation": [[1, 2], [2, 1]]}


def at(path: str, value):
    """An edit of the record (a dict read from its JSON) that sets the field at the dotted `path`."""
    def edit(record):
        *parents, last = [int(key) if key.isdigit() else key for key in path.split(".")]
        inside = record
        for key in parents:
            inside = inside[key]
        inside[last] = value
    return edit


MALFORMED = {  # name: (attribute, its value or an edit of the record, what the message says after "FILE: attribute ")
    "record a string": ("record", '"x"', "record: expected a mapping with the keys version, campaign, parameters"),
    "record an integer": ("record", np.int64(5), "record: expected JSON text, got np.int64(5)"),
    "record nested 100,000 deep": ("record", "[" * 100_000 + "]" * 100_000, "record: is not JSON (maximum recursion"),
    "record without its method": ("record", lambda r: r.pop("method"), "record: method: is required"),
    "record of version 2": ("record", at("version", 2), "record: version: this uqflight reads version 1, the file "
                                                        "holds version 2: fly the campaign again (`uqflight run"),
    "method a string": ("record", at("method", "pseudo_galerkin"), "record: method: expected a mapping with the keys kind"),
    "method order NaN": ("record", at("method.order", float("nan")), "record: method.order: expected an integer >= 0, "
                                                                     "got nan"),
    "method order 1e308": ("record", at("method.order", 1e308), "method.order: expected an integer >= 0, got 1e+308"),
    "method order -3": ("record", at("method.order", -3), "record: method.order: expected an integer >= 0, got -3"),
    "method order true": ("record", at("method.order", True), "method.order: expected an integer >= 0, got True"),
    "band_samples 1e12": ("record", at("campaign.analysis.band_samples", 1e12),
                          "record: campaign.analysis.band_samples: expected an integer >= 100, got 1000000000000.0"),
    "band_samples a word": ("record", at("campaign.analysis.band_samples", "many"),
                            "campaign.analysis.band_samples: expected an integer >= 100, got 'many'"),
    "band_samples 10^12": ("record", at("campaign.analysis", {"band_samples": 10**12, "bootstrap": 0}),
                           "campaign.analysis.band_samples: expected at most 1000000 draws"),
    "bootstrap -1": ("record", at("campaign.analysis.bootstrap", -1),
                     "campaign.analysis.bootstrap: expected an integer >= 0, got -1"),
    "bootstrap 10^9": ("record", at("campaign.analysis.bootstrap", 10**9),
                       "campaign.analysis.bootstrap: expected at most 10000 resamplings"),
    "dependence without kind": ("record", at("campaign.dependence", {"parameters": ["a", "b"]}),
                                "campaign.dependence.kind: is required"),
    "dependence a correlation of 2": ("record", at("campaign.dependence", DEPENDENT),
                                      "campaign.dependence.correlation[0][1]: expected a correlation in [-1, 1], got 2"),
    "a parameter's law unknown": ("record", at("parameters", [{"name": "a"}]),
                                  "record: parameters: expected one entry (name, property, distribution, nominal, "
                                  "lower, upper) per parameter of the campaign (a, b)"),
    "a parameter's bound NaN": ("record", at("parameters.0.lower", float("nan")),
                                "record: parameters.a: holds a value that is not a finite number"),
    "the campaign's parameters not the runs'": ("record", lambda r: r["campaign"]["parameters"].pop("b"),
                                                "record: parameters: expected one entry"),
    "design kind unknown": ("record", at("design.kind", "spiral"), "record: design.kind: expected one of monte_carlo"),
    "design info 5": ("record", at("design.info", 5), "record: design.info: expected a mapping of the design's facts, "
                                                       "got 5"),
    "replicates 10^12": ("record", at("design.info", {"replicates": 10**12}),
                         "record: design.info.replicates: expected an integer >= 1 dividing the 29 runs, "
                         "got 1000000000000"),
    "replicates a word": ("record", at("design.info", {"replicates": "x"}), "design.info.replicates: expected an "
                                                                           "integer >= 1 dividing"),
    "scramble a number": ("record", at("design.info", {"scramble": 2}), "design.info.scramble: expected true or "
                                                                        "false, got 2"),
    "versions 5": ("record", at("versions", 5), "record: versions: expected a mapping of package versions, got 5"),
    "campaign seed a word": ("record", at("campaign.seed", "abc"), "record: campaign.seed: expected an integer >= 0, "
                                                                   "got 'abc'"),
    "campaign name a list": ("record", at("campaign.name", [1]), "record: campaign.name: expected a non-empty string, "
                                                                 "got a list"),
    "campaign a list": ("record", at("campaign", [1]), "record: campaign: expected a mapping with the keys name"),
    "campaign_hash an array": ("campaign_hash", np.array([1, 2]), "campaign_hash: expected text, got array([1, 2])"),
    "created an array": ("created", np.array([1.0]), "created: expected text, got array([1.])"),
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
    """A copy of the sound file in `folder` with `attribute` set to `value` (None: deleted; a function: the
    record edited by it)."""
    path = folder / "r.h5"
    shutil.copy(sound, path)
    with h5py.File(path, "a") as f:
        if value is None:
            del f.attrs[attribute]
        elif callable(value):
            record = json.loads(f.attrs[attribute])
            value(record)
            f.attrs[attribute] = json.dumps(record)
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


@pytest.mark.parametrize("name", ["method a string", "design kind unknown"])
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
    (tmp_path / "edited").mkdir()
    path = malformed(path, tmp_path / "edited", "record", at("design.info", {"n_base": json.loads(n_base)}))
    for command in (["report", path, "--out", tmp_path / "report"], ["info", path]):
        refused(cli_in_process(*command), path, "record",
                "design.info.n_base: expected the base rows n of the 64 runs, n (2 parameters + 2)")


@pytest.mark.parametrize("text", [
    DECAY_TWO_INPUTS.replace("simulator:", "simulator: 5\nwas:"), "{{{", "[1, 2]",
    DECAY_TWO_INPUTS.replace('exp_decay"}', 'exp_decay", excitation: {start_s: abc}}')])
@pytest.mark.slow
def test_a_stored_campaign_text_that_is_no_campaign_is_shown_not_trusted(sound, tmp_path, text):
    # the report shows the stored text and reads the excitation's start from it (where the coefficient decay
    # is drawn from): a text whose simulator or start is no mapping or number was a traceback after the analysis
    path = malformed(sound, tmp_path, "campaign", text)
    done = cli_in_process("report", path, "--out", tmp_path / "report")
    assert done.returncode == 0, done.stdout + done.stderr
    assert (tmp_path / "report" / "report.html").is_file()


def test_a_file_without_its_record_is_refused_by_every_reader_naming_the_fix(sound, tmp_path):
    """D11: a file of an older layout (no record attribute) is refused in one line (exit 2) that names the
    attribute and `run --restart`, by every command that reads results."""
    path = malformed(sound, tmp_path, "record", None)
    said = (f"error: {path}: the results file has no record attribute (the campaign it was made with): a file of "
            "an older layout, or not written by uqflight: fly the campaign again (`uqflight run CAMPAIGN --out FILE "
            "--restart` starts this file over)")
    for command in (["report", path, "--out", tmp_path / "report"], ["check", path, "--baseline", BASELINE],
                    ["surrogate", "export", path, "--out", tmp_path / "s.json"], ["info", path]):
        done = cli_in_process(*command)
        assert done.returncode == 2 and done.stderr.strip() == said, (command, done.stderr)
    assert not (tmp_path / "report").exists() and not (tmp_path / "s.json").exists()
