"""Post-processing of run outputs (paper section 5): moments, bands, PDFs, errors, KLD, Sobol' indices."""
from .density import kde_bandwidth, kde_on_grid, pdf_over_time
from .divergence import kl_divergence
from .errors import error_summary, relative_errors
from .moments import modified_cov, quantile_band, weighted_mean, weighted_std, weighted_variance
from .sobol import pick_freeze_indices

__all__ = [
    "error_summary",
    "kde_bandwidth",
    "kde_on_grid",
    "kl_divergence",
    "modified_cov",
    "pdf_over_time",
    "pick_freeze_indices",
    "quantile_band",
    "relative_errors",
    "weighted_mean",
    "weighted_std",
    "weighted_variance",
]
