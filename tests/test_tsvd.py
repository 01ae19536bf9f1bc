"""The incremental thin SVD against a full SVD of the same data, and statistics from its factors."""
import numpy as np
import pytest

from uqflight.analysis.moments import weighted_moments
from uqflight.store.tsvd import IncrementalSVD, iter_column_blocks, orthogonality_loss


def weighted_mean(U, s, V, w):
    """The weighted mean of A = U diag(s) Vᵀ's columns, from the factors."""
    return weighted_moments(V, w, s[:, None] * U.T)[0]


def weighted_variance(U, s, V, w):
    """The weighted variance of A's columns, from the factors."""
    return weighted_moments(V, w, s[:, None] * U.T)[1]


def low_rank_data(n_times=120, n_samples=1000, rank=6, smallest=1e-5, noise=1e-9, seed=0):
    """Smooth time histories of known rank, amplitudes graded from 1 to `smallest`, an offset, noise."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.0, n_times)[:, None]
    modes = np.sin(np.pi * t * np.arange(1, rank + 1)) * np.exp(-t * np.arange(rank))
    amplitudes = rng.standard_normal((rank, n_samples)) * np.geomspace(1.0, smallest, rank)[:, None]
    return 4.0 + modes @ amplitudes + noise * rng.standard_normal((n_times, n_samples))


def incremental(A, tol, n_batches):
    svd = IncrementalSVD(tol)
    for columns in np.array_split(np.arange(A.shape[1]), n_batches):
        svd.update(A[:, columns])
    return svd


def reconstruction(svd):
    return (svd.U * svd.s) @ svd.V.T


def test_updates_match_a_full_svd():
    A = low_rank_data()
    svd = incremental(A, tol=1e-8, n_batches=50)
    s_full = np.linalg.svd(A, compute_uv=False)
    assert (svd.U.shape, svd.V.shape, svd.n_columns) == ((120, svd.rank), (1000, svd.rank), 1000)
    assert svd.rank == np.count_nonzero(s_full > 1e-8 * s_full[0])
    np.testing.assert_allclose(svd.s, s_full[:svd.rank], rtol=0, atol=1e-8 * s_full[0])
    assert np.abs(reconstruction(svd) - A).max() <= 1e-8 * s_full[0]


@pytest.mark.slow
def test_moments_from_the_factors_match_the_raw_data():
    A = low_rank_data()
    svd = incremental(A, tol=1e-12, n_batches=10)
    w = np.random.default_rng(1).uniform(0.5, 1.5, A.shape[1])
    w /= w.sum()
    mean = A @ w
    variance = ((A - mean[:, None]) ** 2) @ w
    np.testing.assert_allclose(weighted_mean(svd.U, svd.s, svd.V, w), mean, rtol=1e-12)
    np.testing.assert_allclose(weighted_variance(svd.U, svd.s, svd.V, w), variance, rtol=1e-8, atol=1e-14)


def test_variance_keeps_its_digits_under_a_large_mean():
    """A spread of 1e-3 on a mean of 1e4 (an altitude in feet): no E[A²] − m² cancellation."""
    A = 1e4 + 1e-3 * low_rank_data(noise=0.0)
    svd = incremental(A, tol=0.0, n_batches=5)
    w = np.full(A.shape[1], 1.0 / A.shape[1])
    variance = ((A - (A @ w)[:, None]) ** 2) @ w
    error = np.abs(weighted_variance(svd.U, svd.s, svd.V, w) - variance).max()
    assert error < 1e-7 * variance.max()


def test_tighter_tolerance_gives_smaller_errors():
    A = low_rank_data(n_times=60, n_samples=400, rank=12, smallest=1e-12, noise=0.0)
    w = np.full(A.shape[1], 1.0 / A.shape[1])
    mean, variance = A @ w, ((A - (A @ w)[:, None]) ** 2) @ w
    errors = []
    for tol in (1e-2, 1e-4, 1e-8, 1e-12):
        svd = incremental(A, tol, n_batches=8)
        errors.append((np.abs(reconstruction(svd) - A).max(),
                       np.abs(weighted_variance(svd.U, svd.s, svd.V, w) - variance).max() / variance.max()))
        assert np.abs(weighted_mean(svd.U, svd.s, svd.V, w) - mean).max() <= 10 * tol * np.abs(A).max()
    matrix_errors, variance_errors = np.array(errors).T
    assert np.all(np.diff(matrix_errors) < 0) and matrix_errors[-1] < 1e-10
    # the variance error falls with the tolerance until it reaches rounding level
    assert all(b < a or b < 1e-12 for a, b in zip(variance_errors, variance_errors[1:]))
    assert variance_errors[0] > 1e-3 and variance_errors[-1] < 1e-12


def test_orthogonality_holds_over_200_updates():
    A = low_rank_data(n_times=100, n_samples=2000, rank=10, noise=1e-9)
    svd = incremental(A, tol=1e-8, n_batches=200)
    assert orthogonality_loss(svd.U) < 1e-12 and orthogonality_loss(svd.V) < 1e-12


def test_reorthogonalisation_keeps_the_product():
    A = low_rank_data(n_samples=300)
    svd = incremental(A[:, :200], tol=0.0, n_batches=2)
    svd.U[:, 0] *= 1 + 1e-8  # an orthogonality loss far above the threshold
    expected = np.hstack([reconstruction(svd), A[:, 200:]])
    svd.update(A[:, 200:])
    assert orthogonality_loss(svd.U) < 1e-13 and orthogonality_loss(svd.V) < 1e-13
    np.testing.assert_allclose(reconstruction(svd), expected, rtol=0, atol=1e-12)


def test_resume_from_factors_equals_uninterrupted():
    A = low_rank_data(n_samples=400)
    whole = incremental(A, tol=1e-10, n_batches=4)
    half = incremental(A[:, :200], tol=1e-10, n_batches=2)
    resumed = IncrementalSVD.from_factors(half.U, half.s, half.V, tol=1e-10)
    for columns in np.array_split(np.arange(200, 400), 2):
        resumed.update(A[:, columns])
    for a, b in ((whole.U, resumed.U), (whole.s, resumed.s), (whole.V, resumed.V)):
        np.testing.assert_array_equal(a, b)


def test_column_blocks_rebuild_the_samples():
    A = low_rank_data(n_samples=250)
    svd = incremental(A, tol=1e-12, n_batches=3)
    blocks = list(iter_column_blocks(svd.U, svd.s, svd.V, block=100))
    assert [b.shape for b in blocks] == [(100, 120), (100, 120), (50, 120)]
    np.testing.assert_allclose(np.vstack(blocks), A.T, rtol=0, atol=1e-11)


def test_rejects_columns_of_another_height():
    svd = incremental(low_rank_data(n_samples=20), tol=1e-8, n_batches=1)
    with pytest.raises(ValueError, match=r"\(120, n\)"):
        svd.update(np.ones((119, 3)))
