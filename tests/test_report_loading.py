"""The report's reading of a results file: the campaign text it stores (report.loading.campaign_settings), and
the file opened once to analyse it."""
import pytest

from uqflight.report.loading import campaign_settings


def test_unreadable_campaign_text_gives_no_settings():
    # a stored campaign is the file's to hold: a YAML error, a date that is no date, nesting too deep
    # for Python and a mapping that is not one all read as {} instead of failing the report
    for text in ("a: [1, 2", "a: 2001-13-45", "[" * 3000 + "]" * 3000, "- 1\n- 2", "a: !!python/object:os.system x"):
        assert campaign_settings(text) == {}


def test_settings_are_a_copy_of_the_text_read_once():
    text = "seed: 3\nparameters:\n  CL0: {distribution: normal}\n"
    first = campaign_settings(text)
    first["parameters"]["CL0"]["distribution"] = "changed"
    assert campaign_settings(text) == {"seed": 3, "parameters": {"CL0": {"distribution": "normal"}}}


def test_reading_statistics_and_fitting_a_surrogate_open_the_results_file_once(tmp_path, monkeypatch):
    from conftest import run_python_campaign
    from test_closed_forms_end_to_end import LINEAR
    from uqflight.analysis.statistics import read_statistics
    from uqflight.analysis.surrogate import fit_surrogate
    from uqflight.store import ResultStore

    results = run_python_campaign(tmp_path, LINEAR)
    opened = []
    open_file = ResultStore.open.__func__

    def counted(cls, path, *args, **kwargs):
        opened.append(path)
        return open_file(cls, path, *args, **kwargs)

    monkeypatch.setattr(ResultStore, "open", classmethod(counted))
    stats, attrs = read_statistics(results)
    assert opened == [results] and stats.outputs["y"].mean[0] == pytest.approx(3.0, abs=1e-9)  # 3 E[x3]
    opened.clear()
    fit_surrogate(results)
    assert opened == [results]
