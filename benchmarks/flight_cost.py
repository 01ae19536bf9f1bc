"""Cost of one trimmed 50-s flight of the bacm (load, trim, fly), median of repeated runs.

Run: .venv/bin/python benchmarks/flight_cost.py [--repeats N]
"""
import argparse
import statistics
import time

from uqflight.simulators.jsbsim import JSBSimFlight


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeats", type=int, default=50)
    args = parser.parse_args()

    loads, trims, flights = [], [], []
    for _ in range(5):
        t0 = time.perf_counter()
        flight = JSBSimFlight()
        loads.append(time.perf_counter() - t0)
    for i in range(args.repeats):
        settings = {"aero/uq/CL0": 0.20 * (1 + 0.01 * (i % 7 - 3))}
        t0 = time.perf_counter()
        trim = flight.trim(settings)
        t1 = time.perf_counter()
        flight.run_trimmed(trim)
        t2 = time.perf_counter()
        trims.append(t1 - t0)
        flights.append(t2 - t0)
    print("| step | median [ms] | min [ms] | max [ms] |")
    print("|---|---|---|---|")
    for name, values in [("load aircraft", loads), ("trim", trims), ("trim + 50 s flight at 120 Hz", flights)]:
        print(f"| {name} | {1e3 * statistics.median(values):.1f} | {1e3 * min(values):.1f} | {1e3 * max(values):.1f} |")
    target = 0.15
    verdict = "meets" if statistics.median(flights) < target else "MISSES"
    print(f"\none trimmed 50-s flight: {statistics.median(flights):.3f} s ({verdict} the {target} s target)")


if __name__ == "__main__":
    main()
