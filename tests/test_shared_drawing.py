"""Figures drawn by a forked child sharing the report's sections (forking.share_work) are the same bytes
as figures drawn in the process, and a figure that cannot be written in a child fails, its error told."""
import os
import time
from types import SimpleNamespace

import numpy as np
import pytest

from uqflight.running.forking import FORKS, ChildFailed, share_work
from uqflight.report import plots

pytestmark = pytest.mark.skipif(not FORKS, reason="the system cannot fork")


def outputs():
    time = np.linspace(0.0, 10.0, 201)
    return {name: SimpleNamespace(name=name, time=time, cov=0.01 + np.abs(np.sin(k + time)),
                                  mean=offset + np.sin(k + time), std=0.01 + np.abs(np.sin(k + time)), units="")
            for k, (name, offset) in enumerate((("alpha_deg", 0.0), ("h_ft", 15000.0)))}


@pytest.mark.slow
def test_the_same_png_bytes_in_a_child(tmp_path):
    plots.plot_cov(outputs(), tmp_path / "here.png", "CoV")
    plots.warm_text_caches()
    names, parent = [f"shared{k}" for k in range(4)], os.getpid()

    def draw(name):
        if os.getpid() == parent:
            time.sleep(1.0)  # this process's one job keeps it busy: the child draws the others
        plots.plot_cov(outputs(), tmp_path / f"{name}.png", "CoV")
        return os.getpid()

    pids = share_work([lambda name=name: draw(name) for name in names], processes=2)
    assert pids.count(parent) == 1 and len(set(pids)) == 2
    here = (tmp_path / "here.png").read_bytes()
    assert all((tmp_path / f"{name}.png").read_bytes() == here for name in names)


@pytest.mark.slow
def test_a_figure_that_fails_in_a_child_fails_with_its_error_printed(tmp_path, capfd):
    parent = os.getpid()

    def draw():
        if os.getpid() == parent:
            time.sleep(1.0)
        else:
            plots.plot_cov({"y": None}, tmp_path / "cov.png", "CoV")  # no statistics: raises in matplotlib's work

    with pytest.raises(ChildFailed, match="exit 1"):
        share_work([draw, draw], processes=2)
    assert "Traceback" in capfd.readouterr().err  # the child's traceback
    plots.plot_cov(outputs(), tmp_path / "after.png", "CoV")  # drawn in the process again
    assert (tmp_path / "after.png").is_file()


@pytest.mark.slow
def test_a_file_error_in_a_child_is_raised_here_as_that_error(tmp_path):
    missing, parent = tmp_path / "no-such-folder" / "cov.png", os.getpid()

    def draw():
        if os.getpid() == parent:
            time.sleep(1.0)
        else:
            plots.plot_cov(outputs(), missing, "CoV")

    with pytest.raises(FileNotFoundError, match="no-such-folder/cov.png"):  # the report says it cannot write
        share_work([draw, draw], processes=2)
