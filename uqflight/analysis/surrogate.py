"""The PCE surrogate of a results file: export it as strict JSON, load it back and evaluate it.

    uqflight surrogate export RESULTS.h5 --out pce.json
    >>> from uqflight.analysis.surrogate import load
    >>> pce = load("pce.json")
    >>> pce.evaluate(kappa=[[0.25, 5.1, ...]])["theta_deg"]     # (points, times)

The file holds everything needed to evaluate the expansion without uqflight's results file:
the germs (standard variables), the multi-indices (one row per basis polynomial: total degree, or
the terms a sparse PCE selected, then per output), the coefficients of the orthonormal basis per
output and time, the parameters' distributions (name, distribution, lower, upper, nominal: κ ↔ ξ),
their Gaussian copula when they are dependent (`dependence`: {kind, parameters, correlation}; see
docs/dependence.md), the time grid, the method and its order.
The PCE is fitted exactly as the statistics fit it (same runs, same method, same order).
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..methods import MethodSpec
from ..text import Refusal
from ..text.bounded import read_bounded
from ..text.console import listed
from ..text.console import quoted_name, quoted_value

FORMAT = "uqflight-pce"
VERSION = 1
MAX_FILE_BYTES = 64 << 20  # 64 MiB of JSON (about 3 million coefficients); parsing takes about 10 times that


@dataclass
class Surrogate:
    """A PCE over time per output; evaluate it at physical values κ or standard variables ξ."""

    parameters: list[dict]
    germs: list[str]
    indices: dict[str, np.ndarray]  # output -> (Z, d) multi-indices of its basis
    time: np.ndarray  # (T,)
    coefficients: dict[str, np.ndarray]  # output -> (Z, T)
    units: dict[str, str]
    method: MethodSpec
    campaign: str = ""
    dependence: dict | None = None  # the inputs' Gaussian copula {kind, parameters, correlation}, None: independent

    @property
    def outputs(self) -> list[str]:
        return list(self.coefficients)

    def to_standard(self, kappa) -> np.ndarray:
        """ξ (M, d) from physical values κ (M, d), column by column through each parameter's law (and the
        inverse Nataf transform of the `dependence`, if any)."""
        from ..parameters import Parameter, to_standard

        kappa = np.atleast_2d(np.asarray(kappa, dtype=float))
        if kappa.shape[1] != len(self.parameters):
            raise ValueError(f"expected {len(self.parameters)} values per point "
                             f"({listed(p['name'] for p in self.parameters)}), got {kappa.shape[1]}")
        laws = [Parameter(p["name"], p.get("property", p["name"]), p["distribution"], p["nominal"], p["lower"],
                          p["upper"]) for p in self.parameters]
        return to_standard(laws, kappa, _copula(self.dependence))

    def evaluate(self, kappa=None, *, xi=None) -> dict[str, np.ndarray]:
        """{output: (M, T)} at M points given as physical values κ (M, d) or standard variables ξ."""
        from ..methods.basis import orthonormal_basis

        if (kappa is None) == (xi is None):
            raise ValueError("give exactly one of kappa (physical values) or xi (standard variables)")
        points = self.to_standard(kappa) if xi is None else np.atleast_2d(np.asarray(xi, dtype=float))
        if points.shape[1] != len(self.germs):
            raise ValueError(f"expected {len(self.germs)} standard variables per point, got {points.shape[1]}")
        return {name: orthonormal_basis(self.germs, self.indices[name], points) @ c
                for name, c in self.coefficients.items()}

    def mean(self) -> dict[str, np.ndarray]:
        return {name: c[~self.indices[name].any(axis=1)].sum(axis=0) for name, c in self.coefficients.items()}

    def variance(self) -> dict[str, np.ndarray]:
        return {name: (c[self.indices[name].any(axis=1)] ** 2).sum(axis=0) for name, c in self.coefficients.items()}


def fit_surrogate(path, method: MethodSpec | None = None, partial: bool = False, allow_aliasing: bool = False,
                  options=None, progress=None) -> Surrogate:
    """The PCE of every output of the results file `path`, exactly as `uqflight.analysis.statistics.analyse`
    fits it (with `method` overriding the campaign's), after the same checks: pending or failed runs,
    a projection the grid cannot integrate and a rank-deficient fit are refused (statistics.BadInput).
    A method that builds no PCE of its own on this design is exported as its registry entry says
    (`exported_as`: monte_carlo, and integration on a sampled design, as least squares). The export
    and the calibration both fit here. `options`: statistics.Options (default 200 band draws: the PCE
    does not depend on them, and its bands and PDFs are not exported); `progress`: see analyse. The file is
    opened once (`fit_store_surrogate`)."""
    from .statistics import file_record
    from ..store import ResultStore

    with ResultStore.open(path) as store:
        return fit_store_surrogate(store, path, file_record(store, path), method, partial, allow_aliasing, options,
                                   progress)


def fit_store_surrogate(store, path, record, method: MethodSpec | None = None, partial: bool = False,
                        allow_aliasing: bool = False, options=None, progress=None) -> Surrogate:
    """`fit_surrogate` of the open results file `store` read from `path`, whose checked campaign `record`
    (statistics.file_record) the caller has read."""
    from ..designs import REGISTRY as DESIGNS
    from .statistics import BadInput, Options, analyse_store

    design_kind = record.design_kind
    if DESIGNS[design_kind].rare:
        raise BadInput(f"{path}: a {design_kind} design's runs were chosen to reach its event, they are not "
                       "draws of the input law: no expansion of the law is fitted to them; fly a sampled "
                       "design or a grid for a surrogate")
    parameters, time = record.parameter_rows, np.asarray(store.time, dtype=float)
    override = method or MethodSpec(record.campaign.method.kind)
    override = replace(override, kind=override.entry.exported_kind(DESIGNS[design_kind].sampled))
    stats = analyse_store(store, path, method=override, partial=partial, allow_aliasing=allow_aliasing,
                          options=options or Options(band_samples=200, bootstrap=0), progress=progress, record=record)
    pces = {name: out.pce for name, out in stats.outputs.items()}
    units = {name: out.units for name, out in stats.outputs.items()}  # the simulator's, else from the name
    dependence = {k: v for k, v in stats.dependence.items() if k != "sobol_of"} if stats.dependence else None
    return Surrogate(parameters, list(next(iter(pces.values())).germs),
                     {name: np.asarray(pce.indices, dtype=int) for name, pce in pces.items()}, time,
                     {name: np.asarray(pce.coefficients, dtype=float) for name, pce in pces.items()}, units,
                     stats.method, stats.campaign_name, dependence)


def _copula(dependence: dict | None):
    """The GaussianCopula of a `dependence` mapping (ValueError naming the key when it is not one)."""
    from ..parameters.dependence import KINDS, GaussianCopula

    if dependence is None:
        return None
    if not isinstance(dependence, dict) or dependence.get("kind") not in KINDS:
        raise ValueError(f"dependence.kind: expected one of {', '.join(KINDS)}")
    names, rows = dependence.get("parameters"), dependence.get("correlation")
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        raise ValueError(f"dependence.parameters: expected a list of parameter names, got {quoted_value(names)}")
    try:
        return GaussianCopula(tuple(names), _array(rows, "dependence.correlation", (len(names), len(names))))
    except ValueError as exc:
        raise ValueError(str(exc) if str(exc).startswith("dependence") else f"dependence.{exc}") from None


def surrogate_json(surrogate: Surrogate, results: str = "") -> dict:
    """The strict-JSON form (non-finite numbers as null)."""
    def numbers(a):
        return [[v if math.isfinite(v) else None for v in row] for row in np.asarray(a, dtype=float).tolist()]

    bases = list(surrogate.indices.values())
    shared = all(np.array_equal(b, bases[0]) for b in bases)
    data = {
        "format": FORMAT, "version": VERSION, "campaign": surrogate.campaign, "results": results,
        "method": surrogate.method.kind, "order": surrogate.method.order, "split": surrogate.method.split,
        "basis": "orthonormal polynomials of the germs (Hermite for normal, Legendre for uniform), " + (
            "total degree" if shared else "each output's own terms (outputs.NAME.multi_indices)"),
        "parameters": surrogate.parameters, "germs": surrogate.germs,
        **({"dependence": surrogate.dependence} if surrogate.dependence else {}),
        "multi_indices": bases[0].tolist(), "time": surrogate.time.tolist(),
        "outputs": {name: {"units": surrogate.units.get(name, ""), "coefficients": numbers(c),
                           **({} if shared else {"multi_indices": surrogate.indices[name].tolist()})}
                    for name, c in surrogate.coefficients.items()},
    }
    if not shared:
        del data["multi_indices"]
    return data


def export(results, out, method: dict | None = None, progress=None) -> Path:
    """Fit the PCE of `results` and write it to `out` as strict JSON; returns `out`. The folder of
    `out` must exist; nothing is left behind when the write fails (a full disk). `progress` (a
    uqflight.running.progress.Progress) is told the stages."""
    data = surrogate_json(fit_surrogate(results, method, progress=progress), str(results))
    if progress is not None:
        progress.stage(f"writing {out}")
    text = json.dumps(data, allow_nan=False) + "\n"
    if len(text) > MAX_FILE_BYTES:
        raise Refusal(f"{results}: the surrogate takes {len(text) / 2**20:.0f} MiB of JSON, more than the "
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
    """The surrogate written by `export` (or `uqflight surrogate export`); Refusal, naming the
    file and the key, for anything else (a damaged or hand-edited file is never evaluated): a file
    above MAX_FILE_BYTES (refused before it is read), numbers that are strings, booleans or out of
    range, multi-indices that are not integers in [0, MAX_DEGREE] or repeat a row, laws whose germ is
    not the one given, times that do not increase; no regular file (a FIFO, a device: refused unread)."""
    try:
        data = json.loads(read_bounded(path, MAX_FILE_BYTES, "a surrogate"))
    except (OSError, ValueError, RecursionError) as exc:
        raise Refusal(f"{path}: cannot read the surrogate ({exc})") from exc
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise Refusal(f"{path}: not a uqflight PCE surrogate (format {FORMAT!r})")
    try:
        return _checked(data)
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise Refusal(f"{path}: malformed surrogate ({type(exc).__name__}: {exc})") from exc


def _checked(data: dict) -> Surrogate:
    """The Surrogate a parsed file describes, every type, shape and value checked before any array is
    built (ValueError naming the key)."""
    from ..parameters import Parameter
    from ..parameters.germs import GERMS

    if data.get("version") != VERSION:
        raise ValueError(f"version: expected {VERSION}, got {quoted_value(data.get('version'))}")
    germs = data["germs"]
    if not isinstance(germs, list) or not germs or not all(isinstance(g, str) for g in germs):
        raise ValueError(f"germs: expected a list of names ({', '.join(GERMS)}), got {quoted_value(germs)}")
    unknown = [g for g in germs if g not in GERMS]
    if unknown:
        raise ValueError(f"germs: unknown {unknown} (known: {', '.join(GERMS)})")
    d = len(germs)
    parameters = data["parameters"]
    copula = _copula(data.get("dependence"))
    if not isinstance(parameters, list) or len(parameters) != d or not all(
            isinstance(p, dict) and {"name", "distribution", "lower", "upper", "nominal"} <= set(p) for p in parameters):
        raise ValueError(f"parameters: expected {d} entries with name, distribution, lower, upper, nominal")
    for j, p in enumerate(parameters):  # their laws map κ to ξ: built once here so that a bad one is refused now
        for key in ("name", "distribution", "property"):
            if not isinstance(p.get(key, ""), str):
                raise ValueError(f"parameters[{j}].{key}: expected a string, got {quoted_value(p[key])}")
        for key in ("lower", "upper", "nominal"):
            _number(p[key], f"parameters[{j}].{key}")
        law = Parameter(p["name"], p.get("property", p["name"]), p["distribution"], p["nominal"], p["lower"],
                        p["upper"])
        germ = "normal" if copula is not None and law.name in copula.names else law.germ
        if germ != germs[j]:
            raise ValueError(f"parameters[{j}] ({quoted_name(p['name'])}): a {p['distribution']} law is driven by a {germ} "
                             f"germ{' (dependence:)' if germ != law.germ else ''}, but germs[{j}] is {germs[j]}")
    unknown = set(copula.names) - {p["name"] for p in parameters} if copula is not None else set()
    if unknown:
        raise ValueError(f"dependence.parameters: {sorted(unknown)} are not among the parameters")
    order = data["order"]
    if isinstance(order, bool) or not isinstance(order, int) or not 0 <= order <= MAX_DEGREE:
        raise ValueError(f"order: expected an integer in [0, {MAX_DEGREE}], got {quoted_value(order)}")
    shared = _multi_indices(data["multi_indices"], "multi_indices", d, order) if "multi_indices" in data else None
    time = _array(data["time"], "time", (None,))
    if not time.size or np.any(np.diff(time) <= 0):
        raise ValueError("time: expected a list of strictly increasing numbers")
    outputs = data["outputs"]
    if not isinstance(outputs, dict) or not outputs:
        raise ValueError("outputs: expected a mapping of at least one output")
    coefficients, indices = {}, {}
    for name, output in outputs.items():
        if shared is None or "multi_indices" in output:
            indices[name] = _multi_indices(output["multi_indices"], f"outputs.{quoted_name(name)}.multi_indices", d, order)
        else:
            indices[name] = shared
        coefficients[name] = _array(output["coefficients"], f"outputs.{quoted_name(name)}.coefficients",
                                    (len(indices[name]), time.size))
        if not isinstance(output.get("units", ""), str):
            raise ValueError(f"outputs.{quoted_name(name)}.units: expected a string, got {quoted_value(output['units'])}")
    for key, kind in (("method", str), ("split", bool), ("campaign", str)):
        if key in data and not isinstance(data[key], kind):
            raise ValueError(f"{key}: expected a {kind.__name__}, got {quoted_value(data[key])}")
    return Surrogate(parameters, germs, indices, time, coefficients,
                     {name: o.get("units", "") for name, o in outputs.items()},
                     MethodSpec(data["method"], order, data.get("split", False)),
                     data.get("campaign", ""), data.get("dependence"))


def _multi_indices(value, key: str, d: int, order: int) -> np.ndarray:
    """Rows of d integers of total degree <= order, none repeated (ValueError naming `key`)."""
    indices = _array(value, key, (None, d), integers=True)
    if not len(indices) or indices.sum(axis=1).max() > order:
        raise ValueError(f"{key}: expected rows of {d} integers of total degree <= order {order}, "
                         f"got {len(indices)} rows of total degree up to {indices.sum(axis=1).max(initial=0)}")
    rows = {}
    for i, row in enumerate(map(tuple, indices.tolist())):
        if row in rows:
            raise ValueError(f"{key}: row {i} repeats row {rows[row]} ({list(row)})")
        rows[row] = i
    return indices


MAX_DEGREE = 1000  # a multi-index entry or order beyond this is refused (a PCE of useful size stays far below)
_LARGEST = 1.7976931348623157e308


def _number(value, key: str) -> float:
    """A finite JSON number (never a string, a boolean, a null or an integer beyond float range)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not -_LARGEST <= value <= _LARGEST:
        raise ValueError(f"{key}: expected a finite number, got {quoted_value(value)}")
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
            found = "nulls" if cell is None else quoted_value(cell)
            raise ValueError(f"{key}: expected {expected} {what}, got shape {cells.shape} with {found}")
    return cells.astype(np.int64 if integers else float)
