"""The report imports matplotlib only to draw: `surrogate export` and the analysis never load it."""
import subprocess
import sys


def test_the_report_package_imports_no_matplotlib_until_the_page_is_drawn():
    code = "import sys, uqflight.report; print('matplotlib' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip() == "False"


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
