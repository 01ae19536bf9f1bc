"""Accuracy of the non-intrusive methods on the bacm against a sharp reference, with its own floor.

The reference is the randomised-QMC campaign rqmc-normal (16 independent scrambles of 1024 Sobol'
points, 16,384 runs): the spread of its replicates gives the standard error of its mean and
variance at every time, the floor below which it cannot tell a method from the truth. Beside it,
the floor a Monte Carlo reference of N runs would have, σ/√N for the mean and the distribution-free
standard error of the variance, computed from the same runs' moments (no need to fly 10^5 runs to
know how well they would resolve).

Tables:
1. max over time of eps_m and eps_v (paper Eq. 49) for every output, method and grid (grid-gh-l1..l4)
   against the reference, with the reference's floor; "~" marks an error below 2 floors (within the
   reference's noise).
2. The floors: RQMC 16 × 1024 against Monte Carlo with 10^4 and 10^5 runs.
3. Runs per accuracy: the fewest grid runs whose max eps_v lies below the error Monte Carlo makes
   with 10^4 and with 10^5 runs (its floor at that N), per method.
4. When results/mc-normal-1e5.h5 exists (campaigns/mc-normal-1e5.yaml, about 35 minutes on 2 cores):
   its floor measured from its own runs, and its distance from the RQMC reference.
5. With --sparse: sparse PCE (LARS, max order 5, total degree) and least squares of order 3 on unscrambled
   Sobol' designs of 128, 256 and 500 points (qmc-sobol-N: rqmc-normal's campaign with that design),
   beside the grids, with each output's selected order and terms.

Uses results/rqmc-normal.h5 and results/grid-gh-l*.h5 (--levels) in --results, running the missing
campaigns first (about 12 minutes on 2 quiet cores).

Run: .venv/bin/python benchmarks/accuracy.py [--results results] [--levels 1 2 3 4] [--sparse]
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from uqflight.analysis.errors import relative_errors
from uqflight.analysis.floors import floors_from_moments
from uqflight.campaign import load_campaign
from uqflight.running.runner import run_campaign
from uqflight.simulators.aircraft_properties import AircraftProperties
from uqflight.analysis.statistics import BadInput, Options, analyse
from uqflight.store import ResultStore

OUTPUTS = ("theta_deg", "alpha_deg", "q_degps", "h_ft", "vtas_kt")
METHODS = [("pseudo_galerkin", None), ("interpolation", None), ("least_squares", None), ("regression", None)]
LEVELS = (1, 2, 3, 4)
QMC_POINTS = (128, 256, 500)
SPARSE = [("sparse", {"kind": "sparse", "order": 5, "selection": "lars", "q": 1.0}),
          ("least_squares", {"kind": "least_squares", "order": 3})]
CAMPAIGNS = Path(__file__).resolve().parents[1] / "campaigns"
FAST = Options(band_samples=2000, bootstrap=0)


def qmc_campaign(results: Path, n: int) -> Path:
    """rqmc-normal's campaign with one Sobol' design of n points (no replicates), written beside the results."""
    text = (CAMPAIGNS / "rqmc-normal.yaml").read_text()
    text = text.replace("name: rqmc-normal", f"name: qmc-sobol-{n}").replace(
        "design: {kind: sobol, samples: 1024, replicates: 16}", f"design: {{kind: sobol, samples: {n}}}")
    path = results / f"qmc-sobol-{n}.yaml"
    path.write_text(text)
    return path


def ensure_results(results: Path, levels, sparse: bool) -> None:
    """Run the campaigns whose results file is missing or incomplete (a partial file is resumed)."""
    names = {name: CAMPAIGNS / f"{name}.yaml" for name in ["rqmc-normal"] + [f"grid-gh-l{level}" for level in levels]}
    if sparse:
        names.update({f"qmc-sobol-{n}": None for n in QMC_POINTS})
    for name, campaign in names.items():
        path = results / f"{name}.h5"
        if path.exists():
            with ResultStore.open(path) as store:
                if store.pending().size == 0:
                    continue
        campaign = campaign or qmc_campaign(results, int(name.rsplit("-", 1)[1]))
        print(f"running {campaign} into {path} ...", flush=True)
        run_campaign(load_campaign(campaign, AircraftProperties), out=path)


def sparse_rows(results: Path, reference, floor_m: dict, floor_v: dict) -> None:
    """Table 5: sparse PCE and least squares on the QMC designs against the reference."""
    print("\n## Sparse PCE on QMC points: max over time of eps_m / eps_v against the RQMC reference (~: below 2 "
          "floors)\n")
    print("| design | runs | method | " + " | ".join(OUTPUTS) + " |")
    print("|---|---|---|" + "---|" * len(OUTPUTS))
    chosen = []
    for n in QMC_POINTS:
        path = results / f"qmc-sobol-{n}.h5"
        for label, method in SPARSE:
            try:
                stats = analyse(path, options=FAST, method=method)
            except BadInput as exc:
                print(f"| Sobol' {n} | {n} | {label} {method['order']} | refused: {str(exc).split(': ', 2)[-1][:90]} |")
                continue
            cells = []
            for name in OUTPUTS:
                eps_m, eps_v = relative_errors(stats.outputs[name].mean, stats.outputs[name].variance,
                                               reference.outputs[name].mean, reference.outputs[name].variance)
                cells.append(f"{mark(eps_m.max(), floor_m[name])} / {mark(eps_v.max(), floor_v[name])}")
            print(f"| Sobol' {n} | {n} | {label} {method['order']} | " + " | ".join(cells) + " |")
            if label == "sparse":
                chosen.append((n, {name: stats.outputs[name].selection for name in OUTPUTS}))
    print("\n(sparse: order chosen / terms / corrected LOO error of each output's basis)\n")
    print("| runs | " + " | ".join(OUTPUTS) + " |")
    print("|---|" + "---|" * len(OUTPUTS))
    for n, selections in chosen:
        print(f"| {n} | " + " | ".join(f"{s['order']} / {len(s['terms'])} / {s['loo_error']:.1e}"
                                        for s in selections.values()) + " |")


def monte_carlo_floor(reference, name: str, n: int) -> np.ndarray:
    """max over time of the eps_v floor a Monte Carlo reference of n runs would have (its moments)."""
    out = reference.outputs[name]
    fourth = _fourth_central(reference.path, name)
    return floors_from_moments(out.mean, out.variance, fourth, n)["eps_v_floor"].max()


def compare_references(monte_carlo, reference) -> None:
    """The 10^5-run Monte Carlo reference (when run): its own floor, measured from its runs, and its
    distance from the RQMC reference against the two floors together."""
    print(f"\n## Monte Carlo reference, {monte_carlo.completed} runs (campaigns/mc-normal-1e5.yaml)\n")
    print("| | " + " | ".join(OUTPUTS) + " |")
    print("|---|" + "---|" * len(OUTPUTS))
    floors, distance = {}, {}
    for name in OUTPUTS:
        out = monte_carlo.outputs[name]
        floors[name] = floors_from_moments(out.mean, out.variance, out.fourth_central, monte_carlo.completed)
        distance[name] = relative_errors(out.mean, out.variance, reference.outputs[name].mean,
                                         reference.outputs[name].variance)
    print("| its floor, max eps_m / eps_v | " + " | ".join(
        f"{floors[n]['eps_m_floor'].max():.1e} / {floors[n]['eps_v_floor'].max():.1e}" for n in OUTPUTS) + " |")
    print("| its distance from RQMC, max eps_m / eps_v | " + " | ".join(
        f"{distance[n][0].max():.1e} / {distance[n][1].max():.1e}" for n in OUTPUTS) + " |")


def mark(value: float, floor: float) -> str:
    """An error, with ~ when it is below 2 floors of the reference (within its noise)."""
    return f"~{value:.1e}" if value < 2 * floor else f"{value:.1e}"


def _fourth_central(path: str, name: str) -> np.ndarray:
    with ResultStore.open(path) as store:
        Y = store.output_matrix(name)
    return ((Y - Y.mean(axis=0)) ** 4).mean(axis=0)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--results", type=Path, default=Path("results"))
    parser.add_argument("--levels", type=int, nargs="+", default=list(LEVELS), choices=LEVELS,
                        help="Gauss-Hermite grid levels to compare (default: 1 2 3 4)")
    parser.add_argument("--sparse", action="store_true", help="add sparse PCE on QMC designs (table 5)")
    args = parser.parse_args()
    ensure_results(args.results, args.levels, args.sparse)
    reference = analyse(args.results / "rqmc-normal.h5", options=FAST)
    floor_v = {name: reference.outputs[name].replicate_moments[1].std(axis=0, ddof=1).max()
               / np.sqrt(reference.replicates) / reference.outputs[name].variance.max() for name in OUTPUTS}
    floor_m = {name: reference.outputs[name].replicate_moments[0].std(axis=0, ddof=1).max()
               / np.sqrt(reference.replicates) / np.abs(reference.outputs[name].mean).max() for name in OUTPUTS}

    print("## Floors: the errors a reference's own noise makes (max over time of eps_m / eps_v)\n")
    print("| reference | " + " | ".join(OUTPUTS) + " |")
    print("|---|" + "---|" * len(OUTPUTS))
    print(f"| RQMC {reference.replicates} × {reference.completed // reference.replicates} "
          f"({reference.completed} runs) | " + " | ".join(f"{floor_m[n]:.1e} / {floor_v[n]:.1e}" for n in OUTPUTS) + " |")
    mc = {n_runs: {name: monte_carlo_floor(reference, name, n_runs) for name in OUTPUTS} for n_runs in (10**4, 10**5)}
    for n_runs, floors in mc.items():
        mean_floor = {name: np.sqrt(reference.outputs[name].variance / n_runs).max()
                      / np.abs(reference.outputs[name].mean).max() for name in OUTPUTS}
        print(f"| Monte Carlo 10^{int(np.log10(n_runs))} (from the same moments) | "
              + " | ".join(f"{mean_floor[n]:.1e} / {floors[n]:.1e}" for n in OUTPUTS) + " |")

    monte_carlo = args.results / "mc-normal-1e5.h5"
    if monte_carlo.exists():
        compare_references(analyse(monte_carlo, options=FAST), reference)

    print("\n## max over time of eps_m / eps_v against the RQMC reference (~: below 2 floors)\n")
    print("| grid | runs | method | " + " | ".join(OUTPUTS) + " |")
    print("|---|---|---|" + "---|" * len(OUTPUTS))
    best: dict[str, list[tuple[int, dict]]] = {kind: [] for kind, _ in METHODS}
    for level in args.levels:
        path = args.results / f"grid-gh-l{level}.h5"
        with ResultStore.open(path) as store:
            runs = store.status.size
        for kind, _ in METHODS:
            order = level  # the largest order a level-L Gauss-Hermite grid projects (degree 2L + 1)
            try:
                stats = analyse(path, options=FAST, method={"kind": kind, "order": order})
            except BadInput as exc:
                print(f"| GH level {level} | {runs} | {kind} {order} | refused: {str(exc).split(': ', 2)[-1][:90]} |")
                continue
            cells, row = [], {}
            for name in OUTPUTS:
                eps_m, eps_v = relative_errors(stats.outputs[name].mean, stats.outputs[name].variance,
                                               reference.outputs[name].mean, reference.outputs[name].variance)
                row[name] = eps_v.max()
                cells.append(f"{mark(eps_m.max(), floor_m[name])} / {mark(eps_v.max(), floor_v[name])}")
            best[kind].append((runs, row))
            print(f"| GH level {level} | {runs} | {kind} {order} | " + " | ".join(cells) + " |")

    print("\n## Runs for the accuracy of Monte Carlo with 10^4 and 10^5 runs (max eps_v)\n")
    print("| method | " + " | ".join(f"{name}: 10^4 / 10^5" for name in OUTPUTS) + " |")
    print("|---|" + "---|" * len(OUTPUTS))
    for kind, rows in best.items():
        cells = []
        for name in OUTPUTS:
            needs = []
            for n_runs in (10**4, 10**5):
                fewest = next((runs for runs, row in rows if row[name] <= mc[n_runs][name]), None)
                unresolved = mc[n_runs][name] < 2 * floor_v[name]
                needs.append("-" if fewest is None else f"{fewest}" + ("?" if unresolved else ""))
            cells.append(" / ".join(needs))
        print(f"| {kind} | " + " | ".join(cells) + " |")
    largest = max((runs for rows in best.values() for runs, _ in rows), default=0)
    print(f"\n(-: no grid up to {largest} runs reaches it; ?: that Monte Carlo error is within 2 floors of the "
          "RQMC reference, so the comparison is at the reference's resolution)")
    if args.sparse:
        sparse_rows(args.results, reference, floor_m, floor_v)


if __name__ == "__main__":
    main()
