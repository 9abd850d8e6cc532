"""Dense paths for the quadratic eigenvalue problem (M s² + P s + Q) x = 0 (docs/design.md).

Registered in :data:`mbseig.eigen.base.SOLVERS`; ``auto`` picks by structure
(:func:`choose_solver`) and the result says which path ran and why:

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

Every pair carries η and κ (:mod:`mbseig.eigen.measures`).  Of a companion eigenvector both
halves are candidates for x; the one with the smaller η is kept.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..errors import SolverError
from ..numerics import unit_columns
from .base import SOLVERS, QEPSolution, dense_solvers, register, requested_path
from .measures import (
    better_half,
    conditions,
    is_symmetric,
    proportional_real_error,
    rayleigh_fit,
    undamped_pairs,
)

__all__ = ["solve_qep", "choose_solver"]


def _dense(A):
    A = A.toarray() if sp.issparse(A) else np.asarray(A)
    if np.iscomplexobj(A):
        raise SolverError("M, P and Q must be real matrices")
    return np.asarray(A, dtype=float)


def _cholesky(M):
    try:
        return sla.cholesky(M, lower=True)
    except np.linalg.LinAlgError:
        return None


def _diagonal_positive(M):
    """None when M is not diagonal; else whether its diagonal is positive."""
    d = np.diagonal(M)
    if np.count_nonzero(M) != np.count_nonzero(d):
        return None
    return bool(np.all(d > 0))


def choose_solver(M, P, Q, *, sym_tol=1e-13, rayleigh_tol=1e-12, memo=None):
    """(name, reason, extras) of the path ``auto`` takes for these matrices.

    memo : optional dict that caches the symmetry tests (keys "M", "P", "Q") for the caller.
    """
    memo = {} if memo is None else memo

    def sym(key, A):
        if key not in memo:
            memo[key] = is_symmetric(A, sym_tol)
        return memo[key]

    symmetric = sym("M", M) and sym("Q", Q)
    diag = _diagonal_positive(M)
    if diag is not None:  # diagonal M: positive definite iff its diagonal is positive
        pd = diag
    else:
        pd = sym("M", M) and _cholesky(0.5 * (M + M.T)) is not None
    if symmetric and pd:
        if not np.any(P):
            return "eigh", "P = 0, M and Q symmetric, M positive definite", {}
        if sym("P", P):
            ab = rayleigh_fit(M, P, Q, rayleigh_tol)
            if ab is not None:
                return ("proportional", f"P = {ab[0]:.6g} M + {ab[1]:.6g} Q (Rayleigh damping)",
                        {"alpha": ab[0], "beta": ab[1]})
    if pd:
        return "companion", "M symmetric positive definite: mass-normalized companion", {}
    return "qz", "M not symmetric positive definite: scaled QZ on the companion pencil", {}


def _fast_operand(A, density=0.05):
    """A as CSR when sparse enough that products with 2n vectors are cheaper that way."""
    if not sp.issparse(A) and A.size > 10_000 and np.count_nonzero(A) <= density * A.size:
        return sp.csr_matrix(A)
    return A


def _undamped_eigh(M, Q):
    """(ω², V) of Q v = ω² M v, M-orthonormal V; a diagonal M is scaled out (standard eigh)."""
    Qs = 0.5 * (Q + Q.T)
    if _diagonal_positive(M):
        l = np.sqrt(np.diagonal(M))
        w, U = sla.eigh(Qs / np.outer(l, l), check_finite=False)
        return w, U / l[:, None]
    return sla.eigh(Qs, 0.5 * (M + M.T), check_finite=False)


def _structured(M, P, Q, opts, name, reason, norms):
    """eigh and proportional: real undamped modes, checks in real arithmetic (y = x)."""
    alpha, beta = opts.get("alpha", 0.0), opts.get("beta", 0.0)
    w, V = _undamped_eigh(M, Q)
    ops = tuple(_fast_operand(A) for A in (M, P, Q))
    s, X, eta, kappa = undamped_pairs(*ops, w, V, alpha, beta, norms)
    real_error = None
    if name == "proportional":
        fit = np.linalg.norm(P - alpha * M - beta * Q)
        real_error = proportional_real_error(s, kappa, eta, norms, alpha, beta, fit)
    return QEPSolution(s, X, eta, kappa, name, reason, 0, norms,
                       {"second_half_vectors": 0, "left_vectors": False}, real_error,
                       left_vectors=X)


def _solve_eigh(M, P, Q, opts, name, reason, norms):
    return _structured(M, P, Q, opts, name, reason, norms)


def _solve_proportional(M, P, Q, opts, name, reason, norms):
    return _structured(M, P, Q, opts, name, reason, norms)


def _solve_companion(M, P, Q, opts, name, reason, norms):
    n = M.shape[0]
    if _diagonal_positive(M):  # lumped (diagonal) M
        l = np.sqrt(np.diagonal(M))
        Qt = Q / np.outer(l, l)
        Pt = P / np.outer(l, l)
        back = lambda Y: Y / l[:, None]  # L⁻ᵀ y with L = diag(√m)
    else:
        L = sla.cholesky(0.5 * (M + M.T), lower=True)
        Qt = sla.solve_triangular(L, sla.solve_triangular(L, Q, lower=True).T, lower=True).T
        Pt = sla.solve_triangular(L, sla.solve_triangular(L, P, lower=True).T, lower=True).T
        back = lambda Y: sla.solve_triangular(L.T, Y, lower=False)  # L⁻ᵀ y
    gamma = np.sqrt(np.linalg.norm(Qt) / np.sqrt(n)) if np.any(Qt) else 1.0
    gamma = gamma if gamma > 0 else 1.0
    A = np.zeros((2 * n, 2 * n), order="F")
    A[:n, n:] = np.eye(n)
    A[n:, :n] = Qt
    A[n:, :n] *= -1.0 / gamma**2
    A[n:, n:] = Pt
    A[n:, n:] *= -1.0 / gamma
    out = sla.eig(A, left=opts["left"], right=True, overwrite_a=True, check_finite=False)
    mu, W, Z = (out[0], out[1], out[2]) if opts["left"] else (out[0], None, out[1])
    X1 = back(Z[:n])
    X2 = back(Z[n:]) / np.where(mu != 0, mu, 1.0)
    Y = back(W[n:]) if W is not None else None
    return _general_result(M, P, Q, gamma * mu, X1, X2, Y, 0, {"gamma": gamma}, opts, name,
                           reason, norms)


def _solve_qz(M, P, Q, opts, name, reason, norms):
    n = M.shape[0]
    nM, nP, nQ = norms
    gamma = np.sqrt(nQ / nM) if nM > 0 and nQ > 0 else 1.0
    delta = 2.0 / (nQ + nP * gamma) if (nQ + nP * gamma) > 0 else 1.0
    if not opts.get("scale", True):
        gamma, delta = 1.0, 1.0
    Ms, Ps, Qs = gamma**2 * delta * M, gamma * delta * P, delta * Q
    I = np.eye(n)
    A = np.block([[np.zeros((n, n)), I], [-Qs, -Ps]])
    B = np.block([[I, np.zeros((n, n))], [np.zeros((n, n)), Ms]])
    out = sla.eig(A, B, left=opts["left"], right=True, homogeneous_eigvals=True,
                  check_finite=False)
    w, W, Z = (out[0], out[1], out[2]) if opts["left"] else (out[0], None, out[1])
    alpha, beta = w
    inf_tol = opts.get("infinite_tol", 100 * n * np.finfo(float).eps)
    finite = np.abs(beta) > inf_tol * np.abs(alpha)
    mu = alpha[finite] / beta[finite]
    Z = Z[:, finite]
    X1 = Z[:n]
    X2 = Z[n:] / np.where(mu != 0, mu, 1.0)
    Y = W[n:, finite] if W is not None else None
    details = {"gamma": gamma, "delta": delta, "infinite_tol": inf_tol}
    return _general_result(M, P, Q, gamma * mu, X1, X2, Y, int(np.sum(~finite)), details, opts,
                           name, reason, norms)


def _general_result(M, P, Q, s, X1, X2, Y, n_inf, details, opts, name, reason, norms):
    """η of both vector halves, the better one kept; κ from the left vectors (or y = x̄)."""
    ops = tuple(_fast_operand(A) for A in (M, P, Q))
    X, eta, MX, PX, n_second = better_half(ops, s, X1, X2, norms)
    Yc = X if Y is None else unit_columns(Y).conj()  # y = x̄: exact for symmetric M, P, Q
    kappa = conditions(s, X, Yc, MX, PX, norms)
    return QEPSolution(s, X, eta, kappa, name, reason, n_inf, norms,
                       {**details, "second_half_vectors": n_second, "left_vectors": bool(opts["left"])},
                       None, left_vectors=Yc)


def solve_qep(M, P, Q, *, solver: str = "auto", sym_tol: float = 1e-13,
              rayleigh_tol: float = 1e-12, scale: bool = True, left="auto") -> QEPSolution:
    """Solve (M s² + P s + Q) x = 0 by the dense path ``solver`` (``auto`` picks by structure).

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
    name, reason, extras = requested_path(solver, name, reason, extras, dense_solvers())
    if name == "companion" and _cholesky(0.5 * (M + M.T)) is None:
        raise SolverError(f"solver 'companion' needs {SOLVERS['companion'].needs}")
    norms = (np.linalg.norm(M), np.linalg.norm(P), np.linalg.norm(Q))
    if left == "auto":
        left = not all(memo[k] if k in memo else is_symmetric(A, sym_tol)
                       for k, A in (("M", M), ("Q", Q), ("P", P)))
    opts = {**extras, "scale": scale, "left": bool(left)}
    if n == 0:
        e = np.zeros(0)
        return QEPSolution(e.astype(complex), np.zeros((0, 0), complex), e, e, name, reason, 0, norms)
    return _IMPL[name](M, P, Q, opts, name, reason, norms)


_IMPL = {"eigh": _solve_eigh, "proportional": _solve_proportional, "companion": _solve_companion,
         "qz": _solve_qz}


for _name, _needs in {'eigh': 'P = 0, M and Q symmetric, M positive definite', 'proportional': 'P = αM + βQ with M and Q symmetric, M positive definite', 'companion': 'M symmetric positive definite', 'qz': 'nothing (any M, P, Q)'}.items():
    register(_name, partial=False, needs=_needs, driver=solve_qep)
