"""Cost of one trimmed 50-s flight of the bacm (load, trim, fly): JSBSim's trim and the Newton
trim (uqflight.simulators.trim) side by side in one run.

Both simulators fly the same samples (normal draws of the Table 1 coefficients, sigma = interval/3),
alternating sample by sample so that both see the same machine load. "trim" is
`JSBSimFlight.trim` (reset, settings, trim, engines' steady state); "sample" is trim + the 50-s
flight at 120 Hz. The Newton trim's nominal (computed once per process, then cached) is timed
separately. Targets: mean Newton trim <= 3 ms; mean sample <= 0.75 x JSBSim's.

Run: .venv/bin/python benchmarks/flight_cost.py [--repeats N]
"""
import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))  # the study's Table 1 (tests/paper.py)
from paper import TABLE1  # noqa: E402
from uqflight.simulators.scenarios.level_flight import FlightSetup, JSBSimFlight


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeats", type=int, default=100)
    args = parser.parse_args()

    loads = []
    for _ in range(5):
        t0 = time.perf_counter()
        JSBSimFlight()
        loads.append(time.perf_counter() - t0)
    flights = {name: JSBSimFlight(FlightSetup(trim=name)) for name in ("jsbsim", "newton")}
    t0 = time.perf_counter()
    flights["newton"]._level_trim()
    nominal_s = time.perf_counter() - t0

    names = list(TABLE1)
    nominal = np.array([flights["jsbsim"].property_value(f"aero/uq/{p}") for p in names])
    pct = np.array([p for _, p in TABLE1.values()]) / 100
    rows = nominal + np.abs(nominal) * pct / 3 * np.random.default_rng(15).standard_normal((args.repeats, len(names)))
    trims = {name: [] for name in flights}
    samples = {name: [] for name in flights}
    for row in rows:
        settings = {f"aero/uq/{p}": float(v) for p, v in zip(names, row)}
        for name, flight in flights.items():
            t0 = time.perf_counter()
            trim = flight.trim(settings)
            t1 = time.perf_counter()
            flight.run_trimmed(trim)
            t2 = time.perf_counter()
            trims[name].append(t1 - t0)
            samples[name].append(t2 - t0)

    ms = lambda values: 1e3 * statistics.fmean(values)  # noqa: E731
    md = lambda values: 1e3 * statistics.median(values)  # noqa: E731
    print(f"{args.repeats} samples (normal draws of Table 1), alternating; load aircraft "
          f"{md(loads):.1f} ms (median); Newton nominal, once per process: {1e3 * nominal_s:.1f} ms\n")
    print("| trim | trim mean [ms] | trim median [ms] | sample mean [ms] | sample median [ms] |")
    print("|---|---|---|---|---|")
    for name in flights:
        print(f"| {name} | {ms(trims[name]):.2f} | {md(trims[name]):.2f} | {ms(samples[name]):.1f} | {md(samples[name]):.1f} |")
    trim_ratio = ms(trims["newton"]) / ms(trims["jsbsim"])
    sample_ratio = ms(samples["newton"]) / ms(samples["jsbsim"])
    print(f"| newton / jsbsim | {trim_ratio:.3f} | {md(trims['newton']) / md(trims['jsbsim']):.3f} | "
          f"{sample_ratio:.3f} | {md(samples['newton']) / md(samples['jsbsim']):.3f} |")
    print(f"\nfallbacks to JSBSim's trim: {flights['newton']._level_trim().fallbacks} of {args.repeats}")
    ok_trim = ms(trims["newton"]) <= 3.0
    ok_sample = sample_ratio <= 0.75
    print(f"mean Newton trim {ms(trims['newton']):.2f} ms: {'meets' if ok_trim else 'MISSES'} the 3 ms target; "
          f"sample ratio {sample_ratio:.3f}: {'meets' if ok_sample else 'MISSES'} the 0.75 target")


if __name__ == "__main__":
    main()
