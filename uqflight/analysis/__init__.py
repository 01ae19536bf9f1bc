"""Post-processing of run outputs (paper section 5): moments, bands, PDFs, errors, KLD, Sobol' indices."""

# The analysis's defaults (the campaign's `analysis:` keys): draws of an expansion for its bands and
# densities, bootstrap resamplings of the Sobol' intervals, and the quantiles reported over time.
BAND_SAMPLES = 20000
BOOTSTRAP = 200
QUANTILES = (0.005, 0.995)

from .density import kde_bandwidth, kde_on_grid, pdf_over_time
from .divergence import kl_divergence
from .errors import error_summary, relative_errors
from .moments import modified_cov, weighted_mean, weighted_std, weighted_variance
from .sobol import pick_freeze_indices

__all__ = [
    "BAND_SAMPLES",
    "BOOTSTRAP",
    "QUANTILES",
    "error_summary",
    "kde_bandwidth",
    "kde_on_grid",
    "kl_divergence",
    "modified_cov",
    "pdf_over_time",
    "pick_freeze_indices",
    "relative_errors",
    "weighted_mean",
    "weighted_std",
    "weighted_variance",
]
