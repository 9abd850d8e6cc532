"""The checks around the partial paths' Krylov searches, computed once per conjugate pair and
without full-size copies, against the plain definitions they replace.

References: every expected value is the same quantity evaluated directly from its definition
(mbseig.eigen.measures module doc) on the expanded set of returned pairs — an independent route
through the same formulas — or numpy's own norm/gather.  Tolerances: 0 (bitwise) where the two
routes do the same floating-point operations in the same order, else 1e-13 relative (sums of the
same terms in another order: a few ε times the number of terms' growth factor, here ≤ 10³ terms).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

from mbseig.eigen import Problem, Request, measures, solve
from mbseig.eigen.partial_pairs import general_pairs, take_columns
from mbseig.modal.bounds import FORM_BLOCK, modal_forms


def _chain(n, alpha=0.01, beta=2e-4, ground=True):
    """Mass-spring chain (masses 1 + 0.5 sin i, springs 1000), damping αM + βK, plus grounded
    dashpots on every 7th mass when ``ground`` (non-proportional)."""
    m = 1.0 + 0.5 * np.sin(np.arange(n))
    M = sp.diags(m).tocsr()
    K = (1000.0 * sp.diags([-np.ones(n - 1), 2 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1])).tocsr()
    P = alpha * M + beta * K
    if ground:
        d = np.zeros(n)
        d[::7] = 0.3
        P = P + sp.diags(d)
    return M, P.tocsr(), K


def test_colnorm_skips_the_max_pass_only_where_it_cannot_matter():
    rng = np.random.default_rng(0)
    X = rng.standard_normal((500, 6)) + 1j * rng.standard_normal((500, 6))
    X[:, 1] *= 1e200  # squares overflow: needs the scaled path
    X[:, 2] *= 1e-170  # squares underflow: needs the scaled path
    X[:, 3] = 0.0
    got = measures.colnorm(X)
    # reference: numpy's norm of each column scaled by a power of 2 (exact), scaled back
    ref = [np.ldexp(np.linalg.norm(np.ldexp(X[:, j].real, -e) + 1j * np.ldexp(X[:, j].imag, -e)), e)
           for j, e in enumerate(np.frexp(np.max(np.abs(X), axis=0))[1])]
    np.testing.assert_allclose(got, ref, rtol=1e-13)
    assert got[3] == 0.0
    # the fast route gives the bits of the old route (max |X| formed first) on every column
    assert np.array_equal(got, measures.colnorm(X, np.max(np.abs(X), axis=0)))


def test_unit_columns_in_place_is_the_copy_bitwise():
    rng = np.random.default_rng(1)
    X = rng.standard_normal((300, 5)) + 1j * rng.standard_normal((300, 5))
    X[:, 0] *= 1e-200
    ref = measures.unit_columns(X.copy())
    Y = X.copy()
    out = measures.unit_columns(Y, inplace=True)
    assert np.array_equal(out, ref)
    nrm = measures.plain_norms(X[:, 1:])
    assert nrm is not None and measures.plain_norms(X) is None  # the tiny column needs scaling
    assert np.array_equal(X[:, 1:] / nrm, measures.unit_columns(X[:, 1:]))


@pytest.mark.parametrize("order", ["C", "F"])
def test_expand_pairs_with_divisors_is_gather_then_divide(order):
    rng = np.random.default_rng(2)
    X = np.asarray(rng.standard_normal((20000, 4)) + 1j * rng.standard_normal((20000, 4)),
                   order=order)
    d = rng.uniform(0.5, 2.0, 4)
    pos = np.array([0, 0, 2, 1, 1, 3])
    partner = np.array([False, True, False, False, True, False])
    ref = (X / d)[:, pos]
    ref[:, partner] = ref[:, partner].conj()
    got = measures.expand_pairs(X, pos, partner, divide=d)
    assert got.flags.c_contiguous and np.array_equal(got, ref)
    assert np.array_equal(take_columns(X, [2, 0]), X[:, [2, 0]])


def _direct(M, P, Q, s, X, norms):
    eta, MX, PX = measures.backward_errors((M, P, Q), s, X, norms)
    kappa = measures.conditions(s, X, X, MX, PX, norms)
    eta_c, kappa_c = measures.componentwise((M, P, Q), s, X, None)
    return eta, kappa, eta_c, kappa_c


@pytest.mark.parametrize("left", [False, True])
@pytest.mark.parametrize("block", [None, 1 << 20, 3000])
def test_eta_kappa_in_one_pass_is_the_two_steps(monkeypatch, left, block):
    """η and κ formed block by block without M X and P X whole: bitwise those of
    backward_errors_norms then conditions where both take the same blocks of rows (one block,
    and 24), and with their own default blocks (here 1 and 2) the same sums grouped otherwise:
    η to 1e-14 (a norm of 12000 squares regrouped: a few ε), κ to 1e-12 (yᴴ(2sM + P)x of random
    vectors: Σ|terms| / |Σ terms| ≈ √12000 ≈ 110 times a few ε)."""
    if block is not None:
        monkeypatch.setattr(measures, "ROW_BLOCK", block)
        monkeypatch.setattr(measures, "FUSED_BLOCK", block)
    n = 12000
    M, P, Q = _chain(n)
    P = (P + sp.diags(np.linspace(0.0, 0.2, n - 1), 1)).tocsr()  # not symmetric
    rng = np.random.default_rng(4)
    s = rng.standard_normal(6) * 30.0 + 1j * rng.standard_normal(6) * 30.0
    s[0] = 0.3 + 0.1j  # |s| < 1 and > 1: both evaluations of the polynomial
    X = rng.standard_normal((n, 6)) + 1j * rng.standard_normal((n, 6))
    Yc = rng.standard_normal((n, 6)) + 1j * rng.standard_normal((n, 6)) if left else X
    norms = tuple(measures.fro(A) for A in (M, P, Q))
    eta, MX, PX, xn = measures.backward_errors_norms((M, P, Q), s, X, norms)
    kappa = measures.conditions(s, X, Yc, MX, PX, norms, xn=xn)
    got = measures.eta_kappa((M, P, Q), s, X, Yc, norms)
    if block is None:
        assert n * 6 > measures.FUSED_BLOCK and n * 6 <= measures.ROW_BLOCK
        np.testing.assert_allclose(got[0], eta, rtol=1e-14)
        np.testing.assert_allclose(got[1], kappa, rtol=1e-12)
        assert np.array_equal(got[2], xn)
    else:
        for a, b in zip(got, (eta, kappa, xn), strict=True):
            assert np.array_equal(a, b)


@pytest.mark.parametrize("solver,ground", [("partial-proportional", False),
                                           ("partial-companion", True)])
def test_measures_per_pair_are_those_of_every_returned_pair(solver, ground):
    """η, κ, η_c, κ_c formed once per conjugate pair equal the definitions evaluated on every
    returned pair (its conjugate partner included)."""
    M, P, Q = _chain(400, ground=ground)
    sol = solve(Problem(M, P, Q), Request(solver, n_modes=6))
    assert sol.solver == solver
    s, X = sol.eigenvalues, sol.vectors
    assert np.any(s.imag > 0) and np.any(s.imag < 0)  # conjugate pairs were returned
    eta, kappa, eta_c, kappa_c = _direct(M, P, Q, s, X, sol.norms)
    np.testing.assert_allclose(sol.backward_error, eta, rtol=1e-13, atol=1e-30)
    np.testing.assert_allclose(sol.condition, kappa, rtol=1e-13)
    got_c = sol.componentwise()
    np.testing.assert_allclose(got_c[0], eta_c, rtol=1e-13, atol=1e-30)
    np.testing.assert_allclose(got_c[1], kappa_c, rtol=1e-13)
    # a subset asked in any order maps back to the right pairs
    idx = np.array([3, 0, 5])
    sub = sol.componentwise(idx)
    np.testing.assert_allclose(sub[1], kappa_c[idx], rtol=1e-13)


def test_passed_partner_map_is_the_found_one_bitwise():
    """general_pairs given the measured columns and the partner map (as partial-slepc passes
    them) returns the bits it returns when it finds the partners itself in expanded vectors."""
    n = 30
    M, P, Q = _chain(n)
    Md, Pd, Qd = (A.toarray() for A in (M, P, Q))
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Qd, -Pd]])
    B = np.block([[np.eye(n), np.zeros((n, n))], [np.zeros((n, n)), Md]])
    w, V = sla.eig(A, B)
    up = np.flatnonzero(w.imag > 0)[np.argsort(np.abs(w[w.imag > 0]))][:5]
    Xu = np.ascontiguousarray(V[:n, up])
    partner = np.tile([False, True], 5)
    cols = np.repeat(np.arange(5), 2)
    s = np.where(partner, np.conj(w[up][cols]), w[up][cols])
    norms = tuple(measures.fro(A) for A in (M, P, Q))
    Xall = measures.expand_pairs(Xu, cols, partner)
    passed = general_pairs({"s": s, "X": Xu.copy(), "partner": partner}, (M, P, Q), norms, n, 0,
                           1e-6, "test", 1e-13, True)
    found = general_pairs({"s": s, "X1": Xall, "X2": Xall}, (M, P, Q), norms, n, 0, 1e-6, "test",
                          1e-13, True)
    for a, b in zip(passed[:5], found[:5], strict=True):
        assert np.array_equal(a, b)
    idx = np.arange(10)
    for a, b in zip(passed[5](idx), found[5](idx), strict=True):
        assert np.array_equal(a, b)


def test_modal_forms_batched_equal_column_by_column():
    M, P, _ = _chain(60000)
    rng = np.random.default_rng(3)
    X = rng.standard_normal((60000, 20)) + 1j * rng.standard_normal((60000, 20))
    cand = np.array([k for k in range(20) if k not in (5, 13)])
    got = modal_forms(X, cand, M, P)  # large and sparse: the blocked products
    assert 60000 * cand.size > FORM_BLOCK
    for (mx, px, xx), k in zip(got, cand, strict=True):
        x = X[:, k]
        np.testing.assert_allclose(mx, abs(np.vdot(x, M @ x)), rtol=1e-13)
        np.testing.assert_allclose(px, abs(np.vdot(x, P @ x)), rtol=1e-13)
        np.testing.assert_allclose(xx, np.vdot(x, x).real, rtol=1e-13)
