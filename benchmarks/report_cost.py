"""What reading the results costs against flying them: whole-process wall times of `uqflight` commands,
side by side with their targets (issue 26).

  run       campaigns/paper-pg2-l2.yaml (113 JSBSim flights; the reference the report is measured by)
  report    of those 113 runs, plots included                                  target <= 3 s, <= run
  export    `surrogate export` of the same file                                target <= 3 s
  calibrate the README's example as printed: campaigns/grid-gh-l2.yaml's 113 runs as surrogate, the
            `simulate`d flight (CL0 0.223, k2 -0.004, noise 0.05 deg on alpha and theta, seed 1) as
            data, calibrated on alpha and theta with that noise given                 <= 10 s
  mc-1e4    report of a 10^4-run Monte Carlo file in tSVD storage (a closed-form python model of 5
            outputs x 1001 times, 7 normal inputs: its run is not JSBSim's)     target <= 10 s

Measure on a quiet machine (nothing else running): every time here is wall clock of a fresh process,
interpreter start-up and imports included. The package's bytecode is compiled first, as an installed
package's is (pip compiles it; an editable install writes it on first import, unless
PYTHONDONTWRITEBYTECODE is set: then every process would compile uqflight's sources again, 0.1-0.2 s).
The cpu column is the user + system seconds of each command's processes, its forked children included:
a wall time near cpu / 2 says the command kept both cores busy, and only less work would make it faster.

Run: .venv/bin/python benchmarks/report_cost.py [--work DIR] [--skip-calibrate]
"""
from __future__ import annotations

import argparse
import compileall
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import NamedTuple

ROOT = Path(__file__).resolve().parents[1]
UQFLIGHT = str(Path(sys.executable).with_name("uqflight"))
README_CALIBRATE = ("--output", "alpha_deg", "--output", "theta_deg", "--noise", "alpha_deg=0.05",
                    "--noise", "theta_deg=0.05")  # the README's calibrate options
MODEL = '''
import numpy as np
T = np.linspace(0.0, 50.0, 1001)
def f(p):
    """A damped short-period-like response of 5 outputs to 7 inputs (closed form, 1001 times)."""
    w, z = 2.0 * p["w"], 0.3 * p["z"]
    decay = np.exp(-z * w * T) * np.sin(w * np.sqrt(1.0 - z * z) * T)
    return {"time": T, "alpha_deg": 5.0 + p["a"] + p["b"] * decay,
            "theta_deg": 5.0 + p["a"] + 0.5 * p["b"] * T / 50 + decay,
            "h_ft": 15000.0 + 10.0 * p["c"] * T + decay,
            "q_degps": w * np.exp(-z * w * T) * np.cos(w * T) * p["d"],
            "vtas_kt": 200.0 + p["e"] * (1.0 - np.exp(-T / 20.0)) + 0.1 * decay}
'''
MC_CAMPAIGN = """
name: mc-1e4-closed-form
seed: 7
simulator: {kind: python, function: "model.py:f"}
parameters:
""" + "".join(f"  {name}: {{distribution: normal, nominal: 1.0, interval_pct: 30}}\n" for name in "wzabcde") + """
design: {kind: monte_carlo, samples: 10000}
method: {kind: monte_carlo}
execution: {workers: 2, chunk: 500}
storage: {raw: false, tsvd: {tol: 1.0e-10, batch: 1000}}
"""


class Timing(NamedTuple):
    wall: float  # seconds
    cpu: float  # user + system seconds of the command's processes (its forked children included)


def timed(*args, cwd=None, ok=(0,)) -> Timing:
    """Wall and CPU seconds of `uqflight ARGS` in a fresh process; exits when it fails."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run([UQFLIGHT, *map(str, args)], cwd=cwd, capture_output=True, text=True, check=False)
    seconds = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode not in ok:
        sys.exit(f"uqflight {' '.join(map(str, args))} failed ({done.returncode}):\n{done.stderr[-2000:]}")
    return Timing(seconds, (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime))


def flight_data(work: Path) -> Path:
    """The README's simulated flight: CL0 and k2 off nominal, noise on alpha and theta (seeded)."""
    data = work / "flight.csv"
    timed("simulate", "--set", "aero/uq/CL0=0.223", "--set", "aero/uq/k2=-0.004", "--noise", "alpha_deg=0.05",
          "--noise", "theta_deg=0.05", "--seed", "1", "--out", data)
    return data


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--work", type=Path, help="folder for the files (default: a temporary one)")
    parser.add_argument("--skip-calibrate", action="store_true", help="leave out the calibration (113 more flights)")
    args = parser.parse_args()
    compileall.compile_dir(ROOT / "uqflight", quiet=1)
    work = args.work or Path(tempfile.mkdtemp(prefix="report-cost-"))
    work.mkdir(parents=True, exist_ok=True)
    rows = []

    pg2 = work / "pg2.h5"
    flying = timed("run", ROOT / "campaigns/paper-pg2-l2.yaml", "--out", pg2, "--restart")
    rows.append(("run paper-pg2-l2 (113 flights)", flying, None))
    rows.append(("report paper-pg2-l2", timed("report", pg2, "--out", work / "pg2-report"), min(3.0, flying.wall)))
    rows.append(("surrogate export paper-pg2-l2", timed("surrogate", "export", pg2, "--out", work / "pce.json"), 3.0))

    if not args.skip_calibrate:
        grid = work / "grid-gh-l2.h5"
        rows.append(("run grid-gh-l2 (113 flights)", timed("run", ROOT / "campaigns/grid-gh-l2.yaml", "--out", grid,
                                                          "--restart"), None))
        data = flight_data(work)
        rows.append(("calibrate (README example)", timed("calibrate", grid, "--data", data, *README_CALIBRATE,
                                                        "--out", work / "calibrated"), 10.0))

    (work / "model.py").write_text(MODEL)
    (work / "mc.yaml").write_text(MC_CAMPAIGN)
    mc = work / "mc.h5"
    rows.append(("run mc 10^4 (python model, tSVD)", timed("run", work / "mc.yaml", "--out", mc, "--restart"), None))
    rows.append(("report mc 10^4 (tSVD)", timed("report", mc, "--out", work / "mc-report"), 10.0))

    width = max(len(name) for name, _, _ in rows)
    print(f"{'command':<{width}}  {'wall [s]':>8}  {'cpu [s]':>7}  {'target [s]':>10}  met")
    for name, timing, target in rows:
        verdict = "" if target is None else ("yes" if timing.wall <= target else "NO")
        shown = "" if target is None else f"{target:.1f}"
        print(f"{name:<{width}}  {timing.wall:8.2f}  {timing.cpu:7.2f}  {shown:>10}  {verdict}")
    print(f"(files in {work})")


if __name__ == "__main__":
    main()
