"""Dense solver of the first-order (descriptor) eigenproblem (s E − A) x = 0.

QZ (``scipy.linalg.eig(A, E)``, homogeneous form s = α/β) on the pencil; a pair is infinite when
its chordal distance to ∞, |β| / √(|α|² + |β|²) after scaling E and A to unit Frobenius norm, is
at most ``inf_tol`` (a named tolerance, recorded in ``details``).  Infinite pairs are dropped and
counted (``n_infinite``).

Accuracy measures, Frobenius norms, for each finite pair (Higham & Higham 1998; the same
definitions as mbseig's quadratic paths with w(s) = |s|‖E‖ + ‖A‖ and the derivative E):

    η = ‖(sE − A) x‖ / ((|s| ‖E‖ + ‖A‖) ‖x‖)
    κ = (|s| ‖E‖ + ‖A‖) ‖x‖ ‖y‖ / |yᴴ E x|           (y the left vector: yᴴ(sE − A) = 0)

κ·η bounds the error of a simple s to first order.  The result carries the fields of mbseig's
``QEPSolution`` (``norms`` = (‖E‖_F, ‖A‖_F)).

Registered as the family ``descriptor`` with its one path ``descriptor-qz`` (docs/design.md,
"Eigensolvers"): the pencil is posed as the first-order member of mbseig's problem,
``Problem(M=None, P=E, Q=−A)`` ((P s + Q) x = 0), and solved through ``eigen.solve`` with
``Request(solver="descriptor-qz", options={"inf_tol": ..., "zero_tol": ...})``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.linalg as sla

from .base import QEPSolution

__all__ = ["GEPSolution", "deflate_subspace", "deflate_zero", "descriptor_problem",
           "solve_descriptor"]


def deflate_zero(E, A, *, rank_tol=1e-11):
    """Remove the eigenvalue s = 0 of a cyclic structure exactly: while A has a null space
    Z (A Z = 0, singular values ≤ rank_tol·‖A‖₂), take unitary [Z Z⊥] and [Q₁ Q₂] with
    Q₁ spanning E Z; then  Qᴴ(sE − A)[Z Z⊥] = [[s E₁₁, ·], [0, s E₂₂ − A₂₂]]  (A Z = 0 and
    Q₂ᴴ E Z = 0), so the other eigenvalues are those of (E₂₂, A₂₂).  Repeating deflates Jordan
    chains (a heading that feeds a lateral position) as well.  Returns (E₂₂, A₂₂, n_zero);
    every deflated s is exactly 0 (E Z must have full column rank: finite zeros only)."""
    E, A = np.asarray(E), np.asarray(A)
    scale = np.linalg.norm(A, 2) if A.size else 0.0
    n_zero = 0
    while A.shape[0]:
        _, sv, Vh = np.linalg.svd(A)
        r = int(np.sum(sv > rank_tol * scale))
        if r == A.shape[0]:
            break
        V = Vh.conj().T
        Z, Zp = V[:, r:], V[:, :r]
        Qf, _ = np.linalg.qr(E @ Z, mode="complete")
        k = Z.shape[1]
        if np.linalg.matrix_rank(E @ Z) < k:
            break  # an infinite eigenvalue shares the null space: leave it to QZ
        Q2 = Qf[:, k:]
        E, A = Q2.conj().T @ E @ Zp, Q2.conj().T @ A @ Zp
        n_zero += k
    return E, A, n_zero


def deflate_subspace(E, A, S):
    """Remove a declared invariant subspace span S (orthonormal columns) of s E − A exactly:
    with A S = E S J (J = (E S)⁺ A S), unitary [S S⊥] and [Q₁ Q₂] with Q₁ spanning E S,

        Qᴴ (s E − A) [S S⊥] = [[s E₁₁ − A₁₁, ·], [−Q₂ᴴ A S, s E₂₂ − A₂₂]],   Q₂ᴴ A S = Q₂ᴴ E S J = 0

    so the eigenvalues are those of J (the declared ones) and of (E₂₂, A₂₂).  Returns
    (E₂₂, A₂₂, J, residual) with residual = ‖A S − E S J‖ / (‖A‖‖S‖): how exactly S is
    invariant (E S must have full column rank: finite eigenvalues only)."""
    E, A, S = np.asarray(E), np.asarray(A), np.asarray(S)
    k = S.shape[1]
    if k == 0:
        return E, A, np.zeros((0, 0)), 0.0
    ES, AS = E @ S, A @ S
    J = np.linalg.lstsq(ES, AS, rcond=None)[0]
    residual = float(np.linalg.norm(AS - ES @ J) / max(np.linalg.norm(A), 1e-300))
    Sf, _ = np.linalg.qr(S, mode="complete")
    Sp = Sf[:, k:]
    Qf, _ = np.linalg.qr(ES, mode="complete")
    Q2 = Qf[:, k:]
    return Q2.conj().T @ E @ Sp, Q2.conj().T @ A @ Sp, J, residual


@dataclass(frozen=True, eq=False)
class GEPSolution(QEPSolution):
    """Finite eigenvalues of (s E − A) x = 0 with unit right vectors, conjugated left vectors,
    backward errors and condition numbers (module docstring); the fields of ``QEPSolution``,
    ``norms`` = (‖E‖_F, ‖A‖_F) and ``problem`` = (E, A)."""

    @property
    def error_bound(self) -> np.ndarray:
        """κ·η per pair: first-order bound of the error of s."""
        return self.condition * self.backward_error

    def componentwise(self, idx=None):
        """(η_c, κ_c): η_c = maxᵢ |r|ᵢ / ((|s||E| + |A|)|x|)ᵢ,
        κ_c = |y|ᵀ(|s||E| + |A|)|x| / |yᴴEx|."""
        E, A = self.problem
        idx = np.arange(self.eigenvalues.size) if idx is None else np.asarray(idx)
        eta, kap = np.empty(idx.size), np.empty(idx.size)
        for j, i in enumerate(idx):
            s, x, yc = self.eigenvalues[i], self.vectors[:, i], self.left_vectors[:, i]
            W = abs(s) * np.abs(E) + np.abs(A)
            den = W @ np.abs(x)
            r = np.abs((s * E - A) @ x)
            with np.errstate(divide="ignore", invalid="ignore"):
                q = np.where(den > 0, r / den, np.where(r > 0, np.inf, 0.0))
            eta[j] = q.max(initial=0.0)
            kap[j] = (np.abs(yc) @ W @ np.abs(x)) / abs(np.conj(yc) @ E @ x)
        return eta, kap


def solve_descriptor(E, A, *, inf_tol=1e-12, zero_tol=None, solver="descriptor-qz",
                     reason="first-order pencil"):
    """Finite eigenpairs of (s E − A) x = 0 (module docstring).  With ``zero_tol`` the exact
    s = 0 of cyclic coordinates is deflated first (:func:`deflate_zero`) and counted in
    ``details["n_rigid"]``; the vectors are then those of the deflated pencil."""
    E, A = np.asarray(E), np.asarray(A)
    n_rigid = 0
    if zero_tol is not None:
        E, A, n_rigid = deflate_zero(E, A, rank_tol=zero_tol)
    if E.shape != A.shape or E.ndim != 2 or E.shape[0] != E.shape[1]:
        raise ValueError(f"E and A must be square and of one size (got {E.shape}, {A.shape})")
    nE, nA = float(np.linalg.norm(E)), float(np.linalg.norm(A))
    w, vl, vr = sla.eig(A, E, left=True, right=True, homogeneous_eigvals=True)
    alpha, beta = w
    a_s, b_s = alpha / max(nA, 1e-300), beta / max(nE, 1e-300)
    chord = np.abs(b_s) / np.maximum(np.hypot(np.abs(a_s), np.abs(b_s)), 1e-300)
    finite = chord > inf_tol
    s = alpha[finite] / beta[finite]
    X, Y = vr[:, finite], vl[:, finite]
    X = X / np.linalg.norm(X, axis=0)
    Y = Y / np.linalg.norm(Y, axis=0)
    Yc = np.conj(Y)  # conjugated left vectors (yᴴ = columns transposed), as QEPSolution
    wgt = np.abs(s) * nE + nA
    R = E @ X * s - A @ X
    eta = np.linalg.norm(R, axis=0) / wgt
    yEx = np.abs(np.einsum("ij,ij->j", Yc, E @ X))
    with np.errstate(divide="ignore"):
        kappa = np.where(yEx > 0, wgt / yEx, np.inf)
    order = np.lexsort((s.imag, s.real, np.abs(s)))
    cplx = np.iscomplexobj(E) or np.iscomplexobj(A)
    return GEPSolution(s[order], X[:, order], eta[order], kappa[order], solver, reason,
                       n_infinite=int((~finite).sum()), norms=(nE, nA),
                       details={"inf_tol": inf_tol, "zero_tol": zero_tol, "n_rigid": n_rigid},
                       left_vectors=Yc[:, order],
                       n_dof=E.shape[0], complex_problem=cplx, problem=(E, A))


def descriptor_problem(E, A):
    """The :class:`~mbseig.eigen.contract.Problem` of s E − A (module docstring)."""
    from .contract import Problem

    return Problem(None, np.asarray(E), -np.asarray(A))


def _driver(problem, request):
    """The ``descriptor`` family: (P s + Q) x = 0 with M = None, i.e. s E − A with E = P,
    A = −Q; options ``inf_tol`` and ``zero_tol`` of :func:`solve_descriptor`."""
    from ..errors import SolverError

    if problem.M is not None:
        raise SolverError("solver 'descriptor-qz' solves a first-order pencil (M = None)")
    opts = dict(request.options)
    unknown = sorted(set(opts) - {"inf_tol", "zero_tol"})
    if unknown:
        raise SolverError(f"unknown option {unknown[0]!r} of solver 'descriptor-qz'")
    E = problem.P.toarray() if sp.issparse(problem.P) else np.asarray(problem.P)
    A = -(problem.Q.toarray() if sp.issparse(problem.Q) else np.asarray(problem.Q))
    return solve_descriptor(E, A, **opts)


def _register():
    from .contract import register, register_family

    register_family("descriptor", _driver)
    register("descriptor-qz", family="descriptor",
             needs="a first-order pencil s E − A (velocity constraints: a steady motion)",
             kernel=solve_descriptor)


_register()
