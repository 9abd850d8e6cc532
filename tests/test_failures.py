"""Stability where methods fail: each case names the naive method that gets the verdict wrong
(for the badly scaled chain: the damping, off by more than δ, so that its verdict's sign is
rounding's and differs between BLAS kernels) and checks mbseig's answer against the reference
stated in mbseig/failcases.py (closed forms: pendulum ω = √(g/l); Ziegler's flutter load
F_cr = (7/2 − √2) c/l; chain ω_j; static condensation of a massless point; the dissipation
theorem for M, K, C positive definite).
"""

import numpy as np
import pytest

import mbseig
from mbseig.bench import failcases as fc


@pytest.mark.parametrize("case", fc.ALL, ids=lambda f: f.__name__)
def test_naive_wrong_mbseig_right(case):
    c = case()
    assert c.naive_wrong, (f"{c.name}: the naive method ({c.naive_method}) was expected to fail: "
                           f"{c.naive}")
    assert c.mbseig_right, f"{c.name}: mbseig answered {c.mbseig}; reference: {c.reference}"


def test_ziegler_flutter_load_bracketed():
    """mbseig's verdict changes from critical to flutter between 0.999 and 1.001 F_cr."""
    lo = mbseig.modes(*fc.ziegler_matrices(0.999 * fc.ZIEGLER_CRITICAL))
    hi = mbseig.modes(*fc.ziegler_matrices(1.001 * fc.ZIEGLER_CRITICAL))
    assert lo.verdict == "critical" and set(lo.kind) == {"oscillatory"}
    assert hi.verdict == "unstable" and "flutter" in hi.kind
    # Q is not symmetric: the automatic path never used a symmetric solver
    assert hi.solver in ("companion", "qz")


def test_large_undamped_critical_with_recorded_tolerance():
    """Every mode of an undamped chain (general companion path) is critical; each |δ| is within
    the tolerance recorded for it, and the tolerance is tiny against ω (≤ 1e-9 ω_n)."""
    n = 160  # (the failcase itself, n = 120, runs in test_naive_wrong_mbseig_right)
    K = 2000.0 * np.eye(n) - 1000.0 * (np.eye(n, k=1) + np.eye(n, k=-1))  # closed form below
    md = mbseig.modes(np.eye(n), np.zeros((n, n)), K, solver="companion")
    assert np.all(np.abs(md.delta) <= md.tolerance)
    assert np.all(md.tolerance <= 1e-9 * md.omega_n)
    j = np.arange(1, n + 1)
    np.testing.assert_allclose(md.omega_n, 2 * np.sqrt(1000.0) * np.sin(j * np.pi / (2 * (n + 1))),
                               rtol=1e-10)


def test_defective_double_root_listed_twice():
    """Critical damping s² + 2s + 1: s = −1 twice, both listed as overdamped, none spurious."""
    md = mbseig.modes(np.eye(1), 2 * np.eye(1), np.eye(1))
    assert len(md) == 2 and md.kind == ["overdamped", "overdamped"]
    np.testing.assert_allclose(md.eigenvalues.real, -1.0, atol=1e-7)
    assert np.all(md.eigenvalues.imag >= 0)


def test_singular_mass_no_spurious_modes():
    """Massless middle point: 2 finite modes ω² = k/m, 2k/m (static condensation), the two
    infinite eigenvalues dropped and counted."""
    M = np.diag([1.0, 0.0, 1.0])
    K = np.array([[2.0, -1, 0], [-1, 2, -1], [0, -1, 2]])
    md = mbseig.modes(M, np.zeros((3, 3)), K)
    assert md.n_infinite == 2 and len(md) == 2
    np.testing.assert_allclose(md.omega_n, [1.0, np.sqrt(2.0)], rtol=1e-10)
