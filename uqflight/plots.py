"""Matplotlib figures (PNG, headless): one flight's time histories, statistics over time."""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

LABELS = {
    "alpha_deg": "angle of attack α [deg]",
    "theta_deg": "pitch attitude θ [deg]",
    "h_ft": "altitude h [ft]",
    "q_degps": "pitch rate q [deg/s]",
    "vtas_kt": "true airspeed V_TAS [kt]",
}


def label(name: str) -> str:
    return LABELS.get(name, name)


def plot_flight(time: np.ndarray, outputs: dict[str, np.ndarray], path: Path, title: str = "") -> Path:
    """One panel per output against time, like the paper's Fig. 2."""
    names = list(outputs)
    fig, axes = plt.subplots(len(names), 1, figsize=(8, 1.9 * len(names) + 0.6), sharex=True, squeeze=False)
    for ax, name in zip(axes[:, 0], names):
        ax.plot(time, outputs[name], lw=1.2)
        ax.set_ylabel(label(name), fontsize=8)
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel("time [s]")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)
