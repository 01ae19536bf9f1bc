"""A rare-event design's estimate as its results file records it (/rare_event, written and read by `store.rare`):
plain numbers and arrays, so that reading it imports no algorithm and runs no campaign code."""
from __future__ import annotations

import numpy as np

from .estimate import importance_shares


def estimate_record(estimate, spec, ends, campaign) -> dict:
    """The record of an algorithm's RareEventEstimate (designs.rare.estimate) for /rare_event: the event, the
    estimate, the rounds, the runs at the end of each `evaluate` call (`ends`) and the most probable failure
    point in u, ξ and physical values with each input's share of it."""
    from . import germs_from_normal

    d = len(campaign.germs)
    point = estimate.design_point
    u = np.full(d, np.nan) if point is None else np.asarray(point, dtype=float).reshape(d)
    if point is None or not np.any(u):  # no run in the event (the origin would have no direction to share)
        u = xi = kappa = importance = np.full(d, np.nan)
    else:
        xi = germs_from_normal(u[None, :], campaign.germs)
        kappa = campaign.to_physical(xi)[0]
        xi, importance = xi[0], importance_shares(u)
    rounds = estimate.rounds
    event = spec["event"]
    return {"method": spec.kind, "of": event.of, "side": event.side, "threshold": event.threshold,
            "budget": spec["budget"],
            "probability": float(estimate.probability), "lower": float(estimate.lower),
            "upper": float(estimate.upper), "cov": float(estimate.cov),
            "beta": float(estimate.beta), "runs": int(estimate.runs),
            "failed": int(estimate.failed), "stopped": str(estimate.stopped),
            "notes": [str(note) for note in estimate.notes],
            "round_runs": np.array([r.runs for r in rounds], dtype=np.int64),
            "round_probability": np.array([r.probability for r in rounds], dtype=float),
            "round_cov": np.array([r.cov for r in rounds], dtype=float),
            "batch_end": np.array(ends, dtype=np.int64),
            "design_point_u": u, "design_point_xi": xi, "design_point": kappa, "importance": importance}
