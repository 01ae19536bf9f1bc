"""`uqflight surrogate export`: the PCE written as strict JSON, read back by `uqflight.analysis.surrogate.load`,
gives the campaign's moments and the fitted expansion at any point, in ξ or in physical values."""
import json

import numpy as np
import pytest
from conftest import cli_in_process

from uqflight.methods.basis import orthonormal_basis
from uqflight.analysis.statistics import analyse
from uqflight.analysis.surrogate import fit_surrogate, load


def test_surrogate_export_round_trip(decay_results, tmp_path):
    out = tmp_path / "pce.json"
    result = cli_in_process("surrogate", "export", decay_results, "--out", out)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == f"wrote {out}"
    data = json.loads(out.read_text(), parse_constant=lambda c: pytest.fail(f"not strict JSON: {c}"))
    assert data["method"] == "pseudo_galerkin" and data["order"] == 2 and len(data["germs"]) == 2
    assert [p["name"] for p in data["parameters"]] == ["a", "b"] and data["parameters"][1]["nominal"] == 1.4
    surrogate = load(out)
    stats = analyse(decay_results)
    np.testing.assert_allclose(surrogate.mean()["x"], stats.outputs["x"].mean, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(surrogate.variance()["x"], stats.outputs["x"].variance, rtol=1e-10, atol=1e-15)
    rng = np.random.default_rng(1)
    xi = np.column_stack([rng.standard_normal(50), rng.uniform(-1, 1, 50)])
    fitted = fit_surrogate(decay_results)
    expected = orthonormal_basis(fitted.germs, fitted.indices["x"], xi) @ fitted.coefficients["x"]
    np.testing.assert_allclose(surrogate.evaluate(xi=xi)["x"], expected, rtol=1e-12, atol=1e-14)
    kappa = np.column_stack([1.0 + xi[:, 0] / 6, 1.5 + 0.5 * xi[:, 1]])
    np.testing.assert_allclose(surrogate.evaluate(kappa)["x"], expected, rtol=1e-12, atol=1e-14)
    # a quadratic PCE of exp(-a t) · b is close to the model itself at the nominal point
    time = np.asarray(data["time"])
    near = surrogate.evaluate([[1.0, 1.5]])["x"][0]
    assert near.shape == time.shape
    mc = cli_in_process("surrogate", "export", decay_results, "--out", tmp_path / "mc.json", "--method", "monte_carlo")
    assert mc.returncode == 2 and "needs a sampled design" in mc.stderr and not (tmp_path / "mc.json").exists()
