"""Hostile inputs are refused up front with one message: campaign YAML that breaks Python's parser
limits, surrogate files that lie about their sizes and types, calibration data too large for memory,
a byte-order mark, a repeated --noise, and Ctrl-C during sampling."""
import json
import os
import signal
import subprocess
import time

import numpy as np
import pytest
from conftest import NORMAL_2D, UQFLIGHT, cli_in_process, closed_form_campaign, run_python_campaign
from test_damaged_files import surrogate_text  # noqa: F401 - the exported order-2 PCE, a fixture

from uqflight.calibration.likelihood import DataError, parse_noise, read_flight_csv
from uqflight.surrogate import MAX_FILE_BYTES, SurrogateError, load

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
def test_hostile_surrogate_files_are_refused_naming_the_key(surrogate_text, tmp_path, name):  # noqa: F811
    edit, message = HOSTILE_SURROGATES[name]
    path = tmp_path / "pce.json"
    if name == "an order of 1e400":  # not JSON that json.dumps writes: edit the text
        path.write_text(edit(surrogate_text))
    else:
        data = json.loads(surrogate_text)
        edit(data)
        path.write_text(json.dumps(data))
    with pytest.raises(SurrogateError, match=rf"pce\.json: malformed surrogate \(ValueError: {message}"):
        load(path)


def test_a_surrogate_file_above_the_cap_is_refused_before_it_is_read(tmp_path):
    path = tmp_path / "big.json"
    with open(path, "wb") as fh:  # sparse: nothing is written, and parsing it would fail otherwise
        fh.truncate(MAX_FILE_BYTES + 1)
    with pytest.raises(SurrogateError, match=r"big\.json: cannot read the surrogate \(64 MiB, more than the 64 MiB"):
        load(path)


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    """y(t) = 15000 + t (x1² + x2²) at 5 times in [0, 1] on a 4x4 grid."""
    folder = tmp_path_factory.mktemp("calibrate")
    return run_python_campaign(folder, closed_form_campaign("sq", "sum_of_squares", NORMAL_2D, "{kind: tensor_grid, points: 4}",
                                                "method: {kind: pseudo_galerkin, order: 2}\n"))


def test_a_million_row_csv_is_refused_before_it_is_parsed(results, tmp_path):
    data = tmp_path / "big.csv"
    data.write_text("time_s,y\n" + "0.5,15000.5\n" * (10**6 - 1) + "not,a number\n")  # parsed: refused otherwise
    out = tmp_path / "out"
    result = cli_in_process("calibrate", results, "--data", data, "--out", out)
    assert result.returncode == 2, result.stderr
    # 1 output x (50 predictive draws x (2 x 40 noise draws + 3) + 4 x 32 walkers) x 8 bytes = 34.2 kB a row
    assert f"error: {data}: more than 233619 rows of data: calibrating 1 output(s) with 32 walkers and 50 " \
           "predictive draws takes about 34 kB a row, more than the 8 GB memory limit" in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1 and not out.exists()


def test_a_byte_order_mark_is_no_part_of_the_header(tmp_path):
    path = tmp_path / "bom.csv"
    path.write_bytes("\ufefftime_s,y\n0,1.5\n0.5,2.5\n".encode("utf-8"))
    flight = read_flight_csv(path, None, ["y"])
    np.testing.assert_array_equal(flight.time, [0.0, 0.5])
    np.testing.assert_array_equal(flight.values["y"], [1.5, 2.5])


def test_a_noise_given_twice_is_refused(results, tmp_path):
    with pytest.raises(DataError, match=r"--noise y: given twice \(0\.01 and 5\); give it once"):
        parse_noise(["y=0.01", "y=5"], ["y"])
    data = tmp_path / "flight.csv"
    data.write_text("time_s,y\n0,15000\n0.5,15001\n1,15002\n")
    result = cli_in_process("calibrate", results, "--data", data, "--out", tmp_path / "out",
                            "--noise", "y=0.01", "--noise", "y=5")
    assert result.returncode == 2 and result.stderr == "error: --noise y: given twice (0.01 and 5); give it once\n"


@pytest.mark.slow
def test_ctrl_c_in_calibrate_exits_130_with_one_line(results, tmp_path):
    data = tmp_path / "flight.csv"
    data.write_text("time_s,y\n0,15000\n0.25,15000.6\n0.5,15001.1\n0.75,15001.4\n1,15002.1\n")
    process = subprocess.Popen([UQFLIGHT, "calibrate", results, "--data", data, "--out", tmp_path / "out",
                                "--steps", "10000000"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    cpu = 0.0
    while cpu < 6.0 and process.poll() is None:  # start-up and the fit take 2-3 s of CPU: then it samples
        time.sleep(0.2)
        fields = open(f"/proc/{process.pid}/stat").read().rsplit(")", 1)[1].split()
        cpu = (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    process.send_signal(signal.SIGINT)
    stdout, stderr = process.communicate(timeout=60)
    assert process.returncode == 130, stderr[-3000:]
    # off a terminal the progress is log lines ("calibrate: ..."); beside them, one line says it all
    others = [line for line in stderr.splitlines() if not line.startswith("calibrate: ")]
    assert stdout == "" and others == ["", f"interrupted: no calibration written to {tmp_path / 'out'}"], stderr
