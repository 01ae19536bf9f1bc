"""The paper's Table 2 on our model: incremental thin SVD of Monte Carlo histories of alpha(t).

Runs (or resumes) a Monte Carlo campaign of the bacm's angle of attack (default 20,000 runs,
normal inputs, raw storage, results/tsvd-alpha.h5), then for each tolerance compresses the
T x N matrix batch by batch with uqflight.store.tsvd.IncrementalSVD and prints: the number of terms,
the time of the first decomposition, mean and std of the update times, the relative error of the
mean and of the variance after compression (max over time, relative to the max of the exact one),
the memory of the factors against the raw data, and the update time against the simulation time
of its batch.

Run: .venv/bin/python benchmarks/tsvd_table.py [--samples 20000] [--batch 1000] [--workers 2]
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

from uqflight.campaign import parse_campaign
from uqflight.simulators.aircraft_properties import AircraftProperties
from uqflight.running.runner import run_campaign
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))  # the study's Table 1 (tests/paper.py)
from paper import table1_parameters_yaml  # noqa: E402
from uqflight.store import ResultStore, Status
from uqflight.analysis.moments import weighted_moments
from uqflight.store.tsvd import IncrementalSVD

CAMPAIGN = """
name: tsvd-alpha-{samples}
seed: 2023
simulator: {{kind: jsbsim, duration_s: 50, output_rate_hz: 20, outputs: [alpha_deg]}}
parameters:
{parameters}design: {{kind: monte_carlo, samples: {samples}}}
execution: {{workers: {workers}}}
storage: {{raw: true}}
"""
TOLERANCES = (1e-2, 1e-4, 1e-6, 1e-8, 1e-12)


def human(nbytes: float) -> str:
    for unit in ("B", "KB", "MB", "GB"):
        if nbytes < 1024 or unit == "GB":
            return f"{nbytes:.0f} {unit}" if unit == "B" else f"{nbytes:.1f} {unit}"
        nbytes /= 1024


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--samples", type=int, default=20000)
    parser.add_argument("--batch", type=int, default=1000)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", type=Path, default=Path("results/tsvd-alpha.h5"))
    args = parser.parse_args()

    ran, seconds = 0, 0.0
    if not args.out.exists():  # an existing file is reused as it is (delete it to measure the runs again)
        text = CAMPAIGN.format(parameters=table1_parameters_yaml(), samples=args.samples, workers=args.workers)
        summary = run_campaign(parse_campaign(text, "tsvd.yaml", AircraftProperties), out=args.out)
        ran, seconds = summary.ran, summary.seconds
    with ResultStore.open(args.out) as store:
        ok = store.status == Status.OK
        A = store.output_matrix("alpha_deg", np.flatnonzero(ok)).T.copy()  # T x N
    n = A.shape[1]
    w = np.full(n, 1.0 / n)
    mean, var = A @ w, ((A - (A @ w)[:, None]) ** 2) @ w
    sim_per_batch = seconds / ran * args.batch * args.workers if ran else None
    print(f"## Incremental tSVD of alpha(t): {n} runs x {A.shape[0]} times, batches of {args.batch}, "
          f"raw {human(A.nbytes)}\n")
    print("| tol | terms | first [s] | update mean [s] | update std [s] | error mean | error var | memory | ratio |")
    print("|---|---|---|---|---|---|---|---|---|")
    update_means = {}
    for tol in TOLERANCES:
        svd = IncrementalSVD(tol)
        times = []
        for start in range(0, n, args.batch):
            t0 = time.perf_counter()
            svd.update(A[:, start:start + args.batch])
            times.append(time.perf_counter() - t0)
        m, v = weighted_moments(svd.V, w, svd.s[:, None] * svd.U.T)
        err_m = np.max(np.abs(m - mean)) / np.max(np.abs(mean))
        err_v = np.max(np.abs(v - var)) / np.max(np.abs(var))
        memory = svd.U.nbytes + svd.s.nbytes + svd.V.nbytes
        updates = times[1:] or [0.0]
        update_means[tol] = statistics.mean(updates)
        print(f"| {tol:g} | {svd.rank} | {times[0]:.3f} | {statistics.mean(updates):.4f} | "
              f"{statistics.pstdev(updates):.4f} | {err_m:.2e} | {err_v:.2e} | {human(memory)} | "
              f"{A.nbytes / memory:.0f}x |")
    if sim_per_batch:
        print(f"\nsimulation time of one batch of {args.batch} runs (one process): {sim_per_batch:.1f} s; "
              f"update at 1e-8: {100 * update_means[1e-8] / sim_per_batch:.3f} % of it (target < 5 %)")
    else:
        print(f"\n({args.out} reused: delete it to measure the simulation time per batch too)")


if __name__ == "__main__":
    main()
