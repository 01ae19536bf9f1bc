"""`uqflight simulate`: seeded measurement noise, files written under results/ by default, and a trim
that fails for the stall says so and how fast to fly."""
import csv

import numpy as np
import pytest
from conftest import cli_in_process

from uqflight.simulators.noise import add_noise, check_noise


def test_the_noise_has_the_given_std_and_the_same_seed_gives_the_same_bits():
    n, sigma = 40_000, 0.5
    clean = {"a": np.full(n, 3.0), "b": np.zeros(n)}
    noisy = add_noise(clean, {"a": sigma}, seed=7)
    e = noisy["a"] - 3.0
    # standard errors of a normal sample's mean σ/√n and std σ/√(2n): 4 of them (a false failure
    # 6e-5 of the time; a wrong std off by 1.4 % or more fails)
    assert abs(e.mean()) < 4 * sigma / np.sqrt(n)
    assert abs(e.std(ddof=1) - sigma) < 4 * sigma / np.sqrt(2 * n)
    assert np.array_equal(noisy["b"], clean["b"]) and np.array_equal(clean["a"], np.full(n, 3.0))
    again = add_noise(clean, {"a": sigma}, seed=7)
    assert again["a"].tobytes() == noisy["a"].tobytes()
    assert not np.array_equal(add_noise(clean, {"a": sigma}, seed=8)["a"], noisy["a"])
    # an output's noise does not depend on which others are noisy
    assert add_noise(clean, {"a": sigma, "b": 1.0}, seed=7)["a"].tobytes() == noisy["a"].tobytes()


@pytest.mark.parametrize("sigmas, seed, message", [
    ({"c": 1.0}, 0, "--noise: no output 'c' (outputs: a, b)"),
    ({"a": -1.0}, 0, "--noise: expected SIGMA >= 0"),
    ({"a": float("nan")}, 0, "--noise: expected SIGMA >= 0"),
    ({"a": 1.0}, -1, "--seed: expected an integer >= 0, got -1"),
])
def test_bad_noise_is_refused(sigmas, seed, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        check_noise(["a", "b"], sigmas, seed)


def _read(path):
    rows = list(csv.reader(open(path, newline="")))
    return rows[0], np.array(rows[1:], dtype=float)


@pytest.mark.slow
def test_simulate_writes_into_results_and_adds_seeded_noise(tmp_path):
    args = ("simulate", "--duration-s", "10", "--excitation", "none")
    done = cli_in_process(*args, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results"]  # nothing else in the working directory
    assert sorted(p.name for p in (tmp_path / "results").iterdir()) == ["flight.csv", "flight.png"]
    header, clean = _read(tmp_path / "results" / "flight.csv")
    for name in ("a.csv", "b.csv"):
        noisy = cli_in_process(*args, "--noise", "alpha_deg=0.05", "--seed", "3", "--out", tmp_path / name,
                               "--plot", tmp_path / "p.png", cwd=tmp_path)
        assert noisy.returncode == 0 and "noise added (seed 3): alpha_deg sigma 0.05" in noisy.stdout
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()
    _, data = _read(tmp_path / "a.csv")
    column = header.index("alpha_deg")
    error = data[:, column] - clean[:, column]
    # 201 draws: the std's standard error is 5 %; within 4 of them (20 %), and the other outputs untouched
    assert abs(error.std(ddof=1) - 0.05) < 0.2 * 0.05
    others = [i for i in range(len(header)) if i != column]
    assert np.array_equal(data[:, others], clean[:, others])


def test_a_trim_that_fails_for_the_stall_says_so_and_how_fast_to_fly():
    failed = cli_in_process("simulate", "--airspeed-ktas", "150", "--duration-s", "1", "--no-files")
    assert failed.returncode == 1
    assert "150 KTAS: the stall: level flight needs a lift coefficient W/(qbar S) = 1.378" in failed.stderr
    assert "fly faster than 155 KTAS at this altitude" in failed.stderr
    flown = cli_in_process("simulate", "--airspeed-ktas", "155", "--duration-s", "1", "--no-files")
    assert flown.returncode == 0, flown.stderr  # the advice holds


def test_units_are_visible_in_simulate_help():
    text = " ".join(cli_in_process("simulate", "--help").stdout.split())
    for unit in ("altitude [ft]", "airspeed [kt]", "amplitude [deg]", "start [s]", "[Hz]"):
        assert unit in text, (unit, text)


def test_a_mistyped_property_gets_a_did_you_mean():
    result = cli_in_process("simulate", "--set", "aero/uq/CLO=0.2", "--duration-s", "1")
    assert result.returncode == 2 and "did you mean aero/uq/CL0" in result.stderr
