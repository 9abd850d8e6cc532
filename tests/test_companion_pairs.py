"""The dense companion path measures one member of each conjugate pair (mbseig.eigen.dense,
_geev_pairs): every returned pair must be what scipy.linalg.eig's own vectors give, and every
copied η, κ what a direct evaluation on that pair gives."""

import numpy as np
import pytest
import scipy.linalg as sla

from mbseig.eigen import dense
from mbseig.eigen.dense import solve_qep
from mbseig.eigen.measures import backward_errors, conditions, fro


def _problem(n, symmetric, seed=4):
    rng = np.random.default_rng(seed)
    m = rng.uniform(0.5, 2.0, n)
    M = np.diag(m) if symmetric else np.diag(m) + 0.05 * np.eye(n, k=1) + 0.05 * np.eye(n, k=-1)
    K = 1000 * (2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1))
    C = rng.uniform(0, 0.3, (n, n))
    C = C + C.T if symmetric else C  # non-symmetric damping: left vectors from LAPACK
    K[0, 0] -= 1500.0  # one divergent (real positive) pair among the oscillating ones
    return M, C, K


def _reference_companion(M, C, K):
    """The path's companion matrix and back-substitution, built again here from their
    definitions (mbseig.eigen.dense module docstring)."""
    n = M.shape[0]
    L = sla.cholesky(M, lower=True)
    Qt = sla.solve_triangular(L, sla.solve_triangular(L, K, lower=True).T, lower=True).T
    Pt = sla.solve_triangular(L, sla.solve_triangular(L, C, lower=True).T, lower=True).T
    g = np.sqrt(np.linalg.norm(Qt) / np.sqrt(n))
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Qt / g**2, -Pt / g]])
    return A, g, L


@pytest.mark.parametrize("symmetric", [True, False])
def test_pairs_match_scipy_eig_and_direct_measures(symmetric):
    n = 40
    M, C, K = _problem(n, symmetric)
    sol = solve_qep(M, C, K, solver="companion")
    A, g, _ = _reference_companion(M, C, K)
    mu = sla.eig(A, right=False)
    # reference 1: scipy.linalg.eig of the same companion matrix, same LAPACK driver: the
    # eigenvalues in the same order (to 1e-12 relative: our copy of A may round differently)
    np.testing.assert_allclose(sol.eigenvalues, g * mu, rtol=1e-12,
                               atol=1e-12 * np.abs(g * mu).max())
    s = sol.eigenvalues
    assert np.sum(s.imag > 0) == np.sum(s.imag < 0) > 0 and np.any((s.imag == 0) & (s.real > 0))
    assert sol.details["measured_columns"] == np.sum(s.imag >= 0) < s.size
    # partners are exact conjugates, vectors and left vectors alike
    for j in np.flatnonzero(s.imag < 0):
        assert s[j - 1] == np.conj(s[j])
        assert np.array_equal(sol.vectors[:, j], np.conj(sol.vectors[:, j - 1]))
        assert np.array_equal(sol.left_vectors[:, j], np.conj(sol.left_vectors[:, j - 1]))
    assert (sol.left_vectors is sol.vectors) == symmetric
    # reference 2: η and κ evaluated directly on every returned pair (measures' definitions);
    # the copied ones of a partner must equal them (1e-12 relative: rounding of two evaluations)
    norms = tuple(fro(X) for X in (M, C, K))
    eta, MX, PX = backward_errors((M, C, K), s, sol.vectors, norms)
    kap = conditions(s, sol.vectors, sol.left_vectors, MX, PX, norms)
    np.testing.assert_allclose(sol.backward_error, eta, rtol=1e-12, atol=1e-18)
    np.testing.assert_allclose(sol.condition, kap, rtol=1e-12)
    assert np.max(eta) < 1e-13  # backward stable: a few ε (Tisseur 2000, companion + scaling)


def test_undocumented_pair_layout_measures_every_column(monkeypatch):
    """Where geev's output did not follow its documented pair layout the path forms every
    column as scipy.linalg.eig does and measures all of them (no pair is assumed)."""
    M, C, K = _problem(12, True)
    real = sla.get_lapack_funcs

    def shuffled(names, arrays):
        geev, lwork = real(names, arrays)

        def bad_geev(A, **kw):
            wr, wi, vl, vr, info = geev(A, **kw)
            f = np.flatnonzero(wi > 0)[0]
            wr[f + 1] = np.nextafter(wr[f + 1], np.inf)  # pair no longer bitwise conjugate
            return wr, wi, vl, vr, info

        return bad_geev, lwork

    ref = solve_qep(M, C, K, solver="companion")
    monkeypatch.setattr(dense.sla, "get_lapack_funcs", shuffled)
    sol = solve_qep(M, C, K, solver="companion")
    assert sol.details["measured_columns"] == sol.eigenvalues.size == 24
    np.testing.assert_allclose(sol.eigenvalues, ref.eigenvalues, rtol=1e-14)
    assert np.max(sol.backward_error) < 1e-13
