"""Peak resident memory of Monte Carlo campaigns with tSVD-only storage (raw: false).

Each campaign runs in a fresh process; the table shows the peak RSS of the runner process (it
holds the store and the tSVD) and of the largest worker. The target: flat in the number of runs
and under 1 GB. The 10^5 case uses the closed-form `phugoid` model through the python simulator
(five outputs x 1001 times, the aircraft's data volume; the simulator does not touch the store's
memory), so that it runs in minutes; `--jsbsim N` adds a campaign of N runs on the aircraft.

Run: .venv/bin/python benchmarks/memory.py [--sizes 10000 100000] [--jsbsim 10000]
"""
from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import textwrap

PYTHON_MODEL = """
name: memory-{n}
seed: 5
simulator: {{kind: python, function: "uqflight.simulators.models:phugoid"}}
parameters:
  a: {{distribution: normal, nominal: 0, lower: -3, upper: 3}}
  b: {{distribution: normal, nominal: 0, lower: -3, upper: 3}}
  c: {{distribution: normal, nominal: 0, lower: -3, upper: 3}}
design: {{kind: monte_carlo, samples: {n}}}
execution: {{workers: 2, chunk: 64}}
storage: {{raw: false, tsvd: {{tol: 1.0e-8, batch: 1000}}}}
"""
JSBSIM = """
name: memory-jsbsim-{n}
seed: 5
simulator: {{kind: jsbsim}}
parameters:
  CL0:     {{property: aero/uq/CL0,     distribution: normal, interval_pct: 23.05}}
  CLalpha: {{property: aero/uq/CLalpha, distribution: normal, interval_pct: 5.27}}
  CD0:     {{property: aero/uq/CD0,     distribution: normal, interval_pct: 12.4}}
  k2:      {{property: aero/uq/k2,      distribution: normal, interval_pct: 379.74}}
design: {{kind: monte_carlo, samples: {n}}}
execution: {{workers: 2}}
storage: {{raw: false, tsvd: {{tol: 1.0e-8, batch: 1000}}}}
"""
MEASURE = textwrap.dedent("""
    import resource, sys, time
    from uqflight.campaign import load_campaign
from uqflight.simulators.aircraft_properties import AircraftProperties
    from uqflight.running.runner import run_campaign
    t0 = time.perf_counter()
    summary = run_campaign(load_campaign(sys.argv[1], AircraftProperties), out=sys.argv[2])
    print(summary.ran, time.perf_counter() - t0,
          resource.getrusage(resource.RUSAGE_SELF).ru_maxrss,
          resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)
""")


def measure(text: str) -> tuple[int, float, float, float]:
    with tempfile.TemporaryDirectory() as tmp:
        campaign = f"{tmp}/c.yaml"
        with open(campaign, "w") as fh:
            fh.write(text)
        out = subprocess.run([sys.executable, "-c", MEASURE, campaign, f"{tmp}/r.h5"],
                             capture_output=True, text=True, check=True).stdout.split()
    ran, seconds, parent_kb, child_kb = int(out[0]), float(out[1]), float(out[2]), float(out[3])
    return ran, seconds, parent_kb / 1024, child_kb / 1024


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", type=int, nargs="+", default=[10000, 100000])
    parser.add_argument("--jsbsim", type=int, default=0)
    args = parser.parse_args()
    cases = [(f"phugoid model, {n} runs", PYTHON_MODEL.format(n=n)) for n in args.sizes]
    if args.jsbsim:
        cases.append((f"bacm on JSBSim, {args.jsbsim} runs", JSBSIM.format(n=args.jsbsim)))
    print("| campaign (raw: false, tSVD 1e-8) | runs | time [s] | peak RSS runner [MB] | peak RSS worker [MB] |")
    print("|---|---|---|---|---|")
    for name, text in cases:
        ran, seconds, parent, child = measure(text)
        print(f"| {name} | {ran} | {seconds:.0f} | {parent:.0f} | {child:.0f} |")


if __name__ == "__main__":
    main()
