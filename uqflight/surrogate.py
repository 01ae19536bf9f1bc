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
MAX_FILE_BYTES = 64 << 20  # 64 MiB of JSON (about 3 million coefficients); parsing takes about 10 times that


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
                  allow_aliasing: bool = False, progress=None) -> Surrogate:
    """The PCE of every output of the results file `path`, exactly as `uqflight.statistics.analyse`
    fits it (with `method` overriding the campaign's), after the same checks: pending or failed runs,
    a projection the grid cannot integrate and a rank-deficient fit are refused (statistics.BadInput).
    SurrogateError when the method builds no PCE. `progress`: see statistics.analyse."""
    from .statistics import Options, analyse
    from .store import ResultStore

    # few band draws: the PCE does not depend on them, and its bands and PDFs are not exported
    stats = analyse(path, options=Options(band_samples=200, bootstrap=0), method=method, partial=partial,
                    allow_aliasing=allow_aliasing, progress=progress)
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


def export(results, out, method: dict | None = None, progress=None) -> Path:
    """Fit the PCE of `results` and write it to `out` as strict JSON; returns `out`. The folder of
    `out` must exist; nothing is left behind when the write fails (a full disk). `progress` (a
    uqflight.progress.Progress) is told the stages."""
    data = surrogate_json(fit_surrogate(results, method, progress=progress), str(results))
    if progress is not None:
        progress.stage(f"writing {out}")
    text = json.dumps(data, allow_nan=False) + "\n"
    if len(text) > MAX_FILE_BYTES:
        raise SurrogateError(f"{results}: the surrogate takes {len(text) / 2**20:.0f} MiB of JSON, more than the "
                             f"{MAX_FILE_BYTES >> 20} MiB that load() reads; export a lower order (--method KIND:ORDER)")
    out = Path(out)
    tmp = out.with_name(out.name + ".part")
    try:
        tmp.write_text(text, encoding="utf-8")
        tmp.replace(out)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return out


def load(path) -> Surrogate:
    """The surrogate written by `export` (or `uqflight surrogate export`); SurrogateError, naming the
    file and the key, for anything else (a damaged or hand-edited file is never evaluated): a file
    above MAX_FILE_BYTES (refused before it is read), numbers that are strings, booleans or out of
    range, multi-indices that are not integers in [0, MAX_DEGREE] or repeat a row, laws whose germ is
    not the one given, times that do not increase."""
    try:
        size = Path(path).stat().st_size
        if size > MAX_FILE_BYTES:
            raise ValueError(f"{size / 2**20:.0f} MiB, more than the {MAX_FILE_BYTES >> 20} MiB a surrogate takes")
        with open(path, "rb") as fh:
            text = fh.read(MAX_FILE_BYTES + 1)
        if len(text) > MAX_FILE_BYTES:
            raise ValueError(f"more than the {MAX_FILE_BYTES >> 20} MiB a surrogate takes")
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
    """The Surrogate a parsed file describes, every type, shape and value checked before any array is
    built (ValueError naming the key)."""
    from .parameters import Parameter
    from .parameters.germs import GERMS

    if data.get("version") != VERSION:
        raise ValueError(f"version: expected {VERSION}, got {_shown(data.get('version'))}")
    germs = data["germs"]
    if not isinstance(germs, list) or not germs or not all(isinstance(g, str) for g in germs):
        raise ValueError(f"germs: expected a list of names ({', '.join(GERMS)}), got {_shown(germs)}")
    unknown = [g for g in germs if g not in GERMS]
    if unknown:
        raise ValueError(f"germs: unknown {unknown} (known: {', '.join(GERMS)})")
    d = len(germs)
    parameters = data["parameters"]
    if not isinstance(parameters, list) or len(parameters) != d or not all(
            isinstance(p, dict) and {"name", "distribution", "lower", "upper", "nominal"} <= set(p) for p in parameters):
        raise ValueError(f"parameters: expected {d} entries with name, distribution, lower, upper, nominal")
    for j, p in enumerate(parameters):  # their laws map κ to ξ: built once here so that a bad one is refused now
        for key in ("name", "distribution", "property"):
            if not isinstance(p.get(key, ""), str):
                raise ValueError(f"parameters[{j}].{key}: expected a string, got {_shown(p[key])}")
        for key in ("lower", "upper", "nominal"):
            _number(p[key], f"parameters[{j}].{key}")
        law = Parameter(p["name"], p.get("property", p["name"]), p["distribution"], p["nominal"], p["lower"],
                        p["upper"])
        if law.germ != germs[j]:
            raise ValueError(f"parameters[{j}] ({p['name']}): a {p['distribution']} law is driven by a {law.germ} "
                             f"germ, but germs[{j}] is {germs[j]}")
    order = data["order"]
    if isinstance(order, bool) or not isinstance(order, int) or not 0 <= order <= MAX_DEGREE:
        raise ValueError(f"order: expected an integer in [0, {MAX_DEGREE}], got {_shown(order)}")
    indices = _array(data["multi_indices"], "multi_indices", (None, d), integers=True)
    if not len(indices) or indices.sum(axis=1).max() > order:
        raise ValueError(f"multi_indices: expected rows of {d} integers of total degree <= order {order}, "
                         f"got {len(indices)} rows of total degree up to {indices.sum(axis=1).max(initial=0)}")
    rows = {}
    for i, row in enumerate(map(tuple, indices.tolist())):
        if row in rows:
            raise ValueError(f"multi_indices: row {i} repeats row {rows[row]} ({list(row)})")
        rows[row] = i
    time = _array(data["time"], "time", (None,))
    if not time.size or np.any(np.diff(time) <= 0):
        raise ValueError("time: expected a list of strictly increasing numbers")
    outputs = data["outputs"]
    if not isinstance(outputs, dict) or not outputs:
        raise ValueError("outputs: expected a mapping of at least one output")
    coefficients = {}
    for name, output in outputs.items():
        coefficients[name] = _array(output["coefficients"], f"outputs.{name}.coefficients", (len(indices), time.size))
        if not isinstance(output.get("units", ""), str):
            raise ValueError(f"outputs.{name}.units: expected a string, got {_shown(output['units'])}")
    for key, kind in (("method", str), ("split", bool), ("campaign", str)):
        if key in data and not isinstance(data[key], kind):
            raise ValueError(f"{key}: expected a {kind.__name__}, got {_shown(data[key])}")
    return Surrogate(parameters, germs, indices, time, coefficients,
                     {name: o.get("units", "") for name, o in outputs.items()},
                     {"kind": data["method"], "order": order, "split": data.get("split", False)},
                     data.get("campaign", ""))


MAX_DEGREE = 1000  # a multi-index entry or order beyond this is refused (a PCE of useful size stays far below)
_LARGEST = 1.7976931348623157e308


def _number(value, key: str) -> float:
    """A finite JSON number (never a string, a boolean, a null or an integer beyond float range)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not -_LARGEST <= value <= _LARGEST:
        raise ValueError(f"{key}: expected a finite number, got {_shown(value)}")
    return float(value)


def _array(value, key: str, shape: tuple, integers: bool = False) -> np.ndarray:
    """The JSON list (of lists) `value` as an array of `shape` (None: any length), its entries checked
    first: finite numbers, or with `integers` integers in [0, MAX_DEGREE] (a fraction is never truncated)."""
    what = f"integers in [0, {MAX_DEGREE}]" if integers else "finite numbers"
    expected = {(None,): "a list of", (None, shape[-1]): f"rows of {shape[-1]}"}.get(shape, " x ".join(map(str, shape)))
    try:
        cells = np.array(value if isinstance(value, list) else None, dtype=object)
    except ValueError:  # rows of unequal lengths
        raise ValueError(f"{key}: expected {expected} {what}, got rows of unequal lengths") from None
    if cells.ndim != len(shape) or any(n is not None and n != m for n, m in zip(shape, cells.shape)):
        raise ValueError(f"{key}: expected {expected} {what}, got shape {cells.shape}")
    for cell in cells.flat:
        if integers:
            good = type(cell) is int and 0 <= cell <= MAX_DEGREE
        else:
            good = type(cell) in (int, float) and -_LARGEST <= cell <= _LARGEST
        if not good:
            found = "nulls" if cell is None else _shown(cell)
            raise ValueError(f"{key}: expected {expected} {what}, got shape {cells.shape} with {found}")
    return cells.astype(np.int64 if integers else float)


def _shown(value) -> str:
    text = repr(value) if not isinstance(value, int) or abs(value) < 10**50 else "an integer of 50+ digits"
    return text if len(text) <= 60 else text[:57] + "..."
