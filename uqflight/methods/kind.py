"""The base class of the method kinds (`Method`), its keys (`Key`), its result (`Result`) and the registry
that subclassing fills (`METHODS`); the kinds themselves are in their modules (see the package)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, ClassVar

import numpy as np

from ..analysis.moments import as_runs_by_time, weighted_moments
from .pce import PCE

DEFAULT_ORDER = 2  # a method's order (sparse: max_order) when the campaign gives none


@dataclass(frozen=True)
class Key:
    """One key of a `method:` mapping besides `kind`: its default, its meaning in the key reference, and
    what it accepts (an integer >= `minimum`, one of `choices`, true or false, or what `check(value)` says:
    why it is refused, or None). `filled`: validation writes the default into the mapping when absent."""

    default: object
    description: str
    minimum: int | None = None
    choices: tuple[str, ...] = ()
    check: Callable[[object], str | None] | None = None
    filled: bool = False

    def problem(self, value) -> str | None:
        """Why `value` is refused by the key's choices or check, or None (its type: the campaign schema)."""
        if self.choices and value not in self.choices:
            return f"expected one of {', '.join(self.choices)}, got {value!r}"
        return self.check(value) if self.check else None


ORDER = Key(DEFAULT_ORDER, "Total degree of the PCE, >= 0. Default 2, or the largest a grid's projection allows. "
                           "`order: 3`", minimum=0)
SPLIT = Key(False, "Use the paper's split form x = x0 + S (Eq. 22–24) for projections. Default false.", filled=True)
ALLOW_ALIASING = Key(False, "Let a projection's order exceed what the grid integrates exactly (refused otherwise; "
                            "the report says so). Default false.")


@dataclass
class Result:
    """Mean and variance per time (each (T,)), and the PCE when the method builds one (None: the
    statistics are those of the runs themselves, `from_runs`)."""

    mean: np.ndarray
    variance: np.ndarray
    pce: PCE | None

    @property
    def from_runs(self) -> bool:
        return self.pce is None


def scaled(pce: PCE, scale) -> PCE:
    """The PCE of Y = rows @ scale from the PCE of the rows (a method linear in the runs); scale None: itself."""
    return pce if scale is None else PCE(pce.germs, pce.indices, pce.coefficients @ np.asarray(scale, dtype=float))


class Method:
    """A method kind: subclass it with a ``kind`` name and it is registered in METHODS.

    Class attributes say the facts the rest of uqflight asks of a method; hooks say what it does.

    Attributes
    ----------
    kind : str
        Its name in `method: {kind: ...}` and `--method KIND[:ORDER]`.
    label : str
        Its name in the paper's legends.
    rule : str or None
        What its points must satisfy (`validity`): "projection" (a grid exact to degree 2p), "fit"
        (a design matrix of rank Z), "selection" (a candidate set, refused at the fit) or None (no PCE).
    failed_runs : str
        What its statistics are when runs failed, a key of FAILED_RUNS.
    keys : dict of str to Key
        Its keys of `method:` besides ``kind``; ``order_key`` is the one that sets its order.
    sampled_only : bool
        It refuses grids.
    runs_on_sampled : bool
        On a sampled design its statistics are those of the runs themselves (no PCE).
    split : bool
        It accepts the split form x0 (a projection).
    partial : bool
        It is valid on a subset of a design's runs (failed or pending runs left out).
    weighted : bool
        Its fit (and the rank check and leave-one-out error of a fit) weighs the runs by |w|.
    quadrature : bool
        Its mean and variance are the weighted sums of the runs, its PCE serves bands, PDFs and Sobol'.
    exported_as : tuple of str or None
        The kinds whose PCE a surrogate (export, calibration) carries on a sampled design and on a grid;
        None: its own PCE.

    Examples
    --------
    >>> import numpy as np
    >>> from uqflight.methods import METHODS, Method
    >>> pg = Method.of("pseudo_galerkin")
    >>> pg is METHODS["pseudo_galerkin"], pg.order_key, Method.of("sparse").order_key
    (True, 'order', 'max_order')
    >>> xi, w = np.array([[-1.0], [0.0], [1.0]]), np.array([1, 4, 1]) / 6  # Simpson = 3-point Gauss-Lobatto
    >>> result = pg.fit(xi, w, 2 * xi + 1, ["uniform"], order=1)
    >>> float(result.mean[0]), round(float(result.variance[0]), 12)
    (1.0, 1.333333333333)
    """

    kind: ClassVar[str]
    label: ClassVar[str]
    rule: ClassVar[str | None] = None
    failed_runs: ClassVar[str] = "conditional"
    keys: ClassVar[dict[str, Key]] = {"order": ORDER, "split": SPLIT, "allow_aliasing": ALLOW_ALIASING}
    order_key: ClassVar[str] = "order"
    sampled_only: ClassVar[bool] = False
    runs_on_sampled: ClassVar[bool] = False
    split: ClassVar[bool] = False
    partial: ClassVar[bool] = False
    weighted: ClassVar[bool] = True
    quadrature: ClassVar[bool] = False
    exported_as: ClassVar[tuple[str, str] | None] = None

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if "kind" in cls.__dict__:
            METHODS[cls.kind] = cls()

    @staticmethod
    def of(kind: str) -> Method:
        """The method of `kind`; an unknown kind is a ValueError listing the kinds."""
        if kind not in METHODS:
            raise ValueError(f"unknown method kind {kind!r}: expected one of {', '.join(METHODS)}")
        return METHODS[kind]

    @staticmethod
    def of_runs(sampled: bool) -> Method:
        """The method whose statistics are the runs' own: monte_carlo on a sampled design, else integration."""
        return METHODS["monte_carlo" if sampled else "integration"]

    @property
    def settings(self) -> tuple[str, ...]:
        """Its keys its `expansion` takes by name (beyond the order and the split form)."""
        return tuple(k for k in self.keys if k not in (self.order_key, "split", "allow_aliasing"))

    @property
    def projects(self) -> bool:
        """Its PCE is a projection (needs a grid exact to degree 2p)."""
        return self.rule == "projection"

    @property
    def fits(self) -> bool:
        """Its PCE is a least-squares fit (with or without a selection of its basis): a leave-one-out error."""
        return self.rule in ("fit", "selection")

    @property
    def selects(self) -> bool:
        """It chooses its basis from the runs: its out-of-sample error redoes the choice per fold."""
        return self.rule == "selection"

    @property
    def expands(self) -> bool:
        """It builds a PCE, on a grid at least (False: the runs' own statistics, or another kind's PCE)."""
        return self.rule is not None

    def builds_pce(self, sampled: bool) -> bool:
        """Whether it builds a PCE on a design (sampled or a grid), so that its order means something."""
        return self.expands and not (sampled and self.runs_on_sampled)

    def settings_of(self, settings: dict | None) -> dict:
        """The settings its expansion takes (`settings`), defaults filled in for those not given."""
        return {key: (settings or {}).get(key, self.keys[key].default) for key in self.settings}

    def problem(self, method: dict) -> tuple[str, str] | None:
        """(key, why) of the first key of a `method:` mapping its Key refuses, or None."""
        for key, spec in self.keys.items():
            why = spec.problem(method[key]) if key in method else None
            if why:
                return key, why
        return None

    def points_problem(self, order: int, xi, weights, germs: list[str], sampled: bool,
                       allow_aliasing: bool = False) -> str | None:
        """Why its rule refuses a PCE of total `order` on the points xi (N, d) with weights, or None."""
        return None

    def expansion(self, xi, weights, Y, germs, order: int, x0=None, scale=None, **settings) -> PCE:
        """Its PCE of Y = rows @ scale (scale None: Y (N, T)) at the points xi (N, d) with weights (N,)."""
        raise NotImplementedError(f"{self.kind} builds no PCE")

    def fit(self, xi, weights, Y, germs, order: int = DEFAULT_ORDER, x0=None, *, scale=None, sampled: bool = False,
            settings: dict | None = None) -> Result:
        """Apply the method to the runs Y = rows @ scale at points xi (N, d) with weights (N,).

        Y: the runs (N, T), or with ``scale`` (r, T) the rows (N, r) of tSVD factors. ``order`` is the PCE's
        total degree; x0 ((T,) or (N, 1)) selects the split form of the projections (see galerkin).
        ``sampled``: the points are random draws, where a method that `runs_on_sampled` gives the runs' own
        moments. ``settings``: its other keys (`settings`).
        """
        if x0 is not None and not self.split:
            split = " and ".join(k for k, m in METHODS.items() if m.split)
            raise ValueError(f"x0 (the split form x = x0 + S) applies to {split}; {self.kind!r} either builds no "
                             "PCE or fits the constant term itself, so the split would change nothing")
        Y = as_runs_by_time(Y)
        if not self.builds_pce(sampled):
            own = self.run_weights(weights)
            mean, variance = weighted_moments(Y, own, scale, unbiased=own is None)
            return Result(mean, variance, None)
        pce = self.expansion(xi, weights, Y, germs, order, x0, scale, **self.settings_of(settings))
        if self.quadrature:  # quadrature moments; the PCE serves bands, PDFs, Sobol'
            mean, variance = weighted_moments(Y, weights, scale)
        else:
            mean, variance = pce.mean(), pce.variance()
        return Result(mean, variance, pce)

    def run_weights(self, weights):
        """The weights of the runs in its statistics of the runs themselves (None: equal, Monte Carlo's)."""
        return weights

    def exported_kind(self, sampled: bool) -> str:
        """The kind whose PCE a surrogate of this method carries (`exported_as`); a kind that needs a sampled
        design stays itself on a grid, for the analysis to refuse (never another method in its place)."""
        if self.exported_as is None or (self.sampled_only and not sampled):
            return self.kind
        return self.exported_as[0 if sampled else 1]

    def failed_runs_note(self, failed: int, done: int) -> str:
        """The note that says what its statistics are when `failed` of the `done` runs failed."""
        headline, why = FAILED_RUNS[self.failed_runs]
        return f"{headline}: {failed} of {done} runs failed; {why.format(ok=done - failed, kind=self.kind)}"


METHODS: dict[str, Method] = {}  # filled by the subclasses, in the order the package imports them


# (what the statistics are, why) when runs failed; `Method.failed_runs_note` fills in the counts.
FAILED_RUNS = {
    "conditional": ("statistics conditional on success",
                    "they are those of the {ok} successful runs alone, not of the whole input law"),
    "extrapolated": ("statistics of a fit extrapolated over the failed region",
                     "{kind} fits its PCE on the {ok} successful runs and its statistics are the PCE's over the "
                     "whole input law, including the region where the model has no value"),
    "chosen": ("statistics of the method chosen per output",
               "auto chose among the methods the {ok} successful runs allow: a fit extrapolates over the failed "
               "region, the runs' own statistics are conditional on success (each output says which it took)"),
    "projected": ("statistics of a projection of the successful runs, of neither law",
                  "{kind} projects the {ok} successful runs alone: its mean is the mean conditional on success, "
                  "but its PCE (the bands, PDFs and Sobol' indices, and pseudo_galerkin's variance) is that of "
                  "the output divided by the success rate where runs succeeded and 0 where they failed; use "
                  "monte_carlo for statistics conditional on success or least_squares for a fit"),
}
