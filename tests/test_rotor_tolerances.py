"""Tolerances of a spinning flexible rotor: the defective zero eigenvalues of its free spin must
not lend their bound to the whirl modes around them.

Case: cases/overhung_rotor_friswell.toml at Ω = 200 rad/s.  The shaft's free rotation about its
axis gives zero eigenvalues with Jordan blocks (κ ≈ 1e18 computed: their first-order bound κη is
meaningless, their true error the Hölder radius S·η^{1/k}).  Reference: an independent QZ
(scipy.linalg.eig) of the first companion form A − sB of the same reduced M, P, Q; every
eigenvalue of the upper half-plane is listed once, in the same place to within the two
computations' own bounds: the reference's first-order bound κη from its own left and right
vectors (η = ‖(A − sB)x‖/((‖A‖₂ + |s|‖B‖₂)‖x‖), κ = (‖A‖₂ + |s|‖B‖₂)‖x‖‖y‖/|yᴴBx|; the
unscaled pencil is the less accurate of the two, up to 9e-6 of |s| at the top whirl modes, and
how much of that it uses depends on the BLAS kernel: 1e-10 of |s| on one, 1.7e-6 on another)
plus mbseig's own error estimate of s.  Those bounds are below half the gaps between the modes,
so sorting pairs them rightly; and only the zero ones are rigid-body: the whirl modes at 83 and
97 rad/s are oscillatory with tolerances below 1e-6 of their |s|.
"""

import numpy as np
import scipy.linalg as sla

from conftest import CASES
from mbseig.studies import analyze


def _dense(A):
    return np.asarray(A.toarray() if hasattr(A, "toarray") else A, float)


def test_spinning_rotor_whirl_modes_are_not_rigid_body():
    a = analyze(CASES / "overhung_rotor_friswell.toml", params={"Omega": 200.0})
    M, P, Q = (_dense(x) for x in (a.linear.M, a.linear.P, a.linear.Q))
    n = M.shape[0]
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Q, -P]])
    B = np.block([[np.eye(n), np.zeros((n, n))], [np.zeros((n, n)), M]])
    ref, left, right = sla.eig(A, B, left=True, right=True)
    finite = np.isfinite(ref)
    ref, left, right = ref[finite], left[:, finite], right[:, finite]
    nA, nB = np.linalg.norm(A, 2), np.linalg.norm(B, 2)
    weight = nA + np.abs(ref) * nB
    xn, yn = np.linalg.norm(right, axis=0), np.linalg.norm(left, axis=0)
    eta = np.linalg.norm(A @ right - (B @ right) * ref, axis=0) / (weight * xn)
    kappa = weight * xn * yn / np.abs(np.einsum("ij,ij->j", left.conj(), B @ right))
    zero = np.abs(ref) < 1e-3  # the free spin's Jordan blocks (computed |s| ~ 1e-5)
    upper = ~zero & (ref.imag > 0)
    order = np.argsort(np.abs(ref[upper]))
    whirl, ref_bound = np.abs(ref[upper])[order], (kappa * eta)[upper][order]
    md = a.modes
    s = np.asarray(md.eigenvalues)
    kinds = list(md.kind)
    moving = np.array([k != "rigid-body" for k in kinds])
    assert np.all(np.abs(s[~moving]) < 1e-3)  # rigid-body only at the zeros
    order = np.argsort(np.abs(s[moving]))
    got, got_bound = np.abs(s[moving])[order], np.asarray(md.error_estimate)[moving][order]
    assert got.size == whirl.size  # each whirl mode listed once
    bound = ref_bound + got_bound
    gaps = np.diff(whirl)
    assert np.all(bound[:-1] < gaps / 2) and np.all(bound[1:] < gaps / 2)  # pairs by sorting
    assert np.all(np.abs(got - whirl) <= bound)
    for target in (83.4036, 96.8359):  # the disk's backward and forward whirl
        k = int(np.argmin(np.abs(np.abs(s) - target)))
        assert kinds[k] == "oscillatory"
        assert md.tolerance[k] < 1e-6 * abs(s[k])
