"""``partial-projected``: the lowest modes of a large model with general damping from its
undamped modes, with a count certificate (docs/design.md, "Eigensolvers"; docs/scaling.md).

Why.  Shift-invert Arnoldi on the 2n companion pencil (``partial-companion``) needs every
eigenvalue of a complex pair (2·n_modes + 1 of them) in a Krylov basis of vectors twice the
length of the undamped problem's; its Gram–Schmidt, not the one sparse LU, is what costs.  Here
the Krylov part is the undamped Lanczos alone (symmetric, n-vectors, n_modes + 6 values), and
the damping is brought in by a small dense problem and block solves with the same LU.

Method, on the bordered pencil of :mod:`mbseig.eigen.partial` (constraints kept as rows, one LU
of Q_b − σM_b, σ = 0 unless that is singular):

1. Lanczos (``eigsh``, shift-invert at σ) for the k_u = n_modes + 6 undamped modes nearest σ,
   then Rayleigh–Ritz on the x rows of their span: Φ_L, M-orthonormal, Λ_L = diag ω².  No
   purification is needed: ARPACK's vectors lie in the range of (Q_b − σM_b)⁻¹M_b, whose x rows
   are in null(G) (the pollution along M_b's null space is in the multiplier rows, unused).
2. Rayleigh–Ritz of the damped problem on the span W (x rows; every column has G w = 0): the
   small W ᵀ(s²M + sP + Q)W y = 0, all its eigenvalues (companion of size 2k, γ-scaled, LAPACK).
3. Refinement (residual inverse iteration with the fixed LU, accelerated by the growing
   subspace): for each of the n_modes + 2 Ritz pairs (s, x = W y) nearest 0 (more when a
   repeated value sits at the edge), u = −(Q_b − σM_b)⁻¹ [((s² + σ)M + sP) x; 0] (an exact
   pair is a fixed point: u = [x; λ], the multipliers included).  The solves
   A = (Q_b − σM_b)⁻¹[M W, P W; 0] are made once per basis vector, so u = −(A_M y (s² + σ) +
   A_P y s) is one dense product.  s is polished by the two-sided Rayleigh functional
   uᵀT(s)u = 0 (y = x̄ for symmetric M, P, Q) and η of (s, u) on the bordered problem decides:
   pairs above the target put Re u and Im u into W (M-orthogonalized twice, then mapped back
   onto null(G) by the Q-orthogonal projection Q_b⁻¹[Q v; 0] — the rounding of a small
   remainder need not satisfy G v = 0, and a basis off the constraints spoils the projection),
   and step 2 is repeated, until every pair meets the target (η ≤ 4ε, or η stops falling and
   is below ``verify_tol``); at most ``MAX_ITER`` rounds, else :class:`SolverError` naming the
   pairs.  The loop's η uses the definition of :func:`mbseig.eigen.measures.backward_errors`
   on the products it already has; the returned pairs are checked by that function in
   :func:`mbseig.eigen.solve_partial`, like every path's.

Completeness (the count certificate).  Let C = null(G), Φ = [Φ_L Φ_H] the M-orthonormal
undamped modes on C, Ω² = max Λ_L (Lanczos found every ω² below it: all of H has ω² ≥ Ω²),
Π = ΦᵀPΦ.  On the disc |s| ≤ R the eigenvalues of the damped problem are the zeros of
det S(s), S = T_LL − s² Π_LH T_HH⁻¹ Π_HL (T_LL(s) = s²I + sΠ_LL + Λ_L), once T_HH(s) is
invertible there.  With M, P, Q symmetric and M, Q positive definite on C:

- ‖T_HH(s)⁻¹‖ ≤ 1 / (Ω² (1 − Rρ − R²/Ω²)) after the scaling T_HH = Λ_H^½ (I + sΠ̃ + s²Λ_H⁻¹) Λ_H^½
  (numerical range), ρ = max |vᵀPv / vᵀQv| over v ∈ C ∩ H (Arnoldi on (I − Φ_LΦ_LᵀM) Q_b⁻¹P,
  an estimate, raised by 1 %);
- ‖Λ_H^-½ Π_HL‖² ≤ λ_max(Φ_LᵀP Q_b⁻¹ P Φ_L − Π_LL Λ_L⁻¹ Π_LL) (the sum over all modes of
  (φᵀPΦ_L)²/ω², which the LU gives, minus the L part);
- so ‖S(s) − T_LL(s)‖ ≤ τ(R) = R² ‖Λ_H^-½Π_HL‖² / (1 − Rρ − R²/Ω²) on the disc, and when
  σ_min(T_LL(z)) > τ(R) on the circle |z| = R (sampled, plus the Lipschitz bound between
  samples), S and T_LL have as many eigenvalues inside it (Rouché's theorem for matrix
  functions, Gohberg–Sigal 1971; Bindel–Hood 2013 for the pseudospectral form).

The coverage is *verified* when that number equals the number of refined pairs (conjugates
counted) inside the circle, for a radius R between the farthest refined |s| and the next Ritz
value of the last projection (the returned modes lie inside it).  The certificate takes the
converged Lanczos pairs as exact (ARPACK's own convergence test, as every partial path does) and
ρ from Arnoldi; both are said in the coverage note.
When a hypothesis fails (P not symmetric, M or Q not shown positive definite on C — by positive
symmetric pivots of A + αGᵀG —, Rρ + R²/Ω² ≥ 1, the circle too near an eigenvalue of T_LL, the
counts differ) the result says *not verified* and why; in the last three cases k_u is doubled
once first (more undamped modes raise Ω and may restore the bound).  ``auto``
then runs ``partial-companion`` instead (:func:`mbseig.eigen.solve_partial`).
"""

from __future__ import annotations

import itertools
import time

import numpy as np
import scipy.linalg as sla

from ..errors import SolverError
from ..numerics import LazyModule, grow_columns
from .blockop import BlockOp
from .measures import EPS, colnorm, is_symmetric
from .projected_certificate import (
    TIE,
    basis_products,
    certificate,
    hypotheses,
    small_qep,
)
from .selection import cluster_tol, pick, slots, with_partners
from .shift_invert import ShiftLU, undamped_partial

spla = LazyModule("scipy.sparse.linalg")

__all__ = ["EXTRA_UNDAMPED", "MAX_ITER", "projected_search"]

EXTRA_UNDAMPED = 6  # undamped modes beyond n_modes in the first Lanczos run
GUARD = 2  # Ritz pairs refined beyond n_modes (the ranking near the edge can change)
MAX_ITER = 12  # refinement rounds
REFINE_ETA = 4 * EPS  # a pair is refined until η ≤ 4ε (or η stops falling)
BLOCK = 4  # columns of a refined block and of a residual block (memory: 3 complex n-blocks)
SOLVE_BLOCK = 8  # right-hand sides per LU solve of the basis (the solve copies them twice)


def _rayleigh(s0, U, MU, PU, QU):
    """Root nearest s0 of uᵀ(s²M + sP + Q)u = 0 per column, from the products (bilinear: y = x̄
    for symmetric real matrices, so the value is stationary); s0 where it is not a polish."""
    a = np.einsum("ij,ij->j", U, MU)
    b = np.einsum("ij,ij->j", U, PU)
    c = np.einsum("ij,ij->j", U, QU)
    out = np.array(s0, complex)
    for j in range(U.shape[1]):
        if a[j] == 0 or not np.isfinite(a[j] * b[j] * c[j]):
            continue
        r = np.roots([a[j], b[j], c[j]])
        if r.size:
            cand = r[np.argmin(np.abs(r - s0[j]))]
            if abs(cand - s0[j]) <= 1e-3 * max(abs(s0[j]), 1e-300):  # only a polish
                out[j] = cand
    return out


class _Basis:
    """M-orthonormal basis W (n × k) of x rows (every column in null(G)), the projected
    matrices WᵀMW, WᵀPW, WᵀQW, and the solves A = (Q_b − σM_b)⁻¹[M W, P W; 0] (multiplier
    rows included, the columns of A_M then those of A_P): a refined vector of any x = W y is
    then u = −(A_M y (s² + σ) + A_P y s), one product, without a solve (module docstring,
    step 3)."""

    def __init__(self, M, P, Q, lu, m, Phi, lam, psym):
        self.M, self.P, self.Q, self.lu, self.m, self.psym = M, P, Q, lu, m, psym
        self.k = 0
        n = Phi.shape[0]
        self.W = np.zeros((n, 0), order="F")
        self.A = np.zeros((n + m, 0), order="F")
        self.Ms = self.Ps = self.Qs = np.zeros((0, 0))
        self._append(np.asfortranarray(Phi), lam)

    def _solve(self, F):
        rhs = np.zeros((F.shape[0] + self.m, F.shape[1]), order="F")
        rhs[:F.shape[0]] = F
        return self.lu.solve(rhs)

    def _append(self, V, lam=None):
        """Append M-orthonormal columns V; ``lam``: V are the Ritz vectors of the undamped
        problem (VᵀMV = I, VᵀQV = diag(lam)), so those two products are known."""
        n, k, b = V.shape[0], self.k, V.shape[1]
        rhs = np.zeros((n + self.m, 2 * b), order="F")  # [M V, P V; 0]: the products in place
        rhs[:n, :b], rhs[:n, b:] = self.M @ V, self.P @ V
        MV, PV = rhs[:n, :b], rhs[:n, b:]
        PtV = PV if self.psym else self.P.T @ V
        if k:
            W = grow_columns(self, "W", k + b)
            W[:, k:] = V
        else:
            W = V
        def grow(S, AV, AtV):
            out = np.empty((k + b, k + b))
            out[:k, :k] = S
            out[:, k:] = W.T @ AV
            out[k:, :k] = (W[:, :k].T @ AtV).T
            return out
        if lam is not None and k == 0:
            self.Ms, self.Qs = np.eye(b), np.diag(lam)
        else:
            QV = self.Q @ V
            self.Ms, self.Qs = grow(self.Ms, MV, MV), grow(self.Qs, QV, QV)
        self.Ps = grow(self.Ps, PV, PtV)
        del MV, PV, PtV
        for c0 in range(0, 2 * b, SOLVE_BLOCK):  # in place, a block at a time: the LU's copy
            c = slice(c0, min(c0 + SOLVE_BLOCK, 2 * b))  # and work array are a block's, not A's
            rhs[:, c] = self.lu.solve(rhs[:, c])
        self.W = np.asfortranarray(W)
        if k:  # columns [A_M | A_P] kept in that order, A grown in place (no second A)
            A = grow_columns(self, "A", 2 * (k + b))
            for j in range(2 * k - 1, k - 1, -1):  # the old A_P moves right by b, last first
                A[:, j + b] = A[:, j]
            A[:, k:k + b], A[:, 2 * k + b:] = rhs[:, :b], rhs[:, b:]
        else:
            self.A = np.asfortranarray(rhs)
        del rhs
        self.k = k + b

    def add(self, V):
        """Append the part of V's columns M-orthogonal to W (twice), dropping dependent ones;
        returns the number added."""
        V = np.array(V, dtype=float, order="F")
        W = self.W
        nrm0 = np.sqrt(np.abs(np.einsum("ij,ij->j", V, self.M @ V)))
        for _ in range(2):  # classical Gram–Schmidt, twice, in the M inner product
            V -= W @ (W.T @ (self.M @ V))
        G = V.T @ (self.M @ V)
        lam, E = np.linalg.eigh(0.5 * (G + G.T))
        keep = lam > 1e-20 * max(float(np.max(nrm0)) ** 2, np.finfo(float).tiny)
        if not np.any(keep):
            return 0
        V = V @ (E[:, keep] / np.sqrt(lam[keep]))
        # a small remainder carries the rounding of W c, which need not lie in null(G): back onto
        # it by the Q-orthogonal projection (Q_b⁻¹[Q v; 0], x rows), then M-orthogonal once more
        V = self._solve(self.Q @ V - self.lu.sigma * (self.M @ V))[:V.shape[0]]
        V -= W @ (W.T @ (self.M @ V))
        G = V.T @ (self.M @ V)
        L = np.linalg.cholesky(0.5 * (G + G.T))
        V = np.asfortranarray(sla.solve_triangular(L, V.T, lower=True).T)
        del W  # (so that W can grow in place)
        self._append(V)
        return V.shape[1]

    def refined(self, Y, s):
        """u = −(A_M y (s² + σ) + A_P y s) per column: one real product, unit columns."""
        k, p = self.k, s.size
        c2, c1 = Y * (s * s + self.lu.sigma)[None, :], Y * s[None, :]
        C = np.empty((2 * k, 2 * p))
        C[:k, :p], C[:k, p:] = c2.real, c2.imag
        C[k:, :p], C[k:, p:] = c1.real, c1.imag
        # R = A C formed as (Cᵀ Aᵀ)ᵀ: column-major like U, so that its halves go into U's real
        # and imaginary parts without a transposing copy (at 10⁶ rows 0.6 s against 2.2 s)
        U = np.empty((self.A.shape[0], p), complex, order="F")
        for j0 in range(0, p, BLOCK):  # a block of columns at a time: no full real copy of U
            j1 = min(j0 + BLOCK, p)
            R = (C[:, np.r_[j0:j1, p + j0:p + j1]].T @ self.A.T).T
            np.negative(R[:, :j1 - j0], out=U.real[:, j0:j1])
            np.negative(R[:, j1 - j0:], out=U.imag[:, j0:j1])
            del R
        U /= colnorm(U)
        return U


def _upper(s):
    tol = 1e-9 * np.maximum(np.abs(s), 1e-300)
    return np.flatnonzero(s.imag >= -tol), tol


def projected_search(run, want, *, verify_tol, max_iter=MAX_ITER):
    """The lowest ``want`` modes by the projected method (module docstring): a ``found`` dict
    like the other searches of :mod:`mbseig.eigen.partial`, with the certificate in
    ``coverage`` and the figures in ``projected``.  ``run`` is :func:`solve_partial`'s problem
    (:class:`~mbseig.eigen.shift_invert.Search`); the shift-invert LU, undamped Lanczos and
    selection helpers are those of the other searches."""
    M, P, Q = run.M, run.P, run.Q
    Mb, Qb = run.Mb, run.Qb
    n, nb = M.shape[0], Mb.shape[0]
    m = nb - n
    scale = run.w_scale
    if not (is_symmetric(M, run.sym_tol) and is_symmetric(Q, run.sym_tol)):
        raise SolverError("partial-projected needs symmetric M and Q (its basis is the undamped "
                          "modes, by Lanczos); use partial-companion")
    limit = run.dof - 1
    if want + GUARD > limit:
        raise SolverError(f"{want} modes asked of a problem with {run.dof} degrees of freedom: "
                          f"use the dense path")
    clock = {"start": time.perf_counter()}
    lu = ShiftLU(Mb, None, Qb, 0.0, scale * scale, quadratic=False)
    sig = lu.sigma
    clock["lu"] = time.perf_counter()
    Gc = Qb[n:, :n].tocsr() if m else None
    hyp = hypotheses(M, P, Q, Gc, run.sym_tol, sig)
    clock["hypotheses"] = time.perf_counter()
    k_u = min(want + EXTRA_UNDAMPED, limit)
    attempts = []
    while True:
        res = _one_attempt(run, want, k_u, lu, hyp, verify_tol, max_iter, n, m, clock)
        attempts.append({"k_u": k_u, "iterations": res["iterations"], "basis": res["basis"],
                         "why": res["cert"]["why"]})
        if (res["cert"]["verified"] or not res["cert"].get("grow") or k_u >= limit
                or len(attempts) >= 2):
            break
        k_u = min(2 * k_u, limit)
    s, U = res["s"], res["U"]
    cert = res["cert"]
    # the modes kept: n_modes nearest 0 by |s| (a repeated one whole), each with its partner
    upper, tol = _upper(s)
    slot = slots(s[upper], U[:, upper], cluster_tol(scale))
    first = np.flatnonzero(slot == np.arange(slot.size))
    idx, d, note = pick(np.abs(s[upper[first]]), want, 0.0, None, scale)
    idx = np.flatnonzero(np.isin(slot, first[idx]))
    cols, conj, s_out = with_partners(upper[idx], s, tol)

    X = np.empty((U.shape[0], cols.size), complex, order="F")  # column by column: no copies
    for j, (i, cj) in enumerate(zip(cols, conj, strict=True)):
        X[:, j] = U[:, i].conj() if cj else U[:, i]
    figures = {k: res[k] for k in ("iterations", "basis", "eta_history")}
    del res, U
    verified = bool(cert["verified"]) and cert["R"] > d
    if cert["verified"] and not verified:
        cert["why"] = (f"the certified disc |s| < {cert['R']:.6g} does not reach the selection's "
                       f"edge {d:.6g}")
    why = cert["why"]
    basis = ("count certificate (Rouché on the undamped-mode projection; Lanczos pairs taken as "
             "exact, ρ an Arnoldi estimate)")
    cnote = (f"{basis}: the disc |s| < {cert['R']:.6g} holds {cert['n_inside']} eigenvalues and "
             f"all were computed, so every eigenvalue with |s| ≤ {d:.6g} is listed" if verified
             else f"not verified ({why}); the pairs returned are verified by η only")
    note = "; ".join(x for x in (note, cnote) if x)
    info = {"k_u": attempts[-1]["k_u"], "attempts": attempts, "iterations": figures["iterations"],
            "basis_size": figures["basis"], "lu_solves": lu.n_solves, "shift": float(sig),
            "eta_history": figures["eta_history"], "seconds": _stages(clock),
            "certificate": {k: v for k, v in cert.items() if k != "grow"}}
    return {"s": np.asarray(s_out, complex), "X1": X, "X2": X, "k": attempts[-1]["k_u"],
            "shifts": [float(sig)],
            "coverage": {"measure": "|s|", "omega_n": (0.0, d), "note": note, "verified": verified},
            "projected": info}


def _stages(clock):
    """Seconds per stage (the last attempt's) from the time stamps."""
    keys = list(clock)
    return {k: round(clock[k] - clock[p], 4) for p, k in itertools.pairwise(keys)}


def _one_attempt(run, want, k_u, lu, hyp, verify_tol, max_iter, n, m, clock):
    M, P, Q = run.M, run.P, run.Q
    Mb, Qb = run.Mb, run.Qb
    norms = run.norms
    # unpurified: ARPACK's vectors lie in the range of (Q_b − σM_b)⁻¹M_b, whose x rows are in
    # null(G); the pollution along M_b's null space is in the multiplier rows only
    _, V, _ = undamped_partial(Mb, Qb, k_u, lu.sigma, run.w_scale ** 2, run.ncv,
                                run.maxiter, run.tol, False, lu=lu)
    Vx = np.asfortranarray(V[:n])
    del V
    Ms = Vx.T @ (BlockOp(M) @ Vx)
    Qs = Vx.T @ (Q @ Vx)
    lam, Y = sla.eigh(0.5 * (Qs + Qs.T), 0.5 * (Ms + Ms.T))  # Rayleigh–Ritz on the Lanczos span
    Phi = np.asfortranarray(Vx @ Y)
    del Vx
    clock["lanczos"] = time.perf_counter()
    p = want + GUARD
    Mo, Po, Qo, Qbo = BlockOp(M), BlockOp(P), BlockOp(Q), BlockOp(Qb)
    psym = is_symmetric(P, run.sym_tol)
    B = _Basis(Mo, Po, Qo, lu, m, Phi, lam, psym)
    hist = []
    target = REFINE_ETA
    for it in range(1, max_iter + 1):
        s_all, Ys = small_qep(B.Ms, B.Ps, B.Qs)
        up, _ = _upper(s_all)
        order = up[np.argsort(np.abs(s_all[up]), kind="stable")]
        edge = np.abs(s_all[order[min(p, order.size) - 1]])
        order = order[:p + int(np.sum(np.abs(s_all[order[p:]]) <= edge * (1 + TIE)))]  # a
        # repeated value at the edge is refined whole (else the certificate's count differs)
        U = B.refined(Ys[:, order], s_all[order])
        s = np.array(s_all[order], complex)
        rn = np.empty(s.size)
        for c0 in range(0, s.size, BLOCK):  # a block of columns at a time: small temporaries
            b = slice(c0, c0 + BLOCK)
            Ub = U[:, b]
            MU, PU, QU = Mo @ Ub[:n], Po @ Ub[:n], Qbo @ Ub
            sb = s[b] = _rayleigh(s[b], Ub[:n], MU, PU, QU[:n])
            MU *= (sb * sb)[None, :]  # the bordered residual, in place: s²MU + sPU + Q_b U
            PU *= sb[None, :]
            QU[:n] += np.add(MU, PU, out=MU)
            rn[b] = colnorm(QU)
            del MU, PU, QU, Ub
        eta = rn / ((np.abs(s) ** 2 * norms[0] + np.abs(s) * norms[1] + norms[2]) * colnorm(U))
        hist.append(float(np.max(eta)))
        stalled = len(hist) >= 3 and hist[-1] > 0.5 * min(hist[:-1])
        if np.all(eta <= target) or (stalled and hist[-1] <= verify_tol) or it == max_iter:
            break
        bad = np.flatnonzero(eta > target)
        new = [U[:n, j].real for j in bad] + [U[:n, j].imag for j in bad if abs(s[j].imag) > 0]
        if B.add(np.column_stack(new)) == 0:
            break
    if not np.all(eta <= verify_tol):
        badv = ", ".join(f"{z.real:.6g}{z.imag:+.6g}j (η={e:.1e})" for z, e in
                         zip(s[eta > verify_tol][:5], eta[eta > verify_tol][:5], strict=True))
        raise SolverError(f"partial-projected: {int(np.sum(eta > verify_tol))} of the {s.size} "
                          f"Ritz pairs nearest 0 did not reach η ≤ {verify_tol:g} after {it} "
                          f"refinement rounds (basis {B.k}): {badv}")
    basis_k = B.k
    # Q_b⁻¹[PΦ; 0] for the certificate is the first k_u columns of A_P (which starts at column
    # k whatever was appended): only its k_u × k_u products are kept
    products = basis_products(Po, Phi, B.A[:n, basis_k:basis_k + k_u]) if hyp[0] else None
    del B
    clock["refine"] = time.perf_counter()
    cert = certificate(lu, hyp, Phi, lam, products, s, s_all, Mo, Po, n, m)
    clock["certificate"] = time.perf_counter()
    return {"s": s, "U": U, "cert": cert, "iterations": it, "basis": basis_k,
            "eta_history": hist}
