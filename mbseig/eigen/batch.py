"""Many small real dense problems at once: the eigh and companion paths with a leading batch axis.

``M, P, Q`` of shape (B, n, n) are B problems of one order n (the points of a sweep or a sample
set).  Each numpy call works on all B of them (stacked Cholesky, ``eigh`` and ``eig``, products
by ``matmul``), so that the Python cost of a problem is shared by the batch.  The mathematics is
that of the dense driver's paths (:mod:`mbseig.eigen.dense_paths`) and of its measures
(:mod:`mbseig.eigen.measures`):

- structure: M symmetric positive definite (Cholesky M = L Lᵀ); P = 0 with Q symmetric takes
  ``eigh`` (s = ±√(−ω²) of eigh(L⁻¹QL⁻ᵀ)), anything else the mass-normalized ``companion``
  [[0, I], [−Q̃/γ², −P̃/γ]] of P̃ = L⁻¹PL⁻ᵀ, Q̃ = L⁻¹QL⁻ᵀ, γ² = ‖Q̃‖_F/√n, solved by ``eig``;
- vectors: of the companion, the better half (the one with the smaller η) of each column;
- left vectors: x̄ where M, P and Q are symmetric; otherwise the rows of the inverse of the
  companion's eigenvector matrix (W = Z⁻ᴴ), each checked by its own backward error;
- η (normwise backward error) and κ (normwise condition number) of every pair by the formulas of
  :mod:`mbseig.eigen.measures`, in the reversed polynomial for |s| > 1.

A problem the batch does not cover is marked (``covered`` False, with the reason) and must take
the general driver (:func:`mbseig.eigen.solve`) on its own: non-finite entries, magnitudes that
need scaling, a mass matrix that is not symmetric positive definite or too ill-conditioned
(cond > COMPANION_COND), a pair whose η exceeds :data:`~mbseig.eigen.dense_paths.REFINE_ETA` or
whose left vector fails its check.  The general driver refines, scales, verifies and falls back
to QZ; the batch never guesses.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .dense import COMPANION_COND, STRUCTURED_COND
from .dense_paths import REFINE_ETA
from .small_measures import coefficients, ratio

__all__ = ["BatchSolution", "solve_batch", "batch_norms", "solve_descriptor_batch", "E_COND"]

#: a left vector from Z⁻ᴴ is kept where its own backward error ‖yᴴT(s)‖/(w(s)‖y‖) is at most
#: this (a nearly defective pair's inverse is inaccurate; the general driver's geev then decides)
LEFT_ETA = REFINE_ETA
#: a first-order pencil is solved as E⁻¹A where cond₂ E is at most this
#: (:func:`solve_descriptor_batch`)
E_COND = 1e8
_EPS = np.finfo(float).eps


@dataclass
class BatchSolution:
    """The pairs of B problems of order n (k = 2n eigenvalues each).

    eigenvalues (B, k) complex; vectors (B, n, k) unit right vectors; left (B, n, k) conjugated
    unit left vectors ȳ (yᴴ = columns transposed); backward_error, condition (B, k); norms (B, 3)
    = (‖M‖_F, ‖P‖_F, ‖Q‖_F); solver (B,) the path per problem ("eigh" / "companion", "" where
    not covered); covered (B,) bool; reason (B,) why a problem was not covered ("" where it
    was).  The rows of a problem that is not covered hold NaN.
    """

    eigenvalues: np.ndarray
    vectors: np.ndarray
    left: np.ndarray
    backward_error: np.ndarray
    condition: np.ndarray
    norms: np.ndarray
    solver: np.ndarray
    covered: np.ndarray
    reason: np.ndarray

    def __len__(self):
        return self.eigenvalues.shape[0]


def batch_norms(M, P, Q):
    """(B, 3): the Frobenius norms of M, P, Q per problem."""
    return np.stack([np.sqrt(np.einsum("bij,bij->b", A, A)) for A in (M, P, Q)], axis=1)


def _symmetric(A, nA, tol):
    D = A - A.transpose(0, 2, 1)
    return np.sqrt(np.einsum("bij,bij->b", D, D)) <= tol * nA


def _in_range(norms, lo=1e-100, hi=1e100, gamma_range=1e50):
    """Where :func:`mbseig.eigen.dense.problem_scaling` leaves the problem as given."""
    with np.errstate(divide="ignore", invalid="ignore"):
        logs = np.where(norms > 0, np.log(np.where(norms > 0, norms, 1.0)), np.nan)
    lM, lP, lQ = logs.T
    lg = np.where(~np.isnan(lM) & ~np.isnan(lQ), 0.5 * (lQ - lM),
                  np.where(~np.isnan(lM) & ~np.isnan(lP), lP - lM,
                           np.where(~np.isnan(lP) & ~np.isnan(lQ), lQ - lP, 0.0)))
    present = ~np.isnan(logs)
    big = np.where(present, logs, -np.inf).max(axis=1)
    small = np.where(present, logs, np.inf).min(axis=1)
    return (big <= np.log(hi)) & (small >= np.log(lo)) & (np.abs(lg) <= np.log(gamma_range))


def _unit(X):
    """X (B, n, k) with unit columns (a zero column stays zero)."""
    nrm = np.sqrt(np.einsum("bij,bij->bj", X.real, X.real) + np.einsum("bij,bij->bj", X.imag,
                                                                     X.imag))
    return X / np.where(nrm > 0, nrm, 1.0)[:, None, :]


def _residual_eta(M, P, Q, X, co):
    """η of the unit columns X (B, n, k) for the eigenvalues whose coefficients ``co`` holds."""
    MX, PX, QX = M @ X, P @ X, Q @ X
    R = MX * co["cM"][:, None, :] + PX * co["t"][:, None, :] + QX * co["cQ"][:, None, :]
    rn = np.sqrt(np.einsum("bij,bij->bj", R.real, R.real) + np.einsum("bij,bij->bj", R.imag,
                                                                     R.imag))
    return ratio(rn, co["w"]), MX, PX


def solve_batch(M, P, Q, *, sym_tol=1e-13, companion_cond=COMPANION_COND,
                verify_tol=1e-8) -> BatchSolution:
    """Every eigenpair of the B real problems (M s² + P s + Q) x = 0 (module docstring).

    Parameters
    ----------
    M, P, Q : ndarray, shape (B, n, n)
        Real matrices; P may be None (no damping).
    sym_tol : float
        Relative tolerance of the symmetry tests (‖A − Aᵀ‖_F ≤ sym_tol ‖A‖_F).
    companion_cond : float
        Largest condition number of M for the mass-normalized companion.
    verify_tol : float
        Largest backward error accepted (above it the problem is not covered).

    Returns
    -------
    BatchSolution
        The pairs, their measures, and which problems are covered.
    """
    M = np.asarray(M, float)
    Q = np.asarray(Q, float)
    P = np.zeros_like(M) if P is None else np.asarray(P, float)
    B, n = M.shape[0], M.shape[1]
    k = 2 * n
    s_out = np.full((B, k), np.nan + 0j)
    X_out = np.full((B, n, k), np.nan + 0j)
    Y_out = np.full((B, n, k), np.nan + 0j)
    eta_out = np.full((B, k), np.nan)
    kap_out = np.full((B, k), np.nan)
    solver = np.full(B, "", dtype=object)
    reason = np.full(B, "", dtype=object)
    finite = np.isfinite(M).all(axis=(1, 2)) & np.isfinite(P).all(axis=(1, 2)) \
        & np.isfinite(Q).all(axis=(1, 2))
    reason[~finite] = "non-finite entries"
    Mz, Pz, Qz = (np.where(finite[:, None, None], A, 0.0) for A in (M, P, Q))
    norms = batch_norms(Mz, Pz, Qz)
    ok = finite & _in_range(norms)
    reason[finite & ~ok] = "magnitudes that need scaling"
    symM = _symmetric(Mz, norms[:, 0], sym_tol)
    symQ = _symmetric(Qz, norms[:, 2], sym_tol)
    symP = _symmetric(Pz, norms[:, 1], sym_tol)
    Ms = 0.5 * (Mz + Mz.transpose(0, 2, 1))
    lam = np.linalg.eigvalsh(np.where(ok[:, None, None], Ms, np.eye(n)))
    pd = symM & (lam[:, 0] > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        cond = np.where(pd, lam[:, -1] / np.where(pd, lam[:, 0], 1.0), np.inf)
    reason[ok & ~(pd & (cond <= companion_cond))] = \
        "a mass matrix that is not well-conditioned symmetric positive definite"
    ok &= pd & (cond <= companion_cond)
    undamped = ok & ~Pz.any(axis=(1, 2)) & symQ & (cond <= STRUCTURED_COND)
    solver[undamped] = "eigh"
    solver[ok & ~undamped] = "companion"
    if not ok.any():
        return BatchSolution(s_out, X_out, Y_out, eta_out, kap_out, norms, solver, ok, reason)
    idx = np.flatnonzero(ok)
    L = np.linalg.cholesky(Ms[idx])
    Linv = np.linalg.inv(L)
    LinvT = Linv.transpose(0, 2, 1)
    Qt = Linv @ Qz[idx] @ LinvT
    Pt = Linv @ Pz[idx] @ LinvT
    und = undamped[idx]
    s = np.empty((idx.size, k), complex)
    X = np.empty((idx.size, n, k), complex)
    Yc = np.empty((idx.size, n, k), complex)
    symmetric = (symM & symP & symQ)[idx]
    if und.any():
        Qs = Qt[und]
        w, U = np.linalg.eigh(0.5 * (Qs + Qs.transpose(0, 2, 1)))
        V = LinvT[und] @ U
        root = np.sqrt(np.abs(w))
        sp_ = np.where(w >= 0, 1j * root, -root + 0j)  # s₊ (s² = −ω²), then s₋ = −s₊
        s[und] = np.concatenate([sp_, -sp_], axis=1)
        V2 = np.concatenate([V, V], axis=2).astype(complex)
        X[und] = _unit(V2)
        Yc[und] = X[und]
    comp = ~und
    if comp.any():
        Qc, Pc = Qt[comp], Pt[comp]
        nq = np.sqrt(np.einsum("bij,bij->b", Qc, Qc))
        gamma = np.where(nq > 0, np.sqrt(nq / np.sqrt(n)), 1.0)
        gamma = np.where(np.isfinite(gamma) & (gamma > 0), gamma, 1.0)
        nb = comp.sum()
        A = np.zeros((nb, k, k))
        A[:, :n, n:] = np.eye(n)
        A[:, n:, :n] = -Qc / (gamma**2)[:, None, None]
        A[:, n:, n:] = -Pc / gamma[:, None, None]
        mu, Z = np.linalg.eig(A)
        sc = gamma[:, None] * mu
        LT = LinvT[comp]
        X1 = LT @ Z[:, :n]
        with np.errstate(divide="ignore", invalid="ignore"):
            X2 = (LT @ Z[:, n:]) / np.where(mu != 0, mu, 1.0)[:, None, :]
        co = coefficients(sc, norms[idx][comp].T[:, :, None])
        X1u, X2u = _unit(X1), _unit(X2)
        Mi, Pi, Qi = Mz[idx][comp], Pz[idx][comp], Qz[idx][comp]
        e1 = _residual_eta(Mi, Pi, Qi, X1u, co)[0]
        e2 = _residual_eta(Mi, Pi, Qi, X2u, co)[0]
        take2 = (e2 < e1) & np.isfinite(X2u).all(axis=1)
        s[comp] = sc
        X[comp] = np.where(take2[:, None, :], X2u, X1u)
        Yc[comp] = X[comp]
        left = ~symmetric[comp]
        if left.any():
            Zl = Z[left]
            try:
                W = np.linalg.inv(Zl).conj().transpose(0, 2, 1)
            except np.linalg.LinAlgError:
                W = np.full_like(Zl, np.nan)
            Y = LT[left] @ W[:, n:]
            Yu = _unit(Y).conj()
            Yc[np.flatnonzero(comp)[left]] = Yu
    # η and κ of every pair of every covered problem
    co = coefficients(s, norms[idx].T[:, :, None])
    Mi, Pi, Qi = Mz[idx], Pz[idx], Qz[idx]
    eta, MX, PX = _residual_eta(Mi, Pi, Qi, X, co)
    # left check: ‖yᴴ T(s)‖ / (w ‖y‖) (T(s)ᵀ ȳ in the reversed polynomial)
    Yr = Yc
    RL = (Mi.transpose(0, 2, 1) @ Yr) * co["cM"][:, None, :] \
        + (Pi.transpose(0, 2, 1) @ Yr) * co["t"][:, None, :] \
        + (Qi.transpose(0, 2, 1) @ Yr) * co["cQ"][:, None, :]
    left_eta = ratio(np.sqrt(np.einsum("bij,bij->bj", RL.real, RL.real)
                             + np.einsum("bij,bij->bj", RL.imag, RL.imag)), co["w"])
    den = np.abs(np.einsum("bij,bij->bj", Yr, MX * co["dM"][:, None, :]
                           + PX * co["dP"][:, None, :]))
    kappa = ratio(co["w"], den)  # unit x and y: ‖x‖‖y‖ = 1
    with np.errstate(invalid="ignore"):  # (∞·0 where den = 0: replaced by ∞ below)
        kappa = np.where(co["big"], kappa * np.abs(s), kappa)
    kappa = np.where(den > 0, kappa, np.inf)
    kappa = np.where(co["w"] == 0, 0.0, kappa)
    good = (np.isfinite(s).all(axis=1) & ~np.isnan(eta).any(axis=1)
            & (eta <= min(verify_tol, REFINE_ETA)).all(axis=1)
            & (left_eta <= LEFT_ETA).all(axis=1))
    bad = idx[~good]
    reason[bad] = "a pair the batch cannot verify (η, or a left vector, above its bound)"
    solver[bad] = ""
    ok[bad] = False
    keep = idx[good]
    s_out[keep], X_out[keep], Y_out[keep] = s[good], X[good], Yc[good]
    eta_out[keep], kap_out[keep] = eta[good], kappa[good]
    return BatchSolution(s_out, X_out, Y_out, eta_out, kap_out, norms, solver, ok, reason)


def problem_solution(batch, b, M, P, Q):
    """The :class:`~mbseig.eigen.QEPSolution` of problem ``b`` of a batch (for the one-point
    measures that need one: componentwise bounds, a cluster's nullity)."""
    from .base import QEPSolution

    s = batch.eigenvalues[b]
    X = batch.vectors[b]
    Yc = batch.left[b]
    n = X.shape[0]
    return QEPSolution(s, X, batch.backward_error[b], batch.condition[b], batch.solver[b],
                       "batched", 0, tuple(float(x) for x in batch.norms[b]),
                       {"implementation": "batched"}, None, left_vectors=Yc, n_dof=n,
                       complex_problem=False, problem=(M, P, Q, 1.0))


def solve_descriptor_batch(E, A, *, e_cond=E_COND):
    """Eigenvalues of B first-order pencils s E − A (B, k, k) at once: stacked ``eig`` of E⁻¹A
    where E is well conditioned (cond₂ E ≤ ``e_cond``: then |s| ‖E‖/‖A‖ ≤ cond₂ E ≤ 1e8 for
    every eigenvalue, so none is infinite by the QZ path's chordal rule, inf_tol 1e-12, and
    none is dropped), right vectors from ``eig``, left vectors as the rows of (E X)⁻¹ (yᴴE is a
    left vector of E⁻¹A), η and κ by the formulas of :mod:`mbseig.eigen.descriptor`, the
    eigenvalues sorted as it sorts them.  A pencil is not covered (its reason given; it must
    take the QZ path, :func:`~mbseig.eigen.descriptor.solve_descriptor`) where E is not finite
    or not well conditioned, or a pair's right or left vector has a backward error above
    REFINE_ETA.  Returns {"s", "eta", "kappa" (B, k), "reason" (B,) ("" where covered),
    "vectors" and "left" (B, k, k: unit right vectors and conjugated unit left vectors, as
    columns in the order of s), "norms" (B, 2: ‖E‖_F, ‖A‖_F), "cond" (B,: cond₂ E)}."""
    B, k = E.shape[0], E.shape[1]
    reason = [""] * B
    s = np.zeros((B, k), complex)
    eta = np.zeros((B, k))
    kap = np.zeros((B, k))
    if k == 0:
        return _empty(s, eta, kap, reason)
    finite = np.isfinite(E).all(axis=(1, 2)) & np.isfinite(A).all(axis=(1, 2))
    cond = np.full(B, np.inf)
    cond[finite] = np.linalg.cond(E[finite])
    use = finite & (cond <= e_cond)
    for b in np.flatnonzero(~use):
        reason[b] = "E is not well conditioned"
    u = np.flatnonzero(use)
    if not u.size:
        return _empty(s, eta, kap, reason, cond)
    Eu, Au = E[u], A[u]
    w, X = np.linalg.eig(np.linalg.solve(Eu, Au))
    X = X / np.linalg.norm(X, axis=1, keepdims=True)
    EX = Eu @ X
    ok = np.linalg.cond(EX) < 1 / (k * _EPS)
    Yh = np.zeros_like(EX)
    Yh[ok] = np.linalg.inv(EX[ok])        # rows: yᴴ
    Yh = Yh / np.maximum(np.linalg.norm(Yh, axis=2, keepdims=True), 1e-300)
    nE = np.sqrt(np.einsum("bij,bij->b", Eu, Eu))
    nA = np.sqrt(np.einsum("bij,bij->b", Au, Au))
    wgt = np.abs(w) * nE[:, None] + nA[:, None]
    R = EX * w[:, None, :] - Au @ X
    e_r = np.linalg.norm(R, axis=1) / wgt
    Rl = np.einsum("bji,bik->bjk", Yh, Eu) * w[:, :, None] - Yh @ Au
    e_l = np.linalg.norm(Rl, axis=2) / wgt
    yEx = np.abs(np.einsum("bji,bij->bj", Yh, EX))
    with np.errstate(divide="ignore"):
        kp = np.where(yEx > 0, wgt / yEx, np.inf)
    good = ok & (e_r <= REFINE_ETA).all(axis=1) & (e_l <= REFINE_ETA).all(axis=1) \
        & np.isfinite(w).all(axis=1)
    for j, b in enumerate(u):
        if not good[j]:
            reason[b] = "a pair's backward error is above the batch's bound"
    order = np.lexsort((w.imag, w.real, np.abs(w)), axis=-1)
    take = lambda x: np.take_along_axis(x, order, axis=1)  # noqa: E731
    s[u], eta[u], kap[u] = take(w), take(e_r), take(kp)
    vectors = np.zeros((B, k, k), complex)
    left = np.zeros((B, k, k), complex)
    vectors[u] = np.take_along_axis(X, order[:, None, :], axis=2)
    left[u] = np.take_along_axis(np.swapaxes(Yh, 1, 2), order[:, None, :], axis=2)
    norms = np.zeros((B, 2))
    norms[u] = np.stack([nE, nA], axis=1)
    return {"s": s, "eta": eta, "kappa": kap, "reason": reason, "vectors": vectors,
            "left": left, "norms": norms, "cond": cond}


def _empty(s, eta, kap, reason, cond=None):
    """The result of :func:`solve_descriptor_batch` where no pencil is covered (or k = 0)."""
    B, k = s.shape
    return {"s": s, "eta": eta, "kappa": kap, "reason": reason,
            "vectors": np.zeros((B, k, k), complex), "left": np.zeros((B, k, k), complex),
            "norms": np.zeros((B, 2)), "cond": np.full(B, np.inf) if cond is None else cond}
