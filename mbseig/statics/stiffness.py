"""The reduced tangent stiffness at an equilibrium: static stability and self-stress
(docs/design.md, "Equilibrium").

With N an orthonormal basis of null Φ_q(q₀) (the rank rule of :mod:`mbseig.numerics`),

    K_r = Nᵀ (K + Σ λ₀,k ∇²Φ_k) N.

Static stability.  The equilibrium is statically unstable (a divergence) when K_r is symmetric
(within ``SYMMETRY_TOL``) and has an eigenvalue below −``stiffness_tol``·‖K_r‖ (the potential is
not a minimum: unstable with any dissipation), or when K_r is not symmetric and det K_r < 0 (an
odd number of negative real eigenvalues: a real positive root s of det(M s² + P s + K_r) for any
M > 0, P).  ``index`` counts the negative eigenvalues.  A non-symmetric K_r with det K_r > 0, or
with an eigenvalue within the tolerance of zero (the sign of det K_r undecided, ``zero``), is
left to the modes ("undetermined" here).  The common case, a symmetric K_r positive definite
beyond the tolerance, is decided by norm bounds and one Cholesky factorization of the shifted
K_r (Sylvester's law of inertia: :func:`_positive_definite`); only the others compute
eigenvalues, with the exact 2-norms.

Self-stress.  Redundant constraints leave Φ_qᵀ μ = 0 for μ ≠ 0 (the left null space of Φ_q):
every λ₀ + t μ balances the loads, statics cannot choose t, and the stiffness changes with it by
t Nᵀ H(μ) N.  A state μ (unit norm) whose ‖Nᵀ H(μ) N‖ exceeds ``self_stress_tol``·‖H(μ)‖ changes
the stiffness: reported with the constraints it loads.  A compliance c_k per constraint (the
extension of the element per unit of the force it carries, as the element reports it) makes the
multipliers those of least complementary energy, Σ c_k N_k(λ)² minimal among the λ that balance
the loads (Menabrea): :func:`compliant_multipliers`.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..model.tangent import local_basis, triad_coordinates
from ..numerics import dense
from .result import StaticStability

__all__ = ["reduced_stiffness", "static_stability", "self_stress_states", "compliant_multipliers",
           "STIFFNESS_TOL", "SYMMETRY_TOL", "SELF_STRESS_TOL"]

STIFFNESS_TOL = 1e-9  # relative: an eigenvalue of K_r below −tol·‖K_r‖ is a negative stiffness
SYMMETRY_TOL = 1e-10  # relative asymmetry below which K_r is treated as symmetric
SELF_STRESS_TOL = 1e-8  # relative stiffness change of a unit self-stress that counts


def _basis(model, q, rank_tol):
    """(N, left null space of Φ_q, Φ_q, rank).  A model with frames takes the local basis of
    :mod:`mbseig.model.tangent` (the triads by their tangent space, the joints component by
    component: no SVD of the whole Jacobian) where it leaves no constraint redundant (the left
    null space, the self-stress states, is then empty); otherwise the SVD of Φ_q."""
    Phi_q = dense(model.phi_q(q, dense=True))
    if Phi_q.shape[0] == 0:
        return np.eye(model.n), np.zeros((0, 0)), Phi_q, 0
    if triad_coordinates(model)[0].shape[0]:
        local = local_basis(model, q, rank_tol)
        if local.kept is None and local.rank == Phi_q.shape[0]:  # (sparse but for small ones)
            N = local.dense() if local.small else local.N
            return N, np.zeros((Phi_q.shape[0], 0)), Phi_q, local.rank
    U, s, Vt = sla.svd(Phi_q, full_matrices=True)
    rank = int(np.sum(s > rank_tol * s[0])) if s.size and s[0] > 0 else 0
    return Vt[rank:].T, U[:, rank:], Phi_q, rank


def reduced_stiffness(model, q, lam, rank_tol=1e-10):
    """(K_r, N) at q with multipliers λ."""
    N, _, Phi_q, _ = _basis(model, q, rank_tol)
    if sp.issparse(N):  # the local basis: Nᵀ K N from the sparse matrices
        K, _ = model.force_jacobians(q)
        if model.n_constraints:
            K = K + model.constraint_hessian(q, lam)
        return (N.T @ K @ N).toarray(), N
    K, _ = model.force_jacobians(q, dense=True)
    Kt = dense(K)
    if model.n_constraints:
        Kt = Kt + dense(model.constraint_hessian(q, lam, dense=True))
    if Phi_q.shape[0] == 0:  # N = I: Nᵀ K N is K itself (no two products of order n³)
        return np.array(Kt, dtype=float), N
    return N.T @ Kt @ N, N


def static_stability(model, q, lam, *, rank_tol=1e-10, stiffness_tol=STIFFNESS_TOL,
                     symmetry_tol=SYMMETRY_TOL) -> StaticStability:
    """The static-stability record (module docstring)."""
    return StaticStability(**_stability(model, q, lam, rank_tol, stiffness_tol, symmetry_tol))


def _stability(model, q, lam, rank_tol, stiffness_tol, symmetry_tol) -> dict:
    if model.n_constraints == 0 and model.n > SPARSE_CHECK_MIN:  # K_r = K, kept sparse
        K, _ = model.force_jacobians(q)
        if sp.issparse(K):
            fast = _positive_definite_sparse(K, stiffness_tol, symmetry_tol)
            if fast is not None:
                return {"dof": int(model.n), "stiffness_tol": stiffness_tol,
                        "symmetry_tol": symmetry_tol, **fast}
    Kr, N = reduced_stiffness(model, q, lam, rank_tol)
    rec = {"dof": int(Kr.shape[0]), "stiffness_tol": stiffness_tol, "symmetry_tol": symmetry_tol}
    if Kr.shape[0] == 0:
        return {**rec, "verdict": "stable", "index": 0, "symmetric": True, "min_eigenvalue": None,
                "direction": None}
    # decided by bounds and one Cholesky factorization above a few dozen unknowns (below, the
    # eigenvalues cost less than the bounds' Python and give the smallest one and its direction)
    fast = (_positive_definite(Kr, stiffness_tol, symmetry_tol)
            if Kr.shape[0] > SPARSE_CHECK_MIN else None)
    if fast is not None:
        return {**rec, **fast}
    S = Kr - Kr.T
    if not np.any(S):  # exactly symmetric: ‖K_r‖₂ = max |μ|, from the one eigh it needs
        mu, V = np.linalg.eigh(Kr)
        norm = float(np.max(np.abs(mu))) or 1.0
        asym = 0.0
    else:
        mu = None
        norm = float(np.linalg.norm(Kr, 2)) or 1.0
        asym = float(np.linalg.norm(S, 2)) / norm
    symmetric = asym <= symmetry_tol
    rec["symmetric"] = bool(symmetric)
    rec["asymmetry"] = asym
    if symmetric:
        if mu is None:
            mu, V = np.linalg.eigh(0.5 * (Kr + Kr.T))
        index = int(np.sum(mu < -stiffness_tol * norm))
        zero = int(np.sum(np.abs(mu) <= stiffness_tol * norm))
        rec.update(min_eigenvalue=float(mu[0]), index=index, zero=zero,
                   direction=N @ V[:, 0],
                   verdict="unstable" if index else ("neutral" if zero else "stable"))
        return rec
    mu, V = np.linalg.eig(Kr)
    real = np.abs(mu.imag) <= stiffness_tol * norm
    neg = real & (mu.real < -stiffness_tol * norm)
    index = int(np.sum(neg))
    # an eigenvalue within the tolerance of zero leaves the sign of det K_r undecided: an odd
    # count of negative ones then proves nothing (at p = 1e99 on Ziegler's pendulum the springs'
    # k is below the rounding of p k, K_r's small eigenvalue −k²/(p k) is rounding, and its
    # exact index, 2, is even)
    zero = int(np.sum(np.abs(mu) <= stiffness_tol * norm))
    k = int(np.argmin(np.where(real, mu.real, np.inf))) if real.any() else None
    rec.update(min_eigenvalue=None if k is None else float(mu[k].real), index=index, zero=zero,
               direction=None if k is None else N @ V[:, k].real,
               verdict="unstable" if index % 2 == 1 and not zero else
               ("undetermined" if index or zero else "stable?"))
    if rec["verdict"] == "stable?":  # no negative real eigenvalue: statics sees no divergence
        rec["verdict"] = "stable" if np.all(mu.real > stiffness_tol * norm) else "undetermined"
    return rec


def _norm_bounds(A):
    """(lower, upper) bounds of ‖A‖₂ that cost O(n²): ‖A‖_F/√r ≤ ‖A‖₂ ≤ min(‖A‖_F, √(‖A‖₁‖A‖_∞))."""
    fro = float(np.sqrt(np.einsum("ij,ij->", A, A)))
    a = np.abs(A)
    one, inf = float(a.sum(axis=0).max()), float(a.sum(axis=1).max())
    return fro / np.sqrt(min(A.shape)), min(fro, np.sqrt(one * inf))


def _positive_definite(Kr, stiffness_tol, symmetry_tol):
    """The record of a K_r shown symmetric and positive definite beyond its tolerance without
    an eigendecomposition, else None (the caller then decides from the eigenvalues).

    Symmetric: ‖K_r − K_rᵀ‖₂/‖K_r‖₂ ≤ ‖K_r − K_rᵀ‖_F/(‖K_r‖_F/√r) ≤ ``symmetry_tol`` (bounds;
    zero when K_r is exactly symmetric).  Positive beyond the tolerance: a Cholesky
    factorization of K_s − c·I, K_s = ½(K_r + K_rᵀ), c = ``stiffness_tol``·(an upper bound of
    ‖K_r‖₂), succeeds; by Sylvester's law of inertia every eigenvalue of K_s is then above
    c ≥ ``stiffness_tol``·‖K_r‖₂, so the index and the zero count are 0 exactly as the
    eigenvalues would give them.  Where the factorization fails (an eigenvalue at or below
    c: unstable, neutral or close to either) the eigenvalues decide, with the exact norms."""
    S = Kr - Kr.T
    lo, hi = _norm_bounds(Kr)
    if not (np.isfinite(hi) and hi > 0):
        return None
    if np.any(S):
        asym = float(np.sqrt(np.einsum("ij,ij->", S, S))) / lo
        if not asym <= symmetry_tol:
            return None
        Ks = 0.5 * (Kr + Kr.T)
    else:
        asym, Ks = 0.0, Kr
    if not _cholesky_succeeds(Ks, stiffness_tol * hi):
        return None
    return {"symmetric": True, "asymmetry": asym, "min_eigenvalue": None, "index": 0, "zero": 0,
            "direction": None, "verdict": "stable"}


SPARSE_CHECK_MIN = 64  # order of K_r above which the factorization decides (a model without
# constraints: on its sparse K)


def _positive_definite_sparse(K, stiffness_tol, symmetry_tol):
    """:func:`_positive_definite` on a sparse K (a model without constraints: K_r = K), with
    the same bounds from its stored entries and a banded factorization where K is banded;
    None where it does not decide (the caller then forms the dense K_r)."""
    K = sp.csr_matrix(K, dtype=float, copy=True)
    K.sum_duplicates()
    n = K.shape[0]
    a = abs(K)
    fro = float(np.sqrt(np.dot(K.data, K.data)))
    one, inf = float(a.sum(axis=0).max()), float(a.sum(axis=1).max())
    lo, hi = fro / np.sqrt(n), min(fro, np.sqrt(one * inf))
    if not (np.isfinite(hi) and hi > 0):
        return None
    S = (K - K.T).tocsr()
    if S.nnz and np.any(S.data):
        asym = float(np.sqrt(np.dot(S.data, S.data))) / lo
        if not asym <= symmetry_tol:
            return None
        K = (0.5 * (K + K.T)).tocsr()
    else:
        asym = 0.0
    C = K.tocoo()
    low = C.row >= C.col
    r, c, v = C.row[low], C.col[low], C.data[low]
    band = int(np.max(r - c, initial=0))
    if band > n * BANDED_MAX:
        return None
    ab = np.zeros((band + 1, n))
    np.add.at(ab, (r - c, c), v)
    ab[0] -= stiffness_tol * hi
    try:
        sla.cholesky_banded(ab, lower=True, overwrite_ab=True, check_finite=False)
    except np.linalg.LinAlgError:
        return None
    return {"symmetric": True, "asymmetry": asym, "min_eigenvalue": None, "index": 0, "zero": 0,
            "direction": None, "verdict": "stable"}


# half-bandwidth, relative to the order, up to which the banded factorization runs
BANDED_MAX = 1 / 16


def _cholesky_succeeds(A, shift) -> bool:
    """Whether A − shift·I (A symmetric) has a Cholesky factorization: dense LAPACK ``potrf``,
    or its banded form ``pbtrf`` when A is banded (a chain's tridiagonal stiffness: O(n b²)
    instead of O(n³))."""
    n = A.shape[0]
    band = None
    if n > 64:  # the half-bandwidth: diagonals counted outwards until they hold every nonzero
        left, k = int(np.count_nonzero(A)), 0
        while k <= n * BANDED_MAX:
            left -= np.count_nonzero(np.diagonal(A, k)) + (np.count_nonzero(np.diagonal(A, -k))
                                                          if k else 0)
            if left == 0:
                band = k
                break
            k += 1
    try:
        if band is None:
            sla.cholesky(A - shift * np.eye(n), lower=True, check_finite=False, overwrite_a=True)
        else:  # lower banded storage: ab[k, j] = A[j + k, j]
            ab = np.zeros((band + 1, n))
            for k in range(band + 1):
                ab[k, :n - k] = np.diagonal(A, -k)
            ab[0] -= shift
            sla.cholesky_banded(ab, lower=True, overwrite_ab=True, check_finite=False)
    except np.linalg.LinAlgError:
        return False
    return True


def self_stress_states(model, q, *, rank_tol=1e-10, tol=SELF_STRESS_TOL, states=None) -> list:
    """Self-stress states that change the stiffness: [{"constraints", "mu", "stiffness_change"}].

    states : columns spanning the self-stress states to examine (default: the whole left null
        space of Φ_q).
    """
    N, Uo, Phi_q, rank = _basis(model, q, rank_tol)
    Uo = Uo if states is None else states
    out = []
    if Uo.shape[1] == 0:
        return out
    names = model.constraint_row_names()
    # an orthonormal basis of the stiffness changes Nᵀ H(μ) N over the states: one record per
    # independent change (the states that change nothing are dropped)
    changes = []
    for j in range(Uo.shape[1]):
        H = dense(model.constraint_hessian(q, Uo[:, j], dense=True))
        changes.append((N.T @ H @ N).ravel() / _carried_stiffness(model, q, Uo[:, j]))
    C = np.array(changes).T  # columns: the change per state
    if not C.size:
        return out
    Uc, sc, Vct = np.linalg.svd(C, full_matrices=False)
    for j in range(sc.size):
        if sc[j] <= tol:
            continue
        mu = Uo @ Vct[j]
        mu /= np.linalg.norm(mu)
        loaded = sorted({names[i] for i in np.flatnonzero(np.abs(mu) > 1e-3 * np.abs(mu).max())})
        out.append({"constraints": loaded, "mu": mu, "stiffness_change": float(sc[j])})
    return out


def _carried_stiffness(model, q, mu) -> float:
    """Σ_e ‖H_e(μ_e)‖_F: the constraint stiffness a state μ carries, element by element.  The
    scale of a stiffness change: the norm of the sum H(μ) would be only rounding where the
    elements' parts cancel (two copies of one rod, one in tension and one in compression), and
    rounding divided by rounding is not a change."""
    total, k = 0.0, 0
    for c in model.constraints:
        part = mu[k:k + c.n_eq]
        k += c.n_eq
        if np.any(part):
            total += float(np.linalg.norm(dense(c.hess(q, part))))
    return total if total > 0 and np.isfinite(total) else 1.0


def _force_per_multiplier(c, q):
    """d(reaction)/dλ of a one-row element (the reaction is linear in λ), as a norm."""
    cols = []
    for k in range(c.n_eq):
        e = np.zeros(c.n_eq)
        e[k] = 1.0
        v = c.reaction(q, e)["value"]
        cols.append(np.atleast_1d(np.asarray(v, dtype=float)))
    return np.column_stack(cols)


def compliant_multipliers(model, q, lam, compliance: dict, *, rank_tol=1e-10):
    """λ of least complementary energy ½ Σ c_k |N_k(λ)|² among λ + span(self-stress states),
    with ``compliance`` = {constraint name: c} (the element's extension per unit of the force
    it reports, e.g. m/N for a rod).  Returns (λ, the states the compliance leaves
    undetermined, as columns)."""
    _, Uo, _, _ = _basis(model, q, rank_tol)
    if Uo.shape[1] == 0:
        return lam, Uo
    m = model.n_constraints
    W = np.zeros((m, m))
    k = 0
    for c in model.constraints:
        cval = compliance.get(c.name)
        if cval is not None:
            B = _force_per_multiplier(c, q)
            W[k:k + c.n_eq, k:k + c.n_eq] = float(cval) * (B.T @ B)
        k += c.n_eq
    G = Uo.T @ W @ Uo
    u, sv, vt = np.linalg.svd(G)
    keep = sv > 1e-12 * max(float(sv.max(initial=0.0)), 1e-300)
    t = -(vt[keep].T @ ((u[:, keep].T @ (Uo.T @ W @ lam)) / sv[keep]))
    return lam + Uo @ t, Uo @ vt[~keep].T
