"""Sparse PCE (methods.sparse): a 20-input model with a known sparse polynomial structure, OpenTURNS's LARS on
the same points, a time-dependent closed form through the whole tool (campaign, HDF5, summary.json, the
surrogate export), and the refusals."""
import json

import numpy as np
import pytest

from uqflight.calibration.surrogate import calibration_surrogate
from uqflight.campaign import CampaignError, parse_campaign
from uqflight.designs import build_design
from uqflight.running.runner import run_campaign
from uqflight.methods import MethodSpec, fit
from uqflight.methods.basis import orthonormal_basis
from uqflight.methods.loo import relative_loo_error
from uqflight.methods.sparse import hyperbolic_indices
from uqflight.methods.validity import method_problem
from uqflight.methods.parsing import parse_methods
from uqflight.analysis.statistics import analyse, summary_json

D = 20
GERMS = ["uniform"] * D
# y = Σ c_α Ψ_α(ξ) with 7 of the 1771 Legendre terms of total degree ≤ 3 in 20 inputs
TRUE_TERMS = {(): 1.5, ((0, 1),): 2.0, ((2, 2),): 1.0, ((4, 1), (6, 1)): 0.8, ((1, 3),): 0.6, ((9, 1),): 0.4,
              ((3, 1), (12, 1)): 0.3}


def _true_case():
    indices = np.zeros((len(TRUE_TERMS), D), dtype=int)
    for row, term in enumerate(TRUE_TERMS):
        for k, power in term:
            indices[row, k] = power
    return indices, np.array(list(TRUE_TERMS.values()))


def test_the_corrected_loo_error_of_every_prefix_is_chapelles_from_the_plain_leave_one_out_error():
    # one QR for every prefix against the direct formula per prefix: ε_LOO (methods.loo, summed over the
    # columns) · N / (N − Z) · (1 + tr((ΨᵀΨ)⁻¹)); rounding only (1e-12)
    from uqflight.methods.sparse import _corrected_loo

    rng = np.random.default_rng(0)
    X, y = rng.normal(size=(40, 6)), rng.normal(size=(40, 3))
    X[:, 0] = 1
    deviations = ((y - y.mean(axis=0)) ** 2).sum(axis=0)
    for z, error in enumerate(_corrected_loo(X, y), start=1):
        plain = (relative_loo_error(X[:, :z], y) * deviations).sum() / deviations.sum()
        correction = 40 / (40 - z) * (1 + np.trace(np.linalg.inv(X[:, :z].T @ X[:, :z])))
        assert error == pytest.approx(plain * correction, rel=1e-12)


def test_sparse_pce_recovers_a_sparse_20_input_polynomial_where_least_squares_is_refused():
    # The model is in the candidate basis, so the fit is exact up to rounding: 1e-6 is far above the
    # ~1e-14 of a least-squares solve on 200 points, and far below any missed or spurious term (>= 0.09
    # of the variance each).
    indices, c = _true_case()
    design = build_design({"kind": "sobol", "samples": 200}, GERMS, 1)
    Y = orthonormal_basis(GERMS, indices, design.xi) @ c
    assert "rank" in method_problem("least_squares", 3, design.xi, design.weights, GERMS, sampled=True)
    result = fit("sparse", design.xi, design.weights, Y, GERMS, 3, sampled=True, settings={"selection": "lars"})
    variance = (c[1:] ** 2).sum()
    assert result.mean[0] == pytest.approx(c[0], abs=1e-6)
    assert result.variance[0] == pytest.approx(variance, abs=1e-6)
    first = np.zeros(D)
    for term, value in list(TRUE_TERMS.items())[1:]:
        if len(term) == 1:
            first[term[0][0]] += value**2 / variance
    np.testing.assert_allclose(result.pce.sobol_first()[:, 0], first, atol=1e-6)
    assert sorted(map(tuple, result.pce.indices.tolist())) == sorted(map(tuple, indices.tolist()))
    assert result.pce.selection["order"] == 3 and result.pce.selection["loo_error"] < 1e-20


def test_omp_and_hyperbolic_candidates_recover_a_small_sparse_polynomial():
    # 5 inputs, q = 0.75 at order 3: ξ1 ξ2 stays in ((1 + 1)^(4/3) = 2.52), ξ1 ξ2² goes ((1 + 2^0.75)^(4/3)
    # = 3.72 > 3), the pure powers stay; the exact fit's tolerance as above.
    germs = ["normal"] * 5
    kept = set(map(tuple, hyperbolic_indices(5, 3, 0.75).tolist()))
    assert (1, 1, 0, 0, 0) in kept and (1, 2, 0, 0, 0) not in kept and (0, 0, 3, 0, 0) in kept
    indices = np.array([[0, 0, 0, 0, 0], [1, 0, 0, 0, 0], [0, 0, 3, 0, 0], [0, 1, 0, 0, 1]])
    c = np.array([0.5, 1.0, 0.3, -0.7])
    design = build_design({"kind": "latin_hypercube", "samples": 60}, germs, 2)
    Y = orthonormal_basis(germs, indices, design.xi) @ c
    result = fit("sparse", design.xi, design.weights, Y, germs, 3, sampled=True,
                 settings={"selection": "omp", "q": 0.75})
    assert sorted(map(tuple, result.pce.indices.tolist())) == sorted(map(tuple, indices.tolist()))
    assert result.variance[0] == pytest.approx((c[1:] ** 2).sum(), rel=1e-9)


@pytest.mark.slow
def test_sparse_pce_agrees_with_openturns_lars_within_both_leave_one_out_errors():
    # A smooth non-polynomial model of 6 uniform inputs on 200 Sobol' points, order <= 5 total degree: both
    # methods are truncated fits. For a fit f^ with relative error ε = E[(f - f^)²] / var f,
    # |var f^ − var f| <= (2 √ε + ε) var f, so two fits differ by at most the sum of their bounds; the same
    # bound holds for each first-order share S_i var f. ε is each method's own leave-one-out error.
    ot = pytest.importorskip("openturns")
    d, order = 6, 5
    germs = ["uniform"] * d
    design = build_design({"kind": "sobol", "samples": 200}, germs, 3)
    x = design.xi
    y = np.exp(0.3 * x[:, 0]) + np.sin(1.5 * x[:, 1]) + 0.5 * x[:, 2] * x[:, 3] + 0.2 * x[:, 4] ** 2
    ours = fit("sparse", x, design.weights, y, germs, order, sampled=True, settings={"selection": "lars"}).pce
    ours_loo = float(relative_loo_error(orthonormal_basis(germs, ours.indices, x), y))

    distribution = ot.JointDistribution([ot.Uniform(-1.0, 1.0)] * d)
    enumerate_function = ot.LinearEnumerateFunction(d)
    basis = ot.OrthogonalProductPolynomialFactory([ot.LegendreFactory()] * d, enumerate_function)
    size = enumerate_function.getStrataCumulatedCardinal(order)
    selection = ot.LeastSquaresMetaModelSelectionFactory(ot.LARS(), ot.CorrectedLeaveOneOut())
    algorithm = ot.FunctionalChaosAlgorithm(ot.Sample(x), ot.Sample(y[:, None]), distribution,
                                            ot.FixedStrategy(basis, size), ot.LeastSquaresStrategy(selection))
    algorithm.run()
    theirs = algorithm.getResult()
    functions = theirs.getReducedBasis()
    matrix = np.column_stack([np.asarray(f(ot.Sample(x))).ravel() for f in functions])
    their_loo = float(relative_loo_error(matrix, y))
    sobol = ot.FunctionalChaosSobolIndices(theirs)
    their_variance = float(ot.FunctionalChaosRandomVector(theirs).getCovariance()[0, 0])

    bound = sum(2 * np.sqrt(e) + e for e in (ours_loo, their_loo))
    assert ours_loo < 1e-3 and their_loo < 1e-3
    assert abs(ours.variance()[0] - their_variance) <= bound * their_variance
    for i in range(d):
        assert abs(ours.sobol_first()[i, 0] - sobol.getSobolIndex(i)) * their_variance <= bound * their_variance


DECAY = """
name: decay-sparse
seed: 5
simulator: {{kind: python, function: "uqflight.simulators.models:exp_decay"}}
parameters:
  a: {{distribution: normal, lower: 0.7, upper: 1.3}}
  b: {{distribution: uniform, lower: 0, upper: 1}}
design: {{kind: sobol, samples: 64}}
method: {method}
execution: {{workers: 1}}
analysis: {{band_samples: 500, bootstrap: 0}}
storage: {storage}
"""


@pytest.mark.parametrize("raw", [True, pytest.param(False, marks=pytest.mark.slow)])
def test_a_time_dependent_output_gets_one_basis_its_summary_and_its_export(tmp_path, raw):
    # x(t) = exp(−a t), a ~ N(1, 0.1²): E = exp(−t + 0.005 t²); b is inert. Order ≤ 5 in a on 64 points: the
    # truncation error of exp's expansion in 0.1 ξ t is below (0.5)^6/6! ~ 2e-5 of the mean; 1e-4 of the
    # variance is its square's order. raw: False stores the runs as tSVD factors (the fit gets them).
    from uqflight.simulators.models import DECAY_TIME
    from uqflight.analysis.surrogate import export, load

    text = DECAY.format(method="{kind: sparse, selection: lars, max_order: 5, q: 1}", 
                        storage="{raw: true}" if raw else "{raw: false, tsvd: {tol: 1.0e-12, batch: 64}}")
    path = tmp_path / "decay.h5"
    run_campaign(parse_campaign(text, str(tmp_path / "decay.yaml")), out=path)
    stats = analyse(path)
    out = stats.outputs["x"]
    mean = np.exp(-DECAY_TIME + 0.005 * DECAY_TIME**2)
    variance = np.exp(-2 * DECAY_TIME + 0.02 * DECAY_TIME**2) - mean**2
    np.testing.assert_allclose(out.mean, mean, atol=1e-4)
    np.testing.assert_allclose(out.variance, variance, atol=1e-4 * variance.max())
    assert np.nanmax(out.sobol_total["b"]) < 1e-6  # b is inert: terms in it may enter, but carry nothing
    summary = json.loads(json.dumps(summary_json(stats), allow_nan=False))
    assert summary["outputs"]["x"]["selection"]["terms"] == out.pce.indices.tolist()
    export(path, tmp_path / "pce.json")
    surrogate = load(tmp_path / "pce.json")
    xi = np.array([[0.3, -0.5], [-1.0, 0.2]])
    np.testing.assert_allclose(surrogate.evaluate(xi=xi)["x"], out.pce.evaluate(xi), rtol=1e-12)
    calibration = calibration_surrogate(path)  # the calibration carries the same basis and coefficients
    np.testing.assert_array_equal(calibration.output_indices["x"], out.pce.indices)
    np.testing.assert_allclose(calibration.basis(xi) @ calibration.coefficients["x"], out.pce.evaluate(xi), rtol=1e-12)


@pytest.mark.parametrize("method, field", [
    ("{kind: sparse, order: 3}", "method.order"),
    ("{kind: sparse, selection: lasso}", "method.selection"),
    ("{kind: sparse, q: 1.5}", "method.q"),
    ("{kind: sparse, max_order: 0}", "method.max_order"),
])
def test_a_bad_sparse_method_is_refused_naming_its_key(tmp_path, method, field):
    with pytest.raises(CampaignError, match=field.replace(".", r"\.")):
        parse_campaign(DECAY.format(method=method, storage="{raw: true}"), str(tmp_path / "bad.yaml"))


def test_the_cli_form_of_a_sparse_method():
    assert parse_methods(["sparse:4:selection=omp,q=0.75"]) == [
        MethodSpec("sparse", 4, settings=(("selection", "omp"), ("q", 0.75)))]
    with pytest.raises(ValueError, match="selection"):
        parse_methods(["sparse:4:selection=lasso"])
    with pytest.raises(ValueError, match="KEY one of"):
        parse_methods(["least_squares:2:q=1"])
