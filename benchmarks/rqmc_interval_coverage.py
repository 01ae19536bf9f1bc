"""Coverage of the randomised-QMC proportion interval (analysis.proportions: exceedance and failure
probabilities of a `sobol` design with replicates) over independent scrambles, against closed forms.

Two events of known probability p, on the design's own points (designs.build_design, as a campaign draws
them): a small disk ξ1² + ξ2² < r² of uniform germs on [-1, 1]³ (p = π r²/4, curved so that no net
stratifies it exactly) and a normal tail ξ1 + ξ2 + ξ3 > t (p = Φ(−t/√3)). p is set for an expected count
of exceedances (6, 20, 60 over all runs), for R replicates of m points. Printed per case: the coverage of
the Student-t interval of the replicates' proportions alone, of the pooled runs' Wilson interval alone,
and of the hull of both (what the tool reports), each over --seeds designs (s.d. of a coverage of 0.95
over 2000 seeds: 0.005), with the mean width of each.

    .venv/bin/python benchmarks/rqmc_interval_coverage.py [--seeds 2000]
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from scipy import special

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from uqflight.analysis.failures import wilson_interval  # noqa: E402
from uqflight.designs import REGISTRY, build_design  # noqa: E402


def student_t(hits: np.ndarray, replicates: int) -> tuple[float, float]:
    shares = hits.reshape(replicates, -1).mean(axis=1)
    half = special.stdtrit(replicates - 1, 0.975) * shares.std(ddof=1) / np.sqrt(replicates)
    return max(shares.mean() - half, 0.0), min(shares.mean() + half, 1.0)


def events(expected: float, runs: int):
    """(name, germ, probability, hits(xi)) of the two closed forms with `expected` exceedances in `runs`."""
    p = expected / runs
    radius = np.sqrt(4 * p / np.pi)
    threshold = -np.sqrt(3) * special.ndtri(p)
    return [("disk", "uniform", p, lambda xi: xi[:, 0] ** 2 + xi[:, 1] ** 2 < radius**2),
            ("normal tail", "normal", p, lambda xi: xi.sum(axis=1) > threshold)]


def coverage(seeds: int, replicates: int, points: int, expected: float) -> list[str]:
    lines = []
    for name, germ, p, hit in events(expected, replicates * points):
        covered, widths = np.zeros(3), np.zeros(3)
        for seed in range(seeds):
            design = build_design({"kind": "sobol", "samples": points, "replicates": replicates}, [germ] * 3, seed)
            hits = hit(design.xi)
            found = REGISTRY["sobol"].sampling.proportion(hits, np.ones(hits.size, bool), design.info)
            intervals = (student_t(hits, replicates), wilson_interval(hits.mean(), hits.size),
                         (found["lower"], found["upper"]))
            for k, (lower, upper) in enumerate(intervals):
                covered[k] += lower <= p <= upper
                widths[k] += upper - lower
        cover, width = covered / seeds, widths / seeds / p
        lines.append(f"{name:12s} R={replicates:2d} m={points:4d} expected {expected:4g} exceedances: coverage "
                     f"t {cover[0]:.3f}, pooled Wilson {cover[1]:.3f}, hull (reported) {cover[2]:.3f}; "
                     f"mean width / p: {width[0]:.2f}, {width[1]:.2f}, {width[2]:.2f}")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=2000)
    args = parser.parse_args()
    for replicates, points in ((4, 256), (8, 128), (16, 64)):
        for expected in (6, 20, 60):
            print(*coverage(args.seeds, replicates, points, expected), sep="\n", flush=True)


if __name__ == "__main__":
    main()
