"""Runner overhead against a bare JSBSim loop, and parallel scaling (local pool and Dask).

1. Seconds per sample of `uqflight run` with one worker (campaign -> worker -> HDF5) against a
   bare loop with plain `jsbsim` in this process: the same aircraft, trim sequence (JSBSim's trim on
   both sides: `simulator.trim: jsbsim`), 1-deg elevator pulse and five recorded outputs at 20 Hz.
   Target: ratio <= 1.05.
2. The campaign grid-gh-l3 (589 runs, the Newton trim) with 1 and 2 workers (local) and a Dask
   LocalCluster of 2 workers, wall clock including worker start-up. Target: >= 1.9x with 2 workers.
   Beside it, the machine's own ceiling: the same chunks flown by 1 and by 2 bare processes
   (`uqflight.running.worker.run_chunk`, no runner, no HDF5), started the same way (a fresh Python each).

On a shared machine single runs scatter by +-10 %: every repeat measures all rows back to back (in
alternating order), and the tables give the median over the repeats and the best one (the run least
disturbed by others, the closest to a quiet machine's).

Run: .venv/bin/python benchmarks/runner_overhead.py [--samples 200] [--repeats 5]
"""
from __future__ import annotations

import argparse
import pickle
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import jsbsim
import numpy as np

from uqflight.campaign import load_campaign, parse_campaign
from uqflight.simulators.aircraft_properties import AircraftProperties
from uqflight.running.runner import run_campaign
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))  # the study's Table 1 (tests/paper.py)
from paper import table1_parameters_yaml  # noqa: E402
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
    return parse_campaign(text, "bench.yaml", AircraftProperties)


def timed_run(spec, workers: int, executor: str = "local") -> float:
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        summary = run_campaign(spec, out=Path(tmp) / "r.h5", workers=workers, executor=executor)
        elapsed = time.perf_counter() - t0
    assert summary.ran == len(spec.design().xi) and not summary.failures
    return elapsed


FLY_SHARE = """
import pickle, sys
from uqflight.running.worker import run_chunk
with open(sys.argv[1], "rb") as f:
    spec, kappa, share, n_times, outputs = pickle.load(f)
for chunk in share:
    run_chunk(spec, chunk, kappa[chunk], n_times, outputs)
"""


def bare_processes(campaign_spec, processes: int) -> float:
    """Seconds for `processes` fresh Python processes (importing what a worker imports) to fly the
    campaign's chunks, dealt out in turn."""
    from uqflight.running.runner import nominal_kappa, pending_chunks, worker_spec
    from uqflight.running.worker import nominal_flight

    spec, kappa = worker_spec(campaign_spec), to_physical(campaign_spec.parameters, campaign_spec.design().xi)
    nominal = nominal_flight(spec, nominal_kappa(campaign_spec))
    time_grid, outputs = nominal.time, nominal.outputs
    chunks = pending_chunks(np.arange(len(kappa)), campaign_spec.execution.chunk, len(kappa))
    with tempfile.TemporaryDirectory() as tmp:
        shares = []
        for i in range(processes):
            shares.append(Path(tmp) / f"share{i}.pickle")
            shares[-1].write_bytes(pickle.dumps((spec, kappa, chunks[i::processes], len(time_grid), outputs)))
        t0 = time.perf_counter()
        jobs = [subprocess.Popen([sys.executable, "-c", FLY_SHARE, str(share)]) for share in shares]
        codes = [job.wait() for job in jobs]
        elapsed = time.perf_counter() - t0
    assert codes == [0] * processes, codes
    return elapsed


def measure(rows: dict, repeats: int) -> dict[str, list[float]]:
    """{name: seconds of each repeat}, every repeat running all rows, in alternating order."""
    seconds = {name: [] for name in rows}
    for repeat in range(repeats):
        for name in (list(rows) if repeat % 2 == 0 else list(reversed(rows))):
            seconds[name].append(rows[name]())
    return seconds


def overhead(samples: int, repeats: int) -> None:
    spec = campaign(samples, "overhead")
    kappa = to_physical(spec.parameters, spec.design().xi)
    properties = [p.property for p in spec.parameters]

    def bare():
        t0 = time.perf_counter()
        bare_loop(kappa, properties)
        return time.perf_counter() - t0

    seconds = measure({"bare jsbsim loop": bare, "uqflight run, 1 worker": lambda: timed_run(spec, 1)},
                      repeats)
    (b, bare_s), (r, run_s) = seconds.items()
    ratios = [x / y for x, y in zip(run_s, bare_s)]
    print(f"## Runner overhead ({samples} samples, {repeats} repeats)\n")
    print("| loop | s per sample, median | best |\n|---|---|---|")
    for name, values in seconds.items():
        print(f"| {name} | {statistics.median(values) / samples:.4f} | {min(values) / samples:.4f} |")
    print(f"\nratio run / bare: of the medians {statistics.median(run_s) / statistics.median(bare_s):.3f}, "
          f"median of the repeats' {statistics.median(ratios):.3f}, of the best runs "
          f"{min(run_s) / min(bare_s):.3f}, per repeat {', '.join(f'{x:.3f}' for x in ratios)} (target <= 1.05)\n")


def scaling(repeats: int) -> None:
    spec = load_campaign(CAMPAIGNS / "grid-gh-l3.yaml", AircraftProperties)
    runs = len(spec.design().xi)
    rows = {"bare processes, 1": lambda: bare_processes(spec, 1),
            "bare processes, 2": lambda: bare_processes(spec, 2),
            "local, 1 worker": lambda: timed_run(spec, 1),
            "local, 2 workers": lambda: timed_run(spec, 2),
            "dask LocalCluster, 2 workers": lambda: timed_run(spec, 2, "dask")}
    seconds = measure(rows, repeats)
    print(f"## Parallel scaling (grid-gh-l3, {runs} runs, wall clock with start-up, {repeats} repeats)\n")
    print("| executor | runs/s, median | speed-up, median | per repeat | best run's speed-up |")
    print("|---|---|---|---|---|")
    for name, values in seconds.items():
        one = seconds["bare processes, 1" if name.startswith("bare") else "local, 1 worker"]
        per_repeat = [a / b for a, b in zip(one, values)]
        print(f"| {name} | {runs / statistics.median(values):.1f} | {statistics.median(per_repeat):.2f} | "
              f"{', '.join(f'{x:.2f}' for x in per_repeat)} | {min(one) / min(values):.2f} |")
    print("\nbare processes: the machine's own ceiling, the same chunks with no runner and no HDF5.")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--samples", type=int, default=200)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--part", choices=("overhead", "scaling", "both"), default="both")
    args = parser.parse_args()
    if args.part in ("overhead", "both"):
        overhead(args.samples, args.repeats)
    if args.part in ("scaling", "both"):
        scaling(args.repeats)


if __name__ == "__main__":
    main()
