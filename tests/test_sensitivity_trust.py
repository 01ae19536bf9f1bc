"""Wrapped angles, pick-freeze indices that say how sure they are, indices that survive failed runs, and
units (issue 45 items 2, 3, 4, 7), on closed-form models; each tolerance is stated with its reason."""
import math
from pathlib import Path

import numpy as np
import pytest
from conftest import run_python_campaign

from uqflight.statistics import analyse, summary_json

MODELS = Path(__file__).parent / "data" / "sensitivity_models.py"
PI = math.pi
ISHIGAMI_BOX = "".join(f"  x{i}: {{distribution: uniform, lower: {-PI}, upper: {PI}}}\n" for i in (1, 2, 3))
S1 = np.array([0.3139, 0.4424, 0.0])  # Ishigami's closed-form indices (a = 7, b = 0.1)
ST = np.array([0.5576, 0.4424, 0.2437])


def campaign(name: str, function: str, parameters: str, design: str, extra: str = "",
             bootstrap: int = 200) -> str:
    return (f"name: {name}\nseed: 7\nsimulator: {{kind: python, function: \"{MODELS}:{function}\"}}\n"
            f"parameters:\n{parameters}design: {design}\nmethod: {{kind: monte_carlo}}\n{extra}"
            f"analysis: {{band_samples: 2000, bootstrap: {bootstrap}}}\n")


TURN = campaign("turn", "wrapped_turn", "  a: {distribution: uniform, lower: 1, upper: 3}\n"
                "  b: {distribution: uniform, lower: -2, upper: 2}\n", "{kind: monte_carlo, samples: 400}",
                "quantities:\n  final_heading: {of: psi_deg, take: final}\n"
                "  heading_change: {of: psi_deg, take: change}\n"
                "  bank: {of: psi_deg, take: max}\n")
