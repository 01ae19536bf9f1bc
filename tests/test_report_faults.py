"""The report in the face of numbers it cannot hold and of a disk that fills: values whose squares leave
float64 are refused in one line naming the file and the output (exit 2), values below that bound give their
closed-form moments; a full disk while the plots are drawn is "cannot write the report" (exit 2) with the
old report intact. Real campaigns of a python model, real processes, a real full disk."""
from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest

from conftest import UQFLIGHT, cli_in_process, mounted_tmpfs, read_summary, run_python_campaign

MODEL = """import numpy as np
T = np.linspace(0.0, 5.0, 11)
def scaled(p):
    return {{"time": T, "x": {scale} * (1.0 + p["a"] * (1.0 + T))}}
"""
CAMPAIGN = """name: scaled
seed: 3
simulator: {kind: python, function: "model.py:scaled"}
parameters:
  a: {distribution: uniform, lower: 0.5, upper: 1.5}
design: {kind: sparse_grid, level: 3}
method: {kind: pseudo_galerkin, order: 2}
analysis: {band_samples: 500, bootstrap: 0}
"""


def scaled_results(folder, scale: str):
    (folder / "model.py").write_text(MODEL.format(scale=scale))
    return run_python_campaign(folder, CAMPAIGN)


def test_outputs_whose_squares_overflow_are_refused_in_one_line(tmp_path):
    """D09: finite outputs near 1e200 ran fine, but the report's variance overflowed to inf and a plotting child
    died on it (exit 1). Refused before any statistic, by report, check and surrogate export alike."""
    out = scaled_results(tmp_path, "1e200")
    for args in (("report", out, "--out", tmp_path / "rep"), ("surrogate", "export", out, "--out", tmp_path / "s.json")):
        done = cli_in_process(*args)
        assert done.returncode == 2, done.stderr
        errors = [line for line in done.stderr.splitlines() if "error" in line or "Error" in line]
        assert len(errors) == 1 and errors[0].startswith(f"error: {out}: output x holds values up to 9.58e+200, "
                                                         "beyond the 1e+75 its statistics take in float64"), done.stderr
        assert errors[0].endswith("would overflow): record it in larger units")
    assert not (tmp_path / "rep").exists() and not (tmp_path / "s.json").exists()


@pytest.mark.slow
def test_large_outputs_below_the_bound_give_their_closed_form_moments(tmp_path):
    """x = 1e70 (1 + a (1 + t)), a ~ U(0.5, 1.5): E x = 1e70 (2 + t), Var x = 1e140 (1 + t)^2 / 12, skewness 0,
    kurtosis 9/5 (a uniform's). The projection of order 2 on a level-3 grid is exact for this line; tolerance
    1e-12 relative for the moments (a few roundings of float64), 1e-9 for the kurtosis (a ratio of sums of fourth
    powers) and 1e-12 absolute for the skewness (zero: relative to nothing)."""
    out = scaled_results(tmp_path, "1e70")
    done = cli_in_process("report", out, "--out", tmp_path / "rep")
    assert done.returncode == 0, done.stderr
    assert "Warning" not in done.stderr, done.stderr  # nothing overflowed on the way
    x = read_summary(tmp_path / "rep" / "summary.json")["outputs"]["x"]
    t = np.asarray(x["time"])
    np.testing.assert_allclose(x["mean"], 1e70 * (2 + t), rtol=1e-12)
    np.testing.assert_allclose(x["variance"], 1e140 * (1 + t) ** 2 / 12, rtol=1e-12)
    np.testing.assert_allclose(x["skewness"], 0.0, atol=1e-12)
    np.testing.assert_allclose(x["kurtosis"], 1.8, rtol=1e-9)


def _snapshot(folder):
    return {path.relative_to(folder): path.read_bytes() for path in sorted(folder.rglob("*")) if path.is_file()}


@pytest.mark.slow
def test_a_disk_that_fills_while_the_plots_are_drawn_leaves_the_old_report(decay_results, tmp_path):
    """D10: a full disk in a drawing child gave its traceback and RuntimeError "a process drawing them failed"
    (exit 1). A real full disk (a 2 MiB tmpfs holding the old report, filled but for 200 to 400 KiB, where the
    plots are drawn): "cannot write the report" in one line (exit 2), the old report byte for byte, no
    staging folder left."""
    with mounted_tmpfs(tmp_path, "2m") as disk:
        report = disk / "rep"
        first = subprocess.run([UQFLIGHT, "report", str(decay_results), "--out", str(report)], capture_output=True,
                               text=True, timeout=300)
        assert first.returncode == 0, first.stderr
        old = _snapshot(report)
        for free in (200, 300, 400):
            (disk / "filler").unlink(missing_ok=True)
            with open(disk / "filler", "wb") as fh:
                fh.write(b"\0" * max(shutil.disk_usage(disk).free - free * 1024, 0))
            done = subprocess.run([UQFLIGHT, "report", str(decay_results), "--out", str(report)], capture_output=True,
                                  text=True, timeout=300)
            assert done.returncode == 2, (free, done.stderr)
            errors = [line for line in done.stderr.splitlines() if "rror" in line or "Traceback" in line]
            assert errors == ["error: cannot write the report: [Errno 28] No space left on device"], (free, done.stderr)
            assert _snapshot(report) == old
            assert sorted(p.name for p in disk.iterdir()) == ["filler", "rep"]


@pytest.mark.slow
def test_a_quantity_whose_powers_overflow_is_null_with_a_note(tmp_path):
    """D09 for a quantity of interest (one number per run, edited to 1e200 with h5py): its statistics are null in
    summary.json and a note says why; the outputs' report goes on."""
    import h5py

    (tmp_path / "model.py").write_text(MODEL.format(scale="1.0"))
    out = run_python_campaign(tmp_path, CAMPAIGN + "quantities: {final_x: {of: x, take: final}}\n")
    with h5py.File(out, "a") as f:
        f["quantities/final_x"][...] = 1e200 * f["quantities/final_x"][()]
    done = cli_in_process("report", out, "--out", tmp_path / "rep")
    assert done.returncode == 0, done.stderr
    summary = read_summary(tmp_path / "rep" / "summary.json")
    q = summary["quantities"]["final_x"]
    assert q["mean"] is None and q["variance"] is None, q
    assert any(note.startswith("quantity final_x holds values up to ") and "its statistics are null" in note
               for note in summary["notes"]), summary["notes"]
    assert summary["outputs"]["x"]["mean"][0] == pytest.approx(2.0, rel=1e-12)
