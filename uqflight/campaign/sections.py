"""The campaign's settings sections as typed, frozen values: `execution:`, `storage:` (with its `tsvd:`),
`analysis:` and `limits:`. Each class's fields are its keys, their defaults are the only ones, and its
`checked` is the one validator of its section (CampaignError naming the field's path).

>>> from uqflight.campaign.schema import Checker
>>> Execution.checked(Checker("c.yaml"), {"workers": 2})
Execution(workers=2, executor='local', scheduler=None, chunk=16, timeout_s=None)
>>> Storage.checked(Checker("c.yaml"), {"tsvd": {"tol": 1e-6}}, "demo").tsvd
Tsvd(tol=1e-06, batch=1000)
"""
from __future__ import annotations

from dataclasses import dataclass, field, fields

from ..analysis import BAND_SAMPLES, BOOTSTRAP
from ..methods.validity import MAX_TERMS
from ..text.console import quoted_value

EXECUTORS = ("local", "dask")
# A million draws of one output are sorted 100 times at once (statistics.TIME_BLOCK): about 1.6 GB in two threads.
MAX_BAND_SAMPLES = 10**6
MAX_BOOTSTRAP = 10**4


def keys_of(section) -> tuple[str, ...]:
    """A section's keys: its fields' names, in the order the key reference lists them."""
    return tuple(f.name for f in fields(section))


@dataclass(frozen=True)
class Execution:
    """`execution:`: how the runs are flown (`timeout_s` None: derived from a measured nominal flight)."""

    workers: int = 1
    executor: str = "local"
    scheduler: str | None = None
    chunk: int = 16
    timeout_s: float | None = None

    @classmethod
    def checked(cls, check, value) -> Execution:
        given = check.mapping(value, "execution", keys_of(cls))
        timeout = given.get("timeout_s")
        scheduler = given.get("scheduler")
        return cls(workers=check.integer(given.get("workers", cls.workers), "execution.workers", 1),
                   executor=check.string(given.get("executor", cls.executor), "execution.executor", EXECUTORS),
                   scheduler=None if scheduler is None else check.string(scheduler, "execution.scheduler"),
                   chunk=check.integer(given.get("chunk", cls.chunk), "execution.chunk", 1),
                   timeout_s=None if timeout is None else check.number(timeout, "execution.timeout_s", 0.0,
                                                                       strict=True))

    @property
    def on_this_machine(self) -> bool:
        """Whether the workers are processes of this machine (dask without a scheduler: a LocalCluster)."""
        return self.executor == "local" or not self.scheduler


@dataclass(frozen=True)
class Tsvd:
    """`storage.tsvd:`: the outputs compressed on the fly by an incremental thin SVD."""

    tol: float = 1e-8
    batch: int = 1000

    @classmethod
    def checked(cls, check, value) -> Tsvd:
        given = check.mapping(value, "storage.tsvd", keys_of(cls))
        tol = check.number(given.get("tol", cls.tol), "storage.tsvd.tol", 0.0, strict=True)
        if tol >= 1:
            check.fail("storage.tsvd.tol", f"expected a relative tolerance in (0, 1), got {tol!r}")
        return cls(tol, check.integer(given.get("batch", cls.batch), "storage.tsvd.batch", 1))


@dataclass(frozen=True)
class Storage:
    """`storage:`: the results file (default `results/NAME.h5`), raw histories, tSVD factors."""

    path: str
    raw: bool = True
    tsvd: Tsvd | None = None

    @classmethod
    def checked(cls, check, value, name: str) -> Storage:
        given = check.mapping(value, "storage", keys_of(cls))
        path = check.string(given.get("path", f"results/{name}.h5"), "storage.path")
        raw = check.boolean(given.get("raw", cls.raw), "storage.raw")
        tsvd = None if given.get("tsvd") is None else Tsvd.checked(check, given["tsvd"])
        if not raw and tsvd is None:
            check.fail("storage.raw", "false needs storage.tsvd: otherwise nothing of the outputs would be kept")
        return cls(path, raw, tsvd)


@dataclass(frozen=True)
class Analysis:
    """`analysis:`: the statistics' draws and resamplings, the quantiles over time (None: the analysis's
    own), and the exceedance thresholds per quantity ({quantity: [{above: X} | {below: Y}]})."""

    band_samples: int = BAND_SAMPLES
    bootstrap: int = BOOTSTRAP
    quantiles: tuple[float, ...] | None = None
    exceedance: dict = field(default_factory=dict)

    @classmethod
    def checked(cls, check, value, quantities: dict | None = None) -> Analysis:
        """`quantities`: the campaign's checked quantities, which `exceedance:` must name."""
        given = check.mapping(value, "analysis", keys_of(cls))
        exceedance = {}
        if "exceedance" in given:
            from ..quantities.spec import check_exceedance

            exceedance = check_exceedance(check, given["exceedance"], quantities or {})
        band_samples = check.integer(given.get("band_samples", cls.band_samples), "analysis.band_samples", 100)
        if band_samples > MAX_BAND_SAMPLES:
            check.fail("analysis.band_samples", f"expected at most {MAX_BAND_SAMPLES} draws (a million draws of an "
                                                "output, sorted 100 times at once, take about 1.6 GB in two "
                                                f"threads), got {band_samples}")
        bootstrap = check.integer(given.get("bootstrap", cls.bootstrap), "analysis.bootstrap", 0)
        if bootstrap > MAX_BOOTSTRAP:
            check.fail("analysis.bootstrap", f"expected at most {MAX_BOOTSTRAP} resamplings (10^4 of a pick-freeze "
                                             "design of 1024 base rows take about a minute and 1 GB), "
                                             f"got {bootstrap}")
        quantiles = given.get("quantiles")
        if quantiles is not None:
            if not isinstance(quantiles, list) or not quantiles or len(quantiles) > 20:
                check.fail("analysis.quantiles", f"expected a list of 1 to 20 probabilities, got "
                                                 f"{quoted_value(quantiles)}")
            for i, probability in enumerate(quantiles):
                check.number(probability, f"analysis.quantiles[{i}]")
                if not 0.0 < probability < 1.0:
                    check.fail(f"analysis.quantiles[{i}]", f"expected a probability in (0, 1), got {probability!r}")
            quantiles = tuple(float(q) for q in quantiles)
        return cls(band_samples, bootstrap, quantiles, exceedance)


@dataclass(frozen=True)
class Limits:
    """`limits:`: sizes refused before anything is built (`schema.check_size`)."""

    max_runs: int = 1_000_000
    max_memory_gb: float = 8.0
    max_disk_gb: float = 100.0
    max_pce_terms: int = MAX_TERMS

    @classmethod
    def checked(cls, check, value) -> Limits:
        given = check.mapping(value, "limits", keys_of(cls))
        found = {}
        for key in keys_of(cls):
            if key in given:
                default = getattr(cls, key)
                found[key] = (check.integer(given[key], f"limits.{key}", 1) if isinstance(default, int) else
                              check.number(given[key], f"limits.{key}", 0.0, strict=True))
        return cls(**found)
