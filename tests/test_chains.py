"""Spring-mass chains against closed forms up to n = 1000, on every dense solver path.

References (closed form, tridiagonal Toeplitz eigenvalues):
  fixed-fixed  ω_j = 2√(k/m) sin(jπ/(2(n+1))), j = 1..n
  free-free    ω_j = 2√(k/m) sin(jπ/(2n)),     j = 0..n−1 (j = 0: the rigid-body mode)
  damped       s_j = −(c/2k) ω_j² ± iω_j √(1 − (cω_j/2k)²)   (C = (c/k) K)
Tolerance 1e-10 relative (the issue's requirement); the rigid-body mode, whose computed |s| is a
rounding residue of order √ε·ω_max, is checked by kind and by |s| ≤ its own recorded tolerance.
"""

import numpy as np
import pytest
from conftest import CASES

import mbseig
from mbseig.studies import analyze

K, M_, C = 1000.0, 1.0, 0.5


def omega_fixed(n):
    j = np.arange(1, n + 1)
    return 2 * np.sqrt(K / M_) * np.sin(j * np.pi / (2 * (n + 1)))


def s_damped(n):
    w = omega_fixed(n)
    return -(C / (2 * K)) * w**2 + 1j * w * np.sqrt(1 - (C * w / (2 * K)) ** 2)


@pytest.mark.parametrize("n", [10, 100, 1000])
def test_fixed_fixed(n):
    a = analyze(CASES / "chain_fixed_fixed.toml", params={"n": n})
    assert a.modes.solver == "eigh" and len(a.modes) == n
    np.testing.assert_allclose(a.modes.omega_n, omega_fixed(n), rtol=1e-10)
    assert a.modes.verdict == "critical" and set(a.modes.kind) == {"oscillatory"}


@pytest.mark.parametrize("n", [10, 100, 1000])
def test_damped(n):
    a = analyze(CASES / "chain_damped.toml", params={"n": n})
    assert a.modes.solver == "proportional"
    np.testing.assert_allclose(a.modes.eigenvalues, s_damped(n), rtol=1e-10)
    assert a.modes.verdict == "stable"


@pytest.mark.parametrize("n", [10, 100, 1000])
def test_free_free(n):
    a = analyze(CASES / "chain_free_free.toml", params={"n": n})
    md = a.modes
    assert md.kind.count("rigid-body") == 1 and md.kind[0] == "rigid-body"
    assert md.omega_n[0] <= md.tolerance[0]
    j = np.arange(1, n)
    np.testing.assert_allclose(md.omega_n[1:], 2 * np.sqrt(K / M_) * np.sin(j * np.pi / (2 * n)),
                               rtol=1e-10)
    assert len(md) == n


@pytest.mark.parametrize("solver", ["companion", "qz"])
def test_damped_general_paths(solver):
    """The general paths on the damped chain (n = 200) against the same closed form."""
    n = 200
    a = analyze(CASES / "chain_damped.toml", params={"n": n}, solver=solver)
    assert a.modes.solver == solver and len(a.modes) == n
    np.testing.assert_allclose(a.modes.eigenvalues, s_damped(n), rtol=1e-10)
    assert a.modes.verdict == "stable"
    assert np.all(a.modes.backward_error <= 1e-12)


@pytest.mark.parametrize("solver", ["eigh", "proportional", "companion", "qz"])
def test_every_path_on_undamped_chain(solver):
    """Undamped chain (n = 60): every path gives the closed form and calls every mode critical
    (the general paths see rounding-level real parts, judged by the error-aware tolerance)."""
    n = 60
    a = analyze(CASES / "chain_fixed_fixed.toml", params={"n": n}, solver=solver)
    np.testing.assert_allclose(a.modes.omega_n, omega_fixed(n), rtol=1e-10)
    assert a.modes.stability == ["critical"] * n, a.modes.delta


def test_free_free_general_path_lists_rigid_mode_once():
    """The companion path sees the defective double zero split by ~√ε; still one rigid mode."""
    a = analyze(CASES / "chain_free_free.toml", params={"n": 40}, solver="companion")
    assert a.modes.kind.count("rigid-body") == 1 and len(a.modes) == 40


def test_state_space_conversion():
    """python-control StateSpace poles equal the QEP eigenvalues (independent: state matrix eig)."""
    a = analyze(CASES / "chain_damped.toml", params={"n": 5})
    sys = a.linear.to_statespace()
    poles = np.sort_complex(sys.poles())
    s = a.modes.eigenvalues
    full = np.sort_complex(np.concatenate([s, s.conj()]))
    np.testing.assert_allclose(poles, full, rtol=1e-10)


def test_gyroscopic_linear_case_solver_and_verdict():
    a = analyze(CASES / "rotating_mass.toml")
    assert a.modes.solver == "companion"  # P is skew: never through a symmetric solver
    assert a.modes.verdict == "critical"
    # a solver that ignores P sees Q = (ω0² − Ω²) I < 0: a divergence (wrong verdict)
    naive = mbseig.modes(a.linear.M, 0 * a.linear.P, a.linear.Q)
    assert naive.verdict == "unstable"
