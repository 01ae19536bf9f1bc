"""Non-intrusive UQ methods (paper section 4): one class per kind, registered by subclassing `Method`.

A kind's class says which designs it accepts, its keys of `method:` (`Method.keys`), how its PCE is built
(`Method.expansion`), the rule its points must satisfy before it runs, and how its mean and variance follow
(`Method.fit`): monte_carlo (below), integration, pseudo_galerkin and interpolation (`galerkin`),
regression and least_squares (`collocation`), sparse (`sparse`) and auto (`validation`).

Rules before anything runs (`validity.method_problem`): a projection of total order p needs a grid
exact to degree 2p; a fit needs a design matrix of full rank Z on the actual points; a selection (sparse)
needs only a candidate set within the term limit, and refuses at the fit when no basis has a defined
leave-one-out error.

What the statistics are when runs failed (`Method.failed_runs`, the sentence in `FAILED_RUNS`) is a
fact of the method, said once here for every note and report. A grid with failed runs accepts only the
fits (`validity`).
"""
from __future__ import annotations

from .kind import DEFAULT_ORDER, FAILED_RUNS, METHODS, Key, Method, Result, scaled
from .pce import PCE
from .galerkin import Integration, Interpolation, PseudoGalerkin  # registers them, in this order
from .collocation import LeastSquares, Regression


class MonteCarlo(Method):
    """Sample moments of the runs; sampled designs only.

    Examples
    --------
    >>> import numpy as np
    >>> from uqflight.methods import Method
    >>> xi = np.array([[-1.5], [-0.5], [0.5], [1.5]])  # 4 draws; the runs y = 2ξ + 1 are -2, 0, 2, 4
    >>> result = Method.of("monte_carlo").fit(xi, np.array([0.7, 0.1, 0.1, 0.1]), 2 * xi + 1, ["normal"], sampled=True)
    >>> result.from_runs, round(float(result.mean[0]), 12)  # no PCE; each run counts once, whatever its weight
    (True, 1.0)
    >>> round(float(result.variance[0]), 12)  # unbiased: Σ(y − 1)² / (N − 1) = 20/3
    6.666666666667
    """

    kind, label, sampled_only, runs_on_sampled, partial, weighted = "monte_carlo", "MC", True, True, True, False
    exported_as = ("least_squares", "pseudo_galerkin")

    def run_weights(self, weights):
        return None


from .sparse import Sparse  # noqa: E402  (registered after monte_carlo)
from .validation import AUTO_CANDIDATES, Auto  # noqa: E402
from .spec import MethodSpec  # noqa: E402

METHOD_KINDS = tuple(METHODS)


def fit(kind: str, *args, **kwargs) -> Result:
    """Method `kind`'s fit (Method.fit): the one dispatch the statistics, the surrogate export and the
    calibration use."""
    return Method.of(kind).fit(*args, **kwargs)


__all__ = ["AUTO_CANDIDATES", "DEFAULT_ORDER", "FAILED_RUNS", "METHODS", "METHOD_KINDS", "MethodSpec", "PCE", "Auto",
           "Integration", "Interpolation", "Key", "LeastSquares", "Method", "MonteCarlo", "PseudoGalerkin", "Regression",
           "Result", "Sparse", "fit", "scaled"]
