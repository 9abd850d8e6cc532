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


def _cantilever(n, rotation_unit):
    """Euler–Bernoulli FE cantilever (steel, 20 × 30 mm, 1 m, n elements; translation and
    rotation a node, clamped at one end) with rotations in ``rotation_unit`` radians: the
    pencil D K D, D M D, D = diag(1, unit, …), congruent to the one in radians."""
    E, rho, b, h, L = 2.1e11, 7850.0, 0.02, 0.03, 1.0
    A, inertia, le = b * h, h * b**3 / 12, L / n
    k = E * inertia / le**3 * np.array([[12, 6 * le, -12, 6 * le],
                                        [6 * le, 4 * le**2, -6 * le, 2 * le**2],
                                        [-12, -6 * le, 12, -6 * le],
                                        [6 * le, 2 * le**2, -6 * le, 4 * le**2]])
    m = rho * A * le / 420 * np.array([[156, 22 * le, 54, -13 * le],
                                       [22 * le, 4 * le**2, 13 * le, -3 * le**2],
                                       [54, 13 * le, 156, -22 * le],
                                       [-13 * le, -3 * le**2, -22 * le, 4 * le**2]])
    dofs = 2 * np.arange(n)[:, None] + np.arange(4)[None, :]
    rows, cols = np.repeat(dofs, 4, axis=1).ravel(), np.tile(dofs, (1, 4)).ravel()
    size = 2 * (n + 1)
    K = sp.csr_matrix((np.tile(k.ravel(), n), (rows, cols)), shape=(size, size))[2:, 2:]
    M = sp.csr_matrix((np.tile(m.ravel(), n), (rows, cols)), shape=(size, size))[2:, 2:]
    D = sp.diags(np.tile([1.0, rotation_unit], n))
    return (D @ M @ D).tocsr(), (D @ K @ D).tocsr()


def test_a_shift_is_judged_in_no_particular_units():
    """The same cantilever with its rotations in radians and in milliradians: ‖Q‖ ‖Q⁻¹‖ differs
    by about 10⁶ between the two, the scaled condition that decides the shift does not, so σ = 0
    is kept in both (it was moved to −5e11 in milliradians, 5e7 times the lowest ω², and
    Lanczos crawled there; at 600 elements it stopped without converging).  The two pencils are
    congruent, so their eigenvalues are equal: each lowest ω within the two solutions' own
    error estimates."""
    got = []
    for unit in (1.0, 1e-3):
        M, Q = _cantilever(200, unit)
        md = mbseig.modes(M, None, Q, n_modes=3)
        assert [float(s) for s in md.tolerances["shifts"]] == [0.0]
        order = np.argsort(md.omega_n)
        got.append((md.omega_n[order], md.error_estimate[order]))
    (w1, e1), (w2, e2) = got
    assert np.all(np.abs(w1 - w2) <= e1 + e2)
