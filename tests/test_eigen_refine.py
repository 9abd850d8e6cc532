"""The dense paths at the edges of the normwise measures: a gyroscopic pencil nearly without
stiffness (its small eigenvalue recovered by the two-sided Rayleigh functional), an exactly
fixed zero eigenvalue (κ = 0, not ∞), and the shortcuts of the structure tests (the same
decisions and products as the direct tests)."""

import warnings

import numpy as np
import pytest
import scipy.sparse as sp

from mbseig import modes
from mbseig.eigen.dense import choose_solver
from mbseig.eigen.dense_paths import _fast_operand
from mbseig.eigen.structure import is_symmetric, rayleigh_fit


@pytest.mark.parametrize("solver", ["auto", "companion", "qz"])
def test_gyroscopic_pencil_nearly_without_stiffness(solver):
    """M = I, P = [[0, −6], [6, 0]], Q = −k I: det = (s² − k)² + 36 s², so every eigenvalue is
    s = i(±6 ± √(36 − 4k))/2, purely imaginary (closed form); the small one, 2k/(6 + √(36 − 4k)),
    lies far below the companion scale.  Listed within 1e-12 relative of the closed form (η at
    the rounding level, no warning) and critical, as the exact spectrum is."""
    k = 5e-12
    M, P, Q = np.eye(2), np.array([[0.0, -6.0], [6.0, 0.0]]), -k * np.eye(2)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        md = modes(M, P, Q, solver=solver)
    small = 2 * k / (6 + np.sqrt(36 - 4 * k))
    big = (6 + np.sqrt(36 - 4 * k)) / 2
    assert len(md) == 2
    np.testing.assert_allclose(md.omega_d, [small, big], rtol=1e-12)
    assert np.all(np.abs(md.delta) <= md.tolerance)
    assert np.all(md.backward_error < 1e-15)
    assert md.verdict == "critical"


@pytest.mark.parametrize("solver", ["auto", "companion", "qz"])
def test_fixed_zero_has_condition_zero(solver):
    """M = I, P = 0, Q = 0: s = 0 is an eigenvalue of every M + ΔM (the normwise class leaves
    P = Q = 0 as they are), so its condition number is 0 (finite), its four eigenvalues two
    rigid-body modes (x'' = 0 per coordinate: closed form)."""
    md = modes(np.eye(2), np.zeros((2, 2)), np.zeros((2, 2)), solver=solver)
    assert list(md.kind) == ["rigid-body", "rigid-body"]
    assert np.all(md.condition == 0.0)
    assert np.all(md.eigenvalues == 0)
    assert md.accounting["rigid_eigenvalues"] == 4 and md.verdict == "critical"


def _chain(n, seed=0):
    rng = np.random.default_rng(seed)
    k = 1.0 + rng.random(n)
    Q = np.diag(k + np.roll(k, -1)) - np.diag(k[1:], 1) - np.diag(k[1:], -1)
    return np.diag(1.0 + rng.random(n)), Q


@pytest.mark.parametrize("n", [8, 150])
def test_fast_operand_is_the_csr_of_its_nonzeros(n):
    """The CSR built from the mask has the arrays of csr_matrix((A[r, c], (r, c))) (the
    independent construction), so every product with it is the same, bit for bit."""
    _, Q = _chain(n)
    B = _fast_operand(Q)
    if Q.size <= 10_000:
        assert B is Q
        return
    r, c = np.nonzero(Q)
    ref = sp.csr_matrix((Q[r, c], (r, c)), shape=Q.shape)
    assert np.array_equal(B.indptr, ref.indptr) and np.array_equal(B.indices, ref.indices)
    assert np.array_equal(B.data, ref.data)
    V = np.random.default_rng(1).standard_normal((n, 5))
    assert np.array_equal(B @ V, ref @ V)


@pytest.mark.parametrize("where", [(0, 1), (5, 7)])
@pytest.mark.parametrize("skew", [0.0, 1e-15, 1e-9])
def test_shortcut_symmetry_decisions_equal_the_direct_tests(skew, where):
    """choose_solver decides M's symmetry from its diagonal and P's from the Rayleigh fit's
    bound (or its own test first where the first row shows an asymmetry); the path it takes is
    the one the direct tests (is_symmetric, rayleigh_fit) give."""
    M, Q = _chain(120)
    P = 0.1 * M + 0.01 * Q
    P[where] += skew * np.linalg.norm(P)
    name, _, _ = choose_solver(M, P, Q)
    direct = is_symmetric(P, 1e-13) and rayleigh_fit(M, P, Q, 1e-12) is not None
    assert (name == "proportional") == direct
    assert name == ("proportional" if skew <= 1e-15 else "companion")


def _shapes_reference(X, names, n_dominant):
    """Mode by mode, as the listing defines it: each column over its largest |component|, the
    n_dominant largest |entries| (a stable sort by −|x|, equal ones by index) of at least 0.05."""
    shapes, dominant = [], []
    for c in range(X.shape[1]):
        x = X[:, c]
        p = x[int(np.argmax(np.abs(x)))]
        y = x / p if p != 0 else x.copy()
        m = np.abs(y)
        order = np.argsort(-m, kind="stable")[:n_dominant]
        shapes.append(y)
        dominant.append([(names[i], float(m[i])) for i in order if m[i] >= 0.05])
    return np.column_stack(shapes), dominant


@pytest.mark.parametrize("block", [None, 80])
@pytest.mark.parametrize("kind", ["real", "complex", "ties"])
def test_mode_shapes_match_the_column_by_column_rule(kind, block, monkeypatch):
    """The shapes and dominant coordinates of all modes at once equal the column-by-column rule
    (an independent loop) exactly, real and complex, with ties at the cut and a zero column;
    also in blocks of two modes (``SHAPE_BLOCK`` 80 entries, 40 coordinates), and the given
    vectors are left as they were."""
    import importlib

    from mbseig.modal.listing import mode_shapes

    if block is not None:  # (the module: mbseig.modal exports a function of its name)
        monkeypatch.setattr(importlib.import_module("mbseig.modal.listing"), "SHAPE_BLOCK", block)

    rng = np.random.default_rng(3)
    X = rng.standard_normal((40, 9))
    if kind == "complex":
        X = X + 1j * rng.standard_normal((40, 9))
    if kind == "ties":
        X[:, 2] = 0.0
        X[:, 3] = np.where(np.arange(40) % 2, 1.0, -1.0)  # every entry ties
        X[5:9, 4] = X[[1, 1, 1, 1], 4]
    names = [f"c{i}" for i in range(40)]
    given = X.copy()
    shapes, dominant = mode_shapes(X, None, names, 3)
    assert np.array_equal(X, given)
    ref_shapes, ref_dominant = _shapes_reference(X, names, 3)
    assert np.array_equal(shapes, ref_shapes)
    assert dominant == ref_dominant
