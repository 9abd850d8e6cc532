"""Shift-invert at σ = 0 on a matrix that is ill-conditioned in norm but has no eigenvalue near
0 (mbseig.eigen.shift_invert.SHIFT_COND): the shift must stay at 0.

A fine 3-D beam mesh has cond(Q) ≈ 1e12 at σ = 0 while its lowest eigenvalue is far from 0;
moving the shift there by a fraction of ‖Q‖/‖M‖ put it 1e5 lowest eigenvalues below the
spectrum, and Lanczos stalled (9,000 solves on 18,000 DOF, benchmarks/beam3d_large.py).  The
same failure in miniature: Q = diag(k), M = I, k = 1 … 6 then log-spaced to 1e13 (cond 1e13):
the eigenvalues are k exactly (closed form), and a backward-stable LU of a diagonal matrix is
exact, so the six lowest ω² must equal 1 … 6 to rounding: ARPACK converges (tol 0) to ε of
the largest θ = 1/(λ − σ) = 1, a relative ε λ_k/λ_1 ≤ 6ε on λ_k; rtol 1e-14 (≈ 45 ε) allows
for that and the square root and square of ω_n.  With the old threshold (1/(1e4 ε)) ARPACK
did not converge at all here."""

import numpy as np
import scipy.sparse as sp

import mbseig


def test_ill_conditioned_but_regular_shift_is_kept():
    n = 400
    k = np.r_[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, np.logspace(1, 13, n - 6)]
    M, Q = sp.identity(n, format="csr"), sp.diags(k, format="csr")
    md = mbseig.modes(M, sp.csr_matrix((n, n)), Q, n_modes=6, solver="partial-eigh")
    np.testing.assert_allclose(np.sort(md.omega_n) ** 2, k[:6], rtol=1e-14, atol=0)
    assert md.verdict == "critical"  # P = 0: every mode undamped, δ = 0
