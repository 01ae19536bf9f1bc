"""Which ensemble moves sample `calibrate`'s posteriors right: std ratios and τ on closed forms.

An accuracy benchmark (not timing). Each move set runs through uqflight's own `sample` (mode
search, walker ball, burn-in half) on three posteriors whose covariance is known exactly:

* line, noise given: y(t) = a + b·t, normal priors, `LogPosterior` of the order-1 PCE of a python
  campaign (tests/test_calibration_conjugate.py): the conjugate Gaussian;
* line, noise inferred: the same with log σ sampled under uqflight's half-Cauchy prior; exact
  (a, b) marginal by quadrature over σ;
* 7-D Gaussian of covariance F Fᵀ + 0.01 I, F 7 × 3: correlations up to 0.987, condition number
  1234 (the aircraft's CD0–k1–k2 correlate near ±1).

Printed per target, move set and seed: sample std / exact std per parameter, the largest |z| of
those ratios (standard errors from the integrated autocorrelation time of each std's influence
function), τ_max and the acceptance fraction.

    .venv/bin/python benchmarks/sampler_moves.py [--seeds 2] [--steps 5000]

On 2026-12-01 (the table of docs/calibration.md): DE alone is unbiased with the smallest τ, and `calibrate` uses it.
"""
from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import emcee
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tests.test_calibration_conjugate import (PRIOR_STD, SIGMA, conjugate, flight, inferred,  # noqa: E402
                                              make_results, std_z)
from uqflight.calibration.likelihood import FlightData, LogPosterior  # noqa: E402
from uqflight.calibration.sampler import sample  # noqa: E402
from uqflight.calibration.surrogate import calibration_surrogate  # noqa: E402


class SnookerMove(emcee.moves.RedBlueMove):
    """Ter Braak & Vrugt's (2008) snooker update, with their step and acceptance factor (a candidate).

    For a walker x: z, z1, z2 from the complementary walkers, e = (x − z)/‖x − z‖, the proposal
    x' = x + γ ((z1 − z2)·e) e with γ ~ U(1.2, 2.2): a symmetric step along the line through z, so
    the Metropolis factor is the polar-coordinate Jacobian (‖x' − z‖ / ‖x − z‖)^(D−1). (emcee 3.1's
    DESnookerMove scales the step by ‖x − z‖ and uses half that exponent: its chains are too narrow.)"""

    def get_proposal(self, s, c, random):
        c = np.concatenate(c, axis=0)
        ns, ndim = s.shape
        picks = np.argsort(random.random_sample((ns, len(c))), axis=1)[:, :3]  # 3 distinct walkers each
        z, z1, z2 = (c[picks[:, k]] for k in range(3))
        delta = s - z
        norm = np.linalg.norm(delta, axis=1)
        e = delta / norm[:, None]
        gamma = random.uniform(1.2, 2.2, ns)
        q = s + (gamma * np.einsum("ij,ij->i", z1 - z2, e))[:, None] * e
        return q, (ndim - 1.0) * (np.log(np.linalg.norm(q - z, axis=1)) - np.log(norm))


MOVE_SETS = {
    "DE 0.8 + emcee snooker 0.2 (old)": lambda: [(emcee.moves.DEMove(), 0.8), (emcee.moves.DESnookerMove(), 0.2)],
    "DE": lambda: [(emcee.moves.DEMove(), 1.0)],
    "stretch": lambda: [(emcee.moves.StretchMove(), 1.0)],
    "DE 0.8 + corrected snooker 0.2": lambda: [(emcee.moves.DEMove(), 0.8), (SnookerMove(), 0.2)],
}


def gaussian_7d():
    """(label, log density, start, exact std, prior draw) of a 7-D Gaussian with strong correlations."""
    rng = np.random.default_rng(7)
    factor = rng.standard_normal((7, 3))  # three well-identified combinations, four nearly free directions
    cov = factor @ factor.T + 0.01 * np.eye(7)
    precision = np.linalg.inv(cov)
    std = np.sqrt(np.diag(cov))
    print(f"7-D Gaussian: largest |correlation| {np.max(np.abs(cov / np.outer(std, std) - np.eye(7))):.3f}")
    return ("7-D Gaussian", lambda x: -0.5 * np.einsum("ij,jk,ik->i", x, precision, x), np.zeros(7), std,
            lambda r, n: r.standard_normal((n, 7)) * std)


def line_targets(folder: Path, seed: int):
    """(label, log posterior, start, exact std of ξ_a and ξ_b, prior draw) of both lines."""
    surrogate = calibration_surrogate(make_results(folder))
    y = flight(seed)
    data = FlightData("line", surrogate.time, {"y": y})
    out = []
    for label, given, (_, cov) in (("line, noise given", {"y": SIGMA}, conjugate(y, SIGMA)),
                                   ("line, noise inferred", {}, inferred(y))):
        posterior = LogPosterior.build(surrogate.time, surrogate.coefficients, surrogate.error_factors,
                                       surrogate.germs, surrogate.names, surrogate.basis, data, given)
        rest = posterior.start()[2:]
        out.append((label, posterior, posterior.start(), np.sqrt(np.diag(cov)) / PRIOR_STD,  # ξ = (κ − m0) / s0
                    lambda r, n, rest=rest: np.hstack([r.standard_normal((n, 2)), np.tile(rest, (n, 1))])))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=2)
    parser.add_argument("--steps", type=int, default=5000)
    parser.add_argument("--walkers", type=int, default=32)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        targets = [*line_targets(Path(folder), 0), gaussian_7d()]
        print(f"{args.walkers} walkers x {args.steps} steps, the first half burn-in")
        print(f"{'target':<21} {'moves':<33} {'seed':>4}  {'std / exact std per parameter':<44} {'max|z|':>6} "
              f"{'tau_max':>7} {'accept':>6}")
        for label, target, start, exact_std, prior_draw in targets:
            for name, moves in MOVE_SETS.items():
                for seed in range(args.seeds):
                    chain = sample(target, start.size, [f"x{k}" for k in range(start.size)], start, prior_draw,
                                   args.walkers, args.steps, seed, moves=moves())
                    ratio, z = std_z(chain.kept[:, :, :len(exact_std)], exact_std)
                    tau = max(chain.diagnostics["autocorrelation_time"].values())
                    print(f"{label:<21} {name:<33} {seed:>4}  {' '.join(f'{r:.4f}' for r in ratio):<44} "
                          f"{np.max(np.abs(z)):6.1f} {tau:7.1f} {chain.diagnostics['acceptance_fraction']['mean']:6.2f}",
                          flush=True)


if __name__ == "__main__":
    main()
