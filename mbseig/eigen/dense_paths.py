"""Kernels of the dense paths (registered in :mod:`mbseig.eigen.dense`): eigh and proportional
(structured, LAPACK divide and conquer), companion (geev on the mass-normalized companion
matrix) and qz (scaled pencil); η and κ of every pair (:mod:`mbseig.eigen.measures`)."""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..errors import SolverError
from .base import (
    QEPSolution,
)
from .measures import (
    EPS,
    backward_errors,
    better_half,
    colnorm,
    conditions,
    expand_pairs,
    fro,
    unit_columns,
)
from .undamped import proportional_real_error, undamped_pairs


def diagonal_positive(M):
    """None when M is not diagonal; else whether its diagonal is real positive."""
    d = np.diagonal(M)
    if np.count_nonzero(M) != np.count_nonzero(d):
        return None
    return bool(np.all(np.isreal(d)) and np.all(d.real > 0))


def _fast_operand(A, density=0.05):
    """A as CSR when sparse enough that products with 2n vectors are cheaper that way."""
    if not sp.issparse(A) and A.size > 10_000 and A.ndim == 2 and A.flags.c_contiguous:
        flat = A.reshape(-1)
        mask = flat != 0  # a bool mask: its count and indices six times faster than the floats'
        if np.count_nonzero(mask) > density * A.size:
            return A
        idx = np.flatnonzero(mask)  # row-major: already in CSR order, no duplicates
        rows, cols = np.divmod(idx, A.shape[1])
        indptr = np.zeros(A.shape[0] + 1, dtype=np.intp)
        np.cumsum(np.bincount(rows, minlength=A.shape[0]), out=indptr[1:])
        # the arrays of csr_matrix((A[r, c], (r, c))), built directly (no COO conversion)
        return sp.csr_matrix((flat[idx], cols, indptr), shape=A.shape)
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
        w, V = diagonal_mass_eigh(Qs, m)
    else:
        Ms = np.add(M, M.T)
        Ms *= 0.5
        w, U = sla.eigh(Qs, Ms, driver="gvd", overwrite_a=True, overwrite_b=True,
                        check_finite=False)
        V = np.ascontiguousarray(U)
    V /= colnorm(V)
    return w, V


def diagonal_mass_eigh(Qs, m):
    """(ω², V) of Qs v = ω² diag(m) v, Qs symmetric (overwritten): diag(m) scaled out, a
    standard problem for LAPACK's divide and conquer (``syevd``); V in C order."""
    root = np.sqrt(m)
    if np.any(root != 1.0):
        Qs /= root[:, None]
        Qs /= root[None, :]
    w, U = sla.eigh(Qs, driver="evd", overwrite_a=True, check_finite=False)
    return w, np.divide(U, root[:, None], order="C")


def _times(A, V):
    """A @ V for a dense A (as CSR when sparse enough: :func:`_fast_operand`) and C-ordered V."""
    return _fast_operand(A) @ V


def _structured(M, P, Q, opts, name, reason, norms):
    """eigh and proportional: real undamped modes (ω², v), both roots s of each from
    s² + (α + βω²)s + ω² = 0; η and κ of both from the one real residual r = Qv − ω²Mv per mode
    and the deviation ‖P − αM − βQ‖_F of the fit (:func:`~mbseig.eigen.undamped.undamped_pairs`:
    an exact identity, no complex T(s)v formed; P is never multiplied)."""
    alpha, beta = opts.get("alpha", 0.0), opts.get("beta", 0.0)
    fit = opts.get("fit_residual")
    if fit is None:  # not from choose_solver's fit: ‖E‖_F directly (E = P for P = 0)
        fit = fro(P - alpha * M - beta * Q) if (alpha or beta) else fro(P)
    diag = opts["diagonal"] if "diagonal" in opts else diagonal_positive(M)
    m = np.diagonal(M).copy() if diag else None
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


def solve_eigh(M, P, Q, opts, name, reason, norms):
    return _structured(M, P, Q, opts, name, reason, norms)


def solve_proportional(M, P, Q, opts, name, reason, norms):
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


def solve_companion(M, P, Q, opts, name, reason, norms):
    n = M.shape[0]
    if (opts["diagonal"] if "diagonal" in opts else diagonal_positive(M)):  # lumped (diagonal) M
        root = np.sqrt(np.diagonal(M).real)
        with np.errstate(over="ignore", invalid="ignore"):  # judged by _require_finite below
            Qt = Q / np.outer(root, root)
            Pt = P / np.outer(root, root)
        def back(Y):
            return Y / root[:, None]  # L⁻ᵀ y with L = diag(√m)
    else:
        L = opts.get("L")
        L = sla.cholesky(0.5 * (M + M.T), lower=True) if L is None else L
        Qt = _lower_solve(L, _lower_solve(L, Q).T).T
        Pt = _lower_solve(L, _lower_solve(L, P).T).T
        def back(Y):
            return _lower_solve(L, Y, trans=1)  # L⁻ᵀ y

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
    if pos is None:
        return sol
    s = sol.eigenvalues[pos]  # γμ of the measured column; its conjugate for the partner (exact)
    return _with_partners(sol, np.where(partner, np.conj(s), s), pos, partner)


def _lower_solve(L, B, trans=0):
    """L⁻¹B (L⁻ᵀB with trans=1) for the lower-triangular L: LAPACK ``trtrs``, the routine
    ``scipy.linalg.solve_triangular`` calls (the same result), without its checks' overhead
    (≈ 20 µs a call, seven calls a small solve); scipy's function for complex B or a
    singular L (its message)."""
    if L.dtype == np.float64 and B.dtype == np.float64 and B.ndim == 2:
        x, info = _TRTRS(L, B, lower=1, trans=trans)
        if info == 0:
            return x
    return sla.solve_triangular(L, B, lower=True, trans=trans)


_TRTRS = sla.get_lapack_funcs("trtrs", (np.zeros(1),))


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


def _ggev(A, B, left):
    """(w, W, Z) of ``scipy.linalg.eig(A, B, left=left, right=True, homogeneous_eigvals=True)``
    (W None without ``left``), the same numbers: LAPACK ``ggev`` with the workspace of its own
    query, the conjugate pairs' complex vectors formed as scipy forms them, and each vector
    divided by its BLAS ``nrm2``, called directly (scipy's per-column norm, with its finiteness
    check, took 0.6 ms of a 15 ms Campbell speed on 84 columns)."""
    ggev, = sla.get_lapack_funcs(("ggev",), (A, B))
    lwork = ggev(A, B, lwork=-1)[-2][0].real.astype(np.int_)
    if ggev.typecode in "cz":  # a complex pencil: complex eigenvalues and vectors as they are
        alpha, beta, vl, vr, _, info = ggev(A, B, int(left), 1, lwork, 0, 0)
    else:
        alphar, alphai, beta, vl, vr, _, info = ggev(A, B, int(left), 1, lwork, 0, 0)
        alpha = alphar + 1j * alphai
    if info < 0:
        raise SolverError(f"LAPACK ggev: illegal value in argument {-info}")
    if info > 0:  # (scipy's message; _lapack makes it the one SolverError)
        raise np.linalg.LinAlgError("generalized eig algorithm (ggev) did not converge "
                                    f"(LAPACK info={info})")
    w = np.vstack((alpha, beta))
    vectors = [vr, vl] if left else [vr]
    if ggev.typecode not in "cz" and not np.all(w.imag == 0.0):  # pairs: column i + 1 holds
        # the imaginary part of column i's
        pairs = np.flatnonzero(alpha.imag > 0)  # (scipy's rule for homogeneous eigenvalues)
        for k, V in enumerate(vectors):
            Z = np.array(V, dtype=complex)
            if np.any(np.diff(pairs) == 1):  # (not LAPACK's documented layout: scipy's loop)
                for i in pairs:
                    Z.imag[:, i] = V[:, i + 1]
                    np.conj(Z[:, i], Z[:, i + 1])
            else:
                Z.imag[:, pairs] = V[:, pairs + 1]
                Z[:, pairs + 1] = np.conj(Z[:, pairs])
            vectors[k] = Z
    for V in vectors:
        nrm2 = sla.get_blas_funcs("nrm2", dtype=V.dtype, ilp64="preferred")
        for i in range(V.shape[1]):
            V[:, i] /= nrm2(V[:, i])
    return (w, vectors[1], vectors[0]) if left else (w, None, vectors[0])


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


def solve_qz(M, P, Q, opts, name, reason, norms):
    n = M.shape[0]
    gamma, delta = _flvd(norms, opts.get("scale", True))
    Ms, Ps, Qs = gamma**2 * delta * M, gamma * delta * P, delta * Q
    Id = np.eye(n)
    A = np.block([[np.zeros((n, n)), Id], [-Qs, -Ps]])
    B = np.block([[Id, np.zeros((n, n))], [np.zeros((n, n)), Ms]])
    _require_finite(A, "the scaled companion pencil")
    _require_finite(B, "the scaled companion pencil")
    w, W, Z = _lapack(_ggev, A, B, opts["left"])
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
    s, X, Yc, eta, n_refined = _refine(M, P, Q, s, X, Yc, eta, norms, symmetric=Y is None)
    if n_refined:
        MX, PX = M @ X, P @ X
    kappa = conditions(s, X, Yc, MX, PX, norms)
    return QEPSolution(s, X, eta, kappa, name, reason, n_inf, norms,
                       {**details, "second_half_vectors": n_second,
                        "left_vectors": bool(opts["left"]), "refined_vectors": n_refined},
                       None, left_vectors=Yc)


REFINE_ETA = 1e-13  # pairs above it get their vectors refined


REFINE_MAX = 64  # at most this many (one n × n LU each)


def _refine(M, P, Q, s, X, Yc, eta, norms, *, symmetric, steps=2):
    """Inverse iteration on T(s) = s²M + sP + Q for the vectors of pairs whose η exceeds
    REFINE_ETA: the eigenvector of a companion matrix is ill-determined at a defective or nearly
    defective eigenvalue (η ~ √ε from the vector, not from s), while the best x for the computed
    s is T(s)'s smallest singular vector.  Kept only where η improves; left vectors likewise.
    Then s itself: the root nearest s of the two-sided Rayleigh functional yᴴT(s)x = 0 of the
    refined vectors (Newton on that scalar quadratic), kept where η of (s, x) improves.  A small
    eigenvalue of a pencil with a large P (|s|‖P‖ ≫ ‖Q‖ ≫ |s|²‖M‖: a gyroscopic system nearly
    without stiffness) is computed by the companion linearization with an absolute error of
    ε·γ, far above its own scale; the functional recovers it to ε relative.
    Returns (s, X, Yc, η, number of pairs improved)."""
    bad = np.flatnonzero(eta > REFINE_ETA)
    if not bad.size or bad.size > REFINE_MAX:
        return s, X, Yc, eta, 0
    s = np.array(s, dtype=complex)
    real_problem = not any(np.iscomplexobj(A) for A in (M, P, Q))
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
        s_new = _rayleigh_root(M, P, Q, s[j], x, x if symmetric else y.conj(), real_problem)
        if s_new is not None:
            e_s = backward_errors((M, P, Q), np.array([s_new]), x[:, None], norms)[0][0]
            if e_s < e_new:
                s[j], e_new = s_new, e_s
        if e_new < eta[j]:
            X[:, j], eta[j] = x, e_new
            if not symmetric:
                Yc[:, j] = y.conj()
            done += 1
    return s, X, Yc, eta, done


def _rayleigh_root(M, P, Q, s, x, yc, real_problem, steps=3):
    """The root nearest s of a σ² + b σ + c = 0 with a, b, c = yᴴMx, yᴴPx, yᴴQx (``yc`` = ȳ), by
    Newton from s; None where it is not finite or leaves the half-plane of s (a real problem's
    measured member of a pair has Im s > 0; a real s stays real)."""
    with np.errstate(all="ignore"):
        a, b, c = (complex(yc @ (A @ x)) for A in (M, P, Q))
        z = complex(s)
        for _ in range(steps):
            d = 2 * a * z + b
            if d == 0:
                return None
            z = z - ((a * z + b) * z + c) / d
    if not np.isfinite(z):
        return None
    if real_problem:
        if s.imag == 0:
            z = complex(z.real, 0.0)
        elif (z.imag > 0) != (s.imag > 0):
            return None
    return z
