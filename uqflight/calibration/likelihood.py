"""Flight data, the noise model and the log posterior of the standard variables ξ (and log σ).

Model, per output o and data time t_k:

    y_o(t_k) = f_o(t_k, ξ) + ε,   ε ~ N(0, σ_o² + s_o²(t_k))   independent over o and k,

f_o the PCE surrogate with its coefficients interpolated linearly in time onto the data times,
σ_o the measurement noise (given, or inferred with a half-Cauchy prior of scale S_o on σ_o,
sampled as log σ_o), s_o²(t) the surrogate's own error variance (mean square leave-one-out
residual over the runs, interpolated the same way). Prior of ξ: the campaign's germs, each its own
law (`Germ.log_density`, `support`; N(0, 1), U(−1, 1), ...). Plain arrays here: the surrogate
reaches this module as its coefficients and a basis function.
"""
from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from ..text.bounded import OutsideBounds, read_bounded
from ..text import Refusal
from ..text.console import listed, quoted_name
from ..parameters.germs import GERMS, germ_columns


MAX_DATA_BYTES = 64 << 20  # a flight data CSV (about 4 million cells): refused beyond, before it is read
DATA_FORM = "the flight data is a CSV file as `uqflight simulate --out` writes it (time_s and output columns)"


@dataclass
class FlightData:
    """Measured outputs at `time` (n,); NaN marks a missing value."""

    source: str
    time: np.ndarray
    values: dict[str, np.ndarray]


def read_flight_csv(path, outputs: list[str] | None, available: list[str]) -> FlightData:
    """A CSV as `uqflight simulate --out` writes it: `time_s` and one column per output.

    `outputs` (None: every column that is one of `available`) selects the columns; an empty cell
    or NaN is a missing value. Refused: no time_s, non-numeric cells, times not increasing, a
    requested output missing from the file or from the campaign.
    """
    path = Path(path)
    try:  # a byte-order mark is no part of the header
        text = read_bounded(path, MAX_DATA_BYTES, "flight data").decode("utf-8-sig")
        rows = list(csv.reader(io.StringIO(text, newline="")))
    except OutsideBounds as exc:
        raise Refusal(f"{path}: {exc}: {DATA_FORM}") from exc
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise Refusal(f"{path}: cannot read the file ({exc})") from exc
    rows = [row for row in rows if any(cell.strip() for cell in row)]
    if len(rows) < 2:
        raise Refusal(f"{path}: expected a header (time_s, outputs...) and at least one row of data")
    header = [cell.strip() for cell in rows[0]]
    if "time_s" not in header:
        raise Refusal(f"{path}: no time_s column (header: {listed(header)})")
    if outputs is None:
        outputs = [name for name in header if name in available]
        if not outputs:
            raise Refusal(f"{path}: none of the columns {listed(h for h in header if h != 'time_s')} is an "
                          f"output of the campaign ({listed(available)})")
    for name in outputs:
        if name not in available:
            raise Refusal(f"--output {quoted_name(name)}: not an output of the campaign ({listed(available)})")
        if name not in header:
            raise Refusal(f"{path}: no column {name!r} (header: {listed(header)})")
    table = np.full((len(rows) - 1, len(header)), np.nan)
    for i, row in enumerate(rows[1:], start=2):
        if len(row) != len(header):
            raise Refusal(f"{path}: line {i} has {len(row)} cells, the header {len(header)}")
        for j, cell in enumerate(row):
            cell = cell.strip()
            if cell:
                try:
                    table[i - 2, j] = float(cell)
                except ValueError:
                    raise Refusal(f"{path}: line {i}, column {quoted_name(header[j])}: expected a number, "
                                  f"got {cell!r}") from None
    time = table[:, header.index("time_s")]
    if not np.all(np.isfinite(time)) or np.any(np.diff(time) <= 0):
        raise Refusal(f"{path}: time_s must be finite and strictly increasing")
    values = {name: table[:, header.index(name)] for name in outputs}
    for name, column in values.items():
        if np.any(np.isinf(column)):
            raise Refusal(f"{path}: column {name!r} holds an infinite value")
        if not np.isfinite(column).any():
            raise Refusal(f"{path}: column {name!r} holds no value")
    return FlightData(str(path), time, values)


def parse_noise(pairs: list[str]) -> dict[str, float]:
    """`--noise OUTPUT=SIGMA` items as {output: sigma} (SIGMA > 0, in the output's unit); Refusal otherwise."""
    return parse_pairs(pairs, "--noise", "OUTPUT=SIGMA with SIGMA > 0", positive=True)


def check_noise(noise: dict, outputs: list[str]) -> dict[str, float]:
    """The known noise {output: sigma}: each output one of `outputs`, each sigma a finite number > 0;
    Refusal naming the output otherwise."""
    for name, sigma in noise.items():
        if isinstance(sigma, bool) or not isinstance(sigma, (int, float)) or not math.isfinite(sigma) or sigma <= 0:
            raise Refusal(f"--noise {quoted_name(name)}: expected SIGMA > 0 (a finite number), got {sigma!r}")
    return check_names({str(name): float(sigma) for name, sigma in noise.items()}, "--noise", outputs,
                       "the calibrated outputs")


def parse_pairs(pairs: list[str], option: str, form: str, positive: bool = False) -> dict[str, float]:
    """`NAME=VALUE` items of `option` as {name: value}: VALUE finite (and > 0 when `positive`), each NAME
    once; Refusal (naming `option` and `form`, what the items take) otherwise."""
    values = {}
    for pair in pairs:
        name, sep, text = pair.partition("=")
        name = name.strip()
        try:
            value = float(text)
        except ValueError:
            value = float("nan")
        if not sep or not name or not math.isfinite(value) or (positive and not value > 0):
            raise Refusal(f"{option}: expected {form}, got {pair!r}")
        if name in values:
            raise Refusal(f"{option} {quoted_name(name)}: given twice ({values[name]:g} and {value:g}); give it once")
        values[name] = value
    return values


def check_names(values: dict[str, float], option: str, names: list[str], among: str) -> dict[str, float]:
    """`values` when every name is one of `names` (`among` says what they are); Refusal otherwise."""
    for name in values:
        if name not in names:
            raise Refusal(f"{option} {quoted_name(name)}: not one of {among} ({listed(names)})")
    return values


def interpolate_in_time(values: np.ndarray, source: np.ndarray, target: np.ndarray) -> np.ndarray:
    """values (..., T) given at `source` times, linearly interpolated to `target` times (..., n).

    Refuses target times outside [source[0], source[-1]] (beyond a rounding tolerance)."""
    span = source[-1] - source[0]
    slack = 1e-9 * max(span, 1.0)
    if target.min() < source[0] - slack or target.max() > source[-1] + slack:
        raise Refusal(f"data times {target.min():g} to {target.max():g} s reach outside the surrogate's "
                      f"{source[0]:g} to {source[-1]:g} s: crop the data or run a longer campaign")
    t = np.clip(target, source[0], source[-1])
    if source.size == 1:
        return np.repeat(values[..., :1], t.size, axis=-1)
    right = np.clip(np.searchsorted(source, t, side="right"), 1, source.size - 1)
    left = right - 1
    fraction = (t - source[left]) / (source[right] - source[left])
    return values[..., left] * (1.0 - fraction) + values[..., right] * fraction


def error_factors_of(curves: np.ndarray, rtol: float = 1e-10) -> np.ndarray:
    """F (T, r) with F Fᵀ = curvesᵀ curves for error curves (K, T), the directions below rtol of the
    largest singular value dropped."""
    curves = np.asarray(curves, dtype=float)
    if not curves.size or not np.any(curves):
        return np.zeros((curves.shape[1] if curves.ndim == 2 else 0, 0))
    _, s, Vt = np.linalg.svd(curves, full_matrices=False)
    keep = s > rtol * s[0]
    return (Vt[keep].T * s[keep])


LOG_SIGMA_RANGE = (-30.0, 10.0)  # log(σ / S) of an inferred noise: the support of its (cut) prior


@dataclass
class OutputTerm:
    """One output's data, surrogate coefficients and error model at the data times.

    Error covariance: σ² I + U diag(λ) Uᵀ (U orthonormal (n, r)): the noise plus the surrogate's
    error, a random function of time whose covariance comes from error curves (see error_factors_of).
    """

    name: str
    y: np.ndarray            # (n,) observed values (missing ones dropped)
    coefficients: np.ndarray  # (Z, n) PCE coefficients at the data times
    error_basis: np.ndarray   # U (n, r)
    error_eigen: np.ndarray   # λ (r,)
    sigma: float | None      # given noise std; None: inferred
    scale: float             # half-Cauchy scale of an inferred σ

    def __post_init__(self):
        self.projected_y = self.error_basis.T @ self.y              # Uᵀy (r,)
        self.projected_c = self.coefficients @ self.error_basis     # C U (Z, r)

    @property
    def error_variance(self) -> np.ndarray:
        """The surrogate error variance at each data time, (n,)."""
        return (self.error_basis**2) @ self.error_eigen


def error_model(factors: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(U, λ) with U diag(λ) Uᵀ = F Fᵀ, U orthonormal, for factors F (n, k)."""
    if factors.shape[1] == 0 or not np.any(factors):
        return np.zeros((factors.shape[0], 0)), np.zeros(0)
    U, s, _ = np.linalg.svd(factors, full_matrices=False)
    keep = s > 1e-10 * s[0]
    return U[:, keep], s[keep] ** 2


class LogPosterior:
    """log p(θ | data) up to a constant, vectorised: θ (M, D) → (M,).

    θ = (ξ_1 … ξ_d, log σ_o for each output whose noise is inferred)."""

    def __init__(self, germs: list[str], names: list[str], basis: Callable[[np.ndarray], np.ndarray],
                 terms: list[OutputTerm]):
        self.germs, self.names, self.basis, self.terms = list(germs), list(names), basis, terms
        self.inferred = [term for term in terms if term.sigma is None]
        self.labels = self.names + [f"sigma_{term.name}" for term in self.inferred]
        self.ndim = len(self.labels)
        self._laws = [GERMS[g] for g in germs]
        self._lower = np.array([law.support[0] for law in self._laws])
        self._upper = np.array([law.support[1] for law in self._laws])
        self._bounded = bool(np.isfinite(self._lower).any() or np.isfinite(self._upper).any())
        self._germ_columns = germ_columns(self.germs)
        self._log_scales = np.array([math.log(term.scale) for term in self.inferred])
        self._given_sigma = np.array([np.nan if term.sigma is None else term.sigma for term in terms])
        self._inferred_columns = [k for k, term in enumerate(terms) if term.sigma is None]
        self._stack(terms)

    def _stack(self, terms: list[OutputTerm]) -> None:
        """Every output's terms side by side, so that one step evaluates all outputs in a few products.
        |y − bC|² is kept as a quadratic form in b − b_0, b_0 the basis at the prior's centre ξ = 0:
        Z² work per point instead of Z·n, and little cancels about a prediction close to the data."""
        self._centre = self.basis(np.clip(np.zeros((1, len(self.germs))), self._lower, self._upper))[0]
        offsets = [term.y - self._centre @ term.coefficients for term in terms]
        self._offset_square = np.array([o @ o for o in offsets])                       # (K,)
        self._cross = np.stack([t.coefficients @ o for t, o in zip(terms, offsets)], axis=1)  # (Z, K)
        self._gram = np.hstack([t.coefficients @ t.coefficients.T for t in terms])    # (Z, K·Z)
        self._projected_y = np.concatenate([t.projected_y for t in terms])            # (R,)
        self._projected_c = np.hstack([t.projected_c for t in terms])                 # (Z, R)
        self._eigen = np.concatenate([t.error_eigen for t in terms])                  # (R,)
        self._column_term = np.repeat(np.arange(len(terms)), [t.error_eigen.size for t in terms])
        self._members = (self._column_term[:, None] == np.arange(len(terms))).astype(float)  # (R, K)
        self._points = np.array([t.y.size for t in terms], dtype=float)
        self._free = self._points - np.array([t.error_eigen.size for t in terms])    # n − r per output

    @classmethod
    def build(cls, surrogate_time, coefficients: dict, error_factors: dict, germs, names, basis,
              data: FlightData, noise: dict[str, float], extra_error: dict | None = None) -> LogPosterior:
        """`error_factors[o]` (T, r) on the surrogate's times; `extra_error[o]` (n, k): more error
        factors at the data times (e.g. measured at posterior draws), added to the covariance."""
        terms = []
        for name, y in data.values.items():
            keep = np.isfinite(y)
            times = data.time[keep]
            c = interpolate_in_time(coefficients[name], surrogate_time, times)
            factors = interpolate_in_time(error_factors[name].T, surrogate_time, times).T
            if extra_error and name in extra_error:
                factors = np.hstack([factors, extra_error[name][keep]])
            U, eigen = error_model(factors)
            # half-Cauchy scale: the RMS of the data about the prior-mean prediction, prior spread included
            # (the constant term is first in the graded basis)
            prior_var = (c[1:] ** 2).sum(axis=0)
            s2 = (factors**2).sum(axis=1)
            scale = math.sqrt(float(np.mean((y[keep] - c[0]) ** 2 + prior_var + s2)))
            terms.append(OutputTerm(name, y[keep], c, U, eigen, noise.get(name), max(scale, 1e-300)))
        return cls(germs, names, basis, terms)

    def log_prior(self, theta: np.ndarray) -> np.ndarray:
        theta = np.atleast_2d(theta)
        xi = theta[:, :len(self.germs)]
        lp = sum(GERMS[germ].log_density(xi[:, columns]).sum(axis=1)  # −inf outside a support
                 for germ, columns in self._germ_columns)
        outside = ~np.isfinite(lp)
        if self.inferred:
            # half-Cauchy(scale) on each σ, with the Jacobian dσ/dlogσ = σ; log(1 + (σ/S)²) without overflow
            relative = theta[:, len(self.germs):] - self._log_scales
            lp = lp + (math.log(2.0 / math.pi) + relative - np.logaddexp(0.0, 2 * relative)).sum(axis=1)
            # cut at S·e^-30 and S·e^10 (σ from 1e-13 to 2e4 times the data's scale): keeps the variance
            # positive in floating point; the prior mass cut off is below 1e-4
            outside |= ((relative < LOG_SIGMA_RANGE[0]) | (relative > LOG_SIGMA_RANGE[1])).any(axis=1)
        return np.where(outside, -np.inf, lp)

    def sigmas(self, theta: np.ndarray) -> dict[str, np.ndarray]:
        """σ_o per row of θ (M,) for every output (given ones repeated)."""
        return dict(zip((term.name for term in self.terms), self._sigma_matrix(np.atleast_2d(theta)).T))

    def _sigma_matrix(self, theta: np.ndarray) -> np.ndarray:
        """σ (M, K) of every output, in the order of the terms."""
        sigma = np.tile(self._given_sigma, (len(theta), 1))
        sigma[:, self._inferred_columns] = np.exp(theta[:, len(self.germs):])
        return sigma

    def log_likelihood(self, theta: np.ndarray) -> np.ndarray:
        """Σ_o log N(y_o; f_o(ξ), σ_o² I + U_o diag(λ_o) U_oᵀ), with the closed-form inverse and
        determinant of that covariance (its eigenvalues are σ² + λ_k along U and σ² elsewhere)."""
        theta = np.atleast_2d(theta)
        xi = theta[:, :len(self.germs)]
        if self._bounded:  # a bounded germ's basis is only defined on its support
            xi = np.clip(xi, self._lower, self._upper)
        B = self.basis(xi)
        M, K = len(theta), len(self.terms)
        s2 = self._sigma_matrix(theta) ** 2                                            # (M, K)
        D = B - self._centre
        total = (self._offset_square - 2.0 * (D @ self._cross)
                 + ((D @ self._gram).reshape(M, K, -1) * D[:, None, :]).sum(axis=2))    # |y − f|² (M, K)
        projected = (self._projected_y - B @ self._projected_c) ** 2                    # (Uᵀ residual)² (M, R)
        eigen = s2[:, self._column_term] + self._eigen                                  # (M, R)
        across = np.maximum(total - projected @ self._members, 0.0)  # the part outside the error directions
        quadratic = across / s2 + (projected / eigen) @ self._members
        log_det = self._free * np.log(s2) + np.log(eigen) @ self._members
        return -0.5 * (quadratic + log_det + self._points * math.log(2 * math.pi)).sum(axis=1)

    def __call__(self, theta: np.ndarray) -> np.ndarray:
        theta = np.atleast_2d(theta)
        lp = self.log_prior(theta)
        finite = np.isfinite(lp)
        out = np.full(len(theta), -np.inf)
        if finite.any():
            with np.errstate(over="ignore", divide="ignore", invalid="ignore"):  # far tails: -inf below
                out[finite] = lp[finite] + self.log_likelihood(theta[finite])
        out[~np.isfinite(out)] = -np.inf
        return out

    def start(self) -> np.ndarray:
        """A starting θ: the prior mean ξ = 0 and each inferred σ at its half-Cauchy scale / 10."""
        theta = np.zeros(self.ndim)
        for j, term in enumerate(self.inferred):
            theta[len(self.germs) + j] = math.log(term.scale / 10.0)
        return theta
