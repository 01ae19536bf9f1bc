"""Relative errors of a method's mean and variance against a reference over time (Eq. 49)."""
import numpy as np


def _relative_to_peak(value, reference) -> np.ndarray:
    """|value − reference| / max|reference|; an identically zero reference gives the absolute error."""
    reference = np.asarray(reference, dtype=float)
    peak = np.max(np.abs(reference))
    return np.abs(np.asarray(value, dtype=float) - reference) / (peak if peak > 0 else 1.0)


def relative_errors(mean, variance, mean_ref, variance_ref) -> tuple[np.ndarray, np.ndarray]:
    """ε_m and ε_v of Eq. 49, each (T,): errors normalised by the reference's maximum over time.

    Normalising by the maximum rather than pointwise keeps the estimate well conditioned where
    the reference mean or variance passes through zero.
    """
    return _relative_to_peak(mean, mean_ref), _relative_to_peak(variance, variance_ref)


def error_summary(errors) -> dict[str, float]:
    """The maximum and the time average of an error history: {"max": ..., "mean": ...}."""
    errors = np.asarray(errors, dtype=float)
    return {"max": float(errors.max()), "mean": float(errors.mean())}
