"""Dense paths for the quadratic eigenvalue problem (M s² + P s + Q) x = 0 (docs/design.md).

Registered in :data:`mbseig.eigen.base.SOLVERS`; ``auto`` picks by structure and conditioning
(:func:`choose_solver`) and the result says which path ran and why:

``eigh``          P = 0, M and Q symmetric, M positive definite: ``eigh(Q, M)``, s = ±√(−ω²).
``proportional``  P = αM + βQ (Rayleigh damping, fitted and verified), M, Q symmetric, M > 0:
                  the undamped modes with s² + (α + βω²) s + ω² = 0 solved per mode.
``companion``     M symmetric positive definite and well conditioned (cond(M) ≤
                  ``companion_cond``): mass-normalized (M = LLᵀ, x = L⁻ᵀy) first companion
                  matrix scaled by γ, standard eigenproblem (LAPACK geev):

                      A = ┌    0          I    ┐ ,   s = γ μ
                          └ −Q̃/γ²     −P̃/γ   ┘
``qz``            anything else (singular or ill-conditioned M, non-symmetric M, complex M):
                  Fan–Lin–Van Dooren scaled pencil (γ = √(‖Q‖/‖M‖), δ = 2/(‖Q‖ + γ‖P‖)), QZ
                  (LAPACK ggev); infinite eigenvalues of a singular M dropped and counted.  A
                  singular pencil (det ≡ 0: a coordinate, or a combination of coordinates,
                  without mass, damping or stiffness) is refused before QZ
                  (:class:`~mbseig.eigen.base.SingularPencilError`).

Mass normalization divides by √m: with cond(M) = 10⁹ the companion matrix spans 10⁹ more in
its entries than the pencil and loses that much relative accuracy on the slow modes (measured
in tests/test_eigen_trust.py), hence the conditioning limit.  Problems whose norms lie outside
10^±100 (or whose frequency scale √(‖Q‖/‖M‖) lies outside 10^±50) are first scaled as the QZ
pencil is, s = γ μ, and solved in μ, so that no intermediate quantity overflows: η is invariant
under that scaling and κ scales with γ.  Complex M, P, Q (hysteretic damping) are solved on the
companion path (M real SPD) or the QZ path; their eigenvalues do not pair.

Every pair carries η and κ (:mod:`mbseig.eigen.measures`).  Of a companion eigenvector both
halves are candidates for x; the one with the smaller η is kept.
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..errors import SolverError
from ..numerics import blas_limit
from .base import (
    SOLVERS,
    QEPSolution,
    SingularPencilError,
    dense_solvers,
    register,
    requested_path,
)
from .measures import (
    EPS,
    backward_errors,
    better_half,
    colnorm,
    componentwise,
    conditions,
    expand_pairs,
    fro,
    is_symmetric,
    pow2_scale,
    proportional_real_error,
    rayleigh_fit,
    undamped_pairs,
    unit_columns,
)

__all__ = ["choose_solver", "problem_scaling", "solve_qep"]

#: cond(M) above which a positive definite M is not mass-normalized (companion, eigh paths)
COMPANION_COND = 1e5
STRUCTURED_COND = 1.0 / (1e3 * EPS)
SMALL_BLAS = 100  # order up to which the dense solve runs on one BLAS thread


def _dense(A, what):
    A = A.toarray() if sp.issparse(A) else np.asarray(A)
    if A.dtype.kind not in "biufc":
        raise SolverError(f"{what} must be a numeric matrix, got dtype {A.dtype}")
    if A.dtype.kind == "c":
        if np.any(A.imag):
            return np.asarray(A, dtype=complex)
        return np.ascontiguousarray(A.real, dtype=float)  # exactly real: nothing is discarded
    return np.asarray(A, dtype=float)


def _cholesky(M):
    try:
        return sla.cholesky(M, lower=True)
    except np.linalg.LinAlgError:
        return None


def _diagonal_positive(M):
    """None when M is not diagonal; else whether its diagonal is real positive."""
    d = np.diagonal(M)
    if np.count_nonzero(M) != np.count_nonzero(d):
        return None
    return bool(np.all(np.isreal(d)) and np.all(d.real > 0))


def mass_condition(M, memo=None):
    """(positive definite, cond₂(M) estimate) of a real symmetric M; (False, ∞) otherwise.

    Diagonal M: max/min of the diagonal (exact); else the Cholesky factor and LAPACK's 1-norm
    condition estimate (``pocon``).  ``memo`` keeps the Cholesky factor ("L") for the caller.
    """
    memo = {} if memo is None else memo
    if np.iscomplexobj(M):
        return False, np.inf
    diag = _diagonal_positive(M)
    if diag is not None:
        if not diag:
            return False, np.inf
        d = np.diagonal(M).real
        with np.errstate(over="ignore"):  # a subnormal mass: cond = ∞, as it is
            return True, float(d.max() / d.min())
    L = _cholesky(0.5 * (M + M.T))
    if L is None:
        return False, np.inf
    memo["L"] = L
    anorm = float(np.max(np.sum(np.abs(M), axis=0)))
    rcond, info = sla.lapack.dpocon(L, anorm, uplo="L")
    return True, (np.inf if info != 0 or rcond <= 0 else float(1.0 / rcond))


def choose_solver(M, P, Q, *, sym_tol=1e-13, rayleigh_tol=1e-12, memo=None,
                  companion_cond=COMPANION_COND):
    """(name, reason, extras) of the path ``auto`` takes for these matrices.

    memo : optional dict that caches the symmetry tests (keys "M", "P", "Q") and the Cholesky
    factor of M ("L") for the caller.
    companion_cond : largest cond(M) for which M is mass-normalized (companion path); the
    structured paths accept up to 1/(1000 ε).
    """
    memo = {} if memo is None else memo

    def sym(key, A):
        if key not in memo:
            memo[key] = is_symmetric(A, sym_tol)
        return memo[key]

    complex_problem = any(np.iscomplexobj(A) for A in (M, P, Q))
    pd, cond = (sym("M", M) and mass_condition(M, memo)) or (False, np.inf)
    memo["cond_M"] = cond
    if pd and not complex_problem and sym("Q", Q) and cond <= STRUCTURED_COND:
        if not np.any(P):
            return "eigh", "P = 0, M and Q symmetric, M positive definite", {}
        if sym("P", P):
            ab = rayleigh_fit(M, P, Q, rayleigh_tol, residual=True)
            if ab is not None:
                return ("proportional", f"P = {ab[0]:.6g} M + {ab[1]:.6g} Q (Rayleigh damping)",
                        {"alpha": ab[0], "beta": ab[1], "fit_residual": ab[2]})
    what = "complex M, P, Q: " if complex_problem else ""
    if pd and cond <= companion_cond:
        return "companion", f"{what}M symmetric positive definite: mass-normalized companion", {}
    if pd:
        return "qz", (f"{what}M positive definite but cond(M) ≈ {cond:.2g} > {companion_cond:.0g}: "
                      f"scaled QZ on the companion pencil (no division by the mass)"), {}
    return "qz", f"{what}M not symmetric positive definite: scaled QZ on the companion pencil", {}


def problem_scaling(norms, lo=1e-100, hi=1e100, gamma_range=1e50):
    """(log γ, log δ) scaling M, P, Q to γ²δM, γδP, δQ and s to μ = s/γ (after Fan, Lin & Van
    Dooren 2004) when the problem's magnitudes are extreme (a nonzero norm outside [lo, hi], or
    γ outside 10^±50); (0, 0) otherwise, so that ordinary problems are solved as given.

    In logarithms throughout (γ, δ themselves may be out of range, the scaled norms are not):
    γ ≈ √(‖Q‖/‖M‖) (‖P‖/‖M‖ without Q, ‖Q‖/‖P‖ without M), δ ≈ 1/max(γ²‖M‖, γ‖P‖, ‖Q‖), both
    rounded to powers of two so that scaling M, P, Q and mapping s = γμ back add no rounding
    error (an exp(log γ) would carry |log γ|·ε of it: 8e-14 at γ = 1e150); every scaled norm is
    then below 2.
    """
    logs = [np.log(x) if x > 0 else None for x in norms]
    lM, lP, lQ = logs
    if lM is not None and lQ is not None:
        lg = 0.5 * (lQ - lM)
    elif lM is not None and lP is not None:
        lg = lP - lM
    elif lP is not None and lQ is not None:
        lg = lQ - lP
    else:
        lg = 0.0
    present = [x for x in logs if x is not None]
    if not present or (max(present) <= np.log(hi) and min(present) >= np.log(lo)
                        and abs(lg) <= np.log(gamma_range)):
        return 0.0, 0.0
    ln2 = np.log(2.0)  # powers of two: the scaling and s = γμ are then exact in floating point
    lg = round(lg / ln2) * ln2
    scaled = [x + k * lg for x, k in ((lM, 2), (lP, 1), (lQ, 0)) if x is not None]
    return float(lg), float(round(-max(scaled) / ln2) * ln2)


def _scaled(A, log_factor):
    """A · e^log_factor for a log_factor that is a multiple of log 2: exact (ldexp), whatever the
    size of the factor itself."""
    if not log_factor:
        return A
    with np.errstate(under="ignore"):  # an entry below the normal range of the scaled problem
        return pow2_scale(A, int(round(log_factor / np.log(2.0))))  # is negligible against 1


def _fast_operand(A, density=0.05):
    """A as CSR when sparse enough that products with 2n vectors are cheaper that way."""
    if not sp.issparse(A) and A.size > 10_000 and np.count_nonzero(A) <= density * A.size:
        r, c = np.nonzero(A)  # row-major: already in CSR order (twice as fast as csr_matrix(A))
        return sp.csr_matrix((A[r, c], (r, c)), shape=A.shape)
    return A


def _undamped_eigh(M, Q, m=None):
    """(ω², V) of Q v = ω² M v, V with unit columns in C order; M = diag(m) when ``m`` is given
    (then scaled out: a standard eigenproblem).  LAPACK's divide and conquer (``syevd`` /
    ``sygvd``, the driver of ``eigh(Q, M)``) on a symmetrized copy that it may overwrite."""
    Qs = np.add(Q, Q.T)
    Qs *= 0.5
    if m is not None:
        l = np.sqrt(m)
        if np.any(l != 1.0):
            Qs /= l[:, None]
            Qs /= l[None, :]
        w, U = sla.eigh(Qs, driver="evd", overwrite_a=True, check_finite=False)
        V = np.divide(U, l[:, None], order="C")
    else:
        Ms = np.add(M, M.T)
        Ms *= 0.5
        w, U = sla.eigh(Qs, Ms, driver="gvd", overwrite_a=True, overwrite_b=True,
                        check_finite=False)
        V = np.ascontiguousarray(U)
    V /= colnorm(V)
    return w, V


def _times(A, V):
    """A @ V for a dense A (as CSR when sparse enough: :func:`_fast_operand`) and C-ordered V."""
    return _fast_operand(A) @ V


def _structured(M, P, Q, opts, name, reason, norms):
    """eigh and proportional: real undamped modes (ω², v), both roots s of each from
    s² + (α + βω²)s + ω² = 0; η and κ of both from the one real residual r = Qv − ω²Mv per mode
    and the deviation ‖P − αM − βQ‖_F of the fit (:func:`~mbseig.eigen.measures.undamped_pairs`:
    an exact identity, no complex T(s)v formed; P is never multiplied)."""
    alpha, beta = opts.get("alpha", 0.0), opts.get("beta", 0.0)
    fit = opts.get("fit_residual")
    if fit is None:  # not from choose_solver's fit: ‖E‖_F directly (E = P for P = 0)
        fit = fro(P - alpha * M - beta * Q) if (alpha or beta) else fro(P)
    m = np.diagonal(M).copy() if _diagonal_positive(M) else None
    w, V = _lapack(_undamped_eigh, M, Q, m)
    MV = V * m[:, None] if m is not None else _times(M, V)
    R = _times(Q, V)
    R -= MV * w  # r = Qv − ω²Mv per column
    a, vr = np.einsum("ij,ij->j", V, MV), np.einsum("ij,ij->j", V, R)
    s, eta, kappa = undamped_pairs(w, colnorm(MV), colnorm(R), a, vr, alpha, beta, fit, norms)
    X = np.concatenate([V, V], axis=1)
    real_error = None
    if name == "proportional":
        real_error = proportional_real_error(s, kappa, eta, norms, alpha, beta, fit)
    return QEPSolution(s, X, eta, kappa, name, reason, 0, norms,
                       {"second_half_vectors": 0, "left_vectors": False, "alpha": alpha,
                        "beta": beta, "fit_residual": fit},
                       real_error, left_vectors=X)


def _solve_eigh(M, P, Q, opts, name, reason, norms):
    return _structured(M, P, Q, opts, name, reason, norms)


def _solve_proportional(M, P, Q, opts, name, reason, norms):
    return _structured(M, P, Q, opts, name, reason, norms)


def _lapack(fn, *args, **kw):
    """A LAPACK driver; its failure to converge is one SolverError, not a LinAlgError."""
    try:
        return fn(*args, **kw)
    except np.linalg.LinAlgError as exc:
        raise SolverError(f"LAPACK failed ({exc}): the model's magnitudes are likely beyond what "
                          f"double precision resolves; rescale the units") from None


def _require_finite(A, what):
    """LAPACK must never see an inf or NaN (it reports an 'illegal value')."""
    if not np.all(np.isfinite(A)):
        raise SolverError(f"{what} overflowed (entries beyond 1e308): the model's magnitudes "
                          f"are out of range for this path; solver='qz' scales instead of dividing")


def _solve_companion(M, P, Q, opts, name, reason, norms):
    n = M.shape[0]
    if _diagonal_positive(M):  # lumped (diagonal) M
        l = np.sqrt(np.diagonal(M).real)
        with np.errstate(over="ignore", invalid="ignore"):  # judged by _require_finite below
            Qt = Q / np.outer(l, l)
            Pt = P / np.outer(l, l)
        back = lambda Y: Y / l[:, None]  # L⁻ᵀ y with L = diag(√m)
    else:
        L = opts.get("L")
        L = sla.cholesky(0.5 * (M + M.T), lower=True) if L is None else L
        Qt = sla.solve_triangular(L, sla.solve_triangular(L, Q, lower=True).T, lower=True).T
        Pt = sla.solve_triangular(L, sla.solve_triangular(L, P, lower=True).T, lower=True).T
        back = lambda Y: sla.solve_triangular(L, Y, lower=True, trans="T")  # L⁻ᵀ y
    gamma = np.sqrt(np.linalg.norm(Qt) / np.sqrt(n)) if np.any(Qt) else 1.0
    gamma = gamma if np.isfinite(gamma) and gamma > 0 else 1.0
    A = np.zeros((2 * n, 2 * n), dtype=np.result_type(Qt, Pt), order="F")
    A[:n, n:] = np.eye(n)
    A[n:, :n] = Qt
    A[n:, :n] *= -1.0 / gamma**2
    A[n:, n:] = Pt
    A[n:, n:] *= -1.0 / gamma
    _require_finite(A, "the mass-normalized companion matrix")
    if np.iscomplexobj(A):  # complex M, P, Q: no conjugate pairs, every column measured
        out = _lapack(sla.eig, A, left=opts["left"], right=True, overwrite_a=True,
                      check_finite=False)
        mu, W, Z = (out[0], out[1], out[2]) if opts["left"] else (out[0], None, out[1])
        pos = partner = None
    else:
        mu, Z, W, pos, partner = _lapack(_geev_pairs, A, opts["left"])
    mu_m = mu if pos is None else mu[~partner]  # the measured eigenvalues
    X1 = back(Z[:n])
    X2 = _second_half(back(Z[n:]), mu_m, X1)
    Y = back(W[n:]) if W is not None else None
    sol = _general_result(M, P, Q, gamma * mu_m, X1, X2, Y, 0, {"gamma": gamma}, opts, name,
                          reason, norms)
    return sol if pos is None else _with_partners(sol, gamma * mu, pos, partner)


def _geev_pairs(A, left):
    """LAPACK ``geev`` on the real A, called as ``scipy.linalg.eig`` calls it (the workspace of
    its own query, A overwritten), and the vectors of one member of each conjugate pair only.

    Returns (μ, Z, W, pos, partner): all 2n eigenvalues in LAPACK's order; Z (and W, the left
    vectors, or None) the complex vectors of the measured eigenvalues (real ones and the member
    with Im μ > 0 of each pair); ``pos[i]`` the measured column of eigenvalue i and ``partner``
    where it is the conjugate (μ̄, z̄) of that column.  LAPACK stores a pair (Im μ > 0 first) as
    two real columns, z = v_j ± i v_{j+1}: forming only the first halves the complex vectors
    and every measure of them (η, κ of a conjugate pair of a real problem are equal exactly).
    """
    geev, geev_lwork = sla.get_lapack_funcs(("geev", "geev_lwork"), (A,))
    n2 = A.shape[0]
    work, info = geev_lwork(n2, compute_vl=int(left), compute_vr=1)
    lwork = max(int(work.real), 1) if info == 0 else max(1, 4 * n2)
    wr, wi, vl, vr, info = geev(A, lwork=lwork, compute_vl=int(left), compute_vr=1,
                                overwrite_a=1)
    if info < 0:
        raise SolverError(f"LAPACK geev: illegal value in argument {-info}")
    if info > 0:  # as scipy.linalg.eig raises it: _lapack makes it the one SolverError
        raise np.linalg.LinAlgError("eig algorithm (geev) did not converge")
    mu = wr + 1j * wi
    partner = wi < 0
    first, j = np.flatnonzero(wi > 0), np.flatnonzero(partner)
    documented = first.size == j.size and np.array_equal(first + 1, j) and \
        np.array_equal(wr[first], wr[j]) and np.array_equal(wi[first], -wi[j])
    if documented:
        pos = np.cumsum(~partner) - 1
        measured = np.flatnonzero(~partner)

        def vectors(V):
            Z = V[:, measured].astype(complex)
            Z.imag[:, pos[first]] = V[:, j]
            return Z
    else:  # not the documented layout: every column formed (scipy.linalg.eig's rule) and measured
        pos, partner = np.arange(n2), np.zeros(n2, bool)
        pairs = np.flatnonzero((wi[:-1] > 0) | (wi[1:] < 0))  # i and i + 1 both exist

        def vectors(V):
            Z = V.astype(complex)
            for i in pairs:
                Z.imag[:, i] = V[:, i + 1]
                Z[:, i + 1] = np.conj(Z[:, i])
            return Z

    return mu, vectors(vr), (vectors(vl) if left else None), pos, partner


def _with_partners(sol, s, pos, partner):
    """``sol`` of the measured eigenvalues extended to all of them: eigenvalue i is s[i], its
    vectors and measures those of column pos[i], conjugated where ``partner``."""
    X = expand_pairs(sol.vectors, pos, partner)
    Y = sol.left_vectors
    Y = X if Y is sol.vectors else (None if Y is None else expand_pairs(Y, pos, partner))
    details = {**sol.details, "measured_columns": int(sol.eigenvalues.size)}
    return replace(sol, eigenvalues=s, vectors=X, left_vectors=Y, details=details,
                   backward_error=sol.backward_error[pos], condition=sol.condition[pos])


def _second_half(Z2, mu, X1):
    """The second half of companion vectors divided by μ (x = z₂/μ); where that overflows (μ
    tiny against z₂), the first half stands in (it is then the better candidate anyway)."""
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        X2 = Z2 / np.where(mu != 0, mu, 1.0)
    bad = ~np.all(np.isfinite(X2), axis=0)
    if np.any(bad):
        X2[:, bad] = X1[:, bad]
    return X2


def _flvd(norms, scale=True):
    """(γ, δ) of the Fan–Lin–Van Dooren scaling of the companion pencil."""
    nM, nP, nQ = norms
    if not scale:
        return 1.0, 1.0
    gamma = np.sqrt(nQ / nM) if nM > 0 and nQ > 0 else 1.0
    delta = 2.0 / (nQ + nP * gamma) if (nQ + nP * gamma) > 0 else 1.0
    return gamma, delta


def _solve_qz(M, P, Q, opts, name, reason, norms):
    n = M.shape[0]
    gamma, delta = _flvd(norms, opts.get("scale", True))
    Ms, Ps, Qs = gamma**2 * delta * M, gamma * delta * P, delta * Q
    I = np.eye(n)
    A = np.block([[np.zeros((n, n)), I], [-Qs, -Ps]])
    B = np.block([[I, np.zeros((n, n))], [np.zeros((n, n)), Ms]])
    _require_finite(A, "the scaled companion pencil")
    _require_finite(B, "the scaled companion pencil")
    out = _lapack(sla.eig, A, B, left=opts["left"], right=True, homogeneous_eigvals=True,
                  check_finite=False)
    w, W, Z = (out[0], out[1], out[2]) if opts["left"] else (out[0], None, out[1])
    alpha, beta = w
    inf_tol = opts.get("infinite_tol", 100 * n * EPS)
    scale_ab = np.hypot(np.abs(alpha), np.abs(beta))
    if np.any(scale_ab <= inf_tol * max(1.0, float(np.max(scale_ab, initial=0.0)))):
        raise SolverError("QZ returned a pair with α ≈ β ≈ 0 on a regular pencil: the model's "
                          f"magnitudes (‖M‖, ‖P‖, ‖Q‖ = {norms[0]:.3g}, {norms[1]:.3g}, "
                          f"{norms[2]:.3g} after scaling) span more than double precision "
                          f"resolves in one solve; rescale the units")
    finite = np.abs(beta) > inf_tol * np.abs(alpha)
    mu = alpha[finite] / beta[finite]
    Z = Z[:, finite]
    X1 = Z[:n]
    X2 = _second_half(Z[n:], mu, X1)
    Y = W[n:, finite] if W is not None else None
    details = {"gamma": gamma, "delta": delta, "infinite_tol": inf_tol}
    return _general_result(M, P, Q, gamma * mu, X1, X2, Y, int(np.sum(~finite)), details, opts,
                           name, reason, norms)


def _general_result(M, P, Q, s, X1, X2, Y, n_inf, details, opts, name, reason, norms):
    """η of both vector halves, the better one kept; κ from the left vectors (or y = x̄);
    vectors of pairs still above ``REFINE_ETA`` refined (:func:`_refine`)."""
    ops = tuple(_fast_operand(A) for A in (M, P, Q))
    X, eta, MX, PX, n_second = better_half(ops, s, X1, X2, norms)
    Yc = X if Y is None else unit_columns(Y).conj()  # y = x̄: exact for symmetric M, P, Q
    X, Yc, eta, n_refined = _refine(M, P, Q, s, X, Yc, eta, norms, symmetric=Y is None)
    if n_refined:
        MX, PX = M @ X, P @ X
    kappa = conditions(s, X, Yc, MX, PX, norms)
    return QEPSolution(s, X, eta, kappa, name, reason, n_inf, norms,
                       {**details, "second_half_vectors": n_second, "left_vectors": bool(opts["left"]),
                        "refined_vectors": n_refined},
                       None, left_vectors=Yc)


REFINE_ETA = 1e-13  # pairs above it get their vectors refined
REFINE_MAX = 64  # at most this many (one n × n LU each)


def _refine(M, P, Q, s, X, Yc, eta, norms, *, symmetric, steps=2):
    """Inverse iteration on T(s) = s²M + sP + Q for the vectors of pairs whose η exceeds
    REFINE_ETA: the eigenvector of a companion matrix is ill-determined at a defective or nearly
    defective eigenvalue (η ~ √ε from the vector, not from s), while the best x for the computed
    s is T(s)'s smallest singular vector.  Kept only where η improves; left vectors likewise."""
    bad = np.flatnonzero(eta > REFINE_ETA)
    if not bad.size or bad.size > REFINE_MAX:
        return X, Yc, eta, 0
    X = X.astype(complex)
    Yc = X if symmetric else Yc.astype(complex)
    done = 0
    for j in bad:
        z = s[j] * (1 + 8 * EPS) + 8 * EPS * (np.sqrt(norms[2] / norms[0]) if norms[0] > 0 else 1.0)
        T = (z * z) * M + z * P + Q
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore", sla.LinAlgWarning)  # near-singular: the point
            lu = sla.lu_factor(T, check_finite=False)
            x, y = X[:, j].copy(), Yc[:, j].conj().copy()
            for _ in range(steps):
                x = sla.lu_solve(lu, x, check_finite=False)
                x /= np.linalg.norm(x)
                if not symmetric:
                    y = sla.lu_solve(lu, y, trans=2, check_finite=False)
                    y /= np.linalg.norm(y)
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
            continue
        e_new = backward_errors((M, P, Q), s[j:j + 1], x[:, None], norms)[0][0]
        if e_new < eta[j]:
            X[:, j], eta[j] = x, e_new
            if not symmetric:
                Yc[:, j] = y.conj()
            done += 1
    return X, Yc, eta, done


def _equilibrated(T):
    """(R T C, 1/C): T with rows, then columns, scaled to largest entry 1, and the column factors
    (a null vector v of R T C is C v for T); None when T has a zero row or column."""
    r = np.max(np.abs(T), axis=1)
    if np.any(r == 0):
        return None
    T = pow2_scale(T, -np.frexp(r)[1][:, None])  # powers of two: exact, never overflowing
    c = np.max(np.abs(T), axis=0)
    if np.any(c == 0):
        return None
    ec = np.frexp(c)[1]
    return pow2_scale(T, -ec[None, :]), np.ldexp(1.0, ec)


def _null_vector(T):
    """A unit null vector of a (numerically) singular T: a zero column or row if there is one,
    else the last right singular vector of the equilibrated T mapped back."""
    for axis in (0, 1):
        zero = np.flatnonzero(np.max(np.abs(T), axis=axis) == 0)
        if zero.size:
            v = np.zeros(T.shape[0], complex)
            v[zero[0]] = 1.0
            return v, 0.0
    Te, c = _equilibrated(T)
    _, sv, Vh = np.linalg.svd(Te)
    v = Vh[-1].conj() / c
    return v / np.linalg.norm(v), float(sv[-1])


def check_regular(M, P, Q, norms, *, tol=None, seed=20240):
    """Raise :class:`SingularPencilError` when det(M s² + P s + Q) vanishes identically.

    T(z) = z²M + zP + Q, rows and columns equilibrated (so that a regular pencil whose
    eigenvalues span many orders is not mistaken for a singular one), is factorized (LU) at two
    random points z of modulus ~ γ = √(‖Q‖/‖M‖); a regular pencil is nonsingular at both (they
    are no eigenvalue, with probability one).  σ_min is estimated by three steps of inverse
    iteration on TᴴT; the pencil counts as singular when it is ≤ ``tol`` (default 100 n ε) at
    both points, or when T has a zero row or column.  The null vector of T at the last point
    (SVD, only then) is attached for naming.
    """
    n = M.shape[0]
    tol = 100 * n * EPS if tol is None else tol
    nM, _, nQ = norms
    gamma = np.sqrt(nQ / nM) if nM > 0 and nQ > 0 else 1.0
    rng = np.random.default_rng(seed)
    T = None
    for _ in range(2):
        z = gamma * rng.uniform(0.5, 2.0) * np.exp(1j * rng.uniform(0.1, np.pi - 0.1))
        with np.errstate(over="ignore", invalid="ignore"):
            T = (z * z) * M + z * P + Q
        if not np.all(np.isfinite(T)):
            raise SolverError("M s² + P s + Q overflows at |s| ~ √(‖Q‖/‖M‖): the model's entries "
                              "span more than double precision resolves; rescale the units")
        eq = _equilibrated(T)
        if eq is None:
            continue
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", sla.LinAlgWarning)  # an exact zero pivot: singular
            lu = sla.lu_factor(eq[0], check_finite=False)
        if np.any(np.diagonal(lu[0]) == 0):
            continue
        b = rng.standard_normal(n) + 1j * rng.standard_normal(n)
        sigma = 0.0
        with np.errstate(over="ignore", invalid="ignore"):  # overflow: σ_min = 0 to precision
            for _ in range(3):
                x = sla.lu_solve(lu, b / np.linalg.norm(b), check_finite=False)
                y = sla.lu_solve(lu, x / np.linalg.norm(x), trans=2, check_finite=False)
                if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
                    sigma = 0.0
                    break
                sigma = 1.0 / np.sqrt(np.linalg.norm(x) * np.linalg.norm(y))
                b = y
        if sigma > tol:
            return
    v, smin = _null_vector(T)
    raise SingularPencilError(
        f"singular pencil: det(M s² + P s + Q) ≡ 0 (equilibrated σ_min = {smin:.1e} at two "
        f"random s): a coordinate or combination without mass, damping or stiffness; every s "
        f"would be an eigenvalue", vector=v)


def solve_qep(M, P, Q, *, solver: str = "auto", sym_tol: float = 1e-13,
              rayleigh_tol: float = 1e-12, scale: bool = True, left="auto",
              companion_cond: float = COMPANION_COND, verify_tol: float = 1e-8) -> QEPSolution:
    """Solve (M s² + P s + Q) x = 0 by the dense path ``solver`` (``auto`` picks by structure).

    sym_tol : relative tolerance for treating M, Q (and P) as symmetric.
    rayleigh_tol : relative residual under which P counts as αM + βQ.
    scale : Fan–Lin–Van Dooren scaling on the QZ path (``False`` only to measure its value).
    left : left eigenvectors for the condition numbers on the companion and QZ paths.  ``auto``
        computes them only when M, P or Q is not symmetric: for symmetric matrices the left
        vector is the conjugate of the right one, exactly, and LAPACK's left vectors cost about
        10–15 % more time (measured by ``mbseig bench``).  ``False`` always takes y = x̄, which
        is only an estimate of κ for non-symmetric problems (recorded in ``details``).
    companion_cond : largest cond(M) for which ``auto`` mass-normalizes (companion path).
    verify_tol : a pair whose normwise and componentwise backward errors both exceed it is no
        eigenpair of the problem: the solve is refused (SolverError), never listed.

    M, P, Q may be complex (e.g. hysteretic damping (1 + iμ)K); a complex matrix whose
    imaginary part is exactly zero is taken as real.
    """
    M, P, Q = _dense(M, "M"), _dense(P, "P"), _dense(Q, "Q")
    n = M.shape[0]
    if not (M.ndim == P.ndim == Q.ndim == 2 and M.shape == P.shape == Q.shape == (n, n)):
        raise SolverError(f"M, P, Q must be square and of one size, got {M.shape}, {P.shape}, {Q.shape}")
    if not all(np.all(np.isfinite(A)) for A in (M, P, Q)):
        raise SolverError("M, P and Q must be finite")
    complex_problem = any(np.iscomplexobj(A) for A in (M, P, Q))
    norms0 = (fro(M), fro(P), fro(Q))
    lg, ld = problem_scaling(norms0)
    scaled = (lg, ld) != (0.0, 0.0)
    with np.errstate(over="ignore", under="ignore"):
        g0 = float(np.ldexp(1.0, int(round(lg / np.log(2.0)))))
    if not np.isfinite(g0) or g0 == 0.0:
        raise SolverError(f"the frequency scale of M, P, Q (‖M‖, ‖P‖, ‖Q‖ = {norms0[0]:.3g}, "
                          f"{norms0[1]:.3g}, {norms0[2]:.3g}) is beyond double precision: its "
                          f"eigenvalues would overflow or vanish; rescale the units")
    if scaled:  # factors in logarithms: γ²δ, γδ, δ may each be out of range, the products not
        M, P, Q = _scaled(M, 2 * lg + ld), _scaled(P, lg + ld), _scaled(Q, ld)
    norms = (fro(M), fro(P), fro(Q)) if scaled else norms0
    memo = {}
    name, reason, extras = choose_solver(M, P, Q, sym_tol=sym_tol, rayleigh_tol=rayleigh_tol,
                                         memo=memo, companion_cond=companion_cond)
    if scaled and name == "companion":  # no mass normalization of a problem scaled for range
        name, reason = "qz", reason.replace("mass-normalized companion", "scaled QZ (magnitudes out "
                                            "of range: no division by the mass)")
    name, reason, extras = requested_path(solver, name, reason, extras, dense_solvers())
    if name in ("companion", "eigh", "proportional") and not mass_condition(M, memo)[0]:
        raise SolverError(f"solver {name!r} needs {SOLVERS[name].needs}")
    if name in ("eigh", "proportional") and complex_problem:
        raise SolverError(f"solver {name!r} needs real M, P, Q")
    if left == "auto":
        left = not all(memo[k] if k in memo else is_symmetric(A, sym_tol)
                       for k, A in (("M", M), ("Q", Q), ("P", P)))
    opts = {**extras, "scale": scale, "left": bool(left), "L": memo.get("L")}
    if scaled:
        reason += (f"; scaled s = γμ (γ = 1e{lg / np.log(10):.1f}, δ = 1e{ld / np.log(10):.1f}): "
                   f"magnitudes out of range")
    if n == 0:
        e = np.zeros(0)
        return QEPSolution(e.astype(complex), np.zeros((0, 0), complex), e, e, name, reason, 0,
                           norms0, n_dof=0, complex_problem=complex_problem)
    # small problems on one BLAS thread: a second one only adds synchronization there (and on a
    # loaded machine milliseconds per call, more than the whole solve of a few coordinates)
    with blas_limit(1 if n <= SMALL_BLAS else None):
        if name == "qz":
            check_regular(M, P, Q, norms)
        sol = _IMPL[name](M, P, Q, opts, name, reason, norms)
    bad = ~np.isfinite(sol.eigenvalues)
    if np.any(bad):
        raise SolverError(f"{name}: {int(bad.sum())} of {sol.eigenvalues.size} eigenvalues are not "
                          f"finite (NaN or overflow): no listing can be made")
    details = {**sol.details, "cond_M": memo.get("cond_M", np.inf), "scaled": scaled,
               "problem_log10_gamma": lg / np.log(10), "problem_log10_delta": ld / np.log(10),
               "verify_tol": verify_tol}
    _verify(sol, M, P, Q, verify_tol, norms0)
    if not scaled:
        return replace(sol, details=details, n_dof=n, complex_problem=complex_problem,
                        problem=(M, P, Q, 1.0))
    with np.errstate(over="ignore", invalid="ignore"):  # judged just below
        s = sol.eigenvalues * g0
        real_error = None if sol.real_error is None else sol.real_error * g0
        condition = sol.condition * g0  # a bound beyond the double range is ∞: bounds nothing
    keep = np.isfinite(s)  # |s| beyond the double range: an infinite eigenvalue to precision
    if not np.all(keep):
        details["beyond_range"] = int(np.sum(~keep))
        pick = lambda a: a[..., keep] if a is not None else None
        sol = replace(sol, vectors=sol.vectors[:, keep], backward_error=sol.backward_error[keep],
                      left_vectors=pick(sol.left_vectors), n_infinite=sol.n_infinite + int(np.sum(~keep)))
        s, condition, real_error = s[keep], condition[keep], pick(real_error)
    return replace(sol, eigenvalues=s, condition=condition,
                   real_error=real_error, norms=norms0, details=details, n_dof=n,
                   complex_problem=complex_problem, problem=(M, P, Q, g0))


def _verify(sol, M, P, Q, verify_tol, norms0):
    """Refuse pairs that are no eigenpairs (η and η_c above ``verify_tol``, or η not a number)."""
    eta = np.where(np.isnan(sol.backward_error), np.inf, sol.backward_error)
    bad = np.flatnonzero(eta > verify_tol)
    if not bad.size:
        return
    Yc = None if sol.left_vectors is None else sol.left_vectors[:, bad]
    eta_c, _ = componentwise((M, P, Q), sol.eigenvalues[bad], sol.vectors[:, bad], Yc)
    failed = bad[~(eta_c <= verify_tol)]
    if failed.size:
        raise SolverError(
            f"{sol.solver}: {failed.size} of {sol.eigenvalues.size} eigenpairs fail the "
            f"backward-error check (η up to {float(np.max(eta[failed])):.1e} > {verify_tol:g}): "
            f"the model's magnitudes (‖M‖, ‖P‖, ‖Q‖ = {norms0[0]:.3g}, {norms0[1]:.3g}, "
            f"{norms0[2]:.3g}) span more than double precision resolves in one solve; rescale "
            f"the units or the offending entries")


_IMPL = {"eigh": _solve_eigh, "proportional": _solve_proportional, "companion": _solve_companion,
         "qz": _solve_qz}


for _name, _needs in {'eigh': 'P = 0, M and Q symmetric, M positive definite', 'proportional': 'P = αM + βQ with M and Q symmetric, M positive definite', 'companion': 'M symmetric positive definite', 'qz': 'nothing (any M, P, Q)'}.items():
    register(_name, partial=False, needs=_needs, driver=solve_qep)
