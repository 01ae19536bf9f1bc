"""The statistics of a rare-event design (designs.rare): the probability of its event, read from the estimate
its run recorded (/rare_event), and nothing else. Its runs were chosen by the algorithm to reach the event:
they are not draws of the input law, so the means, variances, bands, densities, Sobol' indices and the
failure probability of such runs would not be the law's: they are refused (null, with a note saying why)."""
from __future__ import annotations

import math

import numpy as np

from ..designs.rare import Event
from ..store import ResultStore, Status


def _number(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def exceedance_entry(record: dict, names: list[str]) -> dict:
    """summary.json's quantities.NAME.exceedance entry of a recorded estimate (store.rare)."""
    point = record["design_point"]
    found = np.isfinite(point).all()
    return {record["side"]: record["threshold"], "probability": record["probability"], "lower": record["lower"],
            "upper": record["upper"], "cov": record["cov"], "runs": record["runs"], "method": record["method"],
            "beta": record["beta"],
            "design_point": dict(zip(names, map(float, point))) if found else None,
            "importance": dict(zip(names, map(float, record["importance"]))) if found else None,
            "failed": record["failed"], "stopped": record["stopped"], "flags": [],
            "note": f"{record['method']}: the 95 % interval of its estimator; stopped by {record['stopped']}"}


def rare_statistics(store: ResultStore, stats) -> None:
    """Fill `stats` (statistics.Statistics) of a rare-event design's file: the event's probability in its
    quantity's exceedance, the rounds (`rare_event`), the runs for the report's figures (`rare_runs`), every
    other statistic null with a note. BadInput when the file holds no estimate yet."""
    from .statistics import BadInput, QuantityStatistics, failed_runs, quantity_units

    record = store.rare_event()
    kind, path = stats.design_kind, stats.path
    if record is None:
        campaign = store.attrs.get("campaign_path") or "CAMPAIGN.yaml"
        raise BadInput(f"{path}: the {kind} design has not finished ({stats.completed} runs stored, no estimate "
                          f"in /rare_event yet): resume it with `uqflight run {campaign} --out {path}`")
    names, status = store.parameter_names, store.status
    event = Event(record["of"], record["side"], record["threshold"]).text()
    stats.notes.append(f"the runs of this {kind} design were chosen to reach the event {event}: they are not draws of "
                       "the input law, so no mean, variance, band, density, Sobol' index or failure probability is "
                       f"computed from them (null); the event's probability is quantities.{record['of']}.exceedance")
    stats.notes += [f"{kind}: {note}" for note in record["notes"]]
    stats.failure_probability = {"estimate": None, "lower": None, "upper": None, "n_effective": None,
                                 "method": f"not estimated: the runs of a {kind} design are not draws of the input law"}
    if stats.failed:
        stats.failures = failed_runs(store)
        stats.notes.append(f"{stats.failed} of {stats.runs} runs failed (see failures): the {kind} counts them as "
                           f"outside the event {event}, which biases its probability low if they would have been in it")
    ok, margin = status == Status.OK, np.full(status.size, np.nan)
    for name in store.quantity_names:
        values = store.quantity(name)
        missing = int(np.count_nonzero(ok & ~np.isfinite(values)))
        exceedance = [exceedance_entry(record, names)] if name == record["of"] else []
        stats.quantities[name] = QuantityStatistics(name, missing, None, exceedance, quantity_units(store, stats, name))
        if name == record["of"]:
            margin = Event(name, record["side"], record["threshold"]).margin(values)
            margin[~ok] = np.nan
            if missing:
                stats.notes.append(f"quantity {name} is undefined in {missing} successful runs: the {kind} counts them "
                                   f"as outside the event {event}")
    stats.rare_event = {
        "method": kind, "event": {"of": record["of"], record["side"]: record["threshold"]},
        "budget": record["budget"], "runs": record["runs"], "failed": record["failed"],
        "stopped": record["stopped"], "notes": record["notes"],
        "rounds": [{"runs": int(r), "probability": _number(p), "cov": _number(c)}
                   for r, p, c in zip(record["round_runs"], record["round_probability"], record["round_cov"])]}
    stats.rare_runs = {"kappa": store.kappa, "status": status, "margin": margin, "record": record,
                       "event": event}
