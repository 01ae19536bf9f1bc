"""What `analysis.band_samples` buys: the 99 % band's sampling error and the analysis's cost of a PCE's
draws, for several draw counts, on the paper's expansion (paper-pg2-l2: 7 inputs, order 2).

A PCE's band is the 0.5 % and 99.5 % quantiles of N seeded draws of the expansion, at every time.
The error is measured against the band of --reference draws (default 10^6), in units of the
output's standard deviation at that time, over --seeds seeds and every time after the pulse
(t > 1.5 s, where the outputs vary); the reference's own error is about 0.035 σ · √(20000 / 10^6)
= 0.005 σ. The cost is the CPU seconds of `statistics.analyse` of the file in this process (both of
its threads; the median over the seeds): the whole analysis, of which the draws' rebuilding, sort and
KDE scale with N. docs/performance.md says why the default stays 20,000.

Run: .venv/bin/python benchmarks/band_samples.py [--results results/paper-pg2-l2.h5] [--seeds 8]
     [--counts 2000 8192 20000 50000] [--reference 1000000]
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from uqflight.campaign import load_campaign
from uqflight.running.runner import run_campaign
from uqflight.simulators.aircraft_properties import AircraftProperties
from uqflight.analysis.statistics import Options, analyse

ROOT = Path(__file__).resolve().parents[1]
AFTER_PULSE_S = 1.5  # the band is compared where the outputs vary: before the pulse every draw is the trim


def bands(path: Path, samples: int, seed: int) -> tuple[dict, dict, float]:
    """({output: (2, T') band after the pulse}, {output: (T',) std there}, CPU seconds) of the file's PCE
    with `samples` draws."""
    start = time.process_time()
    stats = analyse(path, options=Options(band_samples=samples, bootstrap=0, seed=seed))
    seconds = time.process_time() - start
    late = {name: out.time > AFTER_PULSE_S for name, out in stats.outputs.items()}
    return ({name: np.array(out.band99)[:, late[name]] for name, out in stats.outputs.items()},
            {name: np.sqrt(out.variance)[late[name]] for name, out in stats.outputs.items()}, seconds)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--results", type=Path, default=ROOT / "results" / "paper-pg2-l2.h5",
                        help="paper-pg2-l2's results file (run first when missing)")
    parser.add_argument("--seeds", type=int, default=8)
    parser.add_argument("--counts", type=int, nargs="+", default=[2000, 8192, 20000, 50000])
    parser.add_argument("--reference", type=int, default=1_000_000)
    args = parser.parse_args()
    if not args.results.exists():
        print(f"running campaigns/paper-pg2-l2.yaml into {args.results} ...", flush=True)
        run_campaign(load_campaign(ROOT / "campaigns" / "paper-pg2-l2.yaml", AircraftProperties), out=args.results)
    reference, std, _ = bands(args.results, args.reference, seed=10**6)
    print(f"{'draws':>7}  {'analysis cpu [s]':>16}  " + "  ".join(f"{name:>18}" for name in reference))
    print(f"{'':>7}  {'':>16}  " + "  ".join(f"{'rms / max [σ]':>18}" for _ in reference))
    for samples in args.counts:
        errors, seconds = {name: [] for name in reference}, []
        for seed in range(args.seeds):
            found, _, took = bands(args.results, samples, seed)
            seconds.append(took)
            for name, band in found.items():
                errors[name].append((band - reference[name]) / np.where(std[name] > 0, std[name], np.nan))
        cells = []
        for name in reference:
            error = np.array(errors[name])
            cells.append(f"{np.sqrt(np.nanmean(error ** 2)):8.4f} / {np.nanmax(np.abs(error)):6.3f}")
        print(f"{samples:7d}  {np.median(seconds):16.2f}  " + "  ".join(f"{cell:>18}" for cell in cells))
    print(f"(reference: {args.reference} draws; {args.seeds} seeds per row; errors in units of the output's std, "
          f"every time after {AFTER_PULSE_S:g} s)")


if __name__ == "__main__":
    main()
