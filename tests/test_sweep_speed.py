"""The sweep's fast paths give the results of the slow ones (issue: speed at every scale).

- numpy-built CSR (numerics.csr_from_triplets, saddle) equals scipy's COO conversion;
- a sweep line with tangents from the previous point's model (statics.continuation,
  Family.Rp_back) reaches the same equilibria as one with forward-difference tangents at every
  point, and still locates a fold;
- the inverse-statics pre-solve reused across a sweep line (statics.inverse, ``cache``) sets the
  actuator as a fresh resolve does.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st

import mbseig.statics.continuation as cont
from mbseig.casefile import read_case
from mbseig.numerics import coo_sum, csr_from_triplets, saddle, scatter
from mbseig.statics import resolve
from mbseig.statics.inverse import command_settings
from mbseig.studies.continuation import family_maker, sweep_line

from conftest import CASES


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 7), st.integers(1, 7), st.integers(0, 40), st.integers(0, 2**32 - 1))
def test_csr_from_triplets_equals_scipy(n_rows, n_cols, count, seed):
    """Reference: scipy's COO → CSR (duplicates summed); equal to 1 ulp of the sums' size
    (the two may add duplicates in another order)."""
    rng = np.random.default_rng(seed)
    r = rng.integers(0, n_rows, count)
    c = rng.integers(0, n_cols, count)
    v = rng.standard_normal(count)
    ours = csr_from_triplets(n_rows, n_cols, r, c, v)
    ref = sp.coo_matrix((v, (r, c)), shape=(n_rows, n_cols)).tocsr()
    assert ours.shape == ref.shape
    assert ours.has_sorted_indices
    scale = np.abs(v).sum() + 1.0
    assert (np.max(np.abs(ours.toarray() - ref.toarray()), initial=0.0)
            <= 4 * np.finfo(float).eps * scale)


def test_csr_from_triplets_refuses_indices_outside():
    with pytest.raises(IndexError):
        csr_from_triplets(2, 2, np.array([2]), np.array([0]), np.array([1.0]))


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 7), st.integers(1, 7), st.integers(0, 5), st.integers(0, 2**32 - 1))
def test_dense_assembly_equals_csr(n_rows, n_cols, count, seed):
    """Reference: the CSR assembly of the same element blocks and triplets (scatter, coo_sum),
    repeated indices included; equal to 4 ulp of the sums' size (another summation order)."""
    rng = np.random.default_rng(seed)
    blocks = []
    for _ in range(count):
        r = rng.integers(0, n_rows, rng.integers(1, 4))
        c = rng.integers(0, n_cols, rng.integers(1, 4))
        blocks.append((r, c, rng.standard_normal((r.size, c.size))))
    trip = [(rng.integers(0, n_rows, 6), rng.integers(0, n_cols, 6), rng.standard_normal(6))
            for _ in range(count)]
    scale = sum(np.abs(b[2]).sum() for b in blocks) + sum(np.abs(t[2]).sum() for t in trip) + 1.0
    for dense, csr in ((scatter(n_rows, n_cols, blocks, dense=True),
                        scatter(n_rows, n_cols, blocks)),
                       (coo_sum(n_rows, n_cols, trip, dense=True), coo_sum(n_rows, n_cols, trip))):
        assert isinstance(dense, np.ndarray) and dense.shape == (n_rows, n_cols)
        assert np.max(np.abs(dense - csr.toarray()), initial=0.0) <= 4 * np.finfo(float).eps * scale


def test_dense_assembly_refuses_indices_outside():
    with pytest.raises(IndexError):
        scatter(2, 2, [(np.array([2]), np.array([0]), np.array([[1.0]]))], dense=True)


def test_small_model_dense_evaluations_equal_csr():
    """Reference: the model's CSR evaluations at the device's equilibrium; the dense ones the
    statics and the continuation use for small models are the same matrices to 4 ulp."""
    from mbseig.statics import equilibrium

    model = resolve(read_case(CASES / "hand_device.toml").build())
    assert model.dense_assembly
    eq = equilibrium(model)
    K, C = model.force_jacobians(eq.q)
    Kd, Cd = model.force_jacobians(eq.q, dense=True)
    for d, s in ((Kd, K), (Cd, C), (model.phi_q(eq.q, dense=True), model.phi_q(eq.q)),
                 (model.constraint_hessian(eq.q, eq.lam, dense=True),
                  model.constraint_hessian(eq.q, eq.lam))):
        assert isinstance(d, np.ndarray)
        ref = s.toarray()
        assert np.max(np.abs(d - ref)) <= 4 * np.finfo(float).eps * max(np.abs(ref).max(), 1.0)


def test_saddle_equals_bmat():
    A = sp.random(6, 6, density=0.5, random_state=2, format="csr")
    G = sp.random(3, 6, density=0.5, random_state=3, format="csr")
    ref = sp.bmat([[A, G.T], [G, None]]).toarray()
    assert np.array_equal(saddle(A, G).toarray(), ref)  # same entries, no arithmetic


def _line(values, monkeypatch=None, exact=False):
    spec = read_case(CASES / "hand_device.toml")
    if exact:  # every tangent by the forward difference (the slow reference)
        monkeypatch.setattr(cont.Family, "Rp_back", lambda self, y, p, p_prev: self.Rp(y, p))
    return sweep_line(spec, None, {}, "k_a", values)


def test_difference_tangents_reach_the_same_equilibria(monkeypatch):
    """Reference: the same line with forward-difference tangents at every point.  Both
    converge every grid point to CTOL = 1e-11 in the model's scales, so the postures agree to a
    few CTOL (1e-9 m/rad allowed) and the eigenvalues to 1e-7 relative.  (The line followed
    point by point: the batched line has no tangents.)"""
    import mbseig.studies.continuation as line

    monkeypatch.setattr(line, "BATCH_LINES", False)
    values = np.linspace(800.0, 1200.0, 6)
    fast = _line(values)
    assert fast["record"]["tangents_by_difference"] >= 3  # the fast path was taken
    slow = _line(values, monkeypatch, exact=True)
    for a, b in zip(fast["points"], slow["points"], strict=True):
        assert a["error"] is None and b["error"] is None
        assert np.max(np.abs(a["q"] - b["q"])) <= 1e-9
        sa, sb = np.sort_complex(a["eigenvalues"]), np.sort_complex(b["eigenvalues"])
        assert np.max(np.abs(sa - sb) / np.abs(sb)) <= 1e-7


def test_presolve_reused_sets_the_actuator_as_a_fresh_resolve():
    """Reference: resolve without hint or cache at each value.  The free length is found to the
    secant's stopping test |λ_d| ≤ 1e-12 |λ_d,0|, so the two agree to 1e-10 relative."""
    spec = read_case(CASES / "hand_device.toml")
    make, state = family_maker(spec, None, {}, "k_a")
    for k_a in (900.0, 950.0, 1000.0):
        fast = command_settings(make(k_a))
        fresh = command_settings(resolve(spec.build(None, k_a=k_a)))
        assert np.allclose(fast, fresh, rtol=1e-10, atol=0)
    assert len(state["presolve"]) == 1  # the released device does not depend on k_a: one pre-solve


def test_newton_start_of_inverse_statics(monkeypatch):
    """The free length from Newton's step on the driver's effort equals the secant's (the
    reference: the same resolve with the Newton start disabled) to 1e-10 relative, both ending
    at |λ_d| ≤ 1e-12 |λ_d,0|; on the device the driver holds the actuator's end points, so λ_d
    is affine in l0 and one solve with the spring ends the iteration."""
    import mbseig.statics.inverse as inv

    spec = read_case(CASES / "hand_device.toml")
    newton = resolve(spec.build(None)).drivers[0]
    monkeypatch.setattr(inv, "_newton_free_length", lambda *a: None)
    secant = resolve(spec.build(None)).drivers[0]
    assert newton["iterations"] == 1 < secant["iterations"]
    a, b = newton["sets"][0]["free_length"], secant["sets"][0]["free_length"]
    assert abs(a - b) <= 1e-10 * abs(b)
    for rec in (newton, secant):
        assert abs(rec["residual_effort"]) <= 1e-12 * abs(rec["effort"])


def test_kept_dense_evaluations_are_read_only_and_current():
    """A small model keeps its last dense K, Φ_q, H by q: the kept arrays cannot be changed by a
    caller (writing raises), and another q gives that q's matrices (reference: a fresh model's
    evaluation at the other q, bitwise)."""
    from mbseig.statics import equilibrium

    spec = read_case(CASES / "hand_device.toml")
    model = resolve(spec.build())
    eq = equilibrium(model)
    K, _ = model.force_jacobians(eq.q, dense=True)
    assert model.force_jacobians(eq.q, dense=True)[0] is K  # kept
    with pytest.raises(ValueError):
        K[0, 0] = 1.0
    q2 = eq.q + 1e-3
    fresh = resolve(spec.build())
    assert np.array_equal(model.force_jacobians(q2, dense=True)[0],
                          fresh.force_jacobians(q2, dense=True)[0])
    assert np.array_equal(model.phi_q(q2, dense=True), fresh.phi_q(q2).toarray())
