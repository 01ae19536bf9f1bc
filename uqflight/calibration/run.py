"""`calibrate` from end to end: surrogate → likelihood → sampler → (if converged) outputs."""
from __future__ import annotations

import json
import math
import os
import shutil
import tempfile
import time as clock
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from ..parameters.germs import GERMS
from ..text import Refusal

from .likelihood import LogPosterior, check_names, check_noise, interpolate_in_time, read_flight_csv
from .outputs import (OUTPUT_FILES, calibrated_campaign, corner_plot, draw_all, informed, marginal, marginals_plot,
                      predictive_plot, pyplot, write_json, write_posterior)
from .sampler import sample
from .size import MAX_STEPS, PREDICTIVE_NOISE_DRAWS, check_size
from .surrogate import (CampaignError, check_campaign_text, open_results, parameter_specs, portable_mapping,
                        prior_summaries, results_record, simulate, surrogate_of, to_physical, to_standard)

TIME_HANDLING = ("PCE coefficients (and the surrogate's error variance) interpolated linearly in time "
                 "onto the data times; data times outside the results file's time range are refused")
NOISE_PRIOR = ("inferred noise: half-Cauchy(0, S) prior on sigma, sampled as log sigma; S = RMS over the "
               "data of (data - prior-mean prediction)^2 + prior variance + surrogate error variance; cut to "
               "S e^-30 < sigma < S e^10")
NOISE_FREE = 1e-6  # an inferred noise below this share of the data's scale: hint that the data look noise-free


class NotConverged(RuntimeError):
    """The chain failed the convergence rule; nothing was written (stale outputs were removed)."""

    def __init__(self, diagnostics: dict, removed: list[str]):
        self.diagnostics, self.removed = diagnostics, removed
        super().__init__("; ".join(diagnostics["problems"]))


@dataclass
class Calibration:
    out: Path
    summary: dict
    written: list[str] = field(default_factory=list)


def calibrate(results, data, out, outputs: list[str] | None = None, noise: dict[str, float] | None = None,
              seed: int = 0, walkers: int | None = None, steps: int | None = None, method: str | None = None,
              order: int | None = None, campaign: str | None = None, predictive_draws: int = 50,
              truth: dict | None = None, progress=None) -> Calibration:
    """Calibrate the campaign of `results` on flight `data`; see docs/calibration.md. `outputs`: the
    calibrated outputs (None: every output the data and the surrogate share); `noise`: {output: known noise
    std}, the others' inferred; `method` and `order`: the surrogate's, instead of the campaign's. `progress` (a
    uqflight.running.progress.Progress) is told the stages and counts the sampler's steps. `steps`: exactly that
    many per walker, or None: until converged (calibration.sampler, at most MAX_STEPS).

    Raises a Refusal (bad input or settings, data too large for memory: calibration.size), NotConverged.
    One BLAS thread: the matrices are small (a few hundred rows), where several threads on a shared
    machine make the SVDs 10-100x slower."""
    started = clock.perf_counter()
    results = Path(results)
    with threadpool_limits(limits=1):
        with open_results(results) as store:  # opened once: the record, the size check, the surrogate
            record = results_record(store, results, Path(campaign) if campaign else None)
            check_size(data, outputs, walkers, steps, predictive_draws, record.campaign.limits.max_memory_gb)
            if truth:
                check_names(truth, "--truth", [p.name for p in record.campaign.parameters],
                            f"the parameters of {results}")
            _stage(progress, f"fitting the surrogate of {results}")
            surrogate = surrogate_of(store, results, record, method, order)
        return _calibrate(surrogate, started, results, data, out, outputs, noise, seed, walkers, steps,
                          predictive_draws, truth, progress)


def _calibrate(surrogate, started, results, data, out, outputs, noise, seed, walkers, steps, predictive_draws,
               truth, progress) -> Calibration:
    """The steps of `calibrate` after the surrogate (fitted from `started`): sample (and refine), summarise,
    write."""
    out = Path(out)
    flight, given, posterior = _fitted(surrogate, data, outputs, noise)
    walkers = walkers or max(32, 2 * posterior.ndim + 2)
    if steps is not None and steps < 100:
        raise Refusal(f"--steps: expected at least 100, got {steps}")
    fitted = clock.perf_counter()
    sampling = Sampling(surrogate, flight, given, walkers, steps, seed, out, progress)
    chain, posterior, predictive, check = sampling.run(posterior, predictive_draws)
    draws, pick, sim_time, runs, failures, ok, _ = predictive
    sampled = sampling.first_sampled
    xi = draws[:, :len(surrogate.names)]
    kappa = to_physical(surrogate.parameters, xi, surrogate.campaign.dependence)
    sigmas = posterior.sigmas(draws)
    specs = parameter_specs(surrogate.parameters)
    prior = prior_summaries(surrogate.parameters)
    post = {name: marginal(kappa[:, k]) for k, name in enumerate(surrogate.names)}
    correlation = _correlation(kappa)
    parameters = _parameter_summaries(surrogate.names, specs, prior, post, xi, truth)
    at_data, band, coverage = _predictive_band(flight, runs, ok, sim_time, sigmas, pick, sampling.rng)
    predicted = clock.perf_counter()
    summary = {
        "results": str(results), "data": str(data), "campaign": surrogate.campaign.name,
        "seed": seed,
        "surrogate": {"kind": surrogate.method.kind, "order": surrogate.method.order, "runs": surrogate.runs,
                      "time_handling": TIME_HANDLING,
                      "error": "mean square leave-one-out residual of the weighted least-squares fit of the same "
                               "basis (or the surrogate's own misfit at the runs, if larger), per output and time, "
                               "added to the noise variance"},
        "noise_model": NOISE_PRIOR,
        "noise": _noise_summary(flight, posterior, surrogate, given, sigmas),
        "parameters": parameters,
        "correlation": {"names": surrogate.names, "matrix": correlation},
        "diagnostics": chain.diagnostics,
        "surrogate_check": check,
        "predictive": {"draws": int(len(pick)), "failed": int((~ok).sum()), "failures": failures,
                       "coverage95": coverage,
                       "band": "2.5 % and 97.5 % quantiles of simulator runs + noise draws at the data times"},
        "seconds": {"surrogate": fitted - started, "first_sampling": sampled - fitted,
                    "predictive_and_refinement": predicted - sampled},
    }
    posterior_draws = PosteriorDraws(xi, kappa, np.column_stack([sigmas[o] for o in flight.values]),
                                     chain.log_prob[chain.burn:].T.reshape(-1), post, prior, specs, correlation)
    _write_outputs(out, results, data, seed, surrogate, flight, posterior, chain, posterior_draws, truth,
                   sampling, at_data, band, int((~ok).sum()), summary, started)
    return Calibration(out, summary, [name for name in OUTPUT_FILES if name != "calibrated.yaml"
                                      or summary["calibrated_campaign"]["written"]])


def _stage(progress, text: str, total: int = 0, unit: str = "steps") -> None:
    """A new stage of `progress` (a uqflight.running.progress.Progress), when there is one."""
    if progress:
        progress.stage(text, total, unit)


def _fitted(surrogate, data, outputs, noise):
    """The flight data, the given noise and the log-posterior on the `surrogate`."""
    flight = read_flight_csv(data, outputs, surrogate.outputs)
    given = check_noise(noise or {}, list(flight.values))
    posterior = LogPosterior.build(surrogate.time, surrogate.coefficients, surrogate.error_factors,
                                   surrogate.germs, surrogate.names, surrogate.basis, flight, given)
    return flight, given, posterior


@dataclass
class Sampling:
    """The sampling step: the chain, its convergence rule, the predictive runs at its draws and, when
    the surrogate's error measured there exceeds the assumed one, the error model refined and the
    posterior sampled again. `rng` (seed + 1) picks the predictive draws, then the band's noise."""

    surrogate: object
    flight: object
    given: dict
    walkers: int
    steps: int | None
    seed: int
    out: Path
    progress: object  # a uqflight.running.progress.Progress, or None
    first_sampled: float = 0.0

    def __post_init__(self):
        self.rng = np.random.default_rng(self.seed + 1)

    def prior_draw(self, posterior, rng, n):
        """`n` draws of the prior in ξ, the noise parameters at their start."""
        germs = self.surrogate.germs
        xi = np.column_stack([GERMS[g].sample(rng, n) for g in germs])
        rest = np.tile(posterior.start()[len(germs):], (n, 1))
        return np.hstack([xi, rest])

    def chain(self, posterior, seed):
        """A converged chain of `posterior`, or NotConverged (with a hint for noise-free data)."""
        until = "" if self.steps else f"; until converged, at most {MAX_STEPS} steps"
        most = self.steps or MAX_STEPS
        _stage(self.progress, f"sampling the posterior ({self.walkers} walkers{until})", most, "steps")
        chain = sample(posterior, posterior.ndim, posterior.labels, posterior.start(),
                       lambda rng, n: self.prior_draw(posterior, rng, n), self.walkers, self.steps, seed,
                       progress=self.progress)
        taken = chain.samples.shape[0]
        if self.progress is not None and taken < most:  # stopped once converged: the stage is done
            self.progress.advance(most - taken, f"sampling the posterior ({self.walkers} walkers): converged at "
                                                f"{taken} steps")
        if chain.diagnostics["converged"]:
            return chain
        germs = self.surrogate.germs
        kept = chain.kept.reshape(-1, chain.kept.shape[2])
        for j, term in enumerate(posterior.inferred):
            sigma = float(np.exp(np.median(kept[:, len(germs) + j])))
            if sigma < NOISE_FREE * term.scale:
                chain.diagnostics["problems"].append(
                    f"the inferred noise of {term.name} is {sigma:.2g}, {sigma / term.scale:.1g} of the data's "
                    f"scale: are the data noise-free (simulated)? Then the posterior is limited only by the "
                    f"surrogate's error and hard to sample: give the measurement noise, --noise {term.name}=SIGMA")
        removed = []
        for name in OUTPUT_FILES:  # outputs of an earlier run in DIR would look like this run's
            if (self.out / name).is_file():
                (self.out / name).unlink()
                removed.append(name)
        raise NotConverged(chain.diagnostics, removed)

    def run(self, posterior, predictive_draws: int):
        """(chain, posterior, the _predictive tuple, surrogate_check) after sampling and any refinement."""
        surrogate, flight = self.surrogate, self.flight
        chain = self.chain(posterior, self.seed)
        self.first_sampled = clock.perf_counter()
        _stage(self.progress, f"flying {predictive_draws} posterior draws")
        predictive = _predictive(chain, posterior, surrogate, flight, self.rng, predictive_draws)
        draws, pick, _, _, _, ok, errors = predictive
        # The surrogate's error measured where the posterior is (the real simulator at its draws): when it
        # is larger than the error model assumed and not negligible against the noise, it joins the error
        # model (as curves over time) and the posterior is sampled again.
        check = _surrogate_check(posterior, errors, draws[pick][ok])
        if check["refine"]:
            extra = {o: _full_rows(flight.values[o], errors[o].T / math.sqrt(errors[o].shape[0])) for o in errors}
            posterior = LogPosterior.build(surrogate.time, surrogate.coefficients, surrogate.error_factors,
                                           surrogate.germs, surrogate.names, surrogate.basis, flight, self.given,
                                           extra_error=extra)
            chain = self.chain(posterior, self.seed + 1)
            _stage(self.progress, f"flying {predictive_draws} posterior draws")
            predictive = _predictive(chain, posterior, surrogate, flight, self.rng, predictive_draws)
            draws, pick, _, _, _, ok, errors = predictive
            check = {**_surrogate_check(posterior, errors, draws[pick][ok]), "refined": True,
                     "first_pass": {k: v for k, v in check.items() if k != "refine"}}
        else:
            check["refined"] = False
        check.pop("refine")
        return chain, posterior, predictive, check


def _correlation(kappa: np.ndarray) -> np.ndarray:
    """The posterior correlation matrix of the parameters (1 for a single one)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.corrcoef(kappa, rowvar=False) if kappa.shape[1] > 1 else np.ones((1, 1))


def _parameter_summaries(names, specs, prior, post, xi, truth) -> dict:
    """summary.json's `parameters`: prior and posterior per parameter, the narrowing, and the truth when given."""
    parameters = {}
    for k, name in enumerate(names):
        ratio = post[name]["std"] / prior[name]["std"] if prior[name]["std"] > 0 else float("nan")
        parameters[name] = {
            "property": specs[name]["property"], "distribution": specs[name]["distribution"],
            "prior": prior[name], "posterior": post[name],
            "posterior_standard": marginal(xi[:, k]),
            "std_ratio": ratio, "narrowing": 1.0 / ratio if ratio > 0 else None,
        }
        if truth and name in truth:
            t = float(truth[name])
            parameters[name]["truth"] = t
            parameters[name]["truth_in_ci95"] = bool(post[name]["ci95"][0] <= t <= post[name]["ci95"][1])
    return parameters


def _predictive_band(flight, runs, ok, sim_time, sigmas, pick, rng):
    """Per output: the predictive runs at the data times, the 95 % band of runs + noise, and the share
    of the data inside it (None without a successful run)."""
    at_data, band, coverage = {}, {}, {}
    for o in flight.values:
        at_data[o] = interpolate_in_time(runs[o][ok], sim_time, flight.time)
        noisy = at_data[o][:, None, :] + sigmas[o][pick][ok][:, None, None] * rng.standard_normal(
            (int(ok.sum()), PREDICTIVE_NOISE_DRAWS, flight.time.size))
        lower, upper = np.quantile(noisy.reshape(-1, flight.time.size), [0.025, 0.975], axis=0)
        band[o] = (lower, upper)
        y = flight.values[o]
        present = np.isfinite(y)
        coverage[o] = float(np.mean((y[present] >= lower[present]) & (y[present] <= upper[present]))) if ok.any() \
            else None
    return at_data, band, coverage


def _noise_summary(flight, posterior, surrogate, given, sigmas) -> dict:
    """summary.json's `noise`: given or inferred per output, with the surrogate's error there."""
    noise_summary = {}
    for j, o in enumerate(flight.values):
        term = posterior.terms[j]
        relative = surrogate.relative_error[o]
        resolved = relative[np.isfinite(relative)]
        noise_summary[o] = {"given": given.get(o), "inferred": None if o in given else marginal(sigmas[o]),
                            "prior": None if o in given else {"kind": "half_cauchy", "scale": term.scale},
                            "surrogate_error_rms": float(np.sqrt(np.mean(term.error_variance))),
                            "surrogate_relative_loo_error": {
                                "median": float(np.median(resolved)) if resolved.size else None,
                                "max": float(np.max(resolved)) if resolved.size else None},
                            "data_points": int(term.y.size)}
    return noise_summary


@dataclass
class PosteriorDraws:
    """The kept draws in ξ and κ, the noise σ per output (columns), their log-probabilities, and the
    marginal summaries, parameter specs and correlation the outputs are written from."""

    xi: np.ndarray
    kappa: np.ndarray
    sigma: np.ndarray
    log_prob: np.ndarray
    post: dict
    prior: dict
    specs: dict
    correlation: np.ndarray


def _write_outputs(out, results, data, seed, surrogate, flight, posterior, chain, draws: PosteriorDraws, truth,
                   sampling: Sampling, at_data, band, failed: int, summary: dict, started: float) -> None:
    """posterior.h5, calibrated.yaml, the plots and summary.json, written into a scratch folder first,
    then moved: an interrupted run leaves no half set of outputs."""
    names, specs = surrogate.names, draws.specs
    _stage(sampling.progress, f"writing {out}")
    out.mkdir(parents=True, exist_ok=True)
    scratch = Path(tempfile.mkdtemp(prefix=".calibrate-", dir=out))
    try:
        (scratch / "plots").mkdir()
        attrs = {"results": str(results), "data": str(data), "campaign": surrogate.campaign.text,
                 "seed": seed, "labels": json.dumps(posterior.labels)}
        write_posterior(scratch / "posterior.h5", names, [specs[n]["property"] for n in names], draws.xi, draws.kappa,
                        list(flight.values), draws.sigma, draws.log_prob, chain.samples, posterior.labels, chain.burn,
                        attrs)
        scores = normal_scores(surrogate.parameters, draws.kappa, draws.post, draws.prior)
        text = calibrated_campaign(portable_mapping(surrogate.campaign), specs, draws.post, draws.prior,
                                   scores, names, f"{results}, {data}")
        try:  # loadable by `uqflight plan`; a text it refuses is a bug here, which costs no finished calibration
            check_campaign_text(text, str(out / "calibrated.yaml"))
        except CampaignError as exc:
            summary["calibrated_campaign"] = {"written": False, "refused": str(exc)}
        else:
            summary["calibrated_campaign"] = {"written": True, "refused": None}
            (scratch / "calibrated.yaml").write_text(text, encoding="utf-8")
        truth_row = np.array([truth.get(n, np.nan) for n in names]) if truth else None
        properties = [specs[n]["property"] for n in names]
        prior_xi = sampling.prior_draw(posterior, np.random.default_rng(seed + 2), 20000)[:, :len(names)]
        prior_kappa = to_physical(surrogate.parameters, prior_xi, surrogate.campaign.dependence)
        plots = scratch / "plots"
        draw_all([lambda: corner_plot(plots / "corner.png", draws.kappa, names, truth_row, properties=properties),
                  lambda: marginals_plot(plots / "marginals.png", prior_kappa, draws.kappa, names, truth_row,
                                         properties=properties),
                  lambda: predictive_plot(plots / "predictive.png", flight.time, flight.values, at_data, band,
                                          surrogate.units, failed)])
        summary["seconds"]["total"] = clock.perf_counter() - started
        write_json(scratch / "summary.json", summary)
        (out / "plots").mkdir(exist_ok=True)
        for name in OUTPUT_FILES:
            if (scratch / name).exists():
                (scratch / name).replace(out / name)
            elif (out / name).is_file():  # an earlier run's calibrated.yaml would look like this run's
                (out / name).unlink()
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def normal_scores(parameters, kappa: np.ndarray, post: dict, prior: dict) -> np.ndarray:
    """The posterior draws κ (M, d) as standard-normal scores Φ⁻¹(F_k(κ_k)) under the marginals F_k that
    calibrated.yaml gives them: the normal N(mean, std²) of an informed parameter's posterior (then the
    score's correlation is that of κ), the prior law of one kept at its prior. Their correlation is the
    Gaussian copula's (Nataf's ρ0) that `dependence:` takes."""
    marginal_xi = to_standard(parameters, kappa)  # each parameter's own germ variable (no dependence)
    scores = np.column_stack([GERMS[p.germ].to_normal(x) for p, x in zip(parameters, marginal_xi.T)])
    for k, p in enumerate(parameters):
        if informed(post[p.name], prior[p.name]):
            scores[:, k] = (kappa[:, k] - post[p.name]["mean"]) / post[p.name]["std"]
    return scores


def _predictive(chain, posterior, surrogate, flight, rng, count):
    """Posterior draws (walker by walker), `count` of them flown with the real simulator, and the
    surrogate's error at those draws and the data times: {output: (K, n)} (data minus nothing: the
    simulator run minus the surrogate)."""
    draws = chain.kept.transpose(1, 0, 2).reshape(-1, posterior.ndim)
    pick = rng.choice(len(draws), size=min(count, len(draws)), replace=False)
    xi = draws[pick, :len(surrogate.names)]
    kappa = to_physical(surrogate.parameters, xi, surrogate.campaign.dependence)
    processes = min(surrogate.campaign.execution.workers, os.cpu_count() or 1)  # the campaign's, on this machine
    # matplotlib (a second to import) is loaded while the flights run: the plots come next
    sim_time, runs, failures = simulate(surrogate.campaign, kappa, list(flight.values), processes, meanwhile=pyplot)
    ok = np.all([np.all(np.isfinite(runs[o]), axis=1) for o in runs], axis=0)
    errors = {}
    basis = surrogate.basis(xi[ok])
    for term in posterior.terms:
        keep = np.isfinite(flight.values[term.name])
        at_data = interpolate_in_time(runs[term.name][ok], sim_time, flight.time[keep])
        errors[term.name] = at_data - basis @ term.coefficients
    return draws, pick, sim_time, runs, failures, ok, errors


REFINE_NOISE_SHARE = 0.01  # measured surrogate error variance above this share of the noise variance ...
REFINE_MODEL_FACTOR = 2.0  # ... and this many times what the error model assumed: refine


def _surrogate_check(posterior, errors: dict, draws: np.ndarray) -> dict:
    """Measured (at posterior draws) against assumed surrogate error, per output."""
    sigmas = posterior.sigmas(draws) if len(draws) else {}
    out, refine = {}, False
    for term in posterior.terms:
        e = errors[term.name]
        measured = float(np.mean(e**2)) if e.size else float("nan")
        assumed = float(np.mean(term.error_variance))
        noise = float(np.mean(sigmas[term.name] ** 2)) if len(draws) else float("nan")
        flag = bool(measured > REFINE_NOISE_SHARE * noise and measured > REFINE_MODEL_FACTOR * assumed)
        refine |= flag
        out[term.name] = {"measured_error_rms": math.sqrt(measured) if measured == measured else None,
                          "assumed_error_rms": math.sqrt(assumed), "noise_rms": math.sqrt(noise)
                          if noise == noise else None, "exceeds": flag}
    return {"outputs": out, "refine": refine}


def _full_rows(values: np.ndarray, kept_rows: np.ndarray) -> np.ndarray:
    """Rows at the data times with values (kept_rows), zero rows where the data are missing."""
    full = np.zeros((values.size, kept_rows.shape[1]))
    full[np.isfinite(values)] = kept_rows
    return full


__all__ = ["Calibration", "NotConverged", "calibrate"]
