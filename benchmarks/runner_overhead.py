"""Runner overhead against a bare JSBSim loop, and parallel scaling (local pool and Dask).

1. Seconds per sample of `uqflight run` with one worker (campaign -> worker -> HDF5) against a
   bare loop with plain `jsbsim` in this process: the same aircraft, trim sequence (JSBSim's trim on
   both sides: `simulator.trim: jsbsim`), 1-deg elevator pulse and five recorded outputs at 20 Hz.
   Measured side by side, alternating, median of the repeats. Target: ratio <= 1.05.
2. The campaign grid-gh-l3 (589 runs, the Newton trim) with 1 and 2 workers (local) and a Dask
   LocalCluster of 2 workers, wall clock including worker start-up, median of the repeats.
   Target: >= 1.9x with 2 workers.

Run: .venv/bin/python benchmarks/runner_overhead.py [--samples 200] [--repeats 3]
"""
from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import jsbsim
import numpy as np

from uqflight.campaign import load_campaign, parse_campaign
from uqflight.simulators.jsbsim_probe import jsbsim_probe
from uqflight.execution import run_campaign
from uqflight.paper import table1_parameters_yaml
from uqflight.parameters import to_physical
from uqflight.simulators.jsbsim import REPO_ROOT

CAMPAIGNS = Path(__file__).resolve().parents[1] / "campaigns"

CAMPAIGN = """
name: bench-{samples}-{tag}
seed: 11
simulator: {{kind: jsbsim, duration_s: 50, output_rate_hz: 20, trim: jsbsim}}
parameters:
{parameters}design: {{kind: monte_carlo, samples: {samples}}}
storage: {{raw: true}}
"""
RECORDED = ["aero/alpha-deg", "attitude/theta-deg", "position/h-sl-ft", "velocities/q-rad_sec",
            "velocities/vtrue-kts"]


def bare_loop(kappa: np.ndarray, properties: list[str]) -> np.ndarray:
    """The same flights with plain jsbsim: load once, then reset/set/trim/fly/record per sample."""
    jsbsim.set_logger(jsbsim.DefaultLogger(jsbsim.LogLevel.FATAL))
    fdm = jsbsim.FGFDMExec(str(REPO_ROOT))
    fdm.set_debug_level(0)
    fdm.load_model("bacm")
    fdm.set_dt(1 / 120)
    pm = fdm.get_property_manager()
    nodes = [pm.get_node(p) for p in RECORDED]
    pulse = pm.get_node("fcs/elevator-excitation-deg")
    out = np.empty((len(kappa), 1001, len(RECORDED)))
    for j, row in enumerate(kappa):
        fdm["ic/h-sl-ft"], fdm["ic/vt-kts"] = 15000.0, 200.0
        fdm["ic/gamma-deg"] = fdm["ic/beta-deg"] = fdm["ic/phi-deg"] = 0.0
        fdm.reset_to_initial_conditions(0)
        for prop, value in zip(properties, row):
            fdm[prop] = value
        fdm["propulsion/fuel_freeze"] = 1
        fdm["fcs/advance-cmd-norm[0]"] = fdm["fcs/advance-cmd-norm[1]"] = 1.0
        fdm["propulsion/set-running"] = -1
        fdm["simulation/do_simple_trim"] = 1
        fdm.get_propulsion().get_steady_state()
        out[j, 0] = [n.get_double_value() for n in nodes]
        for i in range(6000):
            if i == 120:
                pulse.set_double_value(1.0)
            elif i == 240:
                pulse.set_double_value(0.0)
            fdm.run()
            if (i + 1) % 6 == 0:
                out[j, (i + 1) // 6] = [n.get_double_value() for n in nodes]
    return out


def campaign(samples: int, tag: str):
    text = CAMPAIGN.format(parameters=table1_parameters_yaml(), samples=samples, tag=tag)
    return parse_campaign(text, "bench.yaml", jsbsim_probe)


def timed_run(spec, workers: int, executor: str = "local") -> float:
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        summary = run_campaign(spec, out=Path(tmp) / "r.h5", workers=workers, executor=executor)
        elapsed = time.perf_counter() - t0
    assert summary.ran == len(spec.design().xi) and not summary.failures
    return elapsed


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--samples", type=int, default=200)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()

    spec = campaign(args.samples, "overhead")
    kappa = to_physical(spec.parameters, spec.design().xi)
    properties = [p.property for p in spec.parameters]
    bare, runner = [], []
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        bare_loop(kappa, properties)
        bare.append((time.perf_counter() - t0) / args.samples)
        runner.append(timed_run(spec, workers=1) / args.samples)
    b, r = statistics.median(bare), statistics.median(runner)
    print(f"## Runner overhead ({args.samples} samples, median of {args.repeats})\n")
    print("| loop | s per sample |\n|---|---|")
    print(f"| bare jsbsim loop | {b:.4f} |\n| uqflight run, 1 worker | {r:.4f} |")
    print(f"\nratio: {r / b:.3f} (target <= 1.05)\n")

    spec = load_campaign(CAMPAIGNS / "grid-gh-l3.yaml", jsbsim_probe)
    runs = len(spec.design().xi)
    rows = [(name, statistics.median(timed_run(spec, workers, executor) for _ in range(args.repeats)))
            for name, workers, executor in (("local, 1 worker", 1, "local"), ("local, 2 workers", 2, "local"),
                                            ("dask LocalCluster, 2 workers", 2, "dask"))]
    base = runs / rows[0][1]
    print(f"## Parallel scaling (grid-gh-l3, {runs} runs, wall clock with start-up, median of {args.repeats})\n")
    print("| executor | runs/s | speed-up |\n|---|---|---|")
    for name, seconds in rows:
        rate = runs / seconds
        print(f"| {name} | {rate:.1f} | {rate / base:.2f} |")


if __name__ == "__main__":
    main()
