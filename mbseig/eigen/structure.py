"""Structure tests of M, P, Q for the choice of path: symmetry to a relative tolerance (dense or
sparse, without forming the transpose densely) and the Rayleigh fit P = αM + βQ."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

BIG, SMALL = 1e150, 1e-150  # beyond these, norms are computed on a scaled copy
# Σ|x|² by one dot is exact to rounding when it lands in [SUMSQ_LO, SUMSQ_HI]: nothing
# overflowed, and squares that underflowed (|x| < 1.5e-154) add at most 1e8 · 2e-308 against
# at least 1e-200, far below one rounding error (the dense paths stay below 1e8 entries)
SUMSQ_LO, SUMSQ_HI = 1e-200, 1e300


def sumsq(x):
    """Σ|x|² of a flat array by one BLAS dot (no temporaries); ∞ or NaN when it overflows
    (the callers then take the scaled path)."""
    with np.errstate(over="ignore", invalid="ignore", under="ignore"):
        return float(np.vdot(x, x).real) if np.iscomplexobj(x) else float(np.dot(x, x))


def fro(A) -> float:
    """Frobenius norm of a dense or sparse matrix, without overflow or underflow of the squares."""
    data = A.data if sp.issparse(A) else np.asarray(A)
    if data.size == 0:
        return 0.0
    if not sp.issparse(A) and data.size <= 10**8:
        flat = (data.reshape(-1) if data.flags.c_contiguous or data.flags.f_contiguous
                else np.ravel(data))
        ss = sumsq(flat)
        if SUMSQ_LO <= ss <= SUMSQ_HI:
            return float(np.sqrt(ss))
    big = float(np.max(np.abs(data)))
    if big == 0.0:
        return 0.0
    if SMALL < big < BIG:
        if sp.issparse(A):  # duplicates summed first: their squares do not add
            B = A.tocsr(copy=True)
            B.sum_duplicates()
            return float(np.linalg.norm(B.data))
        return float(np.linalg.norm(A))
    return big * float(np.linalg.norm(np.ravel(data) / big))


def _antisymmetric_sumsq(A, block=64):
    """‖A − Aᵀ‖_F² of a dense square A by row slabs of the upper triangle (cache-friendly: no
    strided n × n transpose); None when a partial sum leaves the safe range of :func:`sumsq`."""
    n = A.shape[0]
    total = 0.0
    for i in range(0, n, block):
        j = min(i + block, n)
        D = A[i:j, i:] - A[i:, i:j].T  # rows i..j, columns ≥ i
        d = sumsq(np.ascontiguousarray(D[:, : j - i]).reshape(-1))  # diagonal block: once
        o = sumsq(np.ascontiguousarray(D[:, j - i:]).reshape(-1))  # above it: mirrored below
        total += d + 2.0 * o
    if not np.isfinite(total) or total > SUMSQ_HI:
        return None
    return total


def is_symmetric(A, tol, *, norm=None, found=None) -> bool:
    """‖A − Aᵀ‖_F ≤ tol ‖A‖_F (a zero matrix is symmetric).  ``norm``: ‖A‖_F if known;
    ``found``: a dict that receives ‖A − Aᵀ‖_F as "asymmetry" (where it was computed)."""
    nA = fro(A) if norm is None else norm
    if nA == 0:
        return True
    # fast path when the threshold (tol‖A‖)² is far above what underflowed squares can add
    if not sp.issparse(A) and A.ndim == 2 and A.shape[0] == A.shape[1] and \
            nA * nA <= SUMSQ_HI and (tol * nA) ** 2 >= 1e-190:
        ss = _antisymmetric_sumsq(np.asarray(A))
        if ss is not None:
            a = float(np.sqrt(ss))
            if found is not None:
                found["asymmetry"] = a
            return a <= tol * nA
    a = fro(A - A.T)
    if found is not None:
        found["asymmetry"] = a
    return a <= tol * nA


def rayleigh_fit(M, P, Q, tol, *, probes=None, seed=0, residual=False):
    """(α, β) with P = αM + βQ to relative accuracy ``tol``, or None.

    Dense matrices are fitted entry by entry; with ``probes`` = k the fit uses the products with
    k random vectors instead (sparse matrices, never densified).  ``residual`` (dense only):
    return (α, β, ‖P − αM − βQ‖_F) with the residual norm the fit was judged by, computed
    directly from the entries (the dense proportional path bounds its backward errors with it).
    """
    if residual and probes is not None:
        raise ValueError("rayleigh_fit: residual=True needs the dense (entrywise) fit")
    if fro(P) == 0:
        return (0.0, 0.0, 0.0) if residual else (0.0, 0.0)
    if probes is None:
        fit = _dense_fit(M, P, Q, tol)
        if fit is not False:
            return fit if (fit is None or residual) else fit[:2]
        cols, b = [M.ravel(), Q.ravel()], P.ravel()
    else:  # the fit of P V to M V and Q V: the dense fit's inner products where they serve
        V = np.random.default_rng(seed).standard_normal((M.shape[0], probes))
        MV, QV, PV = M @ V, Q @ V, P @ V
        fit = _dense_fit(MV, PV, QV, tol)  # 10⁶ rows: 0.08 s a call, 0.19 s by lstsq
        if fit is not False:
            return fit if fit is None else fit[:2]
        cols, b = [MV.ravel(), QV.ravel()], PV.ravel()
    A = np.column_stack(cols)
    with np.errstate(all="ignore"):  # entries near the range limits: judged by finiteness below
        coef, *_ = np.linalg.lstsq(A, b, rcond=None)
        rn = float(np.linalg.norm(A @ coef - b))
        fits = bool(np.all(np.isfinite(coef))) and rn <= tol * np.linalg.norm(b)
    if not fits:
        return None
    return (float(coef[0]), float(coef[1])) + ((rn,) if residual else ())


def _dense_fit(M, P, Q, tol):
    """The dense Rayleigh fit from six dot products of the flattened M, Q, P and one residual
    pass (O(n²), no n² × 2 least-squares copy): (α, β, ‖P − αM − βQ‖_F), None when P is not
    αM + βQ to ``tol``,
    or False when the magnitudes leave the range where single dot products are exact or M and Q
    are nearly parallel (the caller then uses lstsq).  The residual ‖P − αM − βQ‖ that decides
    is computed directly, never from the Gram matrix."""
    from scipy.linalg.blas import daxpy

    if any(X.dtype.kind == "c" for X in (M, P, Q)):
        return False
    a, q, b = (np.ascontiguousarray(X, dtype=float).reshape(-1) for X in (M, Q, P))
    aa, qq, bb = sumsq(a), sumsq(q), sumsq(b)
    if not all(x == 0.0 or SUMSQ_LO <= x <= SUMSQ_HI for x in (aa, qq, bb)) or aa == 0.0:
        return False
    na = np.sqrt(aa)
    r12 = float(np.dot(a, q)) / na  # Gram–Schmidt in inner products: q = r12 u1 + r22 u2
    t1 = float(np.dot(a, b)) / na
    w2 = qq - r12 * r12
    if qq == 0.0:
        alpha, beta = t1 / na, 0.0  # Q = 0: all on M, as lstsq's minimum-norm fit
    elif w2 <= 1e-6 * qq:
        return False  # M and Q nearly parallel: cancellation in w2, let lstsq decide
    else:
        r22 = np.sqrt(w2)
        t2 = (float(np.dot(q, b)) - r12 * t1) / r22
        beta = t2 / r22
        alpha = (t1 - r12 * beta) / na
    if not (np.isfinite(alpha) and np.isfinite(beta)):
        return None
    r = b.copy()
    with np.errstate(all="ignore"):
        r = daxpy(a, r, a=-alpha)
        if beta != 0.0:
            r = daxpy(q, r, a=-beta)
        rn2 = sumsq(r)
    if not np.isfinite(rn2):
        return None
    rn = float(np.sqrt(rn2))
    return (float(alpha), float(beta), rn) if rn <= tol * np.sqrt(bb) else None
