"""uqflight.methods.exactness: polynomial exactness and design-matrix rank measured on the points, and
`plan` and `report` refusing a projection or a fit the points cannot carry."""
import numpy as np
import pytest
from conftest import NORMAL_2D, cli_in_process, closed_form_campaign, run_python_campaign

from uqflight.designs import build_design
from uqflight.methods.exactness import (
    design_matrix_rank,
    exact_total_degree,
    max_projection_order,
    quadrature_errors,
)
from uqflight.methods.basis import orthonormal_basis, total_degree_indices
from uqflight.analysis.statistics import analyse
from uqflight.methods import MethodSpec


@pytest.mark.parametrize("points", [1, 2, 3, 5, 8])
def test_gauss_tensor_grids_are_exact_to_2n_minus_1(points):
    germs = ["normal", "uniform"]
    design = build_design({"kind": "tensor_grid", "points": points}, germs, 0)
    assert exact_total_degree(design.xi, design.weights, germs, max_degree=30) == 2 * points - 1
    assert design.info["degree"] == 2 * points - 1


@pytest.mark.parametrize("germs", [["normal"], ["uniform"] * 3, ["normal", "uniform", "normal"], ["normal"] * 7])
@pytest.mark.parametrize("nested", [None, True])
def test_smolyak_grids_reach_the_degree_design_info_claims(germs, nested):
    # Linear growth: the code's level L (0 = the centre point) is exact to 2L + 1, i.e. the paper's
    # level ℓ = L + 1 to 2ℓ − 1. Nested rules (Genz–Keister, Patterson) take their smallest member
    # that is exact enough, so they may exceed it (1-D Genz–Keister level 1 is 3 points: degree 5).
    for level in range(3 if len(germs) == 7 else 4):
        spec = {"kind": "sparse_grid", "level": level, **({"nested": True} if nested else {})}
        design = build_design(spec, germs, 0)
        measured = exact_total_degree(design.xi, design.weights, germs, max_degree=20)
        assert measured == design.info["degree"]
        assert measured == 2 * level + 1 if not nested else measured >= 2 * level + 1


def test_the_first_degree_missed_is_missed_by_the_closed_form_amount():
    # n-point Gauss–Hermite: He_n vanishes at the nodes and He_n² = He_2n + (terms of degree < 2n, which
    # integrate exactly) + n!, so Q[He_n²] = 0 forces Q[He_2n] = −n!: the orthonormal p_2n = He_2n/√(2n)!
    # is missed by n!/√(2n)! (1/√20 for n = 3), O(1) of the sum's scale, far beyond √eps.
    design = build_design({"kind": "tensor_grid", "points": 3}, ["normal"], 0)
    error, scale = quadrature_errors(design.xi, design.weights, ["normal"], 6)
    assert error[0] == pytest.approx(1 / np.sqrt(20.0), rel=1e-12)
    assert error[0] > 0.01 * scale[0]
    assert np.all(quadrature_errors(design.xi, design.weights, ["normal"], 4)[0] < 1e-14)


def test_monte_carlo_points_integrate_only_the_constant():
    # Equal weights summing to 1 make degree 0 exact; E[ξ] = 0 is missed by ~1/√N ≫ √eps.
    for kind in ("monte_carlo", "sobol", "latin_hypercube"):
        design = build_design({"kind": kind, "samples": 1000}, ["normal", "uniform"], 0)
        assert exact_total_degree(design.xi, design.weights, ["normal", "uniform"]) == 0
    design = build_design({"kind": "monte_carlo", "samples": 10}, ["normal"], 0)
    assert exact_total_degree(design.xi, 2 * design.weights, ["normal"]) == -1  # weights summing to 2


def test_max_projection_order_needs_twice_the_order():
    assert [max_projection_order(p) for p in (-1, 0, 1, 2, 3, 5, 7)] == [-1, 0, 0, 1, 1, 2, 3]
    # On a grid exact to degree 5, the order-2 pseudo-Galerkin Gram matrix Σ w Ψ_α Ψ_β is I; order 3 is not.
    germs = ["uniform"] * 3
    design = build_design({"kind": "sparse_grid", "level": 2}, germs, 0)
    order = max_projection_order(exact_total_degree(design.xi, design.weights, germs))
    assert order == 2
    for p, is_identity in ((order, True), (order + 1, False)):
        psi = orthonormal_basis(germs, total_degree_indices(3, p), design.xi)
        gram = psi.T @ (design.weights[:, None] * psi)
        assert np.allclose(gram, np.eye(len(gram)), atol=1e-12) == is_identity


def test_rank_of_3d_gauss_legendre_sparse_level_2_order_3_is_19_of_20():
    # 25 points, 20 basis functions, yet rank 19: every point has a coordinate at the 1-point
    # rule's node 0 (at most two dimensions leave level 1 when |j| ≤ 2), so Ψ_(1,1,1) ∝ ξ1ξ2ξ3
    # vanishes on the whole grid and its coefficient is undetermined.
    germs = ["uniform"] * 3
    design = build_design({"kind": "sparse_grid", "level": 2}, germs, 0)
    assert len(design.xi) == 25
    assert design_matrix_rank(design.xi, germs, 3) == (19, 20)
    assert design_matrix_rank(design.xi, germs, 3, design.weights) == (19, 20)
    assert np.all(np.prod(design.xi, axis=1) == 0)
    assert design_matrix_rank(design.xi, germs, 2) == (10, 10)


def test_rank_of_full_and_deficient_designs():
    germs = ["normal", "normal"]
    tensor = build_design({"kind": "tensor_grid", "points": 3}, germs, 0)
    assert design_matrix_rank(tensor.xi, germs, 2) == (6, 6)
    assert design_matrix_rank(tensor.xi, germs, 4) == (9, 15)  # 9 points can carry at most 9 terms
    # A zero weight removes its point from a weighted fit.
    weights = tensor.weights.copy()
    weights[:4] = 0.0
    assert design_matrix_rank(tensor.xi, germs, 4, weights)[0] == 5
    assert design_matrix_rank(np.zeros((0, 2)), germs, 1) == (0, 3)


def test_plan_refuses_a_projection_the_grid_cannot_integrate(tmp_path):
    text = closed_form_campaign("alias", "sum_of_squares", NORMAL_2D, "{kind: sparse_grid, level: 1}",
                    "method: {kind: pseudo_galerkin, order: 2}\n")
    (tmp_path / "a.yaml").write_text(text)
    plan = cli_in_process("plan", tmp_path / "a.yaml")
    assert plan.returncode == 2
    assert "method.order" in plan.stderr and "exact to degree 3" in plan.stderr
    assert "largest order it can project is 1" in plan.stderr
    (tmp_path / "b.yaml").write_text(text.replace("order: 2}", "order: 2, allow_aliasing: true}"))
    assert cli_in_process("plan", tmp_path / "b.yaml").returncode == 0


def test_report_refuses_an_aliased_order_unless_allowed(tmp_path):
    results = run_python_campaign(tmp_path, closed_form_campaign("l1", "sum_of_squares", NORMAL_2D,
                                                     "{kind: sparse_grid, level: 1}"))
    refused = cli_in_process("report", results, "--method", "pseudo_galerkin", "--order", "4", "--out", tmp_path / "r")
    assert refused.returncode == 2 and "exact to degree 3" in refused.stderr
    allowed = analyse(results, method=MethodSpec("pseudo_galerkin", 4), allow_aliasing=True)
    assert any("aliasing allowed" in note for note in allowed.notes)


def test_plan_refuses_a_rank_deficient_least_squares_fit(tmp_path):
    uniform = "".join(f"  x{i}: {{distribution: uniform, lower: -1, upper: 1}}\n" for i in (1, 2, 3))
    (tmp_path / "r.yaml").write_text(closed_form_campaign("rank", "sum_of_squares", uniform,
                                              "{kind: sparse_grid, level: 2, rule: gauss_legendre}",
                                              "method: {kind: least_squares, order: 3}\n"))
    plan = cli_in_process("plan", tmp_path / "r.yaml")
    assert plan.returncode == 2 and "rank 19" in plan.stderr and "method.order" in plan.stderr
