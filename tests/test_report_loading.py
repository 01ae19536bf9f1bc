"""Reading a results file: the file opened once per command, and the campaign it records checked once per
command."""
import os
from pathlib import Path

import pytest

from conftest import run_python_campaign
from test_closed_forms_end_to_end import LINEAR
from uqflight.analysis.statistics import read_statistics
from uqflight.analysis.surrogate import fit_surrogate
from uqflight.report import write_report
from uqflight.store import ResultStore


def _count_opens(monkeypatch, log: Path) -> None:
    """Every ResultStore.open from now on, in this process and the processes it forks, writes a line
    "PID PATH" to `log`."""
    open_file = ResultStore.open.__func__

    def counted(cls, path, *args, **kwargs):
        with open(log, "a") as lines:
            lines.write(f"{os.getpid()} {path}\n")
        return open_file(cls, path, *args, **kwargs)

    monkeypatch.setattr(ResultStore, "open", classmethod(counted))


def test_reading_statistics_and_fitting_a_surrogate_open_the_results_file_once(tmp_path, monkeypatch):
    results = run_python_campaign(tmp_path, LINEAR)
    log = tmp_path / "opened.log"
    _count_opens(monkeypatch, log)
    stats, attrs = read_statistics(results)
    assert log.read_text().splitlines() == [f"{os.getpid()} {results}"]
    assert stats.outputs["y"].mean[0] == pytest.approx(3.0, abs=1e-9)  # 3 E[x3]
    log.unlink()
    fit_surrogate(results)
    assert log.read_text().splitlines() == [f"{os.getpid()} {results}"]


def test_a_report_opens_its_results_file_once_and_its_drawing_processes_never(tmp_path, monkeypatch):
    # the design figure, the spaghetti plot and the scatter each opened the file again in a drawing child
    results = run_python_campaign(tmp_path, LINEAR)
    log = tmp_path / "opened.log"
    _count_opens(monkeypatch, log)
    written = write_report([results], tmp_path / "report")
    assert log.read_text().splitlines() == [f"{os.getpid()} {results}"]
    assert {"design_c.png", "scatter_c.png"} <= {path.name for path in written}  # y has one time: no spaghetti


def test_each_command_checks_the_campaign_once(tmp_path, monkeypatch):
    # the campaign through its checks (build_campaign): run checks the file's text, a reader the record a run
    # stored (read_record: what the analysis, the report and the export read), once per command, not per reader
    from collections import Counter

    import uqflight.analysis.statistics as statistics
    import uqflight.campaign as campaign
    import uqflight.campaign.record as record
    from uqflight.campaign import load_campaign
    from uqflight.running.runner import run_campaign

    calls = Counter()
    for module, name in ((statistics, "read_record"), (record, "build_campaign"), (campaign, "build_campaign")):
        def counted(*args, _name=name, _original=getattr(module, name), **kwargs):
            calls[_name] += 1
            return _original(*args, **kwargs)
        monkeypatch.setattr(module, name, counted)
    (tmp_path / "c.yaml").write_text(LINEAR)
    run_campaign(load_campaign(tmp_path / "c.yaml"), out=tmp_path / "c.h5", workers=1)
    assert calls == {"build_campaign": 1}
    for command in (lambda: write_report([tmp_path / "c.h5"], tmp_path / "report"),
                    lambda: fit_surrogate(tmp_path / "c.h5")):
        calls.clear()
        command()
        assert calls == {"read_record": 1, "build_campaign": 1}
