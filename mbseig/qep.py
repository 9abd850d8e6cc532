"""Quadratic eigenvalue problem (M s² + P s + Q) x = 0 (DESIGN §5).

Solver paths (a registry, :data:`SOLVERS`; the result says which one ran and why):

``eigh``          P = 0, M and Q symmetric, M positive definite: ``eigh(Q, M)``, s = ±√(−ω²).
``proportional``  P = αM + βQ (Rayleigh damping, fitted and verified), M, Q symmetric, M > 0:
                  the undamped modes with s² + (α + βω²) s + ω² = 0 solved per mode.
``companion``     M symmetric positive definite: mass-normalized (M = LLᵀ, x = L⁻ᵀy) first
                  companion matrix scaled by γ, standard eigenproblem (LAPACK geev):

                      A = ┌    0          I    ┐ ,   s = γ μ
                          └ −Q̃/γ²     −P̃/γ   ┘
``qz``            anything else: Fan–Lin–Van Dooren scaled pencil (γ = √(‖Q‖/‖M‖),
                  δ = 2/(‖Q‖ + γ‖P‖)), QZ (LAPACK ggev); infinite eigenvalues of a singular M
                  dropped and counted.

Every eigenpair carries its backward error (Tisseur 2000, Frobenius-norm weights)

    η = ‖(s²M + sP + Q)x‖ / ((|s|²‖M‖ + |s|‖P‖ + ‖Q‖) ‖x‖)

and its absolute condition number κ = (|s|²‖M‖ + |s|‖P‖ + ‖Q‖)‖x‖‖y‖ / |yᴴ(2sM + P)x| from the
left eigenvector y, so that κ·η bounds the error of s to first order.  Of a companion
eigenvector both halves are candidates for x; the one with the smaller η is kept.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from .errors import SolverError

__all__ = ["QEPSolution", "solve_qep", "choose_solver", "SOLVERS", "backward_errors",
           "proportional_real_error"]

EPS = np.finfo(float).eps


@dataclass(frozen=True, eq=False)
class QEPSolution:
    """All finite eigenvalues s (2n minus the infinite ones) with unit right vectors (columns of
    ``vectors``), backward errors, absolute condition numbers and the path that produced them."""

    eigenvalues: np.ndarray
    vectors: np.ndarray
    backward_error: np.ndarray
    condition: np.ndarray
    solver: str
    reason: str
    n_infinite: int = 0
    norms: tuple = (0.0, 0.0, 0.0)
    details: dict = field(default_factory=dict)
    real_error: object = None  # error bound of Re s where the path knows it better than κη


def proportional_real_error(s, kappa, eta, norms, alpha, beta, fit_residual):
    """Error bound of Re s on the proportional path, oscillatory roots (Re s = −(α + βω²)/2).

    ω² = −s s̄ for the pair; its error is at most 2|s|·κη (first order, undamped pencil), so
    |Δ Re s| ≤ |β| |s| κη + κ |s| ‖P − αM − βQ‖ / w(s) + ε |α + βω²|, w(s) the η weight.
    Real (overdamped) roots get no bound here (κη applies).
    """
    nM, nP, nQ = norms
    weight = np.abs(s) ** 2 * nM + np.abs(s) * nP + nQ
    ke = kappa * np.maximum(eta, EPS)
    with np.errstate(divide="ignore", invalid="ignore"):
        fit = np.where(weight > 0, kappa * np.abs(s) * fit_residual / weight, np.inf)
    err = np.abs(beta) * np.abs(s) * ke + fit + EPS * 2 * np.abs(s.real)
    return np.where(np.abs(s.imag) > 0, err, np.inf)


def _dense(A):
    A = A.toarray() if sp.issparse(A) else np.asarray(A)
    if np.iscomplexobj(A):
        raise SolverError("M, P and Q must be real matrices")
    return np.asarray(A, dtype=float)


def _is_symmetric(A, tol):
    nA = np.linalg.norm(A)
    return np.linalg.norm(A - A.T) <= tol * nA if nA > 0 else True


def _cholesky(M):
    try:
        return sla.cholesky(M, lower=True)
    except np.linalg.LinAlgError:
        return None


def _rayleigh_fit(M, P, Q, tol):
    """(α, β) with P = αM + βQ to relative accuracy tol, or None."""
    nP = np.linalg.norm(P)
    if nP == 0:
        return 0.0, 0.0
    A = np.column_stack([M.ravel(), Q.ravel()])
    coef, *_ = np.linalg.lstsq(A, P.ravel(), rcond=None)
    if np.linalg.norm(A @ coef - P.ravel()) <= tol * nP:
        return float(coef[0]), float(coef[1])
    return None


def choose_solver(M, P, Q, *, sym_tol=1e-13, rayleigh_tol=1e-12, memo=None):
    """(name, reason, extras) of the path ``auto`` takes for these matrices.

    memo : optional dict that caches the symmetry tests (keys "M", "P", "Q") for the caller.
    """
    memo = {} if memo is None else memo

    def sym(key, A):
        if key not in memo:
            memo[key] = _is_symmetric(A, sym_tol)
        return memo[key]

    symmetric = sym("M", M) and sym("Q", Q)
    d = np.diagonal(M)
    if np.count_nonzero(M) == np.count_nonzero(d):  # diagonal M: positive definite iff d > 0
        L = True if np.all(d > 0) else None
    else:
        L = _cholesky(0.5 * (M + M.T)) if sym("M", M) else None
    if symmetric and L is not None:
        if not np.any(P):
            return "eigh", "P = 0, M and Q symmetric, M positive definite", {}
        if sym("P", P):
            ab = _rayleigh_fit(M, P, Q, rayleigh_tol)
            if ab is not None:
                return ("proportional", f"P = {ab[0]:.6g} M + {ab[1]:.6g} Q (Rayleigh damping)",
                        {"alpha": ab[0], "beta": ab[1]})
    if L is not None:
        return "companion", "M symmetric positive definite: mass-normalized companion", {}
    return "qz", "M not symmetric positive definite: scaled QZ on the companion pencil", {}


def backward_errors(M, P, Q, s, X, norms=None):
    """η_k for the pairs (s_k, X[:, k])."""
    nM, nP, nQ = norms if norms is not None else (np.linalg.norm(M), np.linalg.norm(P), np.linalg.norm(Q))
    return _eta_products((M, P, Q), s, X, (nM, nP, nQ))[0]


def _fast_operand(A, density=0.05):
    """A as CSR when sparse enough that products with 2n vectors are cheaper that way."""
    if not sp.issparse(A) and A.size > 10_000 and np.count_nonzero(A) <= density * A.size:
        return sp.csr_matrix(A)
    return A


def _eta_products(ops, s, X, norms):
    """(η, M X, P X): backward errors and the products reused for the condition numbers.

    A pair with zero residual has η = 0 even where the weights vanish (s = 0 with Q = 0).
    """
    M, P, Q = ops
    nM, nP, nQ = norms
    MX, PX = M @ X, P @ X
    R = MX * s  # Horner, in place: (M X s + P X) s + Q X
    R += PX
    R *= s
    R += Q @ X
    rn = _colnorm(R)
    denom = (np.abs(s) ** 2 * nM + np.abs(s) * nP + nQ) * _colnorm(X)
    with np.errstate(divide="ignore", invalid="ignore"):
        eta = np.where(denom > 0, rn / denom, np.where(rn == 0, 0.0, np.inf))
    return eta, MX, PX


def _colnorm(X):
    """Column 2-norms without complex temporaries."""
    if np.iscomplexobj(X):
        return np.sqrt(np.einsum("ij,ij->j", X.real, X.real) + np.einsum("ij,ij->j", X.imag, X.imag))
    return np.sqrt(np.einsum("ij,ij->j", X, X))


def _conditions(M, P, Q, s, X, Y, norms, MX=None, PX=None, Yc=None):
    """κ per pair; ``Yc`` may give the conjugated left vectors directly (yᴴ = Ycᵀ)."""
    nM, nP, nQ = norms
    Yc = Y.conj() if Yc is None else Yc
    num = (np.abs(s) ** 2 * nM + np.abs(s) * nP + nQ) * _colnorm(X) * _colnorm(Yc)
    MX = M @ X if MX is None else MX
    PX = P @ X if PX is None else PX
    den = np.abs(np.einsum("ij,ij->j", Yc, MX * (2 * s) + PX))
    with np.errstate(divide="ignore", invalid="ignore"):
        kappa = num / den
    return np.where(den > 0, kappa, np.inf)


def _unit(X):
    nrm = _colnorm(X)
    nrm[nrm == 0] = 1.0
    return X / nrm


# ---------------------------------------------------------------------------------------------
def _solve_eigh(M, P, Q, opts):
    w, V = sla.eigh(0.5 * (Q + Q.T), 0.5 * (M + M.T))
    return _from_undamped(w, V, 0.0, 0.0)


def _solve_proportional(M, P, Q, opts):
    alpha, beta = opts["alpha"], opts["beta"]
    w, V = sla.eigh(0.5 * (Q + Q.T), 0.5 * (M + M.T))
    return _from_undamped(w, V, alpha, beta)


def _from_undamped(w, V, alpha, beta):
    """Both roots of s² + (α + βω²)s + ω² = 0 per undamped mode (numerically stable form)."""
    c = alpha + beta * w
    disc = c * c - 4.0 * w
    s1 = np.empty(w.size, complex)
    s2 = np.empty(w.size, complex)
    osc = disc < 0
    s1[osc] = -c[osc] / 2 + 0.5j * np.sqrt(-disc[osc])
    s2[osc] = np.conj(s1[osc])
    re = ~osc
    root = np.sqrt(disc[re])
    cr = c[re]
    big = -(cr + np.copysign(root, cr)) / 2  # the root of larger magnitude, no cancellation
    small = np.divide(w[re], big, out=np.zeros_like(big), where=big != 0)
    s1[re], s2[re] = big, small
    s = np.concatenate([s1, s2])
    X = np.concatenate([V, V], axis=1).astype(complex)
    return s, X, X, X, 0


def _undamped_eigh(M, Q):
    """(ω², V) of Q v = ω² M v, M-orthonormal V; a diagonal M is scaled out (standard eigh)."""
    Qs = 0.5 * (Q + Q.T)
    d = np.diagonal(M).copy()
    if np.count_nonzero(M) == np.count_nonzero(d) and np.all(d > 0):
        l = np.sqrt(d)
        w, U = sla.eigh(Qs / np.outer(l, l), check_finite=False)
        return w, U / l[:, None]
    return sla.eigh(Qs, 0.5 * (M + M.T), check_finite=False)


def _colnorm_real(V):
    return np.sqrt(np.einsum("ij,ij->j", V, V))


def undamped_pairs(M, P, Q, w, V, alpha, beta, norms):
    """s₊, s₋ of each undamped mode (ω², v) with s² + (α + βω²)s + ω² = 0; η and κ in real
    arithmetic on the n real vectors (M, P, Q symmetric: y = x, κ = w(s)‖v‖²/|2s vᵀMv + vᵀPv|).

    Returns (s, X, η, κ) with s = [s₊, s₋] and X = [V, V] (real, unit columns).
    """
    s = _from_undamped(w, np.zeros((0, w.size)), alpha, beta)[0]
    V = V / _colnorm_real(V)
    MV, PV, QV = M @ V, P @ V, Q @ V
    nM, nP, nQ = norms
    a, b = np.einsum("ij,ij->j", V, MV), np.einsum("ij,ij->j", V, PV)
    k = w.size
    rn = np.empty(2 * k)
    for half in (slice(0, k), slice(k, 2 * k)):  # s₊ then s₋, both with the vectors V
        sh = s[half]
        s2 = sh * sh
        Rr = MV * s2.real + PV * sh.real + QV
        Ri = MV * s2.imag + PV * sh.imag
        rn[half] = np.sqrt(np.einsum("ij,ij->j", Rr, Rr) + np.einsum("ij,ij->j", Ri, Ri))
        del Rr, Ri
    weight = np.abs(s) ** 2 * nM + np.abs(s) * nP + nQ
    with np.errstate(divide="ignore", invalid="ignore"):
        eta = np.where(weight > 0, rn / weight, np.where(rn == 0, 0.0, np.inf))
        den = np.abs(2 * s * np.concatenate([a, a]) + np.concatenate([b, b]))
        kappa = np.where(den > 0, weight / den, np.inf)
    return s, np.concatenate([V, V], axis=1), eta, kappa


def _solve_companion(M, P, Q, opts):
    n = M.shape[0]
    dM = np.diagonal(M).copy()
    if np.count_nonzero(M) == np.count_nonzero(dM) and np.all(dM > 0):  # lumped (diagonal) M
        l = np.sqrt(dM)
        Qt = Q / np.outer(l, l)
        Pt = P / np.outer(l, l)
        back = lambda Y: Y / l[:, None]  # L⁻ᵀ y with L = diag(√m)
    else:
        L = sla.cholesky(0.5 * (M + M.T), lower=True)
        Linv_Q = sla.solve_triangular(L, Q, lower=True)
        Qt = sla.solve_triangular(L, Linv_Q.T, lower=True).T  # L⁻¹ Q L⁻ᵀ
        Linv_P = sla.solve_triangular(L, P, lower=True)
        Pt = sla.solve_triangular(L, Linv_P.T, lower=True).T
        back = lambda Y: sla.solve_triangular(L.T, Y, lower=False)  # L⁻ᵀ y
    gamma = np.sqrt(np.linalg.norm(Qt) / np.sqrt(n)) if np.any(Qt) else 1.0
    gamma = gamma if gamma > 0 else 1.0
    A = np.zeros((2 * n, 2 * n), order="F")
    A[:n, n:] = np.eye(n)
    A[n:, :n] = Qt
    A[n:, :n] *= -1.0 / gamma**2
    A[n:, n:] = Pt
    A[n:, n:] *= -1.0 / gamma
    if opts.get("left", True):
        mu, W, Z = sla.eig(A, left=True, right=True, overwrite_a=True, check_finite=False)
    else:
        mu, Z = sla.eig(A, left=False, right=True, overwrite_a=True, check_finite=False)
        W = None
    s = gamma * mu
    X1 = back(Z[:n])
    X2 = back(Z[n:]) / np.where(mu != 0, mu, 1.0)
    Y = back(W[n:]) if W is not None else None
    return s, X1, X2, Y, 0, {"gamma": gamma}


def _solve_qz(M, P, Q, opts):
    n = M.shape[0]
    nM, nP, nQ = (np.linalg.norm(A) for A in (M, P, Q))
    gamma = np.sqrt(nQ / nM) if nM > 0 and nQ > 0 else 1.0
    delta = 2.0 / (nQ + nP * gamma) if (nQ + nP * gamma) > 0 else 1.0
    if not opts.get("scale", True):
        gamma, delta = 1.0, 1.0
    Ms, Ps, Qs = gamma**2 * delta * M, gamma * delta * P, delta * Q
    I = np.eye(n)
    A = np.block([[np.zeros((n, n)), I], [-Qs, -Ps]])
    B = np.block([[I, np.zeros((n, n))], [np.zeros((n, n)), Ms]])
    if opts.get("left", True):
        w, W, Z = sla.eig(A, B, left=True, right=True, homogeneous_eigvals=True, check_finite=False)
    else:
        w, Z = sla.eig(A, B, left=False, right=True, homogeneous_eigvals=True, check_finite=False)
        W = None
    alpha, beta = w
    inf_tol = opts.get("infinite_tol", 100 * n * EPS)
    finite = np.abs(beta) > inf_tol * np.abs(alpha)
    mu = alpha[finite] / beta[finite]
    Z = Z[:, finite]
    s = gamma * mu
    X1 = Z[:n]
    X2 = Z[n:] / np.where(mu != 0, mu, 1.0)
    Y = W[n:, finite] if W is not None else None
    return s, X1, X2, Y, int(np.sum(~finite)), {"gamma": gamma, "delta": delta, "infinite_tol": inf_tol}


SOLVERS = {
    "eigh": _solve_eigh,
    "proportional": _solve_proportional,
    "companion": _solve_companion,
    "qz": _solve_qz,
}


def solve_qep(M, P, Q, *, solver: str = "auto", sym_tol: float = 1e-13,
              rayleigh_tol: float = 1e-12, scale: bool = True, left="auto") -> QEPSolution:
    """Solve (M s² + P s + Q) x = 0 by the path ``solver`` (``auto`` picks by structure).

    sym_tol : relative tolerance for treating M, Q (and P) as symmetric.
    rayleigh_tol : relative residual under which P counts as αM + βQ.
    scale : Fan–Lin–Van Dooren scaling on the QZ path (``False`` only to measure its value).
    left : left eigenvectors for the condition numbers on the companion and QZ paths.  ``auto``
        computes them only when M, P or Q is not symmetric: for symmetric matrices the left
        vector is the conjugate of the right one, exactly, and LAPACK's left vectors cost about
        10–15 % more time (measured by ``mbseig bench``).  ``False`` always takes y = x̄, which
        is only an estimate of κ for non-symmetric problems (recorded in ``details``).
    """
    M, P, Q = _dense(M), _dense(P), _dense(Q)
    n = M.shape[0]
    if not (M.shape == P.shape == Q.shape == (n, n)):
        raise SolverError(f"M, P, Q must be square and of one size, got {M.shape}, {P.shape}, {Q.shape}")
    if not all(np.all(np.isfinite(A)) for A in (M, P, Q)):
        raise SolverError("M, P and Q must be finite")
    memo = {}
    name, reason, extras = choose_solver(M, P, Q, sym_tol=sym_tol, rayleigh_tol=rayleigh_tol, memo=memo)
    if solver != "auto":
        if solver not in SOLVERS:
            raise SolverError(f"unknown solver {solver!r} (auto, {', '.join(SOLVERS)})")
        if solver in ("eigh", "proportional") and name not in ("eigh", "proportional"):
            raise SolverError(f"solver {solver!r} does not apply: {reason}")
        if solver == "eigh" and name == "proportional":
            raise SolverError("solver 'eigh' does not apply: P is not zero")
        if solver == "proportional" and name == "eigh":
            extras = {"alpha": 0.0, "beta": 0.0}
        if solver == "companion" and _cholesky(0.5 * (M + M.T)) is None:
            raise SolverError("solver 'companion' needs M symmetric positive definite")
        name, reason = solver, f"requested ({reason})"
    norms = (np.linalg.norm(M), np.linalg.norm(P), np.linalg.norm(Q))
    if left == "auto":
        left = not all(memo[k] if k in memo else _is_symmetric(A, sym_tol)
                       for k, A in (("M", M), ("Q", Q), ("P", P)))
    opts = {**extras, "scale": scale, "left": bool(left)}
    if n == 0:
        e = np.zeros(0)
        return QEPSolution(e.astype(complex), np.zeros((0, 0), complex), e, e, name, reason, 0, norms)
    if name in ("eigh", "proportional"):  # real undamped modes: checks in real arithmetic
        w, V = _undamped_eigh(M, Q)
        ops = tuple(_fast_operand(A) for A in (M, P, Q))
        s, X, eta, kappa = undamped_pairs(*ops, w, V, opts.get("alpha", 0.0), opts.get("beta", 0.0), norms)
        real_error = None
        if name == "proportional":
            fit = np.linalg.norm(P - opts["alpha"] * M - opts["beta"] * Q)
            real_error = proportional_real_error(s, kappa, eta, norms, opts["alpha"], opts["beta"], fit)
        return QEPSolution(s, X, eta, kappa, name, reason, 0, norms,
                           {"second_half_vectors": 0, "left_vectors": False}, real_error)
    out = SOLVERS[name](M, P, Q, opts)
    s, X1, X2, Y, n_inf = out[:5]
    details = out[5] if len(out) > 5 else {}
    X1, X2 = np.ascontiguousarray(_unit(X1)), np.ascontiguousarray(_unit(X2))  # fast sparse products
    ops = tuple(_fast_operand(A) for A in (M, P, Q))
    e1, MX1, PX1 = _eta_products(ops, s, X1, norms)
    e2, MX2, PX2 = _eta_products(ops, s, X2, norms)
    take2 = e2 < e1
    X, MX, PX = X1, MX1, PX1  # the better half per column, in place
    for a, b in ((X, X2), (MX, MX2), (PX, PX2)):
        a[:, take2] = b[:, take2]
    del X2, MX2, PX2
    eta = np.minimum(e1, e2)
    if Y is None:  # y = x̄: exact for symmetric M, P, Q (see ``left``)
        kappa = _conditions(M, P, Q, s, X, None, norms, MX, PX, Yc=X)
    else:
        kappa = _conditions(M, P, Q, s, X, _unit(Y), norms, MX, PX)
    real_error = None
    if name == "proportional":
        fit = np.linalg.norm(P - opts["alpha"] * M - opts["beta"] * Q)
        real_error = proportional_real_error(s, kappa, eta, norms, opts["alpha"], opts["beta"], fit)
    return QEPSolution(s, X, eta, kappa, name, reason, n_inf, norms,
                       {**details, "second_half_vectors": int(np.sum(take2)),
                        "left_vectors": bool(opts["left"]) if name in ("companion", "qz") else False},
                       real_error)
