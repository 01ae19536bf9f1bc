"""Coverage of the calibration's 95 % intervals on the aircraft, over noise seeds.

Study A: a flight is flown with JSBSim at known coefficients inside the Table 1 box (CL0 at +1.5σ,
k2 at −1.2σ, the others nominal); for each noise seed Gaussian noise is added and the posterior is
sampled from the grid-gh-l2 surrogate (113 runs). Parameters the data hardly see then cover their
truth more often than 95 %: it sits at their prior mean. Study B draws the truth from the prior
(cut at the ±3σ box) for every seed and flies it: there the 95 % intervals of every parameter
should hold the truth 95 % of the time if the posterior is right. Printed per parameter: coverage,
narrowing (prior std / posterior std) and the RMS of (posterior mean − truth) / posterior std
(1 when the posterior width matches the actual error). Seed 0 of A also goes through the whole
`calibrate` (plots, posterior predictive from 50 real JSBSim runs).

    .venv/bin/python benchmarks/calibration_coverage.py [--seeds 20] [--results results/grid-gh-l2.h5]
"""
from __future__ import annotations

import argparse
import csv
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from uqflight.calibration.likelihood import FlightData, LogPosterior  # noqa: E402
from uqflight.calibration.run import calibrate  # noqa: E402
from uqflight.calibration.sampler import sample  # noqa: E402
from uqflight.calibration.surrogate import calibration_surrogate, prior_summaries, simulate, to_physical  # noqa: E402

TRUE_XI = {"CL0": 1.5, "k2": -1.2}
NOISE = {"alpha_deg": 0.05, "theta_deg": 0.05, "h_ft": 1.0, "q_degps": 0.05, "vtas_kt": 0.1}


def ensure_results(path: Path) -> Path:
    if path.is_file():
        return path
    from uqflight.campaign import load_campaign
    from uqflight.simulators.aircraft_properties import AircraftProperties
    from uqflight.running.runner import run_campaign

    print(f"running campaigns/grid-gh-l2.yaml into {path} (113 flights)")
    run_campaign(load_campaign(ROOT / "campaigns/grid-gh-l2.yaml", read_aircraft=AircraftProperties), out=path)
    return path


def study(label, args, surrogate, draw_xi, time_grid, clean, given, prior) -> list:
    """Coverage of the 95 % intervals and narrowing over args.seeds noise seeds (and truths)."""
    names = surrogate.names
    inside = np.zeros((args.seeds, len(names)), dtype=bool)
    stds = np.zeros((args.seeds, len(names)))
    errors = np.zeros((args.seeds, len(names)))  # posterior mean - truth
    unconverged, seconds, steps_per_tau = 0, [], []
    print(f"\n{label}", flush=True)
    for seed in range(args.seeds):
        rng = np.random.default_rng(1000 + seed)
        xi_true = draw_xi(rng)
        kappa_true = to_physical(surrogate.parameters, xi_true[None])[0]
        if clean is None:
            grid, flown, failures = simulate(surrogate.campaign, kappa_true[None], surrogate.outputs)
            if failures:
                print(f"seed {seed}: the truth's flight failed ({failures[0]}); skipped")
                continue
        else:
            grid, flown = time_grid, clean
        values = {o: flown[o][0] + NOISE[o] * rng.standard_normal(grid.size) for o in surrogate.outputs}
        data = FlightData(f"seed {seed}", grid, values)
        posterior = LogPosterior.build(surrogate.time, surrogate.coefficients, surrogate.error_factors,
                                       surrogate.germs, names, surrogate.basis, data, given)
        start = time.perf_counter()
        chain = sample(posterior, posterior.ndim, posterior.labels, posterior.start(),
                       lambda r, n: np.hstack([r.standard_normal((n, len(names))),
                                               np.tile(posterior.start()[len(names):], (n, 1))]),
                       args.walkers, args.steps, seed)
        seconds.append(time.perf_counter() - start)
        if not chain.diagnostics["converged"]:
            unconverged += 1
            print(f"seed {seed}: not converged: {chain.diagnostics['problems']}")
            continue
        steps_per_tau.append(chain.diagnostics["steps_per_tau"])
        kappa = to_physical(surrogate.parameters, chain.flat[:, :len(names)])
        lower, upper = np.quantile(kappa, [0.025, 0.975], axis=0)
        inside[seed] = (lower <= kappa_true) & (kappa_true <= upper)
        stds[seed] = kappa.std(axis=0)
        errors[seed] = kappa.mean(axis=0) - kappa_true
        print(f"seed {seed}: {seconds[-1]:.1f} s, {steps_per_tau[-1]:.0f} tau kept, outside the 95 % interval: "
              f"{', '.join(n for n, i in zip(names, inside[seed]) if not i) or 'none'}", flush=True)
    used = stds[:, 0] > 0
    n = int(used.sum())
    print(f"{n} seeds converged ({unconverged} not), {args.walkers} walkers x {args.steps} steps, sampling "
          f"{np.mean(seconds):.1f} s per seed, kept chain {np.min(steps_per_tau):.0f} to {np.max(steps_per_tau):.0f} tau")
    print(f"{'parameter':<10} {'prior std':>11} {'post std':>11} {'narrowing':>9} {'coverage95':>10} "
          f"{'rms(mean-truth)/post std':>25}")
    rows = []
    for k, name in enumerate(names):
        post_std = float(np.mean(stds[used, k]))
        narrowing = prior[name]["std"] / post_std
        coverage = float(np.mean(inside[used, k]))
        spread = float(np.sqrt(np.mean((errors[used, k] / stds[used, k]) ** 2)))
        rows.append([label[0], name, prior[name]["std"], post_std, narrowing, coverage, spread])
        print(f"{name:<10} {prior[name]['std']:11.4g} {post_std:11.4g} {narrowing:9.2f} {coverage:10.0%} {spread:25.2f}")
    print(f"all parameters: {np.mean(inside[used]):.1%} of {inside[used].size} intervals hold the truth", flush=True)
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--steps", type=int, default=3000)
    parser.add_argument("--walkers", type=int, default=32)
    parser.add_argument("--results", type=Path, default=ROOT / "results/grid-gh-l2.h5")
    parser.add_argument("--out", type=Path, default=ROOT / "results/calibration-coverage")
    parser.add_argument("--infer-noise", action="store_true", help="infer σ per output instead of giving it")
    args = parser.parse_args()

    surrogate = calibration_surrogate(ensure_results(args.results))
    names = surrogate.names
    xi_true = np.array([TRUE_XI.get(n, 0.0) for n in names])
    kappa_true = to_physical(surrogate.parameters, xi_true[None])[0]
    truth = dict(zip(names, kappa_true))
    time_grid, clean, failures = simulate(surrogate.campaign, kappa_true[None], surrogate.outputs)
    assert not failures, failures
    prior = prior_summaries(surrogate.parameters)
    given = {} if args.infer_noise else NOISE
    print("truth: " + ", ".join(f"{n} = {v:.6g}" for n, v in truth.items()))
    print("noise: " + ", ".join(f"{o} {s:g}" for o, s in NOISE.items()) + ("(inferred)" if args.infer_noise else
                                                                           " (given)"))

    rows = study("A: fixed truth (CL0 +1.5 sd, k2 -1.2 sd, others nominal), noise seeds", args, surrogate,
                 lambda rng: xi_true, time_grid, clean, given, prior)
    rows += study("B: truth drawn from the prior per seed (one JSBSim flight each), noise seeds", args,
                  surrogate, lambda rng: np.array([np.clip(rng.standard_normal(), -3, 3) if g == 'normal' else rng.uniform(-1, 1)
                                        for g in surrogate.germs]), None, None, given, prior)
    args.out.mkdir(parents=True, exist_ok=True)
    with open(args.out / "coverage.csv", "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(["study", "parameter", "prior_std", "posterior_std", "narrowing", "coverage95",
                         "spread_of_means_over_posterior_std"])
        writer.writerows(rows)

    # seed 0 through the whole command: files, plots and the JSBSim posterior predictive
    rng = np.random.default_rng(1000)
    csv_path = args.out / "flight-seed0.csv"
    with open(csv_path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(["time_s", *surrogate.outputs])
        noisy = {o: clean[o][0] + NOISE[o] * rng.standard_normal(time_grid.size) for o in surrogate.outputs}
        for i, t in enumerate(time_grid):
            writer.writerow([f"{t:g}", *(repr(float(noisy[o][i])) for o in surrogate.outputs)])
    noise_args = [f"{o}={s}" for o, s in given.items()]
    start = time.perf_counter()
    result = calibrate(args.results, csv_path, args.out / "seed0", noise=noise_args, seed=0, walkers=args.walkers,
                       steps=args.steps, truth=truth)
    predictive = result.summary["predictive"]
    print(f"\nseed 0 via calibrate: {time.perf_counter() - start:.1f} s; posterior predictive from "
          f"{predictive['draws']} JSBSim runs ({predictive['failed']} failed): data inside the 95 % band: "
          + ", ".join(f"{o} {c:.1%}" for o, c in predictive["coverage95"].items()))
    print(f"wrote {args.out}/coverage.csv and {args.out}/seed0/")


if __name__ == "__main__":
    main()
