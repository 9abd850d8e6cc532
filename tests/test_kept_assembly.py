"""What one analysis point assembles once and keeps (issue "Flexible models as lean as an FE
code"): the sparse K and C at q₀ within :meth:`Model.keeping_jacobians`, the mass at the
positions where the beams' masses were evaluated, the beams' equal element masses stored once,
and a constant mass without stored zeros.  Every reference is the assembly the shortcut
replaces, evaluated here independently; tolerance: bitwise (the same sums in the same order,
or an exact zero added), so these hold under any kernel or fail under all."""

import numpy as np
import pytest
import scipy.sparse as sp
from conftest import CASES

from mbseig.bench.lean_rows import shaft_case
from mbseig.casefile import load_case
from mbseig.linear import linearize
from mbseig.numerics import nonzero_sum, scatter
from mbseig.statics import equilibrium
from mbseig.studies.point import linear_stage

SHAFT = shaft_case(2, per=8)  # 2 spans of 1 m on universal joints, 16 elements


@pytest.fixture(scope="module")
def shaft(tmp_path_factory):
    path = tmp_path_factory.mktemp("kept") / "shaft.toml"
    path.write_text(SHAFT)
    return load_case(path)


def _same(A, B):
    A, B = sp.csr_matrix(A), sp.csr_matrix(B)
    return (A.shape == B.shape and np.array_equal(A.indptr, B.indptr)
            and np.array_equal(A.indices, B.indices) and np.array_equal(A.data, B.data))


def test_kept_jacobians_are_served_again_only_within_the_scope(shaft):
    q = shaft.q_init
    K0, C0 = shaft.force_jacobians(q)
    assert shaft.force_jacobians(q)[0] is not K0  # no scope: assembled at each call
    with shaft.keeping_jacobians():
        K1, C1 = shaft.force_jacobians(q)
        assert shaft.force_jacobians(q)[0] is K1
        assert _same(K1, K0) and _same(C1, C0)
        with pytest.raises(ValueError):  # shared by every caller: read-only
            K1.data[0] = 1.0
        with shaft.keeping_jacobians():  # a nested scope shares the outer one
            assert shaft.force_jacobians(q)[0] is K1
        assert shaft.force_jacobians(q)[0] is K1
        q2 = q.copy()
        q2[0] += 1e-3
        K2, _ = shaft.force_jacobians(q2)  # another q: assembled (and now the one kept)
        assert K2 is not K1 and _same(K2, shaft._force_jacobians(q2, None, False)[0])
        K3, _ = shaft.force_jacobians(q2, np.zeros(shaft.n))  # a q̇ given: never kept
        assert K3 is not K2
    assert "_kept_sparse" not in shaft.__dict__
    assert shaft.force_jacobians(q)[0] is not K1


def test_one_point_within_the_scope_equals_the_stages_apart(shaft):
    """linear_stage (the check, the solve and the linearization on one kept K) gives the
    linear model of the stages run apart, bitwise."""
    eq, lin = linear_stage(shaft)
    lin0 = linearize(shaft, equilibrium(shaft))
    for a, b in ((lin.M, lin0.M), (lin.P, lin0.P), (lin.Q, lin0.Q)):
        assert _same(a, b)


def test_the_check_in_the_scope_still_names_a_nonfinite_force(shaft):
    """Within the scope the check reads the sums of K and C; a NaN in one element's terms makes
    its sum NaN, and the element is then named as outside the scope."""
    q = shaft.q_init.copy()
    el = shaft.forces[3]
    q[el.idx[0]] = np.nan
    outside = shaft.nonfinite_element(q)
    with shaft.keeping_jacobians():
        inside = shaft.nonfinite_element(q)
    assert outside is not None and inside == outside


@pytest.mark.parametrize("case", ["cantilever_3d_oblique.toml", "four_bar_flexible.toml"])
def test_mass_at_its_reference_is_the_constant_mass(case):
    """At ``mass_reference`` M(q) is ``mass`` without evaluating an element; it equals the sum
    the general path forms (mass + scatter of M_e(q) − M_ref), and the general path still
    runs one step away."""
    model = load_case(CASES / case)
    assert model.mass_elements and np.array_equal(model.mass_reference, model.q_init)
    for q in (model.mass_reference, model.q_init + 1e-4):
        blocks = [(e.idx, e.idx, e.mass(q) - M_ref) for e, M_ref in model.mass_elements]
        ref = (model.mass + scatter(model.n, model.n, blocks)).tocsr()
        ref.eliminate_zeros()
        assert _same(model.mass_matrix(q), ref)


def test_equal_element_masses_are_stored_once(shaft):
    """A uniform beam's element masses at the reference: each the element's own mass there
    (bitwise), read-only, equal ones one array; the constant mass stores no zeros."""
    refs = [M for _, M in shaft.mass_elements]
    for e, M in shaft.mass_elements:
        assert np.array_equal(M, e.mass(shaft.mass_reference)) and not M.flags.writeable
    assert len({id(M) for M in refs}) < len(refs)
    assert len({id(M) for M in refs}) == len({M.tobytes() for M in refs})
    assert shaft.mass.nnz == np.count_nonzero(shaft.mass.data)


def test_nonzero_sum_has_scatters_values_without_its_zeros():
    """nonzero_sum against scatter on blocks half of whose entries are exact zeros (3,000
    blocks on 60 coordinates: about 15 terms an entry).  Both sum the same nonzero terms; scipy
    sums the duplicates of an entry in an order it does not fix, so an entry of k terms may
    differ by the two orders' error bound 2(k − 1) ε Σ|terms| (Higham, Accuracy and Stability
    of Numerical Algorithms, §4.2).  No zero is stored, and the list of blocks is emptied as it
    is read (its arrays let go)."""
    rng = np.random.default_rng(0)
    blocks = []
    for _ in range(3000):
        idx = rng.choice(60, 6, replace=False)
        blocks.append((idx, idx, np.where(rng.random((6, 6)) < 0.5,
                                          rng.standard_normal((6, 6)), 0.0)))
    ref = scatter(60, 60, blocks)
    terms = scatter(60, 60, [(r, c, np.abs(v)) for r, c, v in blocks]).toarray()
    count = scatter(60, 60, [(r, c, (v != 0).astype(float)) for r, c, v in blocks]).toarray()
    given = list(blocks)
    got = nonzero_sum(60, 60, given)
    assert given == []
    assert np.all(got.data != 0) and got.nnz == np.count_nonzero(ref.toarray())
    bound = 2 * np.maximum(count - 1, 0) * np.finfo(float).eps * terms
    assert np.all(np.abs(got.toarray() - ref.toarray()) <= bound)


def test_finite_judges_small_arrays_in_chunks_as_one_by_one():
    """_finite over thousands of small blocks (a beam model's) with one NaN, one inf or a
    Python-float overflow anywhere: False, as a check of each alone; all finite: True."""
    from mbseig.model.system import _FINITE_CHUNK, _finite

    rng = np.random.default_rng(0)
    blocks = [rng.standard_normal((6, 12)) for _ in range(3000)]  # 216,000 entries: 4 chunks
    assert _finite(lambda: iter(blocks))
    for bad in (np.nan, np.inf, -np.inf):
        for where in (0, 1500, 2999):
            spoilt = [b.copy() for b in blocks]
            spoilt[where][3, 7] = bad
            assert not _finite(lambda s=spoilt: iter(s))
    big = np.ones(_FINITE_CHUNK + 1)
    big[-1] = np.nan
    assert not _finite(lambda: iter([np.ones(3), big]))

    def overflow():
        yield np.ones(2)
        yield 10.0 ** 400  # a Python float power: OverflowError

    assert not _finite(overflow)
