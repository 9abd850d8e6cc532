"""Static stability without an eigendecomposition (issue 28): a symmetric reduced stiffness shown
positive definite beyond its tolerance by one Cholesky factorization of the shifted matrix
(Sylvester's law of inertia), with cheap bounds of ‖K_r‖₂; every other case decided by the
eigenvalues as before.

References: matrices of known spectrum Q diag(μ) Qᵀ (Q a random orthogonal matrix), whose
verdict the eigenvalue rule of mbseig.statics.stiffness gives in closed form; the norm bounds
against numpy's 2-norm (SVD), an independent computation.
"""

import numpy as np
import pytest

from mbseig.statics.stiffness import (
    STIFFNESS_TOL,
    SYMMETRY_TOL,
    _norm_bounds,
    _positive_definite,
)


def _known(mu, seed=0):
    rng = np.random.default_rng(seed)
    Q, _ = np.linalg.qr(rng.standard_normal((len(mu), len(mu))))
    return (Q * np.asarray(mu, float)) @ Q.T


@pytest.mark.parametrize("seed", range(5))
def test_norm_bounds_enclose_the_two_norm(seed):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((30, 30)) * rng.uniform(0.1, 10.0, 30)
    lo, hi = _norm_bounds(A)
    two = np.linalg.norm(A, 2)
    assert lo <= two * (1 + 1e-14) and two <= hi * (1 + 1e-14)


def test_positive_definite_decides_stable():
    K = _known(np.linspace(1.0, 1e3, 40))
    K = 0.5 * (K + K.T)  # exactly symmetric
    rec = _positive_definite(K, STIFFNESS_TOL, SYMMETRY_TOL)
    assert rec["verdict"] == "stable" and rec["index"] == 0 and rec["zero"] == 0
    assert rec["asymmetry"] == 0.0


def test_rounding_asymmetry_is_bounded_not_refused():
    K = _known(np.linspace(1.0, 1e3, 40), seed=3)  # Q diag Qᵀ: asymmetric by rounding only
    assert np.any(K != K.T)
    rec = _positive_definite(K, STIFFNESS_TOL, SYMMETRY_TOL)
    assert rec["verdict"] == "stable" and 0 < rec["asymmetry"] <= SYMMETRY_TOL


@pytest.mark.parametrize("low", [-1e-3, -1e-8, 0.0, 1e-12, 5e-10])
def test_negative_or_near_zero_stiffness_goes_to_the_eigenvalues(low):
    """An eigenvalue below, at or within the tolerance (1e-9 ‖K_r‖) of zero: unstable or
    neutral by the eigenvalue rule, so the factorization must not call it stable."""
    K = _known([low, *np.linspace(1.0, 2.0, 9)], seed=1)
    K = 0.5 * (K + K.T)
    assert _positive_definite(K, STIFFNESS_TOL, SYMMETRY_TOL) is None


def test_just_beyond_the_tolerance_is_stable():
    """Eigenvalues (6e-9, 1, 2): the smallest is 3× the eigenvalue rule's threshold
    1e-9·‖K_r‖₂ = 2e-9 and above the factorization's 1e-9·(bound ≤ √3·2): stable by both."""
    small = _known([3 * STIFFNESS_TOL * 2.0, 1.0, 2.0], seed=4)
    small = 0.5 * (small + small.T)
    assert _positive_definite(small, STIFFNESS_TOL, SYMMETRY_TOL)["verdict"] == "stable"


def test_non_symmetric_goes_to_the_eigenvalues():
    K = _known(np.linspace(1.0, 2.0, 6))
    K[0, 1] += 1e-6  # asymmetry 1e-6 ≫ 1e-10: the non-symmetric rule (det, real eigenvalues)
    assert _positive_definite(K, STIFFNESS_TOL, SYMMETRY_TOL) is None


def test_banded_factorization_sees_the_lowest_eigenvalue():
    """A chain's tridiagonal stiffness (n = 200, above the banded threshold): lowest eigenvalue
    2 − 2cos(π/(n + 1)) (closed form); the banded Cholesky of A − c·I succeeds just below it
    and fails just above it (Sylvester's law), as the dense one does."""
    from mbseig.statics.stiffness import _cholesky_succeeds

    n = 200
    A = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    low = 2 - 2 * np.cos(np.pi / (n + 1))
    assert _cholesky_succeeds(A, low * (1 - 1e-6)) and not _cholesky_succeeds(A, low * (1 + 1e-6))
    B = A.copy()
    B[0, -1] = B[-1, 0] = -1e-3  # one far corner: not banded, the dense factorization
    assert _cholesky_succeeds(B, 0.0) == bool(np.linalg.eigvalsh(B)[0] > 0)


def test_sparse_check_agrees_with_the_dense_one():
    """The sparse form (a model without constraints) decides as the dense one: a tridiagonal
    stiffness, shifted just below and just above its lowest eigenvalue (closed form)."""
    import scipy.sparse as sp

    from mbseig.statics.stiffness import _positive_definite_sparse

    n = 200
    A = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    low = 2 - 2 * np.cos(np.pi / (n + 1))
    for shift in (low * (1 - 1e-3), low * (1 + 1e-3)):
        B = A - shift * np.eye(n)
        dense = _positive_definite(B, STIFFNESS_TOL, SYMMETRY_TOL)
        sparse = _positive_definite_sparse(sp.csr_matrix(B), STIFFNESS_TOL, SYMMETRY_TOL)
        assert (dense is None) == (sparse is None) == (shift > low)
