"""The ``partial-projected`` path (mbseig.eigen.projected): lowest modes of constrained models
with general (non-proportional) damping from the undamped modes, refined, with a count
certificate of completeness.

References: the dense general path of mbseig (``solve_qep`` on the null-space reduced matrices:
every eigenvalue by LAPACK, then the same subset), ``partial-companion`` (ARPACK Arnoldi on the
companion pencil: independent code), and closed forms where the model is decoupled.
Tolerance of eigenvalue agreement: rtol 1e-9 (each path's first-order error bound
κ·max(η, ε)/|s| is below 3e-10 on these models, so their sum is below the tolerance; asserted
where the comparison is made).
"""

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

import mbseig
from mbseig.eigen import solve_partial, solve_qep
from mbseig.errors import SolverError


def linked_chain(n, every=10, k=1000.0, c_ground=0.5, beta=2e-4):
    """Fixed-fixed chain, masses 1 + 0.5 sin i, every ``every``-th spring a rigid link
    (constraint rows x_{i+1} − x_i = 0), grounded dashpots on every 7th mass plus βK
    (non-proportional, symmetric positive semidefinite)."""
    i = np.arange(n)
    K = sp.diags([2 * k * np.ones(n), -k * np.ones(n - 1), -k * np.ones(n - 1)], [0, 1, -1],
                 format="csr")
    cd = np.zeros(n)
    cd[::7] = c_ground
    C = (sp.diags(cd) + beta * K).tocsr()
    M = sp.diags(1 + 0.5 * np.sin(i), format="csr")
    a = np.arange(every - 1, n - 1, every)
    r = np.arange(a.size)
    G = sp.csr_matrix((np.r_[-np.ones(a.size), np.ones(a.size)], (np.r_[r, r], np.r_[a, a + 1])),
                      shape=(a.size, n))
    return M, C, K, G


def dense_lowest(M, C, K, G, count):
    """The ``count`` eigenvalues of smallest |s| (conjugates both listed) of the dense general
    path on the null-space reduced problem, their first-order bounds κ·max(η, ε), the path, and
    every eigenvalue (for the certificate's count)."""
    N = sla.null_space(G.toarray()) if G is not None else np.eye(M.shape[0])
    red = [N.T @ A.toarray() @ N for A in (M, C, K)]
    d = solve_qep(*red)
    order = np.argsort(np.abs(d.eigenvalues), kind="stable")[:count]
    bound = d.condition[order] * np.maximum(d.backward_error[order], np.finfo(float).eps)
    return d.eigenvalues[order], bound, d.solver, d.eigenvalues


def assert_same_set(got, ref, rtol):
    """Every eigenvalue of ``got`` has a partner in ``ref`` within rtol·|s| (one to one)."""
    ref = list(ref)
    for z in got:
        j = int(np.argmin([abs(z - r) for r in ref]))
        assert abs(z - ref[j]) <= rtol * abs(z), (z, ref[j])
        ref.pop(j)


def test_projected_agrees_with_dense_and_companion():
    """20 lowest modes of a linked chain (n = 200, 19 rigid links, non-proportional damping):
    the projected path's 40 eigenvalues equal the dense general path's and partial-companion's
    (rtol 1e-9), η ≤ 1e-12 (verify_tol 1e-8), and the count certificate holds.  (n = 200: the
    dense reference's QZ on n = 400 cost 10 s a pass of the suite, and the path's claims do
    not depend on the size.)"""
    M, C, K, G = linked_chain(200)
    sol = solve_partial(M, C, K, G=G, n_modes=20, solver="partial-projected")
    assert sol.solver == "partial-projected" and sol.eigenvalues.size == 40
    assert np.all(sol.backward_error <= 1e-12)
    assert sol.coverage["verified"] and "every eigenvalue with |s| ≤" in sol.coverage["note"]
    cert = sol.details["projected"]["certificate"]
    assert cert["n_projected"] == cert["n_inside"] >= 40 and cert["tau"] < cert["sigma_min"]
    ref, bound, path, spectrum = dense_lowest(M, C, K, G, 40)
    assert path not in ("eigh", "proportional")  # the general dense path
    assert np.all(bound <= 3e-10 * np.abs(ref))
    mine = sol.condition * np.maximum(sol.backward_error, np.finfo(float).eps)
    assert np.all(mine <= 3e-10 * np.abs(sol.eigenvalues))
    assert_same_set(sol.eigenvalues, ref, 1e-9)
    # the certificate's count is the true count: the dense spectrum has exactly that many
    # eigenvalues in |s| < R
    assert np.sum(np.abs(spectrum) < cert["R"]) == cert["n_projected"]
    comp = solve_partial(M, C, K, G=G, n_modes=20, solver="partial-companion")
    assert_same_set(sol.eigenvalues, comp.eigenvalues, 1e-9)
    # the multipliers are part of the checked pair: η is on the bordered problem
    assert sol.details["n_constraint_rows"] == 19


def test_auto_takes_projected_for_lowest_modes_through_modes():
    """``mbseig.modes`` with constraints and n_modes (auto): the projected path, verified,
    the same 6 lowest modes as the dense path (rtol 1e-9) and the same verdict (stable: every
    mode damped)."""
    M, C, K, G = linked_chain(300)
    md = mbseig.modes(M, C, K, n_modes=6, constraints=G)
    assert md.solver == "partial-projected" and "count certificate" in md.solver_reason
    ref, _, _, _ = dense_lowest(M, C, K, G, 12)
    assert_same_set(md.eigenvalues, ref, 1e-9)
    assert md.verdict == "stable"


def _with_extra(k_e, c_e, n=120):
    """The chain (lightly damped) plus one decoupled grounded coordinate of unit mass with
    spring k_e and dashpot c_e: its roots solve s² + c_e s + k_e = 0 (closed form)."""
    M, C, K, G = linked_chain(n, c_ground=0.05)
    M = sp.block_diag([M, sp.identity(1)], format="csr")
    C = sp.block_diag([C, sp.csr_matrix([[c_e]])], format="csr")
    K = sp.block_diag([K, sp.csr_matrix([[k_e]])], format="csr")
    G = sp.hstack([G, sp.csr_matrix((G.shape[0], 1))], format="csr")
    return M, C, K, G


def _with_overdamped_mode(k_h=1e6, c_h=1e7):
    """A stiff spring k_h with a strong dashpot c_h: undamped ω = 1000 rad/s (far above the
    chain's lowest modes), but the slow root s = −2k_h / (c_h + √(c_h² − 4k_h)) ≈ −0.1 is the
    lowest of all by |s| (closed form, written without cancellation)."""
    slow = -2 * k_h / (c_h + np.sqrt(c_h * c_h - 4 * k_h))
    return (*_with_extra(k_h, c_h), slow)


def test_certificate_fails_on_overdamped_high_mode_and_auto_falls_back():
    """A heavily damped high mode gives a slow real eigenvalue that no low undamped mode
    approximates: the projected path misses it and must say *not verified* (ρ·R ≥ 1: the bound
    on the high modes fails); ``auto`` then runs partial-companion, which finds it (closed form,
    rtol 1e-9), and records why."""
    M, C, K, G, slow = _with_overdamped_mode()
    sol = solve_partial(M, C, K, G=G, n_modes=5, solver="partial-projected")
    assert not sol.coverage["verified"]
    assert "not verified" in sol.coverage["note"] and "Rρ" in sol.coverage["note"]
    assert np.min(np.abs(sol.eigenvalues - slow)) > 1e-3 * abs(slow)  # missed, and said so
    assert len(sol.details["projected"]["attempts"]) == 2  # k_u was doubled once first
    auto = solve_partial(M, C, K, G=G, n_modes=5)
    assert auto.solver == "partial-companion" and auto.coverage["verified"]
    assert "partial-projected tried first" in auto.reason
    assert "Rρ" in auto.details["projected_fallback"]
    assert np.min(np.abs(auto.eigenvalues - slow)) <= 1e-9 * abs(slow)


def test_repeated_eigenvalues_taken_whole_and_certified():
    """Two identical linked chains side by side: every eigenvalue is double.  n_modes = 3 takes
    the double third mode whole (4 modes, 8 eigenvalues, said in the note); the values equal the
    dense path's (rtol 1e-9, each twice) and the count certificate holds (it counts
    multiplicities)."""
    M1, C1, K1, G1 = linked_chain(150)
    M, C, K, G = (sp.block_diag([A, A], format="csr") for A in (M1, C1, K1, G1))
    sol = solve_partial(M, C, K, G=G, n_modes=3, solver="partial-projected")
    assert sol.eigenvalues.size == 8 and "repeated" in sol.coverage["note"]
    assert sol.coverage["verified"]
    ref, _, _, spectrum = dense_lowest(M, C, K, G, 8)
    assert_same_set(sol.eigenvalues, ref, 1e-9)
    cert = sol.details["projected"]["certificate"]
    assert np.sum(np.abs(spectrum) < cert["R"]) == cert["n_projected"]
    # the two members of each double value have independent vectors
    s = sol.eigenvalues
    i = np.argsort(np.abs(s - s[0]))[:2]
    X = sol.vectors[:, i]
    assert np.linalg.svd(X, compute_uv=False)[-1] > 1e-3


def test_hypotheses_said_when_they_fail():
    """A non-symmetric P (a skew gyroscopic part): the certificate's numerical-range bound does
    not apply, the result says so (not verified, "P is not symmetric") while every pair still
    meets η ≤ 1e-12; ``auto`` does not take the projected path for it (partial-companion).  A
    band or a target is refused with one line."""
    M, C, K, G = linked_chain(200)
    n = M.shape[0]
    Gy = sp.diags([0.3 * np.ones(n - 1), -0.3 * np.ones(n - 1)], [1, -1], format="csr")
    sol = solve_partial(M, C + Gy, K, G=G, n_modes=4, solver="partial-projected")
    assert not sol.coverage["verified"] and "P is not symmetric" in sol.coverage["note"]
    assert np.all(sol.backward_error <= 1e-12)
    ref = solve_partial(M, C + Gy, K, G=G, n_modes=4, solver="partial-companion")
    assert_same_set(sol.eigenvalues, ref.eigenvalues, 1e-9)
    assert solve_partial(M, C + Gy, K, G=G, n_modes=4).solver == "partial-companion"
    with pytest.raises(SolverError, match="computes the lowest modes"):
        solve_partial(M, C, K, G=G, n_modes=4, target=5.0, solver="partial-projected")


def test_indefinite_stiffness_not_certified():
    """Q indefinite on the constraints (a decoupled coordinate with a negative spring −0.25 and
    no damping: s = ±0.5, closed form, a divergence among the lowest modes): Q is not shown
    positive definite, the projected coverage is not verified and says why; auto falls back to
    partial-companion, which finds s = +0.5 (rtol 1e-9)."""
    M, C, K, G = _with_extra(-0.25, 0.0)
    sol = solve_partial(M, C, K, G=G, n_modes=4, solver="partial-projected")
    assert not sol.coverage["verified"] and "positive definite" in sol.coverage["note"]
    auto = solve_partial(M, C, K, G=G, n_modes=4)
    assert auto.solver == "partial-companion" and "positive definite" in auto.reason
    assert np.min(np.abs(auto.eigenvalues - 0.5)) <= 1e-9 * 0.5
    assert np.all(auto.backward_error <= 1e-12)
