"""The check's right-hand side on precomputed patterns equals the direct assembly array by
array (reference: the assembly it replaces, ``mass + scatter`` of the element blocks and
``sp.bmat`` of M(q) and Φ_q, evaluated here independently; tolerance: bitwise, since the same
sums are formed in the same order), at random states of the bundled 3-D beam cases at small
meshes, including M(q) with exact zeros."""

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from conftest import CASES

from mbseig.check.augmented import AugmentedPattern
from mbseig.check.dynamics import ForwardDynamics
from mbseig.check.tangent import TangentCoordinates
from mbseig.numerics import scatter
from mbseig.statics import solved
from mbseig.studies import analyze


def _same(A, B):
    A, B = A.copy(), B.copy()
    return (A.shape == B.shape and A.format == B.format and np.array_equal(A.indptr, B.indptr)
            and np.array_equal(A.indices, B.indices) and np.array_equal(A.data, B.data))


def _states(a, count, scale=1e-3):
    rng = np.random.default_rng(7)
    q0 = a.eq.q
    return [q0 + scale * a.model.length_scale * rng.standard_normal(q0.size) for _ in range(count)]


@pytest.fixture(scope="module",
                params=["cantilever_3d_oblique.toml", "overhung_rotor_friswell.toml"])
def case(request):
    params = {"n": 2} if "cantilever" in request.param else None
    a = analyze(CASES / request.param, params=params)
    return a, solved(a.model, a.eq)


def test_mass_matrix_equals_the_scattered_sum(case):
    """M(q) = mass + scatter(element blocks) bitwise, structure included; ``fixed`` gives the
    same values on one pattern for every q."""
    a, model = case
    assert model.mass_elements
    pattern = None
    for q in [a.eq.q] + _states(a, 3):
        blocks = [(e.idx, e.idx, e.mass(q) - M_ref) for e, M_ref in model.mass_elements]
        ref = (model.mass + scatter(model.n, model.n, blocks)).tocsr()
        assert _same(model.mass_matrix(q), ref)
        Mf = model.mass_matrix(q, fixed=True)
        assert np.array_equal(Mf.toarray(), ref.toarray())
        if pattern is not None:
            assert np.array_equal(Mf.indptr, pattern[0]) and np.array_equal(Mf.indices, pattern[1])
        pattern = (Mf.indptr, Mf.indices)


def test_augmented_matrix_is_bmats_and_the_accelerations_are_unchanged(case):
    """The refilled augmented matrix equals sp.bmat's bitwise (also with zeros forced into
    M(q), which bmat does not store), so SuperLU's solution is the same bit for bit."""
    a, model = case
    dyn = ForwardDynamics(model, a.eq.q)
    rng = np.random.default_rng(5)
    for q in _states(a, 3):
        Mf, Js = model.mass_matrix(q, fixed=True), model.phi_q(q)
        ref = sp.bmat([[model.mass_matrix(q), Js.T], [Js, None]], format="csc")
        A = dyn._augmented(q)
        assert _same(A, ref)
        b = rng.standard_normal(A.shape[0])
        assert np.array_equal(spla.splu(A).solve(b), spla.splu(ref).solve(b))
        Mz = Mf.copy()
        Mz.data[rng.choice(Mz.nnz, 7, replace=False)] = 0.0
        Mz2 = Mz.copy()
        Mz2.eliminate_zeros()
        assert _same(AugmentedPattern(Mf, Js).fill(Mz, Js),
                     sp.bmat([[Mz2, Js.T], [Js, None]], format="csc"))


def test_tangent_rhs_keeps_the_constraints(case):
    """The lifted states of the tangent right-hand side satisfy Φ = 0 and Φ_q q̇ = 0 to 1e-14
    (scaled residual) and 1e-12 of |q̇| (rounding of Φ_q q̇ summed over a constraint row) at
    perturbations of 1e-4 of the length."""
    a, model = case
    dyn = ForwardDynamics(model, a.eq.q)
    tc = TangentCoordinates(dyn)
    rng = np.random.default_rng(3)
    for _ in range(3):
        x = 1e-4 * model.length_scale * rng.standard_normal(tc.k) / np.sqrt(tc.k)
        u, v, res, _ = tc.lift(x, rng.standard_normal(tc.k))
        q = dyn.q0 + u
        assert res <= 1e-14
        assert np.max(np.abs(model.phi(q)) / dyn.cscale) <= 1e-14
        assert np.max(np.abs(model.phi_q(q) @ v)) <= 1e-12 * np.abs(v).max()
