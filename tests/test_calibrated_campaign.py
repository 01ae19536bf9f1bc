"""calibrated.yaml keeps every key of each parameter but its law: a campaign whose parameters perturb an
aircraft's functions (`function:`, `perturbation:`) calibrates into a campaign `uqflight plan` accepts, with
the real aircraft (JSBSim) checking it; and a calibrated campaign that still fails its check loses nothing of
the finished calibration."""
import csv
import json
import shutil

import numpy as np
import pytest
import yaml
from conftest import cli_in_process

from uqflight.calibration import outputs as outputs_module
from uqflight.store import ResultStore

CAMPAIGN = """
name: perturbed
seed: 3
simulator: {kind: jsbsim, aircraft: bacm, duration_s: 3, output_rate_hz: 10,
            excitation: {kind: pulse, amplitude_deg: 1.0, start_s: 0.5, duration_s: 1.0}}
parameters:
  lift: {function: aero/force/lift, perturbation: scale, distribution: normal, interval_pct: 6}
design: {kind: tensor_grid, points: 4}
method: {kind: pseudo_galerkin, order: 2}
execution: {workers: 1}
"""


@pytest.fixture(scope="module")
def flown(tmp_path_factory):
    """The campaign's results file (4 JSBSim runs), flown once for the module."""
    folder = tmp_path_factory.mktemp("perturbed")
    (folder / "c.yaml").write_text(CAMPAIGN)
    ran = cli_in_process("run", folder / "c.yaml", "--out", folder / "c.h5")
    assert ran.returncode == 0, ran.stderr
    return folder / "c.h5"


def _calibrated(flown, tmp_path, *args):
    shutil.copy(flown, tmp_path / "c.h5")
    with ResultStore.open(tmp_path / "c.h5") as store:  # the data: the run at the grid's last node
        time, alpha = store.time, store.output_matrix("alpha_deg")[-1]
    with open(tmp_path / "flight.csv", "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(["time_s", "alpha_deg"])
        writer.writerows([[repr(float(t)), repr(float(a))] for t, a in zip(time, alpha)])
    return cli_in_process("calibrate", tmp_path / "c.h5", "--data", tmp_path / "flight.csv", "--out",
                          tmp_path / "cal", "--noise", "alpha_deg=0.01", "--steps", "400", "--predictive-draws", "2",
                          *args)


@pytest.mark.slow
def test_a_calibrated_campaign_keeps_function_and_perturbation_and_plans(flown, tmp_path):
    done = _calibrated(flown, tmp_path)
    assert done.returncode == 0, done.stderr
    calibrated = yaml.safe_load((tmp_path / "cal" / "calibrated.yaml").read_text())
    lift = calibrated["parameters"]["lift"]
    assert lift["function"] == "aero/force/lift" and lift["perturbation"] == "scale"
    assert lift["distribution"] == "normal" and "interval_pct" not in lift
    summary = json.loads((tmp_path / "cal" / "summary.json").read_text())
    assert lift["nominal"] == summary["parameters"]["lift"]["posterior"]["mean"]
    assert summary["parameters"]["lift"]["narrowing"] > 1  # informed: the law is the posterior's
    planned = cli_in_process("plan", tmp_path / "cal" / "calibrated.yaml")
    assert planned.returncode == 0, planned.stderr


@pytest.mark.slow
def test_a_calibrated_campaign_that_fails_its_check_keeps_the_calibration_and_says_so(flown, tmp_path, monkeypatch):
    # a calibrated text the campaign check refuses (here a parameter given a key no campaign takes): the
    # posterior, the summary and the plots are kept, calibrated.yaml is not written, one warning says why
    written = outputs_module.calibrated_campaign

    def refused(*args, **kwargs):
        return written(*args, **kwargs).replace("perturbation: scale", "perturbation: scale, bogus: 1")

    monkeypatch.setattr("uqflight.calibration.run.calibrated_campaign", refused)
    done = _calibrated(flown, tmp_path)
    assert done.returncode == 0, done.stderr
    out = tmp_path / "cal"
    assert (out / "posterior.h5").is_file() and (out / "summary.json").is_file()
    assert not (out / "calibrated.yaml").exists()
    warning = [line for line in done.stderr.splitlines() if "calibrated.yaml" in line]
    assert len(warning) == 1 and warning[0].startswith("warning: calibrated.yaml not written: ")
    assert "parameters.lift" in warning[0] and "posterior.h5" in warning[0]
    summary = json.loads((out / "summary.json").read_text())
    assert "parameters.lift" in summary["calibrated_campaign"]["refused"]
    assert np.isfinite(summary["parameters"]["lift"]["posterior"]["mean"])
