"""Bayesian calibration (`uqflight calibrate`) on a closed-form python model whose posterior is known.

Model: y(t) = a + b t + 1e-4 c t² and z(t) = a − b t on t in [0, 2] (21 times). a and b are
normal, so with known noise the posterior of (a, b) is Gaussian in closed form (the c term moves y by
at most 4e-4, a hundredth of the noise: c stays at its uniform prior). The PCE of order 2 contains
the model exactly, so the surrogate error is rounding noise.

On a one-output campaign: calibration data too large for memory, a byte-order mark, a repeated --noise
are refused up front with one message, and Ctrl-C during sampling exits 130 with one line.
"""
import json
import math
import os
import signal
import shutil
import subprocess
import time

import h5py
import numpy as np
import pytest
import typer
from conftest import CLOSED_FORMS, NORMAL_2D, UQFLIGHT, cli_in_process, closed_form_campaign, run_python_campaign
from typer.testing import CliRunner

from uqflight.calibration.command import register
from uqflight.text import Refusal
from uqflight.calibration.likelihood import (FlightData, LogPosterior, interpolate_in_time, parse_noise,
                                             read_flight_csv)
from uqflight.calibration import sampler as sampler_module
from uqflight.calibration.sampler import CHECK_EVERY, FIRST_CHECK, sample, split_rhat
from uqflight.calibration.size import MAX_STEPS
from uqflight.calibration.surrogate import calibration_surrogate
from uqflight.campaign import load_campaign, parse_campaign
from uqflight.simulators.aircraft_properties import AircraftProperties
from uqflight.running.runner import run_campaign
from uqflight.methods import MethodSpec

MODEL = '''
import h5py
import numpy as np
T = np.linspace(0.0, 2.0, 21)

def f(p):
    return {"time": T, "y": p["a"] + p["b"] * T + 1e-4 * p["c"] * T**2, "z": p["a"] - p["b"] * T}
'''
CAMPAIGN = """
name: linear-calibration
seed: 3
simulator: {kind: python, function: "model.py:f"}
parameters:
  a: {distribution: normal, nominal: 1.0, interval_pct: 30}
  b: {distribution: normal, nominal: -0.5, interval_pct: 30}
  c: {distribution: uniform, lower: -1, upper: 1}
design: {kind: latin_hypercube, samples: 40}
method: {kind: regression, order: 2}
execution: {workers: 1, chunk: 64}
"""
TIME = np.linspace(0.0, 2.0, 21)
PRIOR = {"a": (1.0, 0.1), "b": (-0.5, 0.05)}  # mean, std: ±30 % is ±3σ
TRUTH = {"a": 1.12, "b": -0.46, "c": 0.3}
SIGMA = 0.05


def model(a, b, c, t=TIME):
    return {"y": a + b * t + 1e-4 * c * t**2, "z": a - b * t}


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    folder = tmp_path_factory.mktemp("calibration")
    (folder / "model.py").write_text(MODEL)
    (folder / "campaign.yaml").write_text(CAMPAIGN)
    path = folder / "linear.h5"
    summary = run_campaign(parse_campaign(CAMPAIGN, str(folder / "campaign.yaml")), out=path)
    assert not summary.failures
    return path


def write_csv(path, time, columns: dict):
    lines = ["time_s," + ",".join(columns)]
    lines += [f"{t:g}," + ",".join(repr(float(v[i])) for v in columns.values()) for i, t in enumerate(time)]
    path.write_text("\n".join(lines) + "\n")


def synthetic(seed, time=TIME):
    rng = np.random.default_rng(seed)
    clean = model(TRUTH["a"], TRUTH["b"], TRUTH["c"], time)
    return {k: v + SIGMA * rng.standard_normal(v.size) for k, v in clean.items()}


def closed_form(data, time=TIME):
    """Gaussian posterior of (a, b), ignoring the 1e-4 c term: prior N(m0, S0), y = H θ + noise."""
    H = np.vstack([np.column_stack([np.ones_like(time), time]), np.column_stack([np.ones_like(time), -time])])
    y = np.concatenate([data["y"], data["z"]])
    m0 = np.array([PRIOR["a"][0], PRIOR["b"][0]])
    P0 = np.diag([1 / PRIOR["a"][1] ** 2, 1 / PRIOR["b"][1] ** 2])
    cov = np.linalg.inv(P0 + H.T @ H / SIGMA**2)
    return cov @ (P0 @ m0 + H.T @ y / SIGMA**2), cov


def app():
    application = typer.Typer()
    register(application)

    @application.callback()
    def main():
        """test app"""

    return application


def test_surrogate_of_a_polynomial_model_is_exact(results):
    surrogate = calibration_surrogate(results)
    assert surrogate.method == MethodSpec("regression", 2)
    assert max(float(v.max()) for v in surrogate.error_variance.values()) < 1e-20
    xi = np.array([[0.5, -1.0, 0.2]])
    expected = model(1.0 + 0.1 * 0.5, -0.5 - 0.05, 0.2)
    for name in ("y", "z"):
        np.testing.assert_allclose(surrogate.basis(xi) @ surrogate.coefficients[name], expected[name][None], atol=1e-12)


@pytest.mark.slow
def test_posterior_matches_the_closed_form(results):
    surrogate = calibration_surrogate(results)
    data = synthetic(0)
    posterior = LogPosterior.build(surrogate.time, surrogate.coefficients, surrogate.error_factors, surrogate.germs,
                                   surrogate.names, surrogate.basis, FlightData("test", TIME, data),
                                   {"y": SIGMA, "z": SIGMA})
    chain = sample(posterior, posterior.ndim, posterior.labels, posterior.start(),
                   lambda rng, n: np.column_stack([rng.standard_normal((n, 2)), rng.uniform(-1, 1, n)]),
                   walkers=32, steps=2000, seed=1)
    assert chain.diagnostics["converged"], chain.diagnostics["problems"]
    flat = chain.flat
    kappa = np.column_stack([1.0 + 0.1 * flat[:, 0], -0.5 + 0.05 * flat[:, 1]])
    mean, cov = closed_form(data)
    std = np.sqrt(np.diag(cov))
    # ~1500 effective draws: the Monte Carlo error of the mean is ~0.03 std, of the std ~2 %
    np.testing.assert_allclose(kappa.mean(axis=0), mean, atol=0.15 * std.min())
    np.testing.assert_allclose(kappa.std(axis=0), std, rtol=0.1)
    np.testing.assert_allclose(np.corrcoef(kappa, rowvar=False)[0, 1], cov[0, 1] / std.prod(), atol=0.05)
    # c is not identifiable: its posterior is its U(-1, 1) prior (std 1/sqrt(3))
    assert flat[:, 2].std() == pytest.approx(1 / math.sqrt(3), rel=0.1)


@pytest.mark.slow
def test_calibrate_end_to_end(results, tmp_path):
    data = tmp_path / "flight.csv"
    write_csv(data, TIME, synthetic(1))
    out = tmp_path / "out"
    run = CliRunner().invoke(app(), ["calibrate", str(results), "--data", str(data), "--out", str(out),
                                     "--noise", f"y={SIGMA}", "--steps", "2000", "--predictive-draws", "20"])
    assert run.exit_code == 0, run.output
    for name in ("posterior.h5", "summary.json", "calibrated.yaml", "plots/corner.png", "plots/marginals.png",
                 "plots/predictive.png"):
        assert (out / name).is_file(), name
    text = (out / "summary.json").read_text()
    assert "NaN" not in text and "Infinity" not in text
    summary = json.loads(text)
    params = summary["parameters"]
    for name in ("a", "b"):
        lower, upper = params[name]["posterior"]["ci95"]
        assert lower <= TRUTH[name] <= upper
        assert params[name]["narrowing"] > 3
        assert params[name]["prior"]["std"] == pytest.approx(PRIOR[name][1])
    assert params["c"]["std_ratio"] > 0.9  # stays at its prior
    assert set(summary["correlation"]["names"]) == {"a", "b", "c"}
    noise = summary["noise"]
    assert noise["y"]["given"] == SIGMA and noise["y"]["inferred"] is None
    lower, upper = noise["z"]["inferred"]["ci95"]  # inferred with its half-Cauchy prior
    assert lower <= SIGMA <= upper
    assert summary["diagnostics"]["converged"] and summary["diagnostics"]["steps_per_tau"] >= 50
    assert summary["predictive"]["failed"] == 0
    assert min(summary["predictive"]["coverage95"].values()) > 0.75  # 21 points per output
    calibrated = load_campaign(out / "calibrated.yaml", AircraftProperties)  # what `uqflight plan` loads
    by_name = {p.name: p for p in calibrated.parameters}
    assert by_name["a"].distribution == "normal"
    assert by_name["a"].std == pytest.approx(params["a"]["posterior"]["std"])
    assert by_name["c"].distribution == "uniform"  # kept at its prior
    import h5py

    with h5py.File(out / "posterior.h5") as f:
        assert list(f["draws/kappa"].attrs["names"]) == ["a", "b", "c"]
        np.testing.assert_allclose(f["draws/kappa"][:, 0], 1.0 + 0.1 * f["draws/xi"][:, 0])


def test_not_converged_exits_3_and_leaves_no_valid_looking_output(results, tmp_path):
    data = tmp_path / "flight.csv"
    write_csv(data, TIME, synthetic(2))
    out = tmp_path / "out"
    out.mkdir()
    (out / "summary.json").write_text("{}")  # from an earlier run, whose posterior.h5 marks the folder as its
    with h5py.File(out / "posterior.h5", "w") as f:
        f.create_group("draws")
        f.create_dataset("chain", data=np.zeros((2, 2, 1)))
    run = CliRunner().invoke(app(), ["calibrate", str(results), "--data", str(data), "--out", str(out),
                                     "--steps", "100"])
    assert run.exit_code == 3, run.output
    assert "autocorrelation times" in run.output and "--steps" in run.output
    assert not (out / "summary.json").exists()


def test_bad_input_exits_2(results, tmp_path):
    data = tmp_path / "late.csv"
    late = np.linspace(1.0, 2.5, 7)  # beyond the surrogate's 2 s
    write_csv(data, late, {"y": np.zeros(7)})
    runner = CliRunner()
    run = runner.invoke(app(), ["calibrate", str(results), "--data", str(data), "--out", str(tmp_path / "o")])
    assert run.exit_code == 2 and "outside the surrogate" in run.output
    good = tmp_path / "good.csv"
    write_csv(good, TIME, synthetic(3))
    for extra, message in ((["--noise", "y=-1"], "SIGMA > 0"), (["--noise", "w=1"], "not one of"),
                           (["--output", "w"], "not an output"), (["--walkers", "3"], "--walkers"),
                           (["--walkers", "11"], "--walkers: expected an even number, got 11"),
                           (["--steps", "50"], "--steps: expected at least 100, got 50")):
        run = runner.invoke(app(), ["calibrate", str(results), "--data", str(good), "--out", str(tmp_path / "o"),
                                    *extra])
        assert run.exit_code == 2 and message in run.output, (extra, run.output)
    other = tmp_path / "other.yaml"
    other.write_text(CAMPAIGN.replace("seed: 3", "seed: 4"))
    (tmp_path / "model.py").write_text(MODEL)
    for bad, message in ((["--campaign", str(other)], "is not the campaign"), (["--order", "9"], "coefficients")):
        run = runner.invoke(app(), ["calibrate", str(results), "--data", str(good), "--out", str(tmp_path / "o"),
                                    *bad])
        assert run.exit_code == 2 and message in run.output, (bad, run.output)
    run = runner.invoke(app(), ["calibrate", str(good), "--data", str(good), "--out", str(tmp_path / "o")])
    assert run.exit_code == 2, run.output
    assert not (tmp_path / "o" / "summary.json").exists()


def test_time_interpolation_is_linear_and_refuses_extrapolation():
    source = np.array([0.0, 1.0, 3.0])
    values = np.array([[0.0, 2.0, 6.0], [1.0, 1.0, 1.0]])  # 2t and a constant
    np.testing.assert_allclose(interpolate_in_time(values, source, np.array([0.5, 2.0, 3.0])),
                               [[1.0, 4.0, 6.0], [1.0, 1.0, 1.0]])
    with pytest.raises(Refusal, match="outside"):
        interpolate_in_time(values, source, np.array([-0.1, 1.0]))


def test_surrogate_error_widens_the_posterior():
    # one parameter, prior N(0, 1), y = ξ at n = 10 times, noise 0.1. Without surrogate error the
    # posterior variance is 1 / (1 + n / 0.1²). A surrogate error curve that is a constant offset of std
    # 0.3 (covariance 0.09 11ᵀ) cannot be averaged away over times: the information 1ᵀΣ⁻¹1 becomes
    # n / (0.1² + n 0.09), and the same error as independent per time gives n / (0.1² + 0.09).
    n = 10
    coefficients = {"y": np.array([[0.0] * n, [1.0] * n])}
    basis = lambda xi: np.column_stack([np.ones(len(xi)), xi[:, 0]])  # noqa: E731
    data = FlightData("x", np.arange(float(n)), {"y": np.full(n, 0.5)})
    cases = ((np.zeros((n, 0)), n / 0.01), (np.full((n, 1), 0.3), n / (0.01 + n * 0.09)),
             (0.3 * np.eye(n), n / (0.01 + 0.09)))
    for factors, information in cases:
        posterior = LogPosterior.build(np.arange(float(n)), coefficients, {"y": factors}, ["normal"], ["x"], basis,
                                       data, {"y": 0.1})
        theta = np.linspace(-1, 2, 6001)[:, None]
        p = np.exp(posterior(theta) - posterior(theta).max())
        mean = (theta[:, 0] * p).sum() / p.sum()
        std = math.sqrt(((theta[:, 0] - mean) ** 2 * p).sum() / p.sum())
        assert std == pytest.approx(1 / math.sqrt(1 + information), rel=1e-3)
        assert mean == pytest.approx(0.5 * information / (1 + information), rel=1e-3)


def test_log_likelihood_is_the_dense_gaussian_density():
    # two outputs on a 2-D quadratic basis, one with a given noise and a 2-direction surrogate error,
    # one with its noise inferred and none: the stacked quadratic-form evaluation equals scipy's
    # multivariate normal log-density with the full covariance σ²I + F Fᵀ. Data about 15000 (an
    # altitude) so that the expansion about the prior centre is what keeps the digits; 1e-9 relative
    # leaves room for the rounding of |y − f|² formed from a Gram matrix (measured 1e-13).
    from scipy import stats

    from uqflight.methods.basis import Basis, total_degree_indices

    rng = np.random.default_rng(3)
    indices = total_degree_indices(2, 2)
    basis = Basis(["normal", "uniform"], indices)
    times = np.linspace(0.0, 1.0, 40)
    coefficients = {"h": rng.standard_normal((len(indices), 40)), "q": rng.standard_normal((len(indices), 40))}
    coefficients["h"][0] += 15000.0
    factors = {"h": 0.2 * rng.standard_normal((40, 2)), "q": np.zeros((40, 0))}
    truth = np.array([[0.4, -0.3]])
    values = {name: (basis(truth) @ c)[0] + 0.1 * rng.standard_normal(40) for name, c in coefficients.items()}
    data = FlightData("x", times, values)
    posterior = LogPosterior.build(times, coefficients, factors, ["normal", "uniform"], ["a", "b"], basis,
                                   data, {"h": 0.1})
    theta = np.column_stack([rng.normal(0.3, 0.2, 5), rng.uniform(-0.9, 0.9, 5), np.log(rng.uniform(0.05, 0.2, 5))])
    expected = []
    for row in theta:
        f = {name: (basis(row[None, :2]) @ c)[0] for name, c in coefficients.items()}
        cov_h = 0.1**2 * np.eye(40) + factors["h"] @ factors["h"].T
        cov_q = np.exp(row[2]) ** 2 * np.eye(40)
        expected.append(stats.multivariate_normal(f["h"], cov_h).logpdf(values["h"])
                        + stats.multivariate_normal(f["q"], cov_q).logpdf(values["q"]))
    assert posterior.log_likelihood(theta) == pytest.approx(np.array(expected), rel=1e-9)


def test_split_rhat_detects_disagreeing_chains():
    rng = np.random.default_rng(0)
    same = rng.standard_normal((1000, 8, 1))
    assert split_rhat(same)[0] == pytest.approx(1.0, abs=0.01)
    shifted = same + np.arange(8)[None, :, None]
    assert split_rhat(shifted)[0] > 1.5


@pytest.mark.slow
def test_aircraft_calibration_recovers_cl0_and_k2(tmp_path):
    """The real thing (about a minute): grid-gh-l2 on the aircraft, a JSBSim flight at CL0 +1.5σ and
    k2 −1.2σ with noise, calibrated; the JSBSim posterior predictive brackets the data."""
    from pathlib import Path

    from uqflight.calibration.surrogate import simulate, to_physical

    root = Path(__file__).resolve().parents[1]
    campaign = load_campaign(root / "campaigns/grid-gh-l2.yaml", AircraftProperties)
    results = tmp_path / "grid-gh-l2.h5"
    run_campaign(campaign, out=results, workers=2)
    surrogate = calibration_surrogate(results)
    xi = np.array([[1.5 if n == "CL0" else -1.2 if n == "k2" else 0.0 for n in surrogate.names]])
    kappa = to_physical(surrogate.parameters, xi)[0]
    time, clean, failures = simulate(surrogate.campaign, kappa[None], surrogate.outputs)
    assert not failures
    noise = {"alpha_deg": 0.05, "theta_deg": 0.05, "h_ft": 1.0, "q_degps": 0.05, "vtas_kt": 0.1}
    rng = np.random.default_rng(7)
    data = tmp_path / "flight.csv"
    write_csv(data, time, {o: clean[o][0] + noise[o] * rng.standard_normal(time.size) for o in surrogate.outputs})
    out = tmp_path / "out"
    run = CliRunner().invoke(app(), ["calibrate", str(results), "--data", str(data), "--out", str(out),
                                     "--steps", "4000", *[f"--noise={o}={s}" for o, s in noise.items()]])
    assert run.exit_code == 0, run.output
    summary = json.loads((out / "summary.json").read_text())
    truth = dict(zip(surrogate.names, kappa))
    for name in ("CL0", "k2"):
        lower, upper = summary["parameters"][name]["posterior"]["ci95"]
        assert lower <= truth[name] <= upper, (name, truth[name], lower, upper)
        assert summary["parameters"][name]["narrowing"] > 3
    assert summary["parameters"]["Cmq"]["narrowing"] < 1.5  # ±0.53 %: the flight hardly sees it
    assert summary["predictive"]["failed"] == 0
    assert min(summary["predictive"]["coverage95"].values()) > 0.85


def test_the_sampler_is_reproducible_from_its_seed():
    log_prob = lambda theta: -0.5 * (np.atleast_2d(theta) ** 2).sum(axis=1)  # noqa: E731
    draw = lambda rng, n: rng.standard_normal((n, 2))  # noqa: E731
    runs = [sample(log_prob, 2, ["x", "y"], np.zeros(2), draw, walkers=8, steps=200, seed=seed).samples
            for seed in (5, 5, 6)]
    np.testing.assert_array_equal(runs[0], runs[1])
    assert not np.array_equal(runs[0], runs[2])


@pytest.mark.slow
def test_an_adaptive_chain_stops_at_the_second_passing_check_and_is_the_fixed_chain_of_its_length():
    # a correlated 2-D Gaussian: emcee's DE move has tau of about 8 there, so 50 tau are reached well before MAX_STEPS
    precision = np.linalg.inv(np.array([[1.0, 0.8], [0.8, 1.0]]))
    log_prob = lambda theta: -0.5 * np.einsum("mi,ij,mj->m", theta, precision, theta)  # noqa: E731
    draw = lambda rng, n: rng.standard_normal((n, 2))  # noqa: E731
    adaptive = sample(log_prob, 2, ["x", "y"], np.zeros(2), draw, walkers=16, steps=None, seed=3)
    steps = adaptive.samples.shape[0]
    assert FIRST_CHECK + CHECK_EVERY <= steps < MAX_STEPS and steps % CHECK_EVERY == 0
    assert adaptive.diagnostics["converged"] and adaptive.diagnostics["steps"] == steps
    assert adaptive.diagnostics["stopping"].startswith("adaptive")
    fixed = sample(log_prob, 2, ["x", "y"], np.zeros(2), draw, walkers=16, steps=steps, seed=3)
    np.testing.assert_array_equal(adaptive.samples, fixed.samples)
    assert fixed.diagnostics["stopping"] == "fixed" and adaptive.burn == fixed.burn == steps // 2
    # the check before passed too, and the one before that did not (or it was the first)
    verdicts = [sample(log_prob, 2, ["x", "y"], np.zeros(2), draw, walkers=16, steps=n, seed=3)
                .diagnostics["converged"] for n in (steps - CHECK_EVERY, steps - 2 * CHECK_EVERY)]
    assert verdicts[0] and (not verdicts[1] or steps - 2 * CHECK_EVERY < FIRST_CHECK)


def test_an_adaptive_chain_that_never_converges_stops_at_its_longest_and_says_what_failed(monkeypatch):
    # a target that drifts by 0.05 sigma per call: the halves of every chain disagree at every check
    monkeypatch.setattr(sampler_module, "MAX_STEPS", FIRST_CHECK + 2 * CHECK_EVERY)
    calls = [0]

    def log_prob(theta):
        calls[0] += 1
        return -0.5 * ((theta - 0.05 * calls[0]) ** 2).sum(axis=1)

    draw = lambda rng, n: rng.standard_normal((n, 2))  # noqa: E731
    chain = sample(log_prob, 2, ["x", "y"], np.zeros(2), draw, walkers=8, steps=None, seed=0)
    assert chain.samples.shape[0] == FIRST_CHECK + 2 * CHECK_EVERY
    assert not chain.diagnostics["converged"]
    assert any("split-R̂" in problem for problem in chain.diagnostics["problems"])


@pytest.mark.slow
def test_surrogate_error_measured_at_the_posterior_is_added_when_larger(tmp_path):
    # x(t) = exp(-a t), a ~ N(1, 0.2²), order-2 PCE from 30 points: fine near the prior, 6x worse than
    # its LOO estimate at a = 1.75 (3.75σ), where the data are. The check at the posterior draws sees
    # it, adds the measured error curves to the error model and samples again: the truth is covered.
    from uqflight.simulators.models import DECAY_TIME

    text = """
name: decay
seed: 1
simulator: {kind: python, function: "uqflight.simulators.models:exp_decay"}
parameters:
  a: {distribution: normal, nominal: 1.0, interval_pct: 60}
design: {kind: latin_hypercube, samples: 30}
method: {kind: regression, order: 2}
execution: {workers: 1}
"""
    results = tmp_path / "decay.h5"
    run_campaign(parse_campaign(text, str(tmp_path / "decay.yaml")), out=results)
    rng = np.random.default_rng(0)
    data = tmp_path / "decay.csv"
    write_csv(data, DECAY_TIME, {"x": np.exp(-1.75 * DECAY_TIME) + 0.002 * rng.standard_normal(DECAY_TIME.size)})
    out = tmp_path / "out"
    run = CliRunner().invoke(app(), ["calibrate", str(results), "--data", str(data), "--out", str(out),
                                     "--noise", "x=0.002", "--steps", "1000", "--predictive-draws", "30"])
    assert run.exit_code == 0, run.output
    summary = json.loads((out / "summary.json").read_text())
    check = summary["surrogate_check"]
    assert check["refined"] and check["first_pass"]["outputs"]["x"]["exceeds"]
    assert not check["outputs"]["x"]["exceeds"]
    lower, upper = summary["parameters"]["a"]["posterior"]["ci95"]
    assert lower <= 1.75 <= upper


def test_the_memory_limit_is_the_campaigns_own(tmp_path):
    # 32 walkers x 5,000,000 steps keep a 3.8 GB chain: under the default 8 GB, over this campaign's 1 GB
    (tmp_path / "model.py").write_text(MODEL)
    text = CAMPAIGN.replace("design: {kind: latin_hypercube, samples: 40}",
                            "design: {kind: latin_hypercube, samples: 12}\nlimits: {max_memory_gb: 1}")
    (tmp_path / "campaign.yaml").write_text(text)
    path = tmp_path / "small.h5"
    run_campaign(parse_campaign(text, str(tmp_path / "campaign.yaml")), out=path, workers=1)
    good = tmp_path / "good.csv"
    write_csv(good, TIME, synthetic(3))
    run = CliRunner().invoke(app(), ["calibrate", str(path), "--data", str(good), "--out", str(tmp_path / "o"),
                                     "--steps", "5000000"])
    assert run.exit_code == 2 and "the 1 GB memory limit (limits.max_memory_gb)" in run.output, run.output


# -- calibration data and a campaign of one output: hostile inputs refused up front, Ctrl-C
@pytest.fixture(scope="module")
def one_output(tmp_path_factory):
    """y(t) = 15000 + t (x1² + x2²) at 5 times in [0, 1] on a 4x4 grid; the model beside the results file,
    where calibrate's predictive runs look for it."""
    folder = tmp_path_factory.mktemp("calibrate")
    shutil.copy(CLOSED_FORMS, folder / CLOSED_FORMS.name)
    text = closed_form_campaign("sq", "sum_of_squares", NORMAL_2D, "{kind: tensor_grid, points: 4}",
                                "method: {kind: pseudo_galerkin, order: 2}\n")
    return run_python_campaign(folder, text.replace(str(CLOSED_FORMS), CLOSED_FORMS.name))



def test_a_million_row_csv_is_refused_before_it_is_parsed(one_output, tmp_path):
    data = tmp_path / "big.csv"
    data.write_text("time_s,y\n" + "0.5,15000.5\n" * (10**6 - 1) + "not,a number\n")  # parsed: refused otherwise
    out = tmp_path / "out"
    result = cli_in_process("calibrate", one_output, "--data", data, "--out", out)
    assert result.returncode == 2, result.stderr
    # 1 output x (50 predictive draws x (2 x 40 noise draws + 3) + 4 x 32 walkers) x 8 bytes = 34.2 kB a row
    assert f"error: {data}: more than 233619 rows of data: calibrating 1 output(s) with 32 walkers and 50 " \
           "predictive draws takes about 34 kB a row, more than the 8 GB memory limit" in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1 and not out.exists()



def test_a_folder_holding_a_users_files_of_the_calibrations_names_is_refused(one_output, tmp_path):
    # a calibration replaces summary.json, report.html, ... in --out: only those an earlier calibration wrote
    data = tmp_path / "flight.csv"
    data.write_text("time_s,y\n0,15000\n0.5,15001\n1,15002\n")
    out = tmp_path / "mine"
    (out / "plots").mkdir(parents=True)
    (out / "summary.json").write_text('{"mine": true}')
    (out / "plots" / "corner.png").write_bytes(b"not a calibration's")
    (out / "notes.txt").write_text("kept")
    result = cli_in_process("calibrate", one_output, "--data", data, "--out", out, "--noise", "y=0.5")
    assert result.returncode == 2 and result.stdout == ""
    assert result.stderr == (f"error: --out {out}: holds summary.json, plots/corner.png, which a calibration would "
                             "replace and which an earlier calibration did not write (no posterior.h5 of one there); "
                             "choose another --out, or move them away\n")
    assert (out / "summary.json").read_text() == '{"mine": true}' and sorted(p.name for p in out.iterdir()) == [
        "notes.txt", "plots", "summary.json"]


def test_a_byte_order_mark_is_no_part_of_the_header(tmp_path):
    path = tmp_path / "bom.csv"
    path.write_bytes("\ufefftime_s,y\n0,1.5\n0.5,2.5\n".encode("utf-8"))
    flight = read_flight_csv(path, None, ["y"])
    np.testing.assert_array_equal(flight.time, [0.0, 0.5])
    np.testing.assert_array_equal(flight.values["y"], [1.5, 2.5])



def test_a_noise_given_twice_is_refused(one_output, tmp_path):
    with pytest.raises(Refusal, match=r"--noise y: given twice \(0\.01 and 5\); give it once"):
        parse_noise(["y=0.01", "y=5"])
    data = tmp_path / "flight.csv"
    data.write_text("time_s,y\n0,15000\n0.5,15001\n1,15002\n")
    result = cli_in_process("calibrate", one_output, "--data", data, "--out", tmp_path / "out",
                            "--noise", "y=0.01", "--noise", "y=5")
    assert result.returncode == 2 and result.stderr == "error: --noise y: given twice (0.01 and 5); give it once\n"


def test_the_python_api_hands_the_noise_to_the_core_as_numbers(one_output, tmp_path):
    """`uqflight.calibrate(noise={...})` reaches the core as {output: sigma}, checked there as the CLI's is."""
    import uqflight
    from uqflight.calibration.likelihood import check_noise

    assert check_noise({"y": 1}, ["y"]) == {"y": 1.0} and parse_noise(["y = 0.5"]) == {"y": 0.5}
    for noise, message in (({"y": 0.0}, "--noise y: expected SIGMA > 0 (a finite number), got 0.0"),
                           ({"y": float("nan")}, "--noise y: expected SIGMA > 0 (a finite number), got nan"),
                           ({"y": "0.5"}, "--noise y: expected SIGMA > 0 (a finite number), got '0.5'"),
                           ({"w": 0.5}, "--noise w: not one of the calibrated outputs (y)")):
        with pytest.raises(Refusal) as refused:
            check_noise(noise, ["y"])
        assert str(refused.value) == message
    data = tmp_path / "flight.csv"
    data.write_text("time_s,y\n0,15000\n0.5,15001\n1,15002\n")
    with pytest.raises(Refusal, match=r"^--noise w: not one of the calibrated outputs \(y\)$"):
        uqflight.calibrate(one_output, data, tmp_path / "out", noise={"w": 0.5})
    assert not (tmp_path / "out").exists()



@pytest.mark.slow
def test_ctrl_c_in_calibrate_exits_130_with_one_line(one_output, tmp_path):
    data = tmp_path / "flight.csv"
    data.write_text("time_s,y\n0,15000\n0.25,15000.6\n0.5,15001.1\n0.75,15001.4\n1,15002.1\n")
    process = subprocess.Popen([UQFLIGHT, "calibrate", one_output, "--data", data, "--out", tmp_path / "out",
                                "--steps", "10000000"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    cpu = 0.0
    while cpu < 6.0 and process.poll() is None:  # start-up and the fit take 2-3 s of CPU: then it samples
        time.sleep(0.2)
        fields = open(f"/proc/{process.pid}/stat").read().rsplit(")", 1)[1].split()
        cpu = (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    process.send_signal(signal.SIGINT)
    stdout, stderr = process.communicate(timeout=60)
    assert process.returncode == 130, stderr[-3000:]
    # off a terminal the progress is log lines ("calibrate: ..."); beside them, one line says it all
    others = [line for line in stderr.splitlines() if not line.startswith("calibrate: ")]
    assert stdout == "" and others == ["", f"interrupted: no calibration written to {tmp_path / 'out'}"], stderr



def test_a_calibration_opens_the_results_file_once_and_checks_its_campaign_once(one_output, tmp_path, monkeypatch):
    # the memory limit, the surrogate's record and the statistics' fit each opened the file and read the record
    from collections import Counter

    import uqflight
    import uqflight.analysis.statistics as statistics
    from uqflight.store import ResultStore

    calls, open_file, read_record = Counter(), ResultStore.open.__func__, statistics.read_record

    def opened(cls, path, *args, **kwargs):
        calls["open"] += 1
        return open_file(cls, path, *args, **kwargs)

    def read(*args, **kwargs):
        calls["read_record"] += 1
        return read_record(*args, **kwargs)

    monkeypatch.setattr(ResultStore, "open", classmethod(opened))
    monkeypatch.setattr(statistics, "read_record", read)
    data = tmp_path / "flight.csv"
    data.write_text("time_s,y\n0,15000\n0.5,15001\n1,15002\n")
    with pytest.raises(Refusal, match="--noise w"):  # refused once the surrogate is fitted, before the sampler
        uqflight.calibrate(one_output, data, tmp_path / "out", noise={"w": 0.5})
    assert calls == {"open": 1, "read_record": 1}
    from uqflight.calibration.run import calibrate

    with pytest.raises(Refusal, match=r"^--truth zz: not one of the parameters of .*c\.h5 \(x1, x2\)$"):
        calibrate(one_output, data, tmp_path / "out", truth={"zz": 1.0})
