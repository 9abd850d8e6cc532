"""The fast paths added for speed give the answers of the straightforward code they replace.

References, each an independent computation in this file:
- is_symmetric: ‖A − Aᵀ‖_F ≤ tol‖A‖_F with numpy's norm of the explicit difference;
- fro: numpy's norm (ordinary magnitudes) and a scaled sum (entries near 1e±200);
- rayleigh_fit (dense, and sparse on probe products): numpy's lstsq on the same system, residual
  checked directly; the fast fit must accept every P lstsq accepts, and whatever it accepts must
  pass the residual test;
- numerics.scatter: the meshgrid assembly it replaced, bitwise;
- the column-blocked η, κ and componentwise measures: the same functions on one block (the
  measures are per column, so blocking must not change a single bit);
- the lazy package: every name of ``mbseig.__all__`` resolves to the object its module defines;
- a small model's dense K, C, Φ_q, H on keys made once per model: numerics.scatter of the same
  element blocks (the assembly they replace), bitwise, on bundled planar and spatial cases;
- the direct LAPACK calls (triangular solve of the companion path, pivoted QR of the cluster
  rank): scipy.linalg.solve_triangular and scipy.linalg.qr, bitwise;
- the all-pairs ball query of the error bounds: the row-by-row search it replaced;
- numerics.grow_columns (the projected basis grown in place): the old columns bitwise, the new
  ones zero, in place when nothing else holds the array, a copy (the holder untouched) when a
  view does; the whole projected search bitwise the concatenating code it replaced was checked
  with ARPACK's start fixed (not repeatable here: that code is gone).
"""

import importlib
import subprocess
import sys

import numpy as np
import pytest
import scipy.sparse as sp

import mbseig
from mbseig.eigen import measures
from mbseig.numerics import blas_limit, coo_sum, grow_columns, scatter


def _lstsq_fit(M, P, Q, tol):
    A = np.column_stack([M.ravel(), Q.ravel()])
    b = P.ravel()
    coef = np.linalg.lstsq(A, b, rcond=None)[0]
    return tuple(coef) if np.linalg.norm(A @ coef - b) <= tol * np.linalg.norm(b) else None


def test_is_symmetric_and_fro_match_the_plain_formulas():
    rng = np.random.default_rng(3)
    for _ in range(150):
        n = int(rng.integers(1, 140))  # across the 64-row slabs of the blocked test
        A = rng.standard_normal((n, n)) * 10.0 ** int(rng.integers(-60, 60))
        S = A + A.T
        B = S.copy()
        i, j = rng.integers(0, n, 2)
        if i != j:
            B[i, j] += 10.0 ** float(rng.uniform(-15, -11)) * np.abs(S).max()
        for X in (A, S, B):
            ref = np.linalg.norm(X - X.T) <= 1e-13 * np.linalg.norm(X)
            assert measures.is_symmetric(X, 1e-13) == ref
            assert measures.fro(X) == pytest.approx(np.linalg.norm(X), rel=1e-13)
    big = np.full((3, 3), 1e200)  # squares overflow: the scaled path answers
    assert measures.fro(big) == pytest.approx(3e200, rel=1e-14)
    tiny = np.full((3, 3), 1e-200)  # squares underflow: likewise
    assert measures.fro(tiny) == pytest.approx(3e-200, rel=1e-14)
    assert measures.fro(np.zeros((4, 4))) == 0.0 and measures.is_symmetric(np.zeros((4, 4)), 1e-13)


def test_dense_rayleigh_fit_never_misses_what_lstsq_finds():
    rng = np.random.default_rng(5)
    accepted = 0
    for _ in range(300):
        n = int(rng.integers(1, 25))
        A = rng.standard_normal((n, n)) * 10.0 ** int(rng.integers(-40, 40))
        K = A + A.T
        M = np.diag(rng.uniform(0.5, 2.0, n))
        a, b = rng.standard_normal(2) * 10.0 ** rng.integers(-4, 4, 2)
        P = a * M + b * K
        for P2 in (P, P + 1e-6 * np.linalg.norm(P) * np.eye(n)[::-1], rng.standard_normal((n, n))):
            fast, ref = measures.rayleigh_fit(M, P2, K, 1e-12), _lstsq_fit(M, P2, K, 1e-12)
            if ref is not None:
                assert fast is not None
            if fast is not None:
                accepted += 1
                assert np.linalg.norm(P2 - fast[0] * M - fast[1] * K) <= 1e-12 * np.linalg.norm(P2)
    assert accepted >= 250  # the exact combinations (and the n = 1 perturbations) are found
    # Q = 0 and Q ∥ M (the lstsq fallback) still fit
    M = np.eye(4)
    assert measures.rayleigh_fit(M, 0.3 * M, np.zeros((4, 4)), 1e-12) == pytest.approx((0.3, 0.0))
    fit = measures.rayleigh_fit(M, 0.3 * M, 2.0 * M, 1e-12)
    assert fit is not None and abs(fit[0] + 2.0 * fit[1] - 0.3) <= 1e-14


def test_probe_rayleigh_fit_never_misses_what_lstsq_finds():
    """The sparse (probe) fit by the dense fit's inner products: whatever lstsq on the same probe
    products accepts is accepted (an exact combination always), and what is accepted passes the
    residual test on those products, recomputed here."""
    rng = np.random.default_rng(6)
    for _ in range(40):
        n = int(rng.integers(2, 400))
        off = rng.standard_normal(n - 1) * 10.0 ** int(rng.integers(-30, 30))
        K = sp.diags([off, rng.uniform(1.0, 3.0, n) * max(1.0, abs(off).max()), off],
                     [-1, 0, 1]).tocsr()
        M = sp.diags(rng.uniform(0.5, 2.0, n)).tocsr()
        a, b = rng.standard_normal(2) * 10.0 ** rng.integers(-4, 4, 2)
        for P in (a * M + b * K, a * M + b * K + 1e-6 * abs(a) * sp.eye(n, k=1),
                  sp.diags(rng.standard_normal(n))):
            fast = measures.rayleigh_fit(M, P, K, 1e-12, probes=3)
            V = np.random.default_rng(0).standard_normal((n, 3))
            ref = _lstsq_fit(M @ V, P @ V, K @ V, 1e-12)  # the probes rayleigh_fit draws
            if ref is not None:
                assert fast is not None
            if fast is not None:
                R = P @ V - fast[0] * (M @ V) - fast[1] * (K @ V)
                assert np.linalg.norm(R) <= 1e-12 * np.linalg.norm(P @ V)
        assert measures.rayleigh_fit(M, a * M + b * K, K, 1e-12, probes=3) is not None


def test_scatter_is_bitwise_the_meshgrid_assembly():
    rng = np.random.default_rng(0)
    for _ in range(100):
        blocks = []
        for _ in range(15):
            r = rng.integers(0, 9, rng.integers(0, 4))
            c = rng.integers(0, 9, rng.integers(1, 4))
            blocks.append((r, c, rng.standard_normal((r.size, c.size))))
        triplets = []
        for r, c, v in blocks:
            if v.size:
                rr, cc = np.meshgrid(r, c, indexing="ij")
                triplets.append((rr.ravel(), cc.ravel(), v.ravel()))
        A, B = scatter(9, 9, blocks), coo_sum(9, 9, triplets)
        assert np.array_equal(A.indptr, B.indptr) and np.array_equal(A.indices, B.indices)
        assert np.array_equal(A.data, B.data)


def test_row_blocks_agree_with_one_block(monkeypatch):
    """The measures accumulate per-column sums over blocks of rows (measures.ROW_BLOCK): the
    blocked values equal the one-block values up to the summation order of the norms and
    inner products (reference: the same formulas in one block; tolerance 1e-14 relative, a few
    ulp per block over 30 blocks), and η_c, a maximum over rows, is bitwise the same."""
    rng = np.random.default_rng(2)
    n, k = 60, 9
    M = sp.diags(rng.uniform(1, 2, n), format="csr")
    K = sp.random(n, n, density=0.1, random_state=1, format="csr") * 100 + sp.eye(n) * 500
    P = sp.random(n, n, density=0.05, random_state=2, format="csc")  # not CSR: rows sliced as CSR
    s = rng.standard_normal(k) * 30 + 1j * rng.standard_normal(k) * 30
    X = rng.standard_normal((n, k)) + 1j * rng.standard_normal((n, k))
    Y = rng.standard_normal((n, k)) + 1j * rng.standard_normal((n, k))
    X2 = rng.standard_normal((n, k)) + 1j * rng.standard_normal((n, k))
    ops, norms = (M, P, K), (measures.fro(M), measures.fro(P), measures.fro(K))

    def run():
        eta, MX, PX = measures.backward_errors(ops, s, X, norms)
        kap = measures.conditions(s, X, Y, MX, PX, norms)
        ec, kc = measures.componentwise(ops, s, X, Y)
        Xb, eb, _, _, n2 = measures.better_half(ops, s, X, X2, norms)
        return eta, kap, ec, kc, Xb, eb, n2

    one = run()
    assert len(measures._row_blocks(X)) == 1
    monkeypatch.setattr(measures, "ROW_BLOCK", 2 * k)  # two rows a block
    assert len(measures._row_blocks(X)) == 30
    blocked = run()
    assert np.array_equal(one[2], blocked[2])  # η_c: a maximum, no summation
    assert np.array_equal(one[4], blocked[4]) and one[6] == blocked[6]  # same halves kept
    for a, b in zip(one[:2] + one[3:4] + one[5:6], blocked[:2] + blocked[3:4] + blocked[5:6],
                    strict=True):
        np.testing.assert_allclose(b, a, rtol=1e-14, atol=0)
    # and against the definitions, dense and direct (module docstring of measures)
    Md, Pd, Kd = (A.toarray() for A in ops)
    for j in range(k):
        T = s[j] ** 2 * Md + s[j] * Pd + Kd
        w = abs(s[j]) ** 2 * norms[0] + abs(s[j]) * norms[1] + norms[2]
        eta_j = np.linalg.norm(T @ X[:, j]) / (w * np.linalg.norm(X[:, j]))
        np.testing.assert_allclose(blocked[0][j], eta_j, rtol=1e-13)


def test_lazy_package_exports_every_name():
    for name in mbseig.__all__:
        obj = getattr(mbseig, name)
        assert obj is not None
    for name, module in (("write_report", "mbseig.studies.report_data"),
                         ("check_modes", "mbseig.check"), ("run_sweep", "mbseig.studies"),
                         ("modes", "mbseig.modal")):
        assert getattr(mbseig, name) is getattr(importlib.import_module(module), name)
    assert {"write_report", "check_modes", "run_sweep"} <= set(mbseig.__all__) <= set(dir(mbseig))
    with pytest.raises(AttributeError):
        mbseig.no_such_name  # noqa: B018


def test_import_mbseig_loads_no_stage():
    code = ("import sys, mbseig; bad = [m for m in ('scipy', 'mbseig.casefile', 'mbseig.eigen', "
            "'matplotlib', 'control', 'dask') if m in sys.modules]; print(bad)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_blas_limit_is_a_context():
    with blas_limit(1):
        x = np.linalg.solve(np.eye(3) * 2.0, np.ones(3))
    assert np.array_equal(x, np.full(3, 0.5))
    with blas_limit(None):
        pass


@pytest.mark.parametrize("case", ["hand_device", "four_bar", "spatial_double_pendulum",
                                  "rssr_four_bar", "chain_damped"])
def test_dense_model_assembly_is_scatter_bitwise(case):
    """Reference: numerics.scatter of the model's element blocks (dense), at perturbed q."""
    from conftest import CASES

    from mbseig.casefile import load_case
    from mbseig.model.base import BatchForce

    m = load_case(CASES / f"{case}.toml")
    rng = np.random.default_rng(3)
    q = m.q_init + 1e-3 * rng.standard_normal(m.n)
    lam = rng.standard_normal(m.n_constraints)
    qd = np.zeros(m.n)
    singles = [f for f in m.forces if not isinstance(f, BatchForce)]
    parts = [(f.idx, f.jacobians(q, qd)) for f in singles]
    K, C = m._force_jacobians(q, None, True)
    batches = [f for f in m.forces if isinstance(f, BatchForce)]
    Kb = scatter(m.n, m.n, [(i, i, k) for i, (k, _) in parts], dense=True)
    Cb = scatter(m.n, m.n, [(i, i, c) for i, (_, c) in parts], dense=True)
    if batches:
        Kb = Kb + coo_sum(m.n, m.n, [b.jacobian_coo(q, qd)[0] for b in batches], dense=True)
        Cb = Cb + coo_sum(m.n, m.n, [b.jacobian_coo(q, qd)[1] for b in batches], dense=True)
    assert np.array_equal(K, Kb) and np.array_equal(C, Cb)
    off = np.cumsum([0] + [c.n_eq for c in m.constraints])
    G = scatter(m.n_constraints, m.n, [(np.arange(off[k], off[k + 1]), c.idx, c.jac(q))
                                       for k, c in enumerate(m.constraints)], dense=True)
    H = scatter(m.n, m.n, [(c.idx, c.idx, c.hess(q, lam[off[k]:off[k + 1]]))
                           for k, c in enumerate(m.constraints)], dense=True)
    assert np.array_equal(m._phi_q(q, True), G)
    assert np.array_equal(m._constraint_hessian(q, lam, True), H)
    # and the sparse forms hold the same values
    assert np.array_equal(m._phi_q(q, False).toarray(), G)
    assert np.array_equal(m.force_jacobians(q)[0].toarray(), K)


def test_direct_lapack_calls_are_scipy_bitwise():
    """Reference: scipy.linalg.solve_triangular and scipy.linalg.qr(pivoting=True)."""
    import scipy.linalg as sla

    from mbseig.eigen.dense_paths import _lower_solve
    from mbseig.modal.bounds import _pivoted_r

    rng = np.random.default_rng(5)
    for n in (1, 3, 7, 20):
        L = np.tril(rng.standard_normal((n, n))) + n * np.eye(n)
        B = rng.standard_normal((n, n))
        assert np.array_equal(_lower_solve(L, B), sla.solve_triangular(L, B, lower=True))
        assert np.array_equal(_lower_solve(L, B.T), sla.solve_triangular(L, B.T, lower=True))
        assert np.array_equal(_lower_solve(L, B, trans=1),
                              sla.solve_triangular(L, B, lower=True, trans="T"))
        Bc = B + 1j * rng.standard_normal((n, n))  # complex: scipy's own function
        assert np.array_equal(_lower_solve(L, Bc), sla.solve_triangular(L, Bc, lower=True))
        for k in (1, 2, min(n, 4)):
            X = rng.standard_normal((n, k))
            Xc = X + 1j * rng.standard_normal((n, k))
            for A in (X, Xc):
                assert np.array_equal(np.diag(_pivoted_r(A.copy())),
                                      np.diag(sla.qr(A, mode="r", pivoting=True)[0]))


def test_all_pairs_ball_query_is_the_row_search():
    """Reference: the row-by-row flatnonzero search the vectorized query replaced."""
    from mbseig.modal.bounds import AllPairs

    rng = np.random.default_rng(7)
    for k in (1, 2, 5, 12):
        pts = rng.standard_normal((k, 2))
        pts[-1] = pts[0]  # an exact duplicate
        tree = AllPairs(pts)
        r = rng.uniform(0, 1.5, k)
        d = np.abs((pts[:, 0] + 1j * pts[:, 1])[:, None] - tree.z[None, :])
        assert tree.query_ball_point(pts, r) == [np.flatnonzero(d[i] <= r[i]).tolist()
                                                 for i in range(k)]
        assert tree.query_ball_point(pts[0], 0.0) == np.flatnonzero(d[0] <= 0.0).tolist()


def test_blas_held_skips_the_small_solve_cap():
    """Inside a caller's one-thread cap the small dense solve adds none; outside it caps as
    blas_limit(1) does (a null context too where threadpoolctl is missing)."""
    import contextlib

    from mbseig.eigen.dense import small_blas, blas_held

    def null(c):
        with c:  # entered and left, as the solves use it: a cap made here is undone here
            pass
        return isinstance(c, contextlib.nullcontext)

    # blas_limit(1) caps only where threadpoolctl is installed and BLAS runs on more threads
    capping = not null(blas_limit(1))
    assert null(small_blas(3)) is not capping
    with blas_held(1):
        assert null(small_blas(3))
        with blas_held(2):  # a cap of two threads: the small solve still caps at one
            assert null(small_blas(3)) is not capping
        assert null(small_blas(3))
    assert null(small_blas(3)) is not capping
    assert null(small_blas(500))  # large: never capped here


def test_grow_columns_keeps_the_columns_in_place_or_by_copy():
    class Holder:
        pass

    rng = np.random.default_rng(5)
    h = Holder()
    h.A = np.asfortranarray(rng.standard_normal((1000, 6)))
    old, before = h.A.copy(), id(h.A)
    out = grow_columns(h, "A", 10)
    assert out is h.A and id(out) == before  # grown in place: no second array
    assert out.flags.f_contiguous and out.shape == (1000, 10)
    assert np.array_equal(out[:, :6], old) and not np.any(out[:, 6:])
    view = h.A[:, :3]  # a live view: resize would invalidate it, so a copy is made
    out = grow_columns(h, "A", 12)
    assert out is h.A and out is not view.base and out.flags.f_contiguous
    assert np.array_equal(out[:, :6], old) and not np.any(out[:, 6:])
    assert np.array_equal(view, old[:, :3])
