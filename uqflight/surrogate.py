"""The PCE surrogate of a results file: export it as strict JSON, load it back and evaluate it.

    uqflight surrogate export RESULTS.h5 --out pce.json
    >>> from uqflight.surrogate import load
    >>> pce = load("pce.json")
    >>> pce.evaluate(kappa=[[0.25, 5.1, ...]])["theta_deg"]     # (points, times)

The file holds everything needed to evaluate the expansion without uqflight's results file:
the germs (standard variables), the multi-indices (total degree, one row per basis polynomial),
the coefficients of the orthonormal basis per output and time, the parameters' distributions
(name, distribution, lower, upper, nominal: κ ↔ ξ), the time grid, the method and its order.
The PCE is fitted exactly as the statistics fit it (same runs, same method, same order).
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

FORMAT = "uqflight-pce"
VERSION = 1
MAX_FILE_BYTES = 1 << 30  # a surrogate of 10^4 terms x 10^4 times is ~2 GB of JSON: beyond that, not ours


class SurrogateError(ValueError):
    """A results file that has no PCE (e.g. Monte Carlo) or a malformed surrogate file."""


@dataclass
class Surrogate:
    """A PCE over time per output; evaluate it at physical values κ or standard variables ξ."""

    parameters: list[dict]
    germs: list[str]
    indices: np.ndarray  # (Z, d) multi-indices
    time: np.ndarray  # (T,)
    coefficients: dict[str, np.ndarray]  # output -> (Z, T)
    units: dict[str, str]
    method: dict
    campaign: str = ""

    @property
    def outputs(self) -> list[str]:
        return list(self.coefficients)

    def to_standard(self, kappa) -> np.ndarray:
        """ξ (M, d) from physical values κ (M, d), column by column through each parameter's law."""
        from .parameters import Parameter

        kappa = np.atleast_2d(np.asarray(kappa, dtype=float))
        if kappa.shape[1] != len(self.parameters):
            raise ValueError(f"expected {len(self.parameters)} values per point "
                             f"({', '.join(p['name'] for p in self.parameters)}), got {kappa.shape[1]}")
        laws = [Parameter(p["name"], p.get("property", p["name"]), p["distribution"], p["nominal"], p["lower"],
                          p["upper"]) for p in self.parameters]
        return np.column_stack([law.to_standard(kappa[:, j]) for j, law in enumerate(laws)])

    def evaluate(self, kappa=None, *, xi=None) -> dict[str, np.ndarray]:
        """{output: (M, T)} at M points given as physical values κ (M, d) or standard variables ξ."""
        from .methods.basis import orthonormal_basis

        if (kappa is None) == (xi is None):
            raise ValueError("give exactly one of kappa (physical values) or xi (standard variables)")
        points = self.to_standard(kappa) if xi is None else np.atleast_2d(np.asarray(xi, dtype=float))
        if points.shape[1] != len(self.germs):
            raise ValueError(f"expected {len(self.germs)} standard variables per point, got {points.shape[1]}")
        basis = orthonormal_basis(self.germs, self.indices, points)
        return {name: basis @ c for name, c in self.coefficients.items()}

    def mean(self) -> dict[str, np.ndarray]:
        constant = ~self.indices.any(axis=1)
        return {name: c[constant].sum(axis=0) for name, c in self.coefficients.items()}

    def variance(self) -> dict[str, np.ndarray]:
        constant = ~self.indices.any(axis=1)
        return {name: (c[~constant] ** 2).sum(axis=0) for name, c in self.coefficients.items()}


def fit_surrogate(path, method: dict | None = None, partial: bool = False,
                  allow_aliasing: bool = False) -> Surrogate:
    """The PCE of every output of the results file `path`, exactly as `uqflight.statistics.analyse`
    fits it (with `method` overriding the campaign's), after the same checks: pending or failed runs,
    a projection the grid cannot integrate and a rank-deficient fit are refused (statistics.BadInput).
    SurrogateError when the method builds no PCE."""
    from .statistics import analyse
    from .store import ResultStore

    stats = analyse(path, method=method, partial=partial, allow_aliasing=allow_aliasing)
    pces = {name: out.pce for name, out in stats.outputs.items()}
    if any(pce is None for pce in pces.values()):
        raise SurrogateError(f"{path}: method {stats.method['kind']} on a {stats.design_kind} design builds no PCE; "
                             "give a PCE method, e.g. --method least_squares:2")
    with ResultStore.open(path) as store:
        parameters, units, time = _parameters(store), dict(store.units), np.asarray(store.time, dtype=float)
    first = next(iter(pces.values()))
    return Surrogate(parameters, list(first.germs), np.asarray(first.indices, dtype=int), time,
                     {name: np.asarray(pce.coefficients, dtype=float) for name, pce in pces.items()}, units,
                     stats.method, stats.campaign_name)


def _parameters(store) -> list[dict]:
    """The parameters' laws from the stored campaign text (κ ↔ ξ), via the campaign parser."""
    from .campaign.reading import stored_parameters

    found = stored_parameters(store.attrs)
    names = store.parameter_names
    if found is None or [p["name"] for p in found] != names:
        raise SurrogateError("cannot read the parameters' distributions from the campaign text in the results file")
    return found


def surrogate_json(surrogate: Surrogate, results: str = "") -> dict:
    """The strict-JSON form (non-finite numbers as null)."""
    def numbers(a):
        return [[v if math.isfinite(v) else None for v in row] for row in np.asarray(a, dtype=float).tolist()]

    return {
        "format": FORMAT, "version": VERSION, "campaign": surrogate.campaign, "results": results,
        "method": surrogate.method["kind"], "order": surrogate.method["order"],
        "split": bool(surrogate.method.get("split", False)),
        "basis": "orthonormal polynomials of the germs (Hermite for normal, Legendre for uniform), total degree",
        "parameters": surrogate.parameters, "germs": surrogate.germs,
        "multi_indices": surrogate.indices.tolist(), "time": surrogate.time.tolist(),
        "outputs": {name: {"units": surrogate.units.get(name, ""), "coefficients": numbers(c)}
                    for name, c in surrogate.coefficients.items()},
    }


def export(results, out, method: dict | None = None) -> Path:
    """Fit the PCE of `results` and write it to `out` as strict JSON; returns `out`."""
    data = surrogate_json(fit_surrogate(results, method), str(results))
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(out.name + ".part")
    tmp.write_text(json.dumps(data, allow_nan=False) + "\n", encoding="utf-8")
    tmp.replace(out)
    return out


def load(path) -> Surrogate:
    """The surrogate written by `export` (or `uqflight surrogate export`); SurrogateError, naming the
    file and what is wrong, for anything else (a damaged or hand-edited file is never evaluated)."""
    try:
        with open(path, "rb") as fh:
            text = fh.read(MAX_FILE_BYTES + 1)
        if len(text) > MAX_FILE_BYTES:
            raise ValueError(f"larger than {MAX_FILE_BYTES >> 30} GiB")
        data = json.loads(text)
    except (OSError, ValueError, RecursionError) as exc:
        raise SurrogateError(f"{path}: cannot read the surrogate ({exc})") from exc
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise SurrogateError(f"{path}: not a uqflight PCE surrogate (format {FORMAT!r})")
    try:
        return _checked(data)
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise SurrogateError(f"{path}: malformed surrogate ({type(exc).__name__}: {exc})") from exc


def _checked(data: dict) -> Surrogate:
    """The Surrogate a parsed file describes, every shape and value checked (ValueError naming the key)."""
    from .parameters import Parameter
    from .parameters.germs import GERMS

    germs = [str(g) for g in data["germs"]]
    unknown = [g for g in germs if g not in GERMS]
    if unknown:
        raise ValueError(f"germs: unknown {unknown} (known: {', '.join(GERMS)})")
    d = len(germs)
    parameters = data["parameters"]
    if not isinstance(parameters, list) or len(parameters) != d or not all(
            isinstance(p, dict) and {"name", "distribution", "lower", "upper", "nominal"} <= set(p) for p in parameters):
        raise ValueError(f"parameters: expected {d} entries with name, distribution, lower, upper, nominal")
    for p in parameters:  # their laws map κ to ξ: built once here so that a bad one is refused now
        Parameter(p["name"], p.get("property", p["name"]), p["distribution"], p["nominal"], p["lower"], p["upper"])
    indices = np.array(data["multi_indices"], dtype=np.int64)
    if indices.ndim != 2 or indices.shape[1] != d or not len(indices) or (indices < 0).any() or indices.max() > 1000:
        raise ValueError(f"multi_indices: expected rows of {d} integers in [0, 1000], got shape {indices.shape}")
    time = np.array(data["time"], dtype=float)
    if time.ndim != 1 or not np.isfinite(time).all():
        raise ValueError("time: expected a list of finite numbers")
    outputs = data["outputs"]
    if not isinstance(outputs, dict) or not outputs:
        raise ValueError("outputs: expected a mapping of at least one output")
    coefficients = {}
    for name, output in outputs.items():
        values = np.array(output["coefficients"], dtype=float)  # null → NaN, refused below
        if values.shape != (len(indices), time.size) or not np.isfinite(values).all():
            raise ValueError(f"outputs.{name}.coefficients: expected {len(indices)} x {time.size} finite numbers, "
                             f"got shape {values.shape}{'' if np.isfinite(values).all() else ' with nulls'}")
        coefficients[name] = values
    return Surrogate(parameters, germs, indices, time, coefficients,
                     {name: str(o.get("units", "")) for name, o in outputs.items()},
                     {"kind": str(data["method"]), "order": int(data["order"]), "split": bool(data.get("split", False))},
                     str(data.get("campaign", "")))