"""CI regression check: a small campaign on the real aircraft against the committed baseline.

If a deliberate change moves the statistics, regenerate the baseline and commit it with the change:
    uqflight run campaigns/ci-small.yaml --force   # starts over when the aircraft files changed
    uqflight report results/ci-small.h5 --out /tmp/ci --write-baseline tests/baselines/ci-small.json
"""
import subprocess

from conftest import ROOT, UQFLIGHT
from uqflight.campaign import load_campaign
from uqflight.simulators.validation_view import validation_view
from uqflight.execution import run_campaign



def test_small_campaign_matches_the_committed_baseline(tmp_path):
    campaign = load_campaign(ROOT / "campaigns" / "ci-small.yaml", validation_view)
    summary = run_campaign(campaign, out=tmp_path / "ci.h5", workers=2)
    assert summary.ran == 113 and not summary.failures
    check = subprocess.run([UQFLIGHT, "check", str(tmp_path / "ci.h5"), "--baseline",
                            str(ROOT / "tests" / "baselines" / "ci-small.json")], capture_output=True, text=True)
    assert check.returncode == 0, check.stdout + check.stderr
    assert "no drift" in check.stdout
