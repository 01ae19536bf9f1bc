"""Figures written by forked children (report.plots.background_rendering) are the same bytes as
figures written in the process, and a figure that cannot be written fails the report, named."""
from types import SimpleNamespace

import numpy as np
import pytest

from uqflight.report import plots


def outputs():
    time = np.linspace(0.0, 10.0, 201)
    return {name: SimpleNamespace(name=name, time=time, cov=0.01 + np.abs(np.sin(k + time)),
                                  mean=offset + np.sin(k + time), std=0.01 + np.abs(np.sin(k + time)), units="")
            for k, (name, offset) in enumerate((("alpha_deg", 0.0), ("h_ft", 15000.0)))}


def test_the_same_png_bytes_in_a_child(tmp_path):
    plots.plot_cov(outputs(), tmp_path / "here.png", "CoV")
    with plots.background_rendering(processes=2):
        plots.plot_cov(outputs(), tmp_path / "child.png", "CoV")
        plots.plot_cov(outputs(), tmp_path / "child2.png", "CoV")
        plots.plot_cov(outputs(), tmp_path / "child3.png", "CoV")  # waits for a child to finish first
    here = (tmp_path / "here.png").read_bytes()
    assert all((tmp_path / f"{name}.png").read_bytes() == here for name in ("child", "child2", "child3"))


def test_a_figure_that_fails_in_a_child_is_named(tmp_path):
    missing = tmp_path / "no-such-folder" / "cov.png"
    with pytest.raises(RuntimeError, match="cannot write the plot .*no-such-folder/cov.png"), \
            plots.background_rendering():
        plots.plot_cov(outputs(), missing, "CoV")
    plots.plot_cov(outputs(), tmp_path / "after.png", "CoV")  # written in the process again
    assert (tmp_path / "after.png").is_file()
