"""Morris's elementary-effects screening (design kind `morris`): closed forms through the whole tool,
then SALib's `analyze.morris` on the design's own trajectories and outputs. Each tolerance says why."""
import numpy as np
import pytest

from conftest import DATA, run_python_campaign, strict_json
from uqflight.designs import build_design
from uqflight.designs.morris import morris_germs, morris_jump, morris_unit_points
from uqflight.analysis.statistics import analyse, summary_json
from uqflight.store import ResultStore

MODELS = DATA / "morris_models.py"
UNIFORM = ("  x1: {distribution: uniform, lower: 0, upper: 1}\n"
           "  x2: {distribution: uniform, lower: -1, upper: 1}\n"
           "  x3: {distribution: uniform, lower: 2, upper: 6}\n")
PI = 3.141592653589793
MIXED = (f"  x1: {{distribution: uniform, lower: {-PI}, upper: {PI}}}\n"
         f"  x2: {{distribution: uniform, lower: {-PI}, upper: {PI}}}\n"
         "  x3: {distribution: normal, lower: -3, upper: 3}\n")


def campaign(function: str, parameters: str, design: str = "{kind: morris, trajectories: 12}", seed: int = 5,
             bootstrap: int = 100) -> str:
    return (f"name: morris\nseed: {seed}\nsimulator: {{kind: python, function: \"{MODELS}:{function}\"}}\n"
            f"parameters:\n{parameters}design: {design}\nmethod: {{kind: monte_carlo}}\n"
            "quantities: {final: {of: y, take: final}}\n"
            f"analysis: {{band_samples: 500, bootstrap: {bootstrap}}}\n")


def test_the_trajectories_lie_on_the_grid_and_move_each_input_once_by_the_jump():
    u = morris_unit_points(7, 4, 6, seed=3)
    assert u.shape == (7 * 5, 4)
    levels = u * 5
    np.testing.assert_array_equal(levels, np.rint(levels))  # exactly on the 6-level grid
    assert u.min() >= 0.0 and u.max() <= 1.0
    steps = np.diff(u.reshape(7, 5, 4), axis=1)
    assert ((steps != 0).sum(axis=2) == 1).all()  # one input per step
    assert ((steps != 0).sum(axis=1) == 1).all()  # each input once per trajectory
    np.testing.assert_allclose(np.abs(steps[steps != 0]), morris_jump(6), rtol=1e-15)


def test_a_linear_model_gives_mu_star_the_coefficient_times_the_range_and_no_sigma(tmp_path):
    # y = (1 + t)(2 x1 − 3 x2 + 0.5 x3) on ranges 1, 2, 4: every EE_i is (1 + t) a_i (h_i − l_i), exact to
    # rounding (1e-12 relative: a difference of two runs divided by Δ); σ is rounding noise (< 1e-12)
    stats = analyse(run_python_campaign(tmp_path, campaign("linear", UNIFORM)))
    effect = {"x1": 2.0 * 1, "x2": -3.0 * 2, "x3": 0.5 * 4}
    growth = 1.0 + np.linspace(0.0, 1.0, 3)
    for name, value in effect.items():
        found = stats.outputs["y"].screening.measures[name]
        np.testing.assert_allclose(found["mu_star"], abs(value) * growth, rtol=1e-12)
        np.testing.assert_allclose(found["mu"], value * growth, rtol=1e-12)
        np.testing.assert_allclose(found["sigma"], 0.0, atol=1e-12)
        np.testing.assert_allclose([found["mu_star_ci"]["lower"], found["mu_star_ci"]["upper"]],
                                   [abs(value) * growth] * 2, rtol=1e-12)
        final = stats.quantities["final"].output.screening.measures[name]
        assert final["mu_star"][0] == pytest.approx(abs(value) * 2, rel=1e-12)
    summary = strict_json(summary_json(stats))
    assert summary["quantities"]["final"]["morris"]["x2"]["mu"] == pytest.approx(-12.0, rel=1e-12)
    assert len(summary["outputs"]["y"]["morris"]["x3"]["mu_star_ci"]["upper"]) == 3
    assert summary["outputs"]["y"]["sobol_first"] == {}  # no Sobol' indices from a Morris design
    assert any("not draws of the inputs' law" in note for note in summary["notes"])
    assert summary["failure_probability"]["lower"] is None  # the share of fixed points has no interval


def test_an_interaction_gives_sigma_to_the_interacting_inputs_only(tmp_path):
    # y = x1 + (1 + t) x2 x3: x1's effect is 1 on every step (σ rounding noise, < 1e-12); x2's is (1 + t) x3 · 2
    # over the trajectories' x3 levels, which differ (σ well above 0), and x3's likewise
    stats = analyse(run_python_campaign(tmp_path, campaign("interaction", UNIFORM)))
    found = stats.outputs["y"].screening.measures
    np.testing.assert_allclose(found["x1"]["sigma"], 0.0, atol=1e-12)
    np.testing.assert_allclose(found["x1"]["mu_star"], 1.0, rtol=1e-12)
    assert (found["x2"]["sigma"] > 0.1).all() and (found["x3"]["sigma"] > 0.1).all()


def salib_measures(u: np.ndarray, y: np.ndarray, levels: int) -> dict:
    """SALib's μ*, μ, σ of outputs `y` at the unit-cube trajectories `u`."""
    from SALib.analyze import morris

    problem = {"num_vars": u.shape[1], "names": [f"x{i + 1}" for i in range(u.shape[1])],
               "bounds": [[0.0, 1.0]] * u.shape[1]}
    return morris.analyze(problem, u, y, num_levels=levels, num_resamples=10, seed=1)


@pytest.mark.parametrize("levels", [4, 6])
def test_mu_star_mu_and_sigma_equal_salibs_on_the_same_trajectories(tmp_path, levels):
    # the design's germs are its unit-cube trajectories through each germ's quantile (checked exactly); SALib's
    # analyze on those trajectories and the same outputs gives μ*, μ, σ equal to rounding (1e-12 relative)
    text = campaign("nonlinear", MIXED, f"{{kind: morris, trajectories: 10, levels: {levels}}}")
    path = run_python_campaign(tmp_path, text)
    stats = analyse(path)
    u = morris_unit_points(10, 3, levels, seed=5)
    with ResultStore.open(path) as store:
        np.testing.assert_array_equal(store.xi, morris_germs(u, ["uniform", "uniform", "normal"], levels))
        y = store.output_matrix("y", np.arange(len(u)))
    for t in range(3):
        expected = salib_measures(u, y[:, t], levels)
        for i, name in enumerate(("x1", "x2", "x3")):
            found = stats.outputs["y"].screening.measures[name]
            for key in ("mu_star", "mu", "sigma"):
                assert found[key][t] == pytest.approx(expected[key][i], rel=1e-12, abs=1e-12), (key, name, t)


def test_a_trajectory_with_a_failed_run_is_dropped_and_counted(tmp_path):
    # the runs where x1 > 2.5 fail: the trajectories holding one are dropped whole, and SALib on the complete
    # trajectories alone gives the same μ*, μ, σ (1e-12)
    path = run_python_campaign(tmp_path, campaign("failing", MIXED, "{kind: morris, trajectories: 16}"))
    stats = analyse(path)
    u = morris_unit_points(16, 3, 4, seed=5)
    with ResultStore.open(path) as store:
        ok = store.status == 0
        complete = ok.reshape(16, 4).all(axis=1)
        y = store.output_matrix("y", np.flatnonzero(np.repeat(complete, 4)))
    dropped = int((~complete).sum())
    assert 0 < dropped < 14
    assert any(f"{16 - dropped} complete trajectories of 16" in note and f"{dropped} dropped" in note
               for note in stats.notes)
    expected = salib_measures(u[np.repeat(complete, 4)], y[:, 2], 4)
    for i, name in enumerate(("x1", "x2", "x3")):
        for key in ("mu_star", "mu", "sigma"):
            assert stats.outputs["y"].screening.measures[name][key][2] == pytest.approx(expected[key][i], rel=1e-12)


@pytest.mark.slow
def test_the_same_seed_gives_the_same_bits_and_another_seed_other_trajectories(tmp_path):
    spec = {"kind": "morris", "trajectories": 5, "levels": 4}
    germs = ["uniform", "normal", "uniform"]
    first, again, other = (build_design(spec, germs, seed) for seed in (7, 7, 8))
    assert first.xi.tobytes() == again.xi.tobytes()
    assert not np.array_equal(first.xi, other.xi)
    # the bootstrap of μ* follows the campaign's seed: same bits twice, other intervals with another seed
    runs = [analyse(run_python_campaign(tmp_path / f"s{i}", campaign("nonlinear", MIXED, seed=seed)))
            for i, seed in enumerate((5, 5, 6)) if (tmp_path / f"s{i}").mkdir() is None]
    summaries = [strict_json(summary_json(stats))["outputs"]["y"]["morris"] for stats in runs]
    assert summaries[0] == summaries[1]
    assert summaries[0]["x1"]["mu_star_ci"] != summaries[2]["x1"]["mu_star_ci"]


@pytest.mark.parametrize("design, field", [
    ({"kind": "morris", "trajectories": 1}, "design.trajectories"),
    ({"kind": "morris", "trajectories": 4, "levels": 5}, "design.levels"),
    ({"kind": "morris", "trajectories": 4, "samples": 3}, "design.samples"),
])
def test_a_bad_morris_design_is_refused_naming_its_field(design, field):
    with pytest.raises(ValueError, match=f"^{field}: "):
        build_design(design, ["uniform", "normal"], 0)


@pytest.mark.parametrize("info, field", [({"trajectories": 12, "levels": 3}, "design.info.levels"),
                                         ({"trajectories": 11, "levels": 4}, "design.info.trajectories")])
def test_a_design_info_that_does_not_fit_the_runs_is_refused_in_one_line(tmp_path, info, field):
    import json

    import h5py
    from conftest import cli_in_process

    path = run_python_campaign(tmp_path, campaign("linear", UNIFORM))
    with h5py.File(path, "a") as f:
        record = json.loads(f.attrs["record"])
        record["design"]["info"] = info
        f.attrs["record"] = json.dumps(record)
    done = cli_in_process("report", path, "--out", tmp_path / "report")
    assert done.returncode == 2 and "Traceback" not in done.stdout + done.stderr
    line, = done.stderr.strip().splitlines()
    assert line.startswith(f"error: {path}: ") and field in line, line


def test_measures_without_trajectories_are_null_and_sigma_needs_two():
    from uqflight.designs.morris import morris_measures
    from uqflight.analysis.statistics import json_ready

    none = json_ready(morris_measures(np.empty((0, 2, 3)), n_boot=10, seed=0))
    assert none["mu_star"] == [[None] * 3] * 2 and none["sigma"] == [[None] * 3] * 2
    one = morris_measures(np.ones((1, 2, 3)), n_boot=10, seed=0)
    assert (one["mu_star"] == 1.0).all() and np.isnan(one["sigma"]).all()


@pytest.mark.slow
def test_the_report_plots_mu_star_against_sigma_and_ranks_the_inputs_in_the_headline(tmp_path):
    # y(t) = (1 + t)(2 x1 − 3 x2 + 0.5 x3) on ranges 1, 2, 4: μ* at t = 1 is 4, 12 and 4, x2 first
    from conftest import cli_in_process

    path = run_python_campaign(tmp_path, campaign("linear", UNIFORM))
    done = cli_in_process("report", path, "--out", tmp_path / "report")
    assert done.returncode == 0, done.stderr
    page = (tmp_path / "report" / "report.md").read_text()
    assert "## Morris screening" in page and "plots/morris_c.png" in page
    assert "| inputs ranked by μ\\* (Morris) |" in page and "x2 12, " in page
    assert (tmp_path / "report" / "plots" / "morris_c.png").stat().st_size > 10_000
    table = (tmp_path / "report" / "tables" / "morris.csv").read_text().splitlines()
    assert table[0].startswith("file,output or quantity,parameter,mu_star")


def test_morris_lives_in_three_files():
    """The proof of extension: the design (designs/morris.py), its import (designs/__init__.py) and its page
    (report/screenings/morris.py) are all the code that names it; the statistics, summary.json and the report
    reach it through the design kind's screening hook and name (a docstring's example does not count)."""
    import ast
    from pathlib import Path

    package = Path(__file__).resolve().parents[1] / "uqflight"
    naming = set()
    for path in package.rglob("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        docstrings = {id(node.body[0].value) for node in ast.walk(tree)
                      if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef))
                      and node.body and isinstance(node.body[0], ast.Expr)
                      and isinstance(node.body[0].value, ast.Constant)}
        for node in ast.walk(tree):
            words = (node.id if isinstance(node, ast.Name) else node.attr if isinstance(node, ast.Attribute)
                     else node.value if isinstance(node, ast.Constant) and isinstance(node.value, str)
                     and id(node) not in docstrings else
                     " ".join(a.name for a in node.names) + " " + (getattr(node, "module", None) or "")
                     if isinstance(node, (ast.Import, ast.ImportFrom)) else "")
            if "morris" in words.lower() and "sherman" not in words.lower():
                naming.add(str(path.relative_to(package)))
    assert naming == {"designs/morris.py", "designs/__init__.py", "report/screenings/morris.py"}
