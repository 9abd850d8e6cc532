"""The fused small-dense modes path (mbseig.modal.small, mbseig.eigen.small) against the general
path (``modes(..., fused=False)``) on the same matrices.

Reference: the general path itself (an independent implementation of the same mathematics:
dense driver, row-blocked measures, error_bounds, listing).  Tolerances, and why:

* eigenvalues: |Δs| ≤ 1e-12 |s| + 4 ε max|s|: both paths call the same LAPACK routine on the same
  matrix, so they agree to rounding (bitwise on the machine this was written on; the 4 ε max|s|
  term admits a different BLAS's rounding of an eigenvalue near 0);
* κ, ζ, ω_n: 1e-9 relative: formed by the same formulas; a different grouping of a sum
  (another BLAS) moves them by a few ulps, κ of a nearly defective pair amplifies that by at
  most its own size, far below the 1e-9;
* η, and the bounds formed from it: 1e-9 relative plus the rounding of the residual itself.
  η = ‖T(s)x‖/(w(s)‖x‖), w(s) = |s|²‖M‖_F + |s|‖P‖_F + ‖Q‖_F, is at rounding level (1e-16)
  for a backward-stable solver, and the computed T(s)x carries an error of up to
  γ_{n+2}(|s|²|M| + |s||P| + |Q|)|x| (Higham, Accuracy and Stability, §3.5: n products summed,
  two more additions), so each evaluation of η is off by up to γ_{n+2} = (n+2)ε/(1−(n+2)ε)
  absolutely and two evaluations differ by up to 2γ_{n+2} (the former 1e-9 relative alone
  failed under another OpenBLAS kernel: 8.43769e-17 against 8.43809e-17).  The error estimate
  κη and the tolerance (safety × it) carry that times κ (and the safety factor);
* kinds, stabilities, verdict, solver name and reason, multiplicities, accounting, dominant
  coordinates: identical (they are decisions; a decision flipped by rounding would be a bug).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import mbseig
from mbseig.eigen import EPS
from mbseig.eigen.small import SMALL_MAX
from mbseig.modal import modes

ROOT = Path(__file__).resolve().parents[1]
SHARED = Path(__file__).resolve().parents[2] / "shared" / "examples"
FUSED = "fused small-dense"


def _close(a, b, rtol, what, atol=0.0):
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape, what
    both_inf = np.isinf(a) & np.isinf(b) & (np.sign(a) == np.sign(b))
    with np.errstate(invalid="ignore"):  # ∞ − ∞: judged by both_inf
        ok = both_inf | (np.abs(a - b) <= rtol * np.abs(b) + atol)
    assert np.all(ok), f"{what}: {a[~ok]} against {b[~ok]}"


def assert_same(fused, general):
    """The fused listing equals the general one to the tolerances of the module docstring."""
    assert fused.solver == general.solver and fused.solver_reason == general.solver_reason
    s, g = fused.eigenvalues, general.eigenvalues
    assert s.shape == g.shape
    scale = float(np.max(np.abs(g), initial=0.0))
    assert np.all(np.abs(s - g) <= 1e-12 * np.abs(g) + 4 * EPS * scale), (s, g)
    _close(fused.all_eigenvalues, general.all_eigenvalues, 1e-12, "all eigenvalues")
    for name in ("condition", "zeta", "omega_n"):
        _close(getattr(fused, name), getattr(general, name), 1e-9, name)
    n = general.vectors.shape[0]
    eta_rounding = 2 * (n + 2) * EPS / (1 - (n + 2) * EPS)  # 2γ_{n+2}: module docstring
    kappa = np.where(np.isfinite(general.condition), general.condition, 0.0)
    safety = general.tolerances["safety"]
    for name, atol in (("backward_error", eta_rounding), ("error_estimate", kappa * eta_rounding),
                       ("tolerance", safety * kappa * eta_rounding)):
        _close(getattr(fused, name), getattr(general, name), 1e-9, name, atol)
    assert fused.kind == general.kind
    assert fused.stability == general.stability
    assert fused.verdict == general.verdict
    assert np.array_equal(fused.multiplicity, general.multiplicity)
    assert fused.accounting == general.accounting

    def names(md):
        return [[n for n, _ in d] for d in md.dominant]

    assert names(fused) == names(general)
    assert fused.flags == general.flags
    numeric = {k: v for k, v in fused.tolerances.items() if k != "implementation"}
    assert numeric.keys() == general.tolerances.keys()


def _both(M, P, Q, **kw):
    return modes(M, P, Q, **kw), modes(M, P, Q, fused=False, **kw)


def _bundled():
    paths = sorted((ROOT / "cases").glob("*.toml"))
    if SHARED.is_dir():
        paths += sorted(SHARED.glob("*.toml"))
    return paths


def test_bundled_cases_small_enough():
    """Every bundled case whose linearization is small and builds here: both paths agree, and
    the fused one really ran on most of them."""
    compared = fused_ran = 0
    for path in _bundled():
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                model = mbseig.load_case(path)
                lin = mbseig.linearize(model, mbseig.equilibrium(model))
        except Exception:  # noqa: BLE001 (periodic and steady-motion cases: other commands)
            continue
        if lin.M.shape[0] > SMALL_MAX:
            continue
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # statically unstable equilibria: their own tests
            a = modes(lin)
            b = modes(lin, fused=False)
        assert_same(a, b)
        compared += 1
        fused_ran += a.tolerances.get("implementation") == FUSED
    assert compared >= 15 and fused_ran >= 12, (compared, fused_ran)


def _spd(rng, n, spread=1.0):
    A = rng.standard_normal((n, n))
    d = 10.0 ** rng.uniform(0, spread, n)
    return A @ A.T / n + np.diag(d)


@pytest.mark.parametrize("n", [1, 2, 3, 6, 11, 32, 64])
def test_random_damped_and_gyroscopic(n):
    """General damping (companion) and gyroscopic P = D + G (G skew): both paths agree."""
    rng = np.random.default_rng(n)
    for _ in range(3):
        M, Q = _spd(rng, n), _spd(rng, n, 3)
        D = _spd(rng, n) * 0.05
        G = rng.standard_normal((n, n))
        for P in (D, D + (G - G.T), G - G.T):
            a, b = _both(M, P, Q)
            # (of order 1 every damping is Rayleigh damping: the proportional path)
            assert a.tolerances.get("implementation") == FUSED or a.solver == "proportional"
            assert_same(a, b)


def test_undamped_repeated_and_zero_frequencies():
    """eigh with double frequencies (clusters of conjugate pairs) and rigid-body modes."""
    n = 6
    rng = np.random.default_rng(7)
    V = np.linalg.qr(rng.standard_normal((n, n)))[0]
    M = _spd(rng, n)
    L = np.linalg.cholesky(M)
    w2 = np.array([0.0, 0.0, 4.0, 4.0, 25.0, 81.0])
    Q = L @ (V * w2) @ V.T @ L.T  # Q = M^½ V Λ Vᵀ M^½ᵀ: eigenvalues ±i√w2 of (M, Q)
    a, b = _both(M, np.zeros((n, n)), Q)
    assert a.solver == "eigh" and a.tolerances.get("implementation") == FUSED
    assert_same(a, b)
    assert a.kind.count("rigid-body") == 2


def test_diagonal_mass_and_badly_scaled():
    """Lumped (diagonal) M spread over 1e-6 … 1 and stiffness 1e6: both branches of both paths."""
    rng = np.random.default_rng(3)
    n = 5
    M = np.diag(10.0 ** rng.uniform(-6, 0, n))
    K = (np.diag(np.full(n, 2e6)) - np.diag(np.full(n - 1, 1e6), 1)
         - np.diag(np.full(n - 1, 1e6), -1))
    C = 1e-3 * K + np.diag(rng.uniform(0, 1e-3, n))
    for P in (np.zeros((n, n)), C):
        a, b = _both(M, P, K)
        assert_same(a, b)


def test_nonsymmetric_stiffness_left_vectors():
    """Follower load (Q not symmetric): left vectors formed; flutter classified alike."""
    M = np.diag([1.0, 2.0])
    P = np.array([[0.01, 0.0], [0.0, 0.02]])
    for f in (0.5, 2.0, 4.0):
        Q = np.array([[3.0 - f, f - 1.0], [-1.0, 1.0]])
        a, b = _both(M, P, Q)
        assert a.tolerances.get("left_vectors") and a.tolerances.get("implementation") == FUSED
        assert_same(a, b)


def test_defective_and_proportional_fall_back():
    """A critically damped oscillator (defective double root: the general path refines its
    vector) and Rayleigh damping (proportional path): the fused path hands over, same result."""
    a, b = _both(np.eye(1), 2.0 * np.eye(1), np.eye(1))
    assert "implementation" not in a.tolerances
    assert_same(a, b)
    M, Q = np.diag([1.0, 2.0]), np.array([[2.0, -1.0], [-1.0, 1.0]])
    a, b = _both(M, 0.1 * M + 0.01 * Q, Q)
    assert a.solver == "proportional" and "implementation" not in a.tolerances
    assert_same(a, b)


def test_options_and_refusals_take_the_general_path():
    """A request the fused path does not serve runs the general path unchanged."""
    M, P, Q = np.eye(2), 0.1 * np.array([[1.0, 0.2], [0.2, 1.0]]), np.diag([1.0, 3.0])
    forced = modes(M, P, Q, solver="qz")
    assert forced.solver == "qz" and "implementation" not in forced.tolerances
    with pytest.raises(mbseig.errors.SolverError):
        modes(M, P, np.full((2, 2), np.nan))
