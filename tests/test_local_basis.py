"""The local null-space basis (mbseig.model.tangent): node and body triads eliminated by their
exact tangent space, the other constraints component by component.

References: the defining properties of a basis of null Φ_q (orthonormal columns, Φ_q N = 0,
dimension n − rank Φ_q; rounding bounds below), and an independent path to the same modes,
the global SVD null space of the whole Jacobian (mbseig.linear.continuous_null_basis, the basis
mbseig used before): the eigenvalues of M, P, Q reduced by either basis agree within the sum of
their first-order error bounds (each mode's ``error_estimate`` = κ η, with the bounds' safety
factor 10), since both are exact reductions of one problem.
"""

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

import mbseig
from mbseig.bench.lean_rows import shaft_case
from mbseig.linear import continuous_null_basis
from mbseig.model.tangent import local_basis, triad_coordinates

CASES = Path(__file__).resolve().parent.parent / "cases"
EPS = np.finfo(float).eps
WITH_FRAMES = ["spatial_double_pendulum", "rssr_four_bar", "overhung_rotor_friswell",
               "cantilever_3d_oblique", "column_buckling_3d", "spinning_shaft_rayleigh",
               "rigid_rotor"]


def _at_rest(name):
    model = mbseig.load_case(CASES / f"{name}.toml")
    eq = mbseig.equilibrium(model)
    return model, eq


@pytest.mark.parametrize("name", WITH_FRAMES)
def test_local_basis_is_an_orthonormal_null_space_basis(name):
    """‖NᵀN − I‖ and ‖Φ_q N‖ at the level of the triads' own rounding: every column is a unit
    combination of at most 9 + (a component's) coordinates, so c·ε with c = 100 covers the
    sums; the dimension equals n − rank of the whole Jacobian's SVD (relative threshold
    rank_tol)."""
    model, eq = _at_rest(name)
    rank_tol = float(eq.tolerances.get("rank_tol", 1e-10))
    assert triad_coordinates(model)[0].shape[0] > 0
    lb = local_basis(model, eq.q, rank_tol)
    N = lb.N.toarray()
    G = model.phi_q(eq.q, dense=True)
    _, rank, _, _ = continuous_null_basis(G, model.n, rank_tol)
    assert lb.kept is None
    assert N.shape == (model.n, model.n - rank) and lb.rank == rank
    assert np.abs(N.T @ N - np.eye(N.shape[1])).max() <= 100 * EPS
    # Φ_q N: the triad rows vanish where the triads are orthonormal (their residual at q0)
    assert np.abs(G @ N).max() <= 100 * EPS * max(1.0, np.abs(G).max()) \
        + 10 * np.abs(model.phi(eq.q)).max()


@pytest.mark.parametrize("name", WITH_FRAMES)
def test_local_and_global_bases_give_the_same_modes(name):
    """Reference: the global SVD basis of the whole Jacobian (module docstring)."""
    model, eq = _at_rest(name)
    lin = mbseig.linearize(model, eq)
    assert lin.tolerances["basis"] == "local"
    a = mbseig.modes(lin)
    rank_tol = lin.tolerances["rank_tol"]
    G = model.phi_q(eq.q, dense=True)
    Z, _, _, _ = continuous_null_basis(G, model.n, rank_tol)
    K, C = model.force_jacobians(eq.q, dense=True)
    K = K + model.constraint_hessian(eq.q, eq.lam, dense=True)
    Md = model.mass_matrix(eq.q).toarray()
    b = mbseig.modes(Z.T @ Md @ Z, Z.T @ C @ Z, Z.T @ K @ Z)
    assert a.eigenvalues.size == b.eigenvalues.size
    sa, sb = a.all_eigenvalues, b.all_eigenvalues
    for s, err in zip(a.eigenvalues, a.error_estimate, strict=True):
        j = int(np.argmin(np.abs(b.eigenvalues - s)))
        # the bounds (safety 10 on κη), plus the rounding of a zero eigenvalue (rigid-body
        # modes: their κη is ~0), 10 ε of the largest |s|
        bound = 10 * (err + b.error_estimate[j]) + 10 * EPS * max(1.0, np.abs(sa).max(),
                                                                 np.abs(sb).max())
        assert abs(b.eigenvalues[j] - s) <= bound, (s, b.eigenvalues[j], bound)


def _shaft(tmp_path, spans=3, per=4):
    """A free–free steel shaft on universal joints (translations and twist held) at every
    metre: SPANS spans of PER Euler–Bernoulli elements (the bench's multi-span shaft)."""
    path = tmp_path / "shaft.toml"
    path.write_text(shaft_case(spans, per))
    return mbseig.load_case(path)


def test_shaft_on_universal_joints_is_the_standard_fe_problem(tmp_path):
    """A shaft on universal joints at its supports: each support removes its node's three
    translations and its twist, so N keeps the other 2 rotations there as unit columns and is
    the standard FE basis (6 per node) elsewhere: each support row touches one column of T."""
    spans, per = 12, 4  # (6 × 49 columns of T: beyond a small model's one dense SVD)
    model = _shaft(tmp_path, spans, per)
    eq = mbseig.equilibrium(model)
    lb = local_basis(model, eq.q, 1e-10)
    assert not lb.small
    nodes = spans * per + 1
    assert lb.triads == nodes and lb.components == 4 * (spans + 1) and lb.largest == 1
    assert lb.N.shape[1] == 6 * nodes - 4 * (spans + 1)
    # every column is a node's translation (one unit entry) or rotation about a global axis
    # (two entries ±1/√2 at the reference: e_i × e_i = 0)
    counts = np.diff(sp.csc_matrix(lb.N).indptr)
    assert set(counts.tolist()) == {1, 2}


def test_a_component_beyond_the_local_limit_stays_bordered(tmp_path):
    """With the component limit below the size of the joints' components, their rows stay in
    the bordered pencil of the partial path, in N's columns; the lowest modes equal the dense
    reduction's within the bounds (reference: the dense path on the same model)."""
    model = _shaft(tmp_path)
    eq = mbseig.equilibrium(model)
    lb = local_basis(model, eq.q, 1e-10, local_max=0)
    assert lb.kept is not None and lb.kept_rows.size == 16 and lb.rank == 6 * lb.triads
    assert lb.kept.shape[1] == lb.N.shape[1]
    G = model.phi_q(eq.q, dense=True)
    # the kept rows in N's columns are the model's rows times N
    np.testing.assert_allclose(lb.kept.toarray(), G[lb.kept_rows] @ lb.N.toarray(),
                               atol=100 * EPS * np.abs(G).max())
    N = lb.N
    K, C = model.force_jacobians(eq.q)
    K = K + model.constraint_hessian(eq.q, eq.lam)
    M = model.mass_matrix(eq.q)
    part = mbseig.modes(*((N.T @ A @ N).tocsr() for A in (M, C, K)), constraints=lb.kept,
                        n_modes=4)
    full = mbseig.modes(mbseig.linearize(model, eq))
    for s, err in zip(part.eigenvalues, part.error_estimate, strict=True):
        j = int(np.argmin(np.abs(full.eigenvalues - s)))
        # the bounds (safety 10 on κη) plus the rounding of forming Nᵀ A N in two bases:
        # sums of up to 24 terms an entry, 1e3 ε |s| covers it
        assert abs(full.eigenvalues[j] - s) <= 10 * (err + full.error_estimate[j]) \
            + 1e3 * EPS * abs(s)


def test_clustered_lowest_modes_in_one_lanczos_run(tmp_path):
    """A shaft on 401 supports: its lowest bending modes come in equal pairs (a circular
    section), one pair per span, 20 of them within 0.15 %: the case the coverage
    margin is for (with a margin of 1e-3 this model doubled k to 44).  The 20 lowest are found
    in one run of k = 22 and equal an independent shift-invert Lanczos run on the same reduced
    matrices (reference: scipy's eigsh at σ = 0, its default tolerance: machine precision)
    within the bounds."""
    import scipy.sparse.linalg as spla

    model = _shaft(tmp_path, spans=400, per=2)
    eq = mbseig.equilibrium(model)
    lin = mbseig.linearize(model, eq, sparse=True)
    md = mbseig.modes(lin, n_modes=20)
    assert md.tolerances["arpack_k"] == 22 and len(md.tolerances["shifts"]) == 1
    w = np.sqrt(np.sort(spla.eigsh(lin.Q.tocsc(), 20, lin.M.tocsc(), sigma=0.0,
                                   return_eigenvectors=False)))
    # mbseig's bounds (safety 10 on κη) plus the reference's own convergence: eigsh to
    # machine precision on ω², a few hundred ulps on ω (1e3 ε |ω|)
    assert np.all(np.abs(np.sort(md.omega_n) - w) <= 10 * md.error_estimate + 1e3 * EPS * w)
    assert w[19] / w[0] < 1.0015


@pytest.mark.parametrize("name", ["column_buckling_3d", "overhung_rotor_friswell",
                                  "spatial_double_pendulum"])
def test_statics_with_the_local_basis(name, monkeypatch):
    """The static stability of a model with frames from the local basis: the same verdict,
    index and smallest eigenvalue of K_r as from the SVD basis (reference: the SVD of the whole
    Φ_q, forced by hiding the triads).  The two K_r are similar by an orthogonal matrix, so
    their eigenvalues agree to rounding: c·ε·‖K_r‖ with c = 1e3 (n ≤ 100)."""
    import mbseig.statics.stiffness as st

    model, eq = _at_rest(name)
    a = st.static_stability(model, eq.q, eq.lam)
    Kr_a, _ = st.reduced_stiffness(model, eq.q, eq.lam)
    monkeypatch.setattr(st, "triad_coordinates", lambda m: (np.zeros((0, 6)), None))
    b = st.static_stability(model, eq.q, eq.lam)
    Kr_b, _ = st.reduced_stiffness(model, eq.q, eq.lam)
    assert (a.verdict, a.index, a.dof) == (b.verdict, b.index, b.dof)
    mu_a, mu_b = np.linalg.eigvalsh(Kr_a), np.linalg.eigvalsh(Kr_b)
    assert np.abs(mu_a - mu_b).max() <= 1e3 * EPS * np.abs(mu_b).max()


def test_shaft_equals_the_standard_fe_assembly(tmp_path):
    """Reference: an independent FE code, the bench's floor script (numpy assembly of the
    standard 12 × 12 Euler–Bernoulli shaft element, the held degrees of freedom removed, scipy's
    eigsh at σ = 0), on the same mesh.  Same element, same mesh: the 20 lowest frequencies agree
    to rounding: ε (ω_max/ω_min)² ≈ 2e-12 here (ω_max/ω_min = 91), 1e-10 covers it."""
    import json
    import subprocess
    import sys

    from mbseig.bench.lean_rows import FLOOR_SCRIPT

    spans, per = 3, 4
    out = subprocess.run([sys.executable, "-c", FLOOR_SCRIPT, str(spans), str(per)],
                         capture_output=True, text=True, check=True)
    ref = json.loads(out.stdout.strip().splitlines()[-1])
    model = _shaft(tmp_path, spans, per)
    md = mbseig.modes(mbseig.linearize(model, mbseig.equilibrium(model)))
    assert md.eigenvalues.size == ref["dof"]
    w = np.sort(md.omega_n)[:20]
    np.testing.assert_allclose(w, ref["omega"], rtol=1e-10)


def test_dense_linearization_projects_on_the_sparse_local_basis(tmp_path):
    """A model below the sparse threshold whose local basis was found sparse (beyond a small
    model's one dense SVD): the dense linearization forms Nᵀ A N from the sparse Jacobians and
    the sparse basis, and only then makes it dense, so its M, P, Q are exactly the sparse
    linearization's (the same products; reference: ``linearize(sparse=True)``), and N is the
    local basis itself."""
    model = _shaft(tmp_path, 12, 4)
    eq = mbseig.equilibrium(model)
    dense = mbseig.linearize(model, eq)
    sparse = mbseig.linearize(model, eq, sparse=True)
    assert not sp.issparse(dense.M) and sp.issparse(sparse.M)
    assert dense.tolerances["basis"] == "local" and dense.dof == sparse.dof
    for a, b in ((dense.M, sparse.M), (dense.P, sparse.P), (dense.Q, sparse.Q)):
        assert np.array_equal(a, b.toarray())
    assert np.array_equal(dense.N, sparse.N.toarray())
    # the coordinates N keeps as unit columns, found among the sparse basis's entries, are
    # those of the dense N (a column with one entry of modulus 1)
    N = dense.N
    unit = np.flatnonzero((np.abs(N) == 1.0).sum(axis=0) == 1)
    rows = np.sort(np.argmax(np.abs(N[:, unit]), axis=0))
    assert dense.independent == tuple(model.coordinate_names[i] for i in rows)
    assert len(dense.independent) > 0
