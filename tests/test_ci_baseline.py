"""CI regression check: small campaigns on the real aircraft against their committed baselines, in the
default suite ci-small's 15-point level-1 grid (tests/baselines/ci-tiny.yaml), in the slow suite
campaigns/ci-small.yaml's 113 points.

If a deliberate change moves the statistics, regenerate both baselines and commit them with the change:
    uqflight run campaigns/ci-small.yaml --force   # starts over when the aircraft files changed
    uqflight report results/ci-small.h5 --out /tmp/ci --write-baseline tests/baselines/ci-small.json
    uqflight run tests/baselines/ci-tiny.yaml --force
    uqflight report results/ci-tiny.h5 --out /tmp/ci-tiny --write-baseline tests/baselines/ci-tiny.json
"""
import pytest
from conftest import ROOT, cli_in_process

from uqflight.campaign import load_campaign
from uqflight.running.runner import run_campaign
from uqflight.simulators.aircraft_properties import AircraftProperties

BASELINES = ROOT / "tests" / "baselines"


@pytest.mark.parametrize("campaign, baseline, runs", [
    pytest.param(BASELINES / "ci-tiny.yaml", BASELINES / "ci-tiny.json", 15, id="ci-tiny"),
    pytest.param(ROOT / "campaigns" / "ci-small.yaml", BASELINES / "ci-small.json", 113, id="ci-small",
                 marks=pytest.mark.slow)])
def test_small_campaign_matches_the_committed_baseline(tmp_path, campaign, baseline, runs):
    summary = run_campaign(load_campaign(campaign, AircraftProperties), out=tmp_path / "ci.h5", workers=2)
    assert summary.ran == runs and not summary.failures
    check = cli_in_process("check", tmp_path / "ci.h5", "--baseline", baseline)
    assert check.returncode == 0, check.stdout + check.stderr
    assert "no drift" in check.stdout
