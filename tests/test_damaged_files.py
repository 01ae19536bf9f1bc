"""Damaged and foreign results files: every reader refuses them with one line naming the file and what
is wrong (exit 2), never a traceback, never a report. Real HDF5 files from a real campaign, then cut.
Damaged, lying or oversized surrogate files are refused naming the key."""
import json
import shutil

import h5py
import numpy as np
import pytest
from conftest import DATA, cli_in_process, hostile_campaign, run_python_campaign

from uqflight.campaign import parse_campaign
from uqflight.running.runner import run_campaign
from uqflight.report.loading import load_entries
from uqflight.analysis.statistics import BadInput, read_statistics
from uqflight.store import CorruptFile, ResultStore
from uqflight.analysis.surrogate import MAX_FILE_BYTES, load
from uqflight.text import Refusal

N, T = 12, 5000
CAMPAIGN = f"""
name: damaged
seed: 5
simulator: {{kind: python, function: "{DATA / 'hostile_model.py'}:long_histories"}}
parameters:
  x: {{distribution: uniform, lower: -2, upper: 2}}
design: {{kind: monte_carlo, samples: {N}}}
execution: {{workers: 1, chunk: 4}}
"""
BASELINE = DATA.parent / "baselines" / "ci-small.json"  # any sound baseline: the results file is refused first
TSVD = "storage: {raw: false, tsvd: {tol: 1.0e-10, batch: 4}}\n"


@pytest.fixture(scope="module")
def sound(tmp_path_factory):
    """A raw and a tSVD-only results file of 12 runs."""
    root = tmp_path_factory.mktemp("sound")
    files = {}
    for storage, extra in (("raw", ""), ("tsvd", TSVD)):
        files[storage] = root / f"{storage}.h5"
        run_campaign(parse_campaign(CAMPAIGN + extra, str(DATA / "damaged.yaml")), out=files[storage])
    return files


def replaced(path, data, **attrs):
    def damage(f):
        kept = dict(f[path].attrs)
        del f[path]
        f.create_dataset(path, data=data).attrs.update({**kept, **attrs})
    return damage


def assign(path, index, value):
    def damage(f):
        f[path][index] = value
    return damage


def declared(path, shape, dtype="f8"):
    """`path` replaced by a chunked dataset that declares `shape` and holds nothing (a few bytes on disk)."""
    def damage(f):
        del f[path]
        f.create_dataset(path, shape=shape, dtype=dtype, chunks=(1,) * (len(shape) - 1) + (1000,))
    return damage


DAMAGES = {  # name: (storage, damage, what the message says)
    "status of floats": ("raw", replaced("samples/status", np.zeros(N)), "/samples/status holds float64"),
    "status too short": ("raw", replaced("samples/status", np.zeros(N - 1, "i1")), r"expected \(11, any\)"),
    "reasons of integers": ("raw", replaced("samples/reason", np.zeros(N, int)), "/samples/reason holds int64"),
    "reasons too short": ("raw", replaced("samples/reason", np.array([b""] * (N - 2))),
                          r"/samples/reason has shape \(10,\), expected \(12,\)"),
    "weights too short": ("raw", replaced("samples/weight", np.ones(N - 1)), "/samples/weight has shape"),
    "a NaN weight": ("raw", assign("samples/weight", 3, np.nan), "/samples/weight holds 1 values that are not finite"),
    "a NaN in the design": ("raw", assign("samples/xi", (2, 0), np.nan), "/samples/xi holds 1 values"),
    "an infinite physical value": ("raw", assign("samples/kappa", (0, 0), np.inf), "/samples/kappa holds 1"),
    "parameter names missing": ("raw", lambda f: f["samples/kappa"].attrs.__delitem__("names"),
                                "attribute names lists 0 parameters, expected 1"),
    "no design": ("raw", lambda f: f.__delitem__("samples/xi"), "/samples/xi is missing"),
    "no times": ("raw", lambda f: f.__delitem__("time"), "/time is missing"),
    "times of another length": ("raw", replaced("time", np.linspace(0, 1, T - 1)),
                                r"/outputs/y has shape \(12, 5000\), expected \(12, 4999\)"),
    "times decreasing": ("raw", replaced("time", np.linspace(1, 0, T)), "strictly increasing"),
    "times in two columns": ("raw", replaced("time", np.zeros((T, 2))), r"/time has shape \(5000, 2\)"),
    "histories of strings": ("raw", replaced("outputs/y", np.full((N, 3), b"a")), "/outputs/y holds |S1"),
    "no outputs": ("raw", lambda f: f.__delitem__("outputs"), "no outputs: neither /outputs nor /tsvd"),
    "an empty outputs group": ("raw", lambda f: [f.__delitem__("outputs/y")], "/outputs must be a group of at least"),
    "no campaign": ("raw", lambda f: f.attrs.__delitem__("campaign"), "the root attribute campaign"),
    "factors of another rank": ("tsvd", lambda f: replaced("tsvd/y/s", np.ones(f["tsvd/y/s"].shape[0] + 1))(f),
                                "/tsvd/y/s has shape"),
    "factors for a run outside the design": ("tsvd", assign("tsvd/y/columns", 0, N + 5),
                                             r"/tsvd/y/columns must name distinct runs in \[0, 12\)"),
    "a run held twice": ("tsvd", lambda f: assign("tsvd/y/columns", 1, f["tsvd/y/columns"][0])(f),
                         "must name distinct runs"),
    "a status declaring 10^12 runs": ("raw", declared("samples/status", (10**12,), "i1"),
                                      "/samples/status declares 1000000000000 runs, more than any campaign"),
    "times declaring 10^11 values": ("raw", declared("time", (10**11,)), "/time declares 100000000000 times"),
    "a design declaring 10^9 parameters": ("raw", declared("samples/xi", (N, 10**9)), "declares 1000000000 parameters"),
    "factors declaring a rank of 10^6": ("tsvd", declared("tsvd/y/U", (T, 10**6)), "declares rank 1000000"),
    "a design linked from another file": ("raw", lambda f: (f.__delitem__("samples/xi"), f["samples"].__setitem__(
        "xi", h5py.ExternalLink("elsewhere.h5", "/xi"))), "/samples/xi is a ExternalLink, not data stored in this file"),
    "a status linked inside the file": ("raw", lambda f: (f.__delitem__("samples/status"), f["samples"].__setitem__(
        "status", h5py.SoftLink("/samples/weight"))), "/samples/status is a SoftLink"),
    "a resolution of another length": ("raw", lambda f: f.create_group("resolution").create_dataset("y", data=[1.0]),
                                       r"/resolution/y has shape \(1,\), expected \(5000,\)"),
    "a negative resolution": ("raw", lambda f: f.create_group("resolution").create_dataset("y", data=-np.ones(T)),
                              "/resolution/y must hold finite values ≥ 0"),
    "a tSVD tolerance of NaN": ("tsvd", lambda f: f["tsvd"].attrs.__setitem__("tol", np.nan), "tol must be a finite"),
}


@pytest.mark.parametrize("name", DAMAGES)
def test_a_damaged_file_is_refused_by_every_reader_naming_what_is_wrong(sound, tmp_path, name):
    storage, damage, message = DAMAGES[name]
    path = tmp_path / "damaged.h5"
    shutil.copy(sound[storage], path)
    with h5py.File(path, "r+") as f:
        damage(f)
    for mode in ("r", "a"):
        with pytest.raises(CorruptFile, match=message):
            ResultStore.open(path, mode)
    with pytest.raises(BadInput, match=message):
        read_statistics(path)
    for command in (["info", path], ["report", path, "--out", tmp_path / "report"], ["check", path, "--baseline", BASELINE]):
        result = cli_in_process(*command)
        assert result.returncode == 2, (command, result.stdout, result.stderr)
        assert f"{path}:" in result.stderr and "Traceback" not in result.stderr + result.stdout
    assert not (tmp_path / "report").exists()


@pytest.mark.parametrize("storage", ["raw", "tsvd"])
def test_a_sound_file_passes(sound, storage):
    with ResultStore.open(sound[storage]) as store:
        assert store.pending().size == 0 and store.verify() == []
    assert read_statistics(sound[storage])[0].runs == N


def test_an_ok_run_without_finite_values_is_refused_by_the_analysis(sound, tmp_path):
    """The layout is sound but a run with status ok holds an infinity: no statistics from it."""
    path = tmp_path / "inf.h5"
    shutil.copy(sound["raw"], path)
    with h5py.File(path, "r+") as f:
        f["outputs/y"][4, 10] = np.inf
    with pytest.raises(BadInput, match=r"inf\.h5: output y: 1 runs with status ok hold values that are not "
                                        r"finite \(e\.g\. run 4\)"):
        read_statistics(path)
    assert cli_in_process("info", path).returncode == 2


def test_a_garbled_campaign_text_does_not_stop_the_report(sound, tmp_path):
    """The campaign text is shown, never read as a campaign: the campaign is the file's record
    (campaign.record)."""
    path = tmp_path / "garbled.h5"
    shutil.copy(sound["raw"], path)
    with h5py.File(path, "r+") as f:
        f.attrs["campaign"] = "{{{: ["
    (entry,), _ = load_entries([path], None)
    assert entry.inputs == "uniform" and entry.stats.runs == N


def test_run_refuses_to_resume_a_damaged_file_and_restart_starts_it_over(sound, tmp_path):
    yaml, path = tmp_path / "damaged.yaml", tmp_path / "damaged.h5"
    yaml.write_text(CAMPAIGN)
    shutil.copy(sound["raw"], path)
    with h5py.File(path, "r+") as f:
        f["samples/weight"][0] = np.nan
    refused = cli_in_process("run", yaml, "--out", path)
    assert refused.returncode == 2 and "/samples/weight holds 1 values that are not finite" in refused.stderr
    assert f"uqflight run {yaml} --out {path} --restart" in refused.stderr
    assert cli_in_process("run", yaml, "--out", path, "--restart").returncode == 0
    assert read_statistics(path)[0].runs == N


def test_a_time_grid_the_reader_would_refuse_is_refused_before_any_run(tmp_path):
    (tmp_path / "model.py").write_text(
        "import numpy as np\n"
        "def backwards(p):\n"
        "    return {'time': np.array([2.0, 1.0, 0.0]), 'y': np.full(3, p['x'])}\n")
    yaml = tmp_path / "c.yaml"
    yaml.write_text(CAMPAIGN.replace(f"{DATA / 'hostile_model.py'}:long_histories", "model.py:backwards"))
    refused = cli_in_process("run", yaml, "--out", tmp_path / "r.h5")
    assert refused.returncode == 2 and "'time' must be finite and strictly increasing" in refused.stderr
    assert not (tmp_path / "r.h5").exists()
    with pytest.raises(ValueError, match="finite and strictly increasing"):
        ResultStore.create(tmp_path / "direct.h5", campaign_text="x", xi=np.zeros((2, 1)), kappa=np.zeros((2, 1)),
                           weights=np.ones(2), parameter_names=["x"], outputs=["y"], time=np.array([0.0, 0.0]))


SURROGATE_DAMAGES = {  # name: (edit of the parsed JSON, what the message says)
    "no germs": (lambda s: s.pop("germs"), "KeyError: 'germs'"),
    "an unknown germ": (lambda s: s.update(germs=["cauchy"]), r"germs: unknown \['cauchy'\]"),
    "multi-indices of another width": (lambda s: s.update(multi_indices=[[0], [1]]), "multi_indices: expected rows of 2"),
    "a negative degree": (lambda s: s["multi_indices"].__setitem__(1, [-1, 0]), "multi_indices"),
    "coefficients of another shape": (lambda s: s["outputs"]["y"].update(coefficients=[[1.0]]),
                                      r"outputs.y.coefficients: expected 6 x 5 finite numbers, got shape \(1, 1\)"),
    "a null coefficient": (lambda s: s["outputs"]["y"]["coefficients"][0].__setitem__(0, None), "with nulls"),
    "a parameter without bounds": (lambda s: s["parameters"][0].pop("lower"), "parameters: expected 2 entries"),
    "a parameter of an unknown law": (lambda s: s["parameters"][0].update(distribution="cauchy"), "unknown distribution"),
    "outputs as a list": (lambda s: s.update(outputs=[1, 2]), "outputs: expected a mapping"),
}


@pytest.fixture(scope="module")
def surrogate_text(tmp_path_factory):
    """The order-2 PCE of y = 15000 + t (x1² + x2²) (5 times) on a 4x4 grid, exported."""
    from conftest import NORMAL_2D, closed_form_campaign

    from uqflight.analysis.surrogate import export

    folder = tmp_path_factory.mktemp("surrogate")
    results = run_python_campaign(folder, closed_form_campaign("sq", "sum_of_squares", NORMAL_2D, "{kind: tensor_grid, points: 4}",
                                                   "method: {kind: pseudo_galerkin, order: 2}\n"))
    return export(results, folder / "pce.json").read_text()


@pytest.mark.parametrize("name", SURROGATE_DAMAGES)
def test_a_damaged_surrogate_file_is_refused_naming_what_is_wrong(surrogate_text, tmp_path, name):
    import json

    from uqflight.analysis.surrogate import load

    edit, message = SURROGATE_DAMAGES[name]
    data = json.loads(surrogate_text)
    assert load_ok(surrogate_text, tmp_path)
    edit(data)
    path = tmp_path / "pce.json"
    path.write_text(json.dumps(data))
    with pytest.raises(Refusal, match=rf"pce\.json: malformed surrogate \(.*{message}"):
        load(path)
    path.write_text('{"format": "uqflight-pce", "germs": ' + "[" * 100000)
    with pytest.raises(Refusal, match="cannot read the surrogate"):
        load(path)


def load_ok(text, folder) -> bool:
    from uqflight.analysis.surrogate import load

    (folder / "sound.json").write_text(text)
    return load(folder / "sound.json").evaluate(xi=[[0.3, -0.2]])["y"].shape == (1, 5)


def test_a_flipped_byte_is_reported(tmp_path):
    out = tmp_path / "r.h5"
    run_campaign(hostile_campaign("slow", samples=4), out=out)
    with h5py.File(out, "r") as f:
        offset = f["outputs/y"].id.get_chunk_info(0).byte_offset
    with open(out, "r+b") as fh:
        fh.seek(offset + 3)
        byte = fh.read(1)
        fh.seek(offset + 3)
        fh.write(bytes([byte[0] ^ 0x10]))
    info = cli_in_process("info", out)
    assert info.returncode == 2
    assert "data corrupted: a checksum (fletcher32) does not match" in info.stderr


def test_an_unknown_status_code_is_an_error(tmp_path):
    out = tmp_path / "r.h5"
    run_campaign(hostile_campaign("slow", samples=2), out=out)
    with h5py.File(out, "a") as f:
        f["samples/status"][1] = 9
    with pytest.raises(CorruptFile, match=r"unknown status codes \[9\]"):
        ResultStore.open(out)
    info = cli_in_process("info", out)
    assert info.returncode == 2 and "unknown status codes [9]" in info.stderr


HOSTILE_SURROGATES = {  # name: (edit of the file's text or parsed JSON, the key and what is wrong)
    "an order of 1e400": (lambda t: t.replace('"order": 2', '"order": 1e400'),
                          r"order: expected an integer in \[0, 1000\], got inf"),
    "a huge multi-index": (lambda s: s["multi_indices"].__setitem__(1, [10**30, 0]),
                           r"multi_indices: expected rows of 2 integers in \[0, 1000\]"),
    "a fractional multi-index": (lambda s: s["multi_indices"].__setitem__(1, [0.9, 0]),
                                 r"multi_indices: .* with 0\.9"),
    "a repeated multi-index": (lambda s: s["multi_indices"].__setitem__(2, s["multi_indices"][1]),
                               r"multi_indices: row 2 repeats row 1"),
    "a coefficient as a string": (lambda s: s["outputs"]["y"]["coefficients"][0].__setitem__(0, "1.5"),
                                  r"outputs\.y\.coefficients: expected 6 x 5 finite numbers, .* with '1\.5'"),
    "a time as a string": (lambda s: s["time"].__setitem__(0, "0.0"), r"time: .* with '0\.0'"),
    "a bound as a string": (lambda s: s["parameters"][0].update(lower="-3"),
                            r"parameters\[0\]\.lower: expected a finite number, got '-3'"),
    "a uniform germ for a normal law": (lambda s: s.update(germs=["uniform", "normal"]),
                                        r"parameters\[0\] \(x1\): a normal law is driven by a normal germ, "
                                        r"but germs\[0\] is uniform"),
    "decreasing times": (lambda s: s.update(time=s["time"][::-1]), "time: expected a list of strictly increasing"),
    "a boolean coefficient": (lambda s: s["outputs"]["y"]["coefficients"][1].__setitem__(1, True),
                              r"outputs\.y\.coefficients: .* with True"),
}


@pytest.mark.parametrize("name", HOSTILE_SURROGATES)
def test_hostile_surrogate_files_are_refused_naming_the_key(surrogate_text, tmp_path, name):
    edit, message = HOSTILE_SURROGATES[name]
    path = tmp_path / "pce.json"
    if name == "an order of 1e400":  # not JSON that json.dumps writes: edit the text
        path.write_text(edit(surrogate_text))
    else:
        data = json.loads(surrogate_text)
        edit(data)
        path.write_text(json.dumps(data))
    with pytest.raises(Refusal, match=rf"pce\.json: malformed surrogate \(ValueError: {message}"):
        load(path)



def test_a_surrogate_file_above_the_cap_is_refused_before_it_is_read(tmp_path):
    path = tmp_path / "big.json"
    with open(path, "wb") as fh:  # sparse: nothing is written, and parsing it would fail otherwise
        fh.truncate(MAX_FILE_BYTES + 1)
    with pytest.raises(Refusal, match=r"big\.json: cannot read the surrogate \(64 MiB, more than the 64 MiB"):
        load(path)

