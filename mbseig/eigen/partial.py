"""Partial spectrum of large sparse models: shift-invert Krylov methods
(docs/design.md, "Eigensolvers").

The modes asked for (``n_modes`` nearest a target frequency, or every mode in a band of ω_n)
of (M s² + P s + Q) x = 0 with sparse M, P, Q, without ever forming a dense matrix.  Paths
(recorded in the result as ``solver``):

``partial-eigh``          P = 0, M and Q symmetric: ARPACK Lanczos (``eigsh``) in shift-invert
                          mode on Q v = ω² M v with one sparse LU of Q − σM, σ = target².
``partial-proportional``  P = αM + βQ (Rayleigh damping, checked on random probe vectors): the
                          same undamped modes, then s² + (α + βω²) s + ω² = 0 per mode.
``partial-companion``     anything else: ARPACK Arnoldi (``eigs``) on the companion pencil
                          A − sB of size 2n, shift-invert operator (A − σB)⁻¹B applied through
                          one sparse LU of the n×n matrix σ²M + σP + Q:

                              (A − σB) z = B v  ⇔  (σ²M + σP + Q) z₁ = −(M v₂ + (P + σM) v₁),
                                                    z₂ = v₁ + σ z₁,         s = σ + 1/μ.

Constraints Φ_q = G (m × n) stay in the pencil as a bordered matrix instead of a null-space
basis (the multipliers λ are extra unknowns; their infinite eigenvalues map to μ = 0 and are
never returned):

    M_b = ┌ M  0 ┐    P_b = ┌ P  0 ┐    Q_b = ┌ Q    c Gᵀ ┐     (c = ‖Q‖/‖G‖ balances the rows)
          └ 0  0 ┘          └ 0  0 ┘          └ c G   0   ┘

Every returned pair is verified by its backward error on the (bordered) problem; a pair whose η
exceeds ``verify_tol`` or an ARPACK run that does not converge raises :class:`SolverError`.
Eigenvectors are returned in the coordinates of M (full coordinates when G is given).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import SolverError
from ..numerics import unit_columns
from .base import QEPSolution, partial_solvers, register, requested_path
from .measures import (
    better_half,
    conditions,
    fro,
    is_symmetric,
    proportional_real_error,
    rayleigh_fit,
    undamped_pairs,
)

__all__ = ["solve_partial", "sparse_structure"]


def _csr(A, n=None):
    if A is None:
        return sp.csr_matrix((n, n))
    A = sp.csr_matrix(A) if not sp.issparse(A) else A.tocsr()
    if np.iscomplexobj(A.data):
        raise SolverError("M, P and Q must be real matrices")
    return A.astype(float)


def sparse_structure(M, P, Q, *, sym_tol=1e-13, rayleigh_tol=1e-12, probes=3, seed=0):
    """(name, reason, extras) for sparse M, P, Q: the partial path ``auto`` takes.

    Proportional damping P = αM + βQ is fitted on ``probes`` random vectors v (P v against
    M v, Q v) and accepted when the relative residual is below ``rayleigh_tol``.
    """
    symmetric = is_symmetric(M, sym_tol) and is_symmetric(Q, sym_tol)
    if symmetric and fro(P) == 0:
        return "partial-eigh", "P = 0, M and Q symmetric", {}
    if symmetric and is_symmetric(P, sym_tol):
        ab = rayleigh_fit(M, P, Q, rayleigh_tol, probes=probes, seed=seed)
        if ab is not None:
            return ("partial-proportional", f"P = {ab[0]:.6g} M + {ab[1]:.6g} Q (Rayleigh damping)",
                    {"alpha": ab[0], "beta": ab[1]})
    return "partial-companion", "general damping or non-symmetric: shift-invert on the companion pencil", {}


class _ShiftLU:
    """LU of σ²M + σP + Q (σ real or complex), retried at nearby shifts if exactly singular."""

    def __init__(self, M, P, Q, sigma, scale, quadratic=True):
        last = None
        for k in range(4):
            sig = sigma if k == 0 else sigma - (10.0 ** (k - 10)) * scale
            A = (sig * sig * M + sig * P + Q) if quadratic else (Q - sig * M)
            try:
                self.lu = spla.splu(A.tocsc())
                self.sigma = sig
                return
            except RuntimeError as exc:  # exactly singular: σ is an eigenvalue
                last = exc
        raise SolverError(f"shift-invert: σ²M + σP + Q is singular near σ = {sigma:.6g} ({last})")

    def solve(self, b, trans="N"):
        return self.lu.solve(b, trans=trans)


def _bordered(M, P, Q, G):
    m = G.shape[0]
    nQ, nG = fro(Q), fro(G)
    c = nQ / nG if nG > 0 and nQ > 0 else 1.0
    Z = sp.csr_matrix((m, m))
    Mb = sp.block_diag([M, Z], format="csr")
    Pb = sp.block_diag([P, Z], format="csr")
    Qb = sp.bmat([[Q, c * G.T], [c * G, Z]], format="csr")
    return Mb, Pb, Qb, c


def _arpack(fn, what, **kw):
    try:
        return fn(**kw)
    except spla.ArpackNoConvergence as exc:
        got = 0 if exc.eigenvalues is None else len(exc.eigenvalues)
        raise SolverError(f"{what}: ARPACK did not converge ({got} of {kw.get('k')} eigenvalues "
                          f"after {kw.get('maxiter') or 'default'} iterations); ask for fewer modes, "
                          f"move the target or raise maxiter") from None
    except spla.ArpackError as exc:
        raise SolverError(f"{what}: ARPACK failed: {exc}") from None


def _undamped_partial(Mb, Qb, k, sigma, scale, ncv, maxiter, tol):
    """k eigenpairs (ω², v) of Q v = ω² M v nearest σ (Lanczos, shift-invert mode)."""
    nb = Mb.shape[0]
    lu = _ShiftLU(Mb, None, Qb, sigma, scale, quadratic=False)
    OPinv = spla.LinearOperator((nb, nb), matvec=lambda x: lu.solve(np.asarray(x).ravel()), dtype=float)
    w, V = _arpack(spla.eigsh, "partial-eigh", A=Qb, k=k, M=Mb, sigma=lu.sigma, which="LM",
                   OPinv=OPinv, ncv=ncv, maxiter=maxiter, tol=tol)
    order = np.argsort(w)
    return w[order], V[:, order], lu.sigma


def _companion_partial(Mb, Pb, Qb, k, sigma, scale, ncv, maxiter, tol):
    """k eigenpairs of the companion pencil nearest σ in the s-plane (Arnoldi, shift-invert)."""
    nb = Mb.shape[0]
    lu = _ShiftLU(Mb, Pb, Qb, sigma, scale)
    sig = lu.sigma
    PsM = (Pb + sig * Mb).tocsr()
    dtype = complex if np.iscomplex(sig) else float

    def op(v):
        v = np.asarray(v).ravel()
        v1, v2 = v[:nb], v[nb:]
        z1 = -lu.solve(np.asarray(Mb @ v2 + PsM @ v1, dtype=dtype))
        return np.concatenate([z1, v1 + sig * z1])

    OP = spla.LinearOperator((2 * nb, 2 * nb), matvec=op, dtype=dtype)
    mu, Z = _arpack(spla.eigs, "partial-companion", A=OP, k=k, which="LM", ncv=ncv,
                    maxiter=maxiter, tol=tol)
    ok = mu != 0
    mu, Z = mu[ok], Z[:, ok]
    s = sig + 1.0 / mu
    return s, Z[:nb], Z[nb:] / np.where(s != 0, s, 1.0), sig








def solve_partial(M, P, Q, *, n_modes: int | None = None, target: float | None = None,
                  band=None, G=None, solver: str = "auto", sym_tol: float = 1e-13,
                  rayleigh_tol: float = 1e-12, verify_tol: float = 1e-8, arpack_tol: float = 0.0,
                  ncv: int | None = None, maxiter: int | None = None, left: bool = True,
                  max_modes: int = 2000) -> QEPSolution:
    """The requested modes of (M s² + P s + Q) x = 0 (M, P, Q sparse or dense, never densified).

    n_modes : number of modes (a complex pair counts once) nearest ``target``; default 20.
    target : angular frequency ω (rad/s) the modes are sought around; default 0 (lowest modes).
    band : (ω_lo, ω_hi): every mode with ω_lo ≤ ω_n ≤ ω_hi (the count grows until all are found).
    G : constraint Jacobian Φ_q (m × n); M, P, Q are then in full coordinates (bordered pencil).
    solver : ``auto`` or a partial path of :data:`mbseig.eigen.base.SOLVERS`.
    verify_tol : largest backward error accepted for a returned pair (else SolverError).
    arpack_tol, ncv, maxiter : ARPACK's own options (0 = machine precision).
    left : on the companion path with non-symmetric matrices, compute left eigenvectors (a second
        ARPACK run on the transposed problem) for the condition numbers; otherwise κ is estimated
        with the right vector (exact for symmetric M, P, Q).
    """
    n = M.shape[0]
    M, Q = _csr(M), _csr(Q)
    P = _csr(P, n)
    if not (M.shape == P.shape == Q.shape == (n, n)):
        raise SolverError(f"M, P, Q must be square and of one size, got {M.shape}, {P.shape}, {Q.shape}")
    for A in (M, P, Q):
        if not np.all(np.isfinite(A.data)):
            raise SolverError("M, P and Q must be finite")
    if band is not None:
        lo, hi = (float(b) for b in band)
        if not (0 <= lo <= hi):
            raise SolverError(f"band must be (ω_lo, ω_hi) with 0 ≤ ω_lo ≤ ω_hi, got {band!r}")
    if n_modes is not None and int(n_modes) < 1:
        raise SolverError(f"n_modes must be a positive integer, got {n_modes!r}")
    name, reason, extras = sparse_structure(M, P, Q, sym_tol=sym_tol, rayleigh_tol=rayleigh_tol)
    name, reason, extras = requested_path(solver, name, reason, extras, partial_solvers(),
                                          "partial solver")
    m = 0 if G is None else G.shape[0]
    if m:
        G = _csr(G) if sp.issparse(G) else sp.csr_matrix(np.asarray(G, dtype=float))
        if G.shape[1] != n:
            raise SolverError(f"G must have {n} columns like M, got {G.shape}")
        Mb, Pb, Qb, c = _bordered(M, P, Q, G)
        reason += f"; {m} constraint rows kept in a bordered pencil (row scale {c:.3g})"
    else:
        Mb, Pb, Qb = M, P, Q
    nb = Mb.shape[0]
    norms = (fro(Mb), fro(Pb), fro(Qb))
    scale = norms[2] if norms[2] > 0 else 1.0
    w_scale = np.sqrt(norms[2] / norms[0]) if norms[0] > 0 else 1.0
    omega_t = 0.0 if target is None else float(target)
    if band is not None:
        omega_t = 0.5 * (lo + hi) if name != "partial-companion" else 0.0
    want = 20 if n_modes is None else int(n_modes)
    symmetric_path = name in ("partial-eigh", "partial-proportional")
    limit = nb - 2 if symmetric_path else 2 * nb - 2
    while True:
        k = want if symmetric_path else 2 * want + 1
        if k > limit:
            raise SolverError(f"{want} modes asked of a problem with {nb} unknowns: use the dense path")
        if symmetric_path:
            w, V, sig = _undamped_partial(Mb, Qb, k, omega_t**2, scale / max(norms[0], 1e-300), ncv,
                                          maxiter, arpack_tol)
            found = np.sqrt(np.abs(w))
            radius = np.max(np.abs(w - sig))
            done_band = band is None or radius >= max(sig - lo**2, hi**2 - sig) or k >= limit
        else:
            sig = 1j * omega_t if omega_t else 0.0
            s, X1, X2, sig = _companion_partial(Mb, Pb, Qb, k, sig, w_scale, ncv, maxiter, arpack_tol)
            done_band = band is None or np.max(np.abs(s)) > hi
        if done_band:
            break
        if want >= max_modes:
            raise SolverError(f"band {band!r} holds more than max_modes = {max_modes} modes")
        want = min(2 * want, max_modes)
    if symmetric_path:
        if band is not None:
            inside = (found >= lo) & (found <= hi)
            w, V = w[inside], V[:, inside]
        s, X, eta, kappa = undamped_pairs(Mb, Pb, Qb, w, V, extras.get("alpha", 0.0),
                                          extras.get("beta", 0.0), norms)
        n_second, Yc = 0, X
    else:
        X, eta, _, _, n_second = better_half((Mb, Pb, Qb), s, X1, X2, norms)
        del X1, X2
        s, X, eta = _select(s, X, eta, want if band is None else None, omega_t, band)
        symmetric_all = all(is_symmetric(A, sym_tol) for A in (Mb, Pb, Qb))
        Yc = X if symmetric_all or not left else \
            _left_vectors(Mb, Pb, Qb, s, k, sig, ncv, maxiter, arpack_tol, w_scale).conj()
        kappa = conditions(s, X, Yc, Mb @ X, Pb @ X, norms)
    bad = eta > verify_tol
    if np.any(bad):
        worst = ", ".join(f"{z.real:.6g}{z.imag:+.6g}j (η={e:.1e})" for z, e in zip(s[bad][:5], eta[bad][:5]))
        raise SolverError(f"{name}: {int(bad.sum())} returned pairs fail the backward-error check "
                          f"η ≤ {verify_tol:g}: {worst}")
    Xq = unit_columns(X[:n]) if m else X
    real_error = None
    if name == "partial-proportional":
        a, b = extras["alpha"], extras["beta"]
        fit = fro((P - a * M - b * Q).tocsr())
        real_error = proportional_real_error(s, kappa, eta, norms, a, b, fit)
    return QEPSolution(s, Xq, eta, kappa, name, reason, 0, norms,
                       {**extras, "shift": complex(sig) if np.iscomplex(sig) else float(np.real(sig)),
                        "n_requested": want, "arpack_k": k, "n_constraint_rows": m,
                        "verify_tol": verify_tol, "second_half_vectors": n_second},
                       real_error, left_vectors=(unit_columns(Yc[:n]) if m else Yc), partial=True)




def _select(s, X, eta, count, omega_t, band):
    """Keep whole modes (a complex pair with both members) nearest ω_t, or those in the band."""
    tol = 1e-9 * np.maximum(np.abs(s), 1e-300)
    upper = s.imag >= -tol
    s_u = s[upper]
    key = np.abs(np.abs(s_u) - omega_t)
    if band is not None:
        keep_u = (np.abs(s_u) >= band[0]) & (np.abs(s_u) <= band[1])
    else:
        keep_u = np.zeros(s_u.size, bool)
        keep_u[np.argsort(key, kind="stable")[:count]] = True
    chosen = np.flatnonzero(upper)[keep_u]
    out_s, out_X, out_e = [], [], []
    for i in chosen:
        out_s.append(s[i])
        out_X.append(X[:, i])
        out_e.append(eta[i])
        if abs(s[i].imag) > tol[i]:  # add the conjugate partner (exact for real matrices)
            out_s.append(np.conj(s[i]))
            out_X.append(np.conj(X[:, i]))
            out_e.append(eta[i])
    if not out_s:
        return np.zeros(0, complex), np.zeros((X.shape[0], 0), complex), np.zeros(0)
    return np.array(out_s), np.column_stack(out_X), np.array(out_e)


def _left_vectors(Mb, Pb, Qb, s, k, sig, ncv, maxiter, tol, scale):
    """Left eigenvectors: right eigenvectors of the transposed problem, matched by eigenvalue."""
    st, Y1, Y2, _ = _companion_partial(Mb.T.tocsr(), Pb.T.tocsr(), Qb.T.tocsr(), k, sig, scale, ncv,
                                       maxiter, tol)
    Y = np.empty((Mb.shape[0], s.size), complex)
    for j, z in enumerate(s):
        i = int(np.argmin(np.abs(st - z)))
        Y[:, j] = Y1[:, i]
    return Y.conj()  # yᴴ(s²M + sP + Q) = 0 ⇔ (s²Mᵀ + sPᵀ + Qᵀ) ȳ = 0


for _name, _needs in (("partial-eigh", "P = 0, M and Q symmetric"),
                      ("partial-proportional", "P = αM + βQ with M and Q symmetric"),
                      ("partial-companion", "nothing (any sparse M, P, Q)")):
    register(_name, partial=True, needs=_needs, driver=solve_partial)
