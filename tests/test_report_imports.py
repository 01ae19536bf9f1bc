"""The report's modules load ahead of use: matplotlib is imported in a thread during the analysis."""
import subprocess
import sys

import pytest

from uqflight.progress import Progress
from uqflight.report import FirstCount, importing_ahead


def test_the_report_package_imports_no_matplotlib_until_the_page_is_drawn():
    code = "import sys, uqflight.report; print('matplotlib' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip() == "False"


def test_modules_imported_ahead_are_there_on_leaving_and_a_failure_is_left_to_the_import_for_use(tmp_path, monkeypatch,
                                                                                                capfd):
    (tmp_path / "ahead_fine.py").write_text("VALUE = 1\n")
    (tmp_path / "ahead_broken.py").write_text("raise RuntimeError('broken on import')\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    called = []
    with importing_ahead(("ahead_fine", "ahead_broken"), then=lambda: called.append(1)) as start:
        start()
        start()  # once only
    assert called == []  # not after a failed import
    assert sys.modules["ahead_fine"].VALUE == 1 and "ahead_broken" not in sys.modules
    assert "broken on import" not in capfd.readouterr().err  # nothing printed by the thread
    with pytest.raises(RuntimeError, match="broken on import"):
        import ahead_broken  # noqa: F401
    del sys.modules["ahead_fine"]


def test_nothing_is_imported_ahead_unless_started(tmp_path, monkeypatch):
    (tmp_path / "ahead_unstarted.py").write_text("VALUE = 1\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    with importing_ahead(("ahead_unstarted",)):
        pass
    assert "ahead_unstarted" not in sys.modules


def test_the_hook_runs_once_at_the_first_counted_stage(capsys):
    calls = []
    progress = FirstCount(Progress(0, quiet=True), lambda: calls.append(1))
    progress.stage("opening")  # no count: the file is opened and checked
    assert calls == []
    progress.stage("analysing", 5, "outputs")
    progress.advance()
    progress.stage("analysing the next", 5, "outputs")
    assert calls == [1] and progress.done == 0 and progress.total == 5


def test_then_runs_in_the_thread_after_the_imports(tmp_path, monkeypatch):
    import threading

    (tmp_path / "ahead_then.py").write_text("VALUE = 2\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    seen = []
    with importing_ahead(("ahead_then",), then=lambda: seen.append((sys.modules["ahead_then"].VALUE,
                                                                      threading.current_thread()))) as start:
        start()
    assert seen and seen[0][0] == 2 and seen[0][1] is not threading.main_thread()
    del sys.modules["ahead_then"]


def test_the_fonts_are_warmed_once_from_any_thread_without_pyplot_figures(monkeypatch):
    import threading

    import matplotlib.pyplot as plt

    from uqflight.report import plots

    monkeypatch.setattr(plots, "_warmed", False)
    before = plt.get_fignums()
    thread = threading.Thread(target=plots.warm_text_caches)
    thread.start()
    thread.join()
    assert plots._warmed and plt.get_fignums() == before
    monkeypatch.setattr(plots, "Figure", None)  # drawn once only: a second call draws nothing
    plots.warm_text_caches()
