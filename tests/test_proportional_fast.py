"""The eigh and proportional dense paths form η and κ from the real residual of the undamped
pair (mbseig.eigen.undamped, "Undamped and proportional pairs"): the values they report must be
what the definitions give on the returned pairs.

References, each an independent evaluation in this file or another solver path:
- η: :func:`mbseig.eigen.measures.backward_errors`, the definition evaluated on the complex
  residual (s²M + sP + Q)x of each returned pair.  The reported η is a bound: it may not be
  smaller than the direct one by more than the rounding of either evaluation (16 ε), nor larger
  by more than that plus ‖E‖_F/‖P‖ (the fit deviation E = P − αM − βQ enters as ‖E‖_F).
- κ: :func:`mbseig.eigen.measures.conditions` with y = x on the same pairs; the reported κ may
  only exceed it, by at most the relative size of ‖E‖_F in its denominator (1e-9 here).
- eigenvalues: the companion path (LAPACK geev on the 2n companion) on the same matrices,
  matched within 10 κη + 1e-13 |s| per eigenvalue (first-order error bound of both sides).
"""

import numpy as np
import pytest

from mbseig.eigen import measures, solve_qep

EPS = np.finfo(float).eps


def _chain(n, damped=True, k=1000.0, c=0.5):
    K = 2 * k * np.eye(n) - k * (np.eye(n, k=1) + np.eye(n, k=-1))
    M = np.diag(1.0 + 0.5 * np.sin(np.arange(n)))
    return M, ((c / k) * K if damped else np.zeros((n, n))), K


def _dense(n, seed):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    B = rng.standard_normal((n, n))
    return B @ B.T / n + np.eye(n), A @ A.T + n * np.eye(n)


def _problems():
    M, _, K = _chain(60)
    yield "chain undamped", M, np.zeros_like(M), K
    yield "chain C = βK", *_chain(60)
    Md, Kd = _dense(40, 1)
    yield "dense eigh", Md, np.zeros_like(Md), Kd
    yield "dense light", Md, 0.3 * Md + 2e-3 * Kd, Kd
    yield "dense overdamped", Md, 5.0 * Md + 0.5 * Kd, Kd  # real root pairs
    Kneg = Kd - 60.0 * Md  # a few negative ω²: divergence pairs
    yield "dense divergence", Md, np.zeros_like(Md), Kneg
    rng = np.random.default_rng(7)  # a fit that is not exact: ‖E‖ ≈ 3e-13 ‖P‖ (tol 1e-12)
    P = 0.3 * Md + 2e-1 * Kd
    E = rng.standard_normal(P.shape)
    E = E + E.T
    yield "dense inexact fit", Md, P + 3e-13 * np.linalg.norm(P) / np.linalg.norm(E) * E, Kd


@pytest.mark.parametrize("name, M, P, Q", list(_problems()), ids=[p[0] for p in _problems()])
def test_structured_measures_are_the_definitions(name, M, P, Q):
    sol = solve_qep(M, P, Q)
    assert sol.solver == ("eigh" if not np.any(P) else "proportional")
    s, X = sol.eigenvalues, sol.vectors
    norms = sol.norms
    eta_d, MX, PX = measures.backward_errors((M, P, Q), s, X, norms)
    kappa_d = measures.conditions(s, X, X, MX, PX, norms)
    fit = sol.details["fit_residual"]
    a, b = sol.details["alpha"], sol.details["beta"]
    assert fit == pytest.approx(np.linalg.norm(P - a * M - b * Q), abs=4 * EPS * norms[1])
    fit_rel = fit / norms[1] if norms[1] else 0.0
    assert np.all(sol.backward_error >= eta_d - 16 * EPS)
    assert np.all(sol.backward_error <= eta_d + 16 * EPS + fit_rel)
    assert np.all(sol.condition >= kappa_d * (1 - 1e-12))
    assert np.all(sol.condition <= kappa_d * (1 + 1e-9))
    ref = solve_qep(M, P, Q, solver="companion").eigenvalues
    for sk, kk, ek in zip(s, sol.condition, sol.backward_error, strict=True):
        assert np.min(np.abs(ref - sk)) <= 10 * kk * max(ek, EPS) + 1e-13 * abs(sk)


def test_inexact_fit_shows_in_eta():
    """With ‖E‖ = 3e-13 ‖P‖ the direct η of the damped pairs is far above ε: a bound that
    left E out would fall below it (the first assertion of the test above catches that)."""
    *_, (_, M, P, Q) = list(_problems())
    sol = solve_qep(M, P, Q)
    eta_d = measures.backward_errors((M, P, Q), sol.eigenvalues, sol.vectors, sol.norms)[0]
    assert eta_d.max() > 50 * EPS  # measured ≈ 100 ε; without E the bound would be ≈ ε


def test_rayleigh_fit_residual_is_the_entrywise_norm():
    M, K = _dense(30, 3)
    for P in (0.3 * M + 2e-3 * K, 0.3 * M + 2e-3 * K + 1e-14 * np.eye(30)[::-1], 0.3 * M):
        a, b, r = measures.rayleigh_fit(M, P, K, 1e-12, residual=True)
        assert r == pytest.approx(np.linalg.norm(P - a * M - b * K),
                                  abs=4 * EPS * np.linalg.norm(P))
        assert measures.rayleigh_fit(M, P, K, 1e-12) == (a, b)
    assert measures.rayleigh_fit(M, np.zeros_like(M), K, 1e-12, residual=True) == (0.0, 0.0, 0.0)
    assert measures.rayleigh_fit(M, np.eye(30)[::-1] + 0.0, K, 1e-12, residual=True) is None
