"""A rare-event design's estimate as recorded in its results file (/rare_event, `store.rare`) and read back:
plain numbers and arrays, so that reading it imports no algorithm and runs no campaign code."""
from __future__ import annotations

import math

import numpy as np

FIELDS = ("probability", "lower", "upper", "cov", "beta")  # the estimate's numbers, NaN where undefined


def reliability_index(probability: float) -> float:
    """β = −Φ⁻¹(p): inf for p = 0, −inf for p = 1, NaN for no estimate."""
    from scipy.special import ndtri

    return float(-ndtri(probability)) if math.isfinite(probability) else math.nan


def shares(u: np.ndarray) -> np.ndarray:
    """α_k² = u_k²/|u|² of a design point in standard-normal space (summing to 1); NaN for u = 0."""
    u = np.asarray(u, dtype=float)
    total = float(u @ u)
    return u**2 / total if total > 0 else np.full(u.shape, np.nan)


def estimate_record(estimate, settings, ends, campaign) -> dict:
    """The record of an algorithm's RareEventEstimate (designs.rare.estimate) for /rare_event: the event, the
    estimate, the rounds, the runs at the end of each `evaluate` call (`ends`) and the most probable failure
    point in u, ξ and physical values with each input's share of it."""
    from . import germs_from_normal

    d = len(campaign.germs)
    point = estimate.design_point
    if point is None:
        u = xi = kappa = importance = np.full(d, np.nan)
    else:
        u = np.asarray(point, dtype=float).reshape(d)
        xi = germs_from_normal(u[None, :], campaign.germs)
        kappa = campaign.to_physical(xi)[0]
        xi, importance = xi[0], shares(u)
    rounds = estimate.rounds
    return {"method": settings.kind, "of": settings.event.of, "side": settings.event.side,
            "threshold": settings.event.threshold, "budget": settings.budget,
            "probability": float(estimate.probability), "lower": float(estimate.lower),
            "upper": float(estimate.upper), "cov": float(estimate.cov),
            "beta": reliability_index(float(estimate.probability)), "runs": int(estimate.runs),
            "failed": int(estimate.failed), "stopped": str(estimate.stopped),
            "notes": [str(note) for note in estimate.notes],
            "round_runs": np.array([r.runs for r in rounds], dtype=np.int64),
            "round_probability": np.array([r.probability for r in rounds], dtype=float),
            "round_cov": np.array([r.cov for r in rounds], dtype=float),
            "batch_end": np.array(ends, dtype=np.int64),
            "design_point_u": u, "design_point_xi": xi, "design_point": kappa, "importance": importance}
