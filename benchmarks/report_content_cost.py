"""What the report's headline, trajectories (spaghetti and scatter) and sensitivity figure cost, beside
two figures the report drew before them (mean and band, first-order Sobol'), on one results file.

Each part is run once to warm up (imports, fonts) and then timed: wall and CPU seconds. The target: the
three parts together well under 1 s for paper-pg2-l2's 113 runs.

Run: .venv/bin/python benchmarks/report_content_cost.py results/paper-pg2-l2.h5 [--times 10,25,end]
"""
from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from uqflight.report import plots
from uqflight.report.headline import headline_section
from uqflight.report.loading import load_entries
from uqflight.report.sensitivity import plot_sensitivity
from uqflight.report.trajectories import trajectories_section


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", type=Path)
    parser.add_argument("--times", default="10,25,end")
    args = parser.parse_args()
    times = [float("inf") if t == "end" else float(t) for t in args.times.split(",")]
    entries, _ = load_entries([args.results], None)
    entry = entries[0]
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder)
        (out / "plots").mkdir()
        parts = [("headline", lambda: headline_section(entry, times)),
                 ("trajectories", lambda: trajectories_section(entries, times, out)),
                 ("sensitivity", lambda: plot_sensitivity(entry.outputs, out / "plots" / "s.png", "s")),
                 ("(before) plot_mean_band", lambda: plots.plot_mean_band(entry.outputs, out / "plots" / "m.png", "m")),
                 ("(before) plot_sobol", lambda: plots.plot_sobol(entry.outputs, out / "plots" / "o.png", "o"))]
        print(f"{'part':<26}{'wall [s]':>10}{'cpu [s]':>10}")
        total = [0.0, 0.0]
        for name, part in parts:
            part()
            wall, cpu = time.perf_counter(), time.process_time()
            part()
            wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
            if not name.startswith("("):
                total = [total[0] + wall, total[1] + cpu]
            print(f"{name:<26}{wall:>10.2f}{cpu:>10.2f}")
        print(f"{'new parts together':<26}{total[0]:>10.2f}{total[1]:>10.2f}")


if __name__ == "__main__":
    main()
