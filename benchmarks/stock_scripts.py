"""JSBSim's own scripts flown as a new user would, with the default expansion, and what the report says.

Four flights no campaign of this repository was written for:

  737-rudder-kick    scripts/rudder_kick.xml: the 737's rudder kick, 6 lateral/directional coefficients
                     (normal, ±20 %), a level-2 sparse grid and pseudo-Galerkin order 2 (the defaults)
  c172x-doublet      scripts/c172_elevator_doublet.xml: the c172x's elevator doublet, 4 longitudinal
                     coefficients, the same defaults
  x15-x153           scripts/x153.xml: the X-15, 4 coefficients, the same defaults
  c172p-landing-turb the c172p landing of campaigns/c172p-landing-turbulence.yaml (a seed parameter:
                     Monte Carlo of 64 runs)

For each, every output and quantity is printed with its mean ± std, its 99 % band, the range the runs
themselves span, its units and its flags (summary.json's `flags`): a band far outside the runs' range with
no flag would be a silent wrong number.

Run: .venv/bin/python benchmarks/stock_scripts.py [--work DIR] [--only NAME]
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from uqflight.analysis.angles import angle_period, on_branch
from uqflight.store import ResultStore, Status

ROOT = Path(__file__).resolve().parents[1]
UQFLIGHT = str(Path(sys.executable).with_name("uqflight"))


def scaled(functions: dict[str, str], pct: float, law: str = "normal") -> str:
    """`parameters:` entries scaling each JSBSim function by a law of ± pct %."""
    return "".join(f"  {name}: {{function: {function}, perturbation: scale, distribution: {law}, "
                   f"interval_pct: {pct}}}\n" for name, function in functions.items())


CASES = {
    "737-rudder-kick": """
name: 737-rudder-kick
seed: 1
simulator:
  kind: jsbsim
  scenario: {kind: script, script: rudder_kick}
  output_rate_hz: 10
  outputs: [attitude/phi-deg, attitude/psi-deg, h_ft, aero/beta-deg]
parameters:
""" + scaled({"Cl_beta": "Clb", "Cl_p": "Clp", "Cl_r": "Clr", "Cn_beta": "Cnb", "Cn_r": "Cnr",
              "Cn_dr": "Cndr"}, 20) + """
design: {kind: sparse_grid, level: 2}
method: {kind: pseudo_galerkin, order: 2}
execution: {workers: 2, chunk: 4}
quantities:
  peak_bank_deg: {of: attitude/phi-deg, take: max}
  final_heading_deg: {of: attitude/psi-deg, take: final}
analysis:
  exceedance:
    peak_bank_deg: [{above: 45}]
""",
    "c172x-doublet": """
name: c172x-doublet
seed: 1
simulator:
  kind: jsbsim
  scenario: {kind: script, script: c172_elevator_doublet}
  output_rate_hz: 10
  outputs: [theta_deg, alpha_deg, h_ft, accelerations/Nz]
parameters:
""" + scaled({"CL_alpha": "CLwbh", "Cm_alpha": "Cmalpha", "Cm_q": "Cmq", "Cm_de": "Cmde"}, 10) + """
design: {kind: sparse_grid, level: 2}
method: {kind: pseudo_galerkin, order: 2}
execution: {workers: 2, chunk: 4}
quantities:
  peak_load_factor: {of: accelerations/Nz, take: max}
analysis:
  exceedance:
    peak_load_factor: [{above: 5.5}]
""",
    "x15-x153": """
name: x15-x153
seed: 1
simulator:
  kind: jsbsim
  scenario: {kind: script, script: x153}
  output_rate_hz: 5
  outputs: [h_ft, theta_deg, alpha_deg, vtas_kt]
parameters:
""" + scaled({"CD_min": "CDmin", "CL_alpha": "CLalpha", "Cm_alpha": "Cmalpha", "Cm_q": "Cmq"}, 10) + """
design: {kind: sparse_grid, level: 2}
method: {kind: pseudo_galerkin, order: 2}
execution: {workers: 2, chunk: 4}
quantities:
  peak_altitude_ft: {of: h_ft, take: max}
""",
}


def landing_case() -> str:
    """campaigns/c172p-landing-turbulence.yaml with a 64-run Monte Carlo design."""
    text = (ROOT / "campaigns" / "c172p-landing-turbulence.yaml").read_text()
    text = text.replace("name: c172p-landing-turbulence", "name: c172p-landing-turb")
    text = text.replace("design: {kind: pick_freeze, samples: 256}", "design: {kind: monte_carlo, samples: 64}")
    return text.replace("scripts/c172p-landing.xml", str(ROOT / "campaigns" / "scripts" / "c172p-landing.xml"))


def runs_range(path: Path, name: str, entry: dict, quantity: bool, at: int) -> tuple[float, float]:
    """The smallest and largest value the completed runs themselves took (an output's at time index `at`),
    an angle seen as the statistics see it (analysis.angles.on_branch: unwrapped, on the mean's branch)."""
    with ResultStore.open(path) as store:
        ok = store.status == Status.OK
        data = store.quantity(name)[ok][:, None] if quantity else store.output_matrix(name)[ok]
    period = angle_period(entry.get("units", ""))
    if period is not None:
        mean = entry["mean"][0] if isinstance(entry["mean"], list) else entry["mean"]
        data = on_branch(data, mean, period)
    data = data[:, at]
    data = data[np.isfinite(data)]
    return (float(data.min()), float(data.max())) if data.size else (float("nan"), float("nan"))


def peak_index(entry: dict) -> int:
    """The time index of an output's largest std (-1 for a quantity or where no std is defined)."""
    if not isinstance(entry["std"], list):
        return -1
    std = np.array([np.nan if v is None else v for v in entry["std"]], dtype=float)
    return int(np.nanargmax(std)) if np.isfinite(std).any() else -1


def peak(entry: dict, key: str) -> float | None:
    """A statistic at the time of the output's largest std (a quantity's is one number)."""
    value = entry[key]
    return value[peak_index(entry)] if isinstance(value, list) else value


def show(case: str, work: Path) -> None:
    campaign = work / f"{case}.yaml"
    campaign.write_text(landing_case() if case == "c172p-landing-turb" else CASES[case])
    results, report = work / f"{case}.h5", work / f"{case}-report"
    subprocess.run([UQFLIGHT, "run", str(campaign), "--out", str(results), "--force"], check=True,
                   stdout=subprocess.DEVNULL)
    subprocess.run([UQFLIGHT, "report", str(results), "--out", str(report)], check=True,
                   stdout=subprocess.DEVNULL)
    summary = json.loads((report / "summary.json").read_text())
    print(f"\n## {case}: {summary['completed']} runs ok, {summary['failed']} failed; notes: {len(summary['notes'])}")
    print("| name | units | mean | std | band99 | runs span | flags |  (outputs: at the time of their largest std)")
    print("|---|---|---|---|---|---|---|")
    for group, quantity in (("outputs", False), ("quantities", True)):
        for name, entry in summary.get(group, {}).items():
            if "mean" not in entry:
                continue
            lo, hi = runs_range(results, name, entry, quantity, peak_index(entry))
            band = {**(entry.get("band99") or {"lower": None, "upper": None}), "std": entry["std"]}
            lower, upper = peak(band, "lower"), peak(band, "upper")
            fmt = lambda v: "—" if v is None else f"{v:.4g}"  # noqa: E731
            print(f"| {name} | {entry.get('units', '')} | {fmt(peak(entry, 'mean'))} | {fmt(peak(entry, 'std'))} | "
                  f"{fmt(lower)} … {fmt(upper)} | {lo:.4g} … {hi:.4g} | {'; '.join(entry.get('flags', [])) or '—'} |")
        for name, entry in summary.get("quantities", {}).items() if quantity else ():
            for row in entry.get("exceedance", []):
                print(f"  exceedance {name} {row}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--work", type=Path, default=None)
    parser.add_argument("--only", choices=[*CASES, "c172p-landing-turb"], action="append")
    args = parser.parse_args()
    work = args.work or Path(tempfile.mkdtemp(prefix="stock-scripts-"))
    work.mkdir(parents=True, exist_ok=True)
    for case in args.only or [*CASES, "c172p-landing-turb"]:
        show(case, work)
    print(f"\nfiles in {work}")


if __name__ == "__main__":
    main()
