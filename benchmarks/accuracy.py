"""Accuracy of the non-intrusive methods on the bacm against Monte Carlo, and runs per accuracy.

Uses the results of the shipped campaigns mc-normal, grid-gh-l1..l4 and grid-gk-l1..l4 in
--results, and runs those that are missing first (about 10 minutes on 2 cores for all of them).

Tables:
1. max over time of eps_m and eps_v (paper Eq. 49) for every output, method and grid, against
   the Monte Carlo reference (results/mc-normal.h5, 10^4 runs).
2. Runs per accuracy: the reference above resolves eps_v only down to its own sampling error
   (~sqrt(2/N) = 1.4 % at N = 10^4). The highest grid (2437 points, pseudo-Galerkin of order 4)
   serves as a sharper reference instead, once checked against the Monte Carlo one. For theta,
   alpha and V_TAS: max eps_v of PG-2 on the 113-point grid against it, and the number of Monte
   Carlo runs whose max eps_v (median over disjoint subsets of mc-normal) first falls below it.

Run: .venv/bin/python benchmarks/accuracy.py [--results results]
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from uqflight.analysis.errors import relative_errors
from uqflight.campaign import load_campaign
from uqflight.simulators.jsbsim_probe import jsbsim_probe
from uqflight.execution import run_campaign
from uqflight.statistics import Options, analyse
from uqflight.store import ResultStore, Status

OUTPUTS = ("theta_deg", "alpha_deg", "q_degps", "h_ft", "vtas_kt")
METHODS = [("integration", 2), ("pseudo_galerkin", 2), ("interpolation", 2), ("regression", 2),
           ("least_squares", 2)]
CAMPAIGNS = Path(__file__).resolve().parents[1] / "campaigns"
FAST = Options(band_samples=2000, bootstrap=0)


def max_errors(stats, reference):
    row = {}
    for name in OUTPUTS:
        eps_m, eps_v = relative_errors(stats.outputs[name].mean, stats.outputs[name].variance,
                                       reference.outputs[name].mean, reference.outputs[name].variance)
        row[name] = (eps_m.max(), eps_v.max())
    return row


def method_table(results: Path, reference) -> None:
    print("## max over time of eps_m / eps_v against Monte Carlo (10^4 runs)\n")
    print("| grid | runs | method | " + " | ".join(OUTPUTS) + " |")
    print("|---|---|---|" + "---|" * len(OUTPUTS))
    for grid in ("gh", "gk"):
        for level in (1, 2, 3, 4):
            path = results / f"grid-{grid}-l{level}.h5"
            if not path.exists():
                continue
            with ResultStore.open(path) as store:
                runs = store.status.size
            for kind, order in METHODS:
                try:
                    stats = analyse(path, options=FAST, method={"kind": kind, "order": order})
                except ValueError as exc:  # e.g. too few points for the regression's terms
                    print(f"| {grid}-l{level} | {runs} | {kind} {order} | {exc} |")
                    continue
                cells = [f"{m:.1e} / {v:.1e}" for m, v in max_errors(stats, reference).values()]
                print(f"| {grid}-l{level} | {runs} | {kind} {order} | " + " | ".join(cells) + " |")


def runs_per_accuracy(results: Path, reference) -> None:
    grid_ref = analyse(results / "grid-gh-l4.h5", options=FAST, method={"kind": "pseudo_galerkin", "order": 4})
    pg2 = analyse(results / "grid-gh-l2.h5", options=FAST, method={"kind": "pseudo_galerkin", "order": 2})
    with ResultStore.open(results / "mc-normal.h5") as store:
        ok = np.flatnonzero(store.status == Status.OK)
        runs = {name: store.output_matrix(name, ok) for name in ("theta_deg", "alpha_deg", "vtas_kt")}
    print("\n## Runs per accuracy (reference: PG-4 on the 2437-point grid)\n")
    print("| output | PG-4/2437 vs MC 10^4: max eps_v | PG-2/113: max eps_v | MC runs for the same | ratio |")
    print("|---|---|---|---|---|")
    for name, Y in runs.items():
        ref_mean, ref_var = grid_ref.outputs[name].mean, grid_ref.outputs[name].variance
        check = relative_errors(ref_mean, ref_var, reference.outputs[name].mean, reference.outputs[name].variance)[1]
        target = relative_errors(pg2.outputs[name].mean, pg2.outputs[name].variance, ref_mean, ref_var)[1].max()
        needed, error = None, np.inf
        for n in (50, 100, 200, 400, 800, 1600, 3200, 5000, 10000):
            if n > len(Y):
                break
            subsets = [Y[i:i + n] for i in range(0, len(Y) - n + 1, n)]
            errors = [relative_errors(s.mean(0), s.var(0, ddof=1), ref_mean, ref_var)[1].max() for s in subsets]
            error, largest = np.median(errors), n
            if error <= target:
                needed = n
                break
        if needed:
            shown, ratio = f"{needed}", f"{needed / 113:.0f}x"
        else:  # Monte Carlo's error falls as N^-1/2: extrapolate from the largest subset
            estimate = largest * (error / target) ** 2
            shown, ratio = f"> {largest} (~{estimate:.0e} by N^-1/2)", f"~{estimate / 113:.0e}x"
        print(f"| {name} | {check.max():.1e} | {target:.1e} | {shown} | {ratio} |")


def complete(path: Path) -> bool:
    if not path.exists():
        return False
    with ResultStore.open(path) as store:
        return store.pending().size == 0


def ensure_results(results: Path) -> None:
    """Run the campaigns whose results file is missing (a partial file is resumed)."""
    for name in ["mc-normal"] + [f"grid-{rule}-l{level}" for rule in ("gh", "gk") for level in (1, 2, 3, 4)]:
        path = results / f"{name}.h5"
        if not complete(path):
            print(f"running campaigns/{name}.yaml into {path} ...", flush=True)
            run_campaign(load_campaign(CAMPAIGNS / f"{name}.yaml", jsbsim_probe), out=path)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--results", type=Path, default=Path("results"))
    args = parser.parse_args()
    ensure_results(args.results)
    reference = analyse(args.results / "mc-normal.h5", options=FAST)
    method_table(args.results, reference)
    runs_per_accuracy(args.results, reference)


if __name__ == "__main__":
    main()
