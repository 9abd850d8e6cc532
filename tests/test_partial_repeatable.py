"""The partial (ARPACK) paths start from a fixed vector: the same pencil gives the same
eigenvalues and vectors, in the same order, on every call (mbseig.eigen.shift_invert.arpack)."""

import numpy as np
import scipy.sparse as sp

import mbseig


def _grid(n):
    """Stiffness of an n × n grid of unit masses on unit springs: every eigenvalue off the
    diagonal of the grid's symmetry is double (a degenerate pair, x ↔ y)."""
    L = sp.diags([-np.ones(n - 1), 2 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1])
    eye = sp.identity(n)
    return (sp.kron(L, eye) + sp.kron(eye, L)).tocsr()


def test_two_calls_give_the_same_modes_bitwise():
    K = _grid(40)  # 1,600 DOF: above the dense path's reach for n_modes
    M = sp.identity(K.shape[0], format="csr")
    a = mbseig.modes(M, None, K, n_modes=6)
    b = mbseig.modes(M, None, K, n_modes=6)
    assert a.solver.startswith("partial")
    assert np.array_equal(a.eigenvalues, b.eigenvalues)
    assert np.array_equal(a.vectors, b.vectors)
