"""The SLEPc section of ``mbseig bench`` (mbseig.bench.slepc_rows): the reduced problem SLEPc is
given is the constrained model's, and the goal rows apply the issue's thresholds (no timing is
asserted here)."""

import numpy as np
import scipy.linalg as sla
from scipy.optimize import linear_sum_assignment

from mbseig.bench.slepc_rows import reduced, slepc_targets
from mbseig.bench.sparse_rows import large_chain


def _qep_eigenvalues(M, P, Q):
    """All eigenvalues of (M s² + P s + Q) x = 0 from the first companion pencil (dense QZ)."""
    n = M.shape[0]
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Q, -P]])
    B = np.block([[np.eye(n), np.zeros((n, n))], [np.zeros((n, n)), M]])
    return np.sort_complex(sla.eigvals(A, B))


def test_reduced_problem_is_the_constrained_one():
    """Reference: the same chain projected on an independent orthonormal null basis of its link
    rows (scipy.linalg.null_space, SVD); the eigenvalues agree to 1e-9 of the largest |s| (QZ on two
    bases of one subspace, |s| ≤ 70 here: rounding of a 54-DOF problem)."""
    M, C, K, G = large_chain(60)
    Mr, Pr, Qr = (A.toarray() for A in reduced(M, C, K, G))
    N = sla.null_space(G.toarray())
    assert Mr.shape[0] == N.shape[1] == 60 - G.shape[0]
    ref = _qep_eigenvalues(*(N.T @ A.toarray() @ N for A in (M, C, K)))
    got = _qep_eigenvalues(Mr, Pr, Qr)
    # one-to-one matching (a conjugate pair's order under sorting is rounding's choice)
    rows, cols = linear_sum_assignment(np.abs(got[:, None] - ref[None, :]))
    assert np.max(np.abs(got[rows] - ref[cols])) <= 1e-9 * np.abs(ref).max()


def test_goal_rows_apply_the_thresholds():
    """≤ 2× SLEPc's time and ≤ 1.5× its memory for mbseig; ≤ 1.2× for partial-slepc against
    SLEPc on the same pencil; a row without a reference gives no target."""
    rows = [{"method": "mbseig", "model": "constrained", "n": 10**5, "time": 2.0, "ratio": 1.9,
             "mem_ratio": 1.4},
            {"method": "mbseig", "model": "unconstrained", "n": 10**5, "time": 2.0, "ratio": 1.9,
             "mem_ratio": 1.6},
            {"method": "pslepc", "model": "constrained", "n": 10**5, "time": 4.0, "ratio": 1.25,
             "mem_ratio": 1.0},
            {"method": "slepc", "model": "constrained", "n": 10**5, "time": 1.0}]
    met = [t[3] for t in slepc_targets(rows)]
    assert met == [True, False, False]
