"""Tolerances of a spinning flexible rotor: the defective zero eigenvalues of its free spin must
not lend their bound to the whirl modes around them.

Case: cases/overhung_rotor_friswell.toml at Ω = 200 rad/s.  The shaft's free rotation about its
axis gives zero eigenvalues with Jordan blocks (κ ≈ 1e18 computed: their first-order bound κη is
meaningless, their true error the Hölder radius S·η^{1/k}).  Reference: an independent QZ
(scipy.linalg.eig) of the first companion form of the same reduced M, P, Q; every eigenvalue of
the upper half-plane is listed once, in the same place to 1e-7 relative (the unscaled reference
is the less accurate of the two: its backward errors reach 9e-14 and κ 3e5 by its own left and
right vectors, so it is good to ≈ 3e-8; the modes are ≥ 1e-2 apart, so no mismatch hides in
1e-7), and only the zero ones are rigid-body: the whirl modes at 83 and 97 rad/s are
oscillatory with tolerances below 1e-6 of their |s|.
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
    ref = sla.eig(A, B, right=False)
    ref = ref[np.isfinite(ref)]
    zero = np.abs(ref) < 1e-3  # the free spin's Jordan blocks (computed |s| ~ 1e-5)
    whirl = np.sort(np.abs(ref[~zero & (ref.imag > 0)]))
    md = a.modes
    s = np.asarray(md.eigenvalues)
    kinds = list(md.kind)
    moving = np.array([k != "rigid-body" for k in kinds])
    assert np.all(np.abs(s[~moving]) < 1e-3)  # rigid-body only at the zeros
    got = np.sort(np.abs(s[moving]))
    assert got.size == whirl.size  # each whirl mode listed once
    np.testing.assert_allclose(got, whirl, rtol=1e-7)
    for target in (83.4036, 96.8359):  # the disk's backward and forward whirl
        k = int(np.argmin(np.abs(np.abs(s) - target)))
        assert kinds[k] == "oscillatory"
        assert md.tolerance[k] < 1e-6 * abs(s[k])
