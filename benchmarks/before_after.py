"""The same commands on two revisions of uqflight, side by side: is a change (a restructure) slower?

Rows, each a whole process timed by the wall clock (start-up and imports included):

1. `run` of the paper's flight (bacm, Table 1's seven coefficients, 1-deg elevator pulse, 50 s at 20 Hz)
   with SAMPLES Monte Carlo samples in one worker: the runner's cost per sample is the row's seconds / SAMPLES.
2. `report` of campaigns/paper-pg2-l2.yaml (113 JSBSim flights on the level-2 Gauss-Hermite grid).
3. `report` of campaigns/737-turn.yaml: JSBSim's own 737_cruise_steady_turn script with quantities of interest
   and an exceedance.

The revision BEFORE is checked out in a git worktree under WORK and imported through PYTHONPATH; AFTER is this
checkout. Each side flies its own results files first (untimed: the two revisions may store them differently),
and each side compiles its bytecode first, as an install does. Every repeat times every row on both sides back
to back, in alternating order (before first, then after first), so that a shared machine's drift falls on both;
the table gives the median over the repeats and the best one (the least disturbed), and after / before taken pair
by pair (a repeat's two runs of a row, back to back), whose median a drifting machine moves least.

Run: .venv/bin/python benchmarks/before_after.py [--before REV] [--samples 200] [--repeats 5] [--work DIR]
"""
from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

AFTER = Path(__file__).resolve().parents[1]
RUN_CAMPAIGN = """name: runner-cost
seed: 1
simulator:
  kind: jsbsim
  aircraft: bacm
  flight: {{altitude_ft: 15000, airspeed_ktas: 200}}
  excitation: {{kind: pulse, amplitude_deg: 1.0, start_s: 1.0, duration_s: 1.0}}
  duration_s: 50
  output_rate_hz: 20
  outputs: [alpha_deg, theta_deg, h_ft, q_degps, vtas_kt]
parameters:
  CL0:     {{property: aero/uq/CL0,     distribution: normal, interval_pct: 23.05}}
  CLalpha: {{property: aero/uq/CLalpha, distribution: normal, interval_pct: 5.27}}
  CD0:     {{property: aero/uq/CD0,     distribution: normal, interval_pct: 12.4}}
  k1:      {{property: aero/uq/k1,      distribution: normal, interval_pct: 89.16}}
  k2:      {{property: aero/uq/k2,      distribution: normal, interval_pct: 379.74}}
  Cm0:     {{property: aero/uq/Cm0,     distribution: normal, interval_pct: 10.46}}
  Cmq:     {{property: aero/uq/Cmq,     distribution: normal, interval_pct: 0.53}}
design: {{kind: monte_carlo, samples: {samples}}}
method: {{kind: monte_carlo}}
execution: {{workers: 1}}
"""


def console_script(side: Path) -> str:
    """Python that calls the checkout's `uqflight` console script (its entry point in pyproject.toml)."""
    module, function = re.search(r'^uqflight = "([\w.]+):(\w+)"', (side / "pyproject.toml").read_text(),
                                 re.MULTILINE).groups()
    return f"import sys; sys.argv[0] = 'uqflight'; from {module} import {function}; {function}()"


def uqflight(side: Path, *args, cwd: Path) -> float:
    """Seconds of one `uqflight ARGS` of the checkout `side` (its package first on the path: `cwd`, which
    Python puts before it, holds no package)."""
    env = {**os.environ, "PYTHONPATH": str(side)}
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    started = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", console_script(side), *map(str, args)], cwd=cwd, env=env,
                          capture_output=True, text=True)
    seconds = time.perf_counter() - started
    if done.returncode != 0:
        raise SystemExit(f"{side}: uqflight {' '.join(map(str, args))} failed:\n{done.stderr[-2000:]}")
    return seconds


def prepare(side: Path, folder: Path, samples: int) -> dict[str, list]:
    """The side's results files flown (untimed) and its rows' commands."""
    folder.mkdir(parents=True, exist_ok=True)
    subprocess.run([sys.executable, "-m", "compileall", "-q", str(side / "uqflight")], check=True)
    (folder / "runner-cost.yaml").write_text(RUN_CAMPAIGN.format(samples=samples))
    for name in ("paper-pg2-l2", "737-turn"):
        uqflight(side, "run", AFTER / "campaigns" / f"{name}.yaml", "--out", folder / f"{name}.h5", "--force",
                 cwd=folder)
    return {f"run {samples} samples, 1 worker": ["run", folder / "runner-cost.yaml", "--out", folder / "run.h5",
                                                 "--restart"],  # every repeat flies every sample again
            "report paper-pg2-l2": ["report", folder / "paper-pg2-l2.h5", "--out", folder / "paper-report"],
            "report 737-turn (script, quantities)": ["report", folder / "737-turn.h5", "--out",
                                                     folder / "turn-report"]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--before", default="HEAD~1", help="the revision to compare with (a commit, tag or branch; "
                                                           "default HEAD~1)")
    parser.add_argument("--samples", type=int, default=200, help="Monte Carlo samples of the run row")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--work", type=Path, help="folder for the worktree and the files (default: a temporary one)")
    args = parser.parse_args()
    work = (args.work or Path(tempfile.mkdtemp(prefix="uqflight-before-after-"))).resolve()
    before = work / "before"
    if not before.exists():
        subprocess.run(["git", "-C", str(AFTER), "worktree", "add", "--detach", str(before), args.before], check=True,
                       capture_output=True)
    try:
        sides = {"before": before, "after": AFTER}
        rows = {name: prepare(side, work / f"{name}-files", args.samples) for name, side in sides.items()}
        times = {(name, row): [] for name in sides for row in rows["after"]}
        for repeat in range(args.repeats):
            order = list(sides) if repeat % 2 == 0 else list(reversed(sides))
            for row in rows["after"]:
                for name in order:
                    times[name, row].append(uqflight(sides[name], *rows[name][row], cwd=work / f"{name}-files"))
        revision = subprocess.run(["git", "-C", str(before), "rev-parse", "--short", "HEAD"], capture_output=True,
                                  text=True).stdout.strip()
        print(f"before: {args.before} ({revision}); after: this checkout; {args.repeats} repeats; seconds, wall clock")
        print("| row | before median | after median | after / before, median of the pairs (min-max) | before best "
              "| after best |")
        print("|---|---|---|---|---|---|")
        for row in rows["after"]:
            b, a = times["before", row], times["after", row]
            ratios = [x / y for x, y in zip(a, b)]  # each repeat's two runs of the row, back to back
            print(f"| {row} | {statistics.median(b):.2f} | {statistics.median(a):.2f} | "
                  f"{statistics.median(ratios):.2f} ({min(ratios):.2f}-{max(ratios):.2f}) | {min(b):.2f} | {min(a):.2f} |")
        per_sample = [statistics.median(times[name, f"run {args.samples} samples, 1 worker"]) / args.samples
                      for name in sides]
        print(f"\nrunner, seconds per sample (start-up included): before {per_sample[0]:.4f}, after {per_sample[1]:.4f}")
    finally:
        subprocess.run(["git", "-C", str(AFTER), "worktree", "remove", "--force", str(before)], capture_output=True)


if __name__ == "__main__":
    main()
