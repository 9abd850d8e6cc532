"""Structure tests and accuracy measures of eigenpairs, for dense and sparse M, P, Q alike.

Backward error of a pair (s, x) (Tisseur 2000, Frobenius-norm weights)::

    η = ‖(s²M + sP + Q)x‖ / (w(s) ‖x‖),    w(s) = |s|²‖M‖ + |s|‖P‖ + ‖Q‖

Absolute condition number from the left vector y (yᴴ(s²M + sP + Q) = 0)::

    κ = w(s) ‖x‖ ‖y‖ / |yᴴ(2sM + P)x|

so that κ·η bounds the error of s to first order (docs/design.md, "Eigenpair errors").

The componentwise pair (Higham & Higham 1998) perturbs each entry relative to itself, so a zero
entry stays zero::

    η_c = maxᵢ |r|ᵢ / ((|s|²|M| + |s||P| + |Q|)|x|)ᵢ,   κ_c = |y|ᵀ(|s|²|M| + |s||P| + |Q|)|x| / |yᴴ(2sM + P)x|

and κ_c·η_c is an error bound of s as valid as κ·η (the computed pair is exact for a perturbation
of M, P, Q bounded entrywise by η_c); it is much sharper for badly scaled models and structured
zeros (an exact zero eigenvalue of a coordinate without stiffness has κ_c = 0).

For |s| > 1 every quantity is evaluated on the reversed polynomial (t = 1/s:
M + tP + t²Q, the same ratios divided by |s|²), so |s| up to the overflow threshold gives finite
η and κ: no |s|² is ever formed.

Undamped and proportional pairs (:func:`undamped_pairs`).  With a real unit v and ω² = w from
the undamped problem, its residual r = Qv − wMv, and P = αM + βQ + E (E the deviation of the
Rayleigh fit; E = 0 and α = β = 0 when P = 0), every root s of s² + (α + βw)s + w = 0 has,
exactly::

    (s²M + sP + Q)v = ρ(s) Mv + (1 + βs) r + s Ev,    ρ(s) = s² + (α + βw)s + w

so that, with ‖Ev‖ ≤ ‖E‖_F,

    η ≤ (|ρ(s)| ‖Mv‖ + |1 + βs| ‖r‖ + |s| ‖E‖_F) / w(s)

and, as vᵀPv = (α + βw)vᵀMv + β vᵀr + vᵀEv,

    κ ≤ w(s) / (|(2s + α + βw) vᵀMv + β vᵀr| − ‖E‖_F).

|ρ(s)| of the computed s is evaluated in extended precision and increased by the rounding bound
of that evaluation; r, Mv, vᵀMv, vᵀr are the only quantities that involve the matrices: one
real residual per mode, for both roots, no complex n-vector.  ρ is at the rounding level of s,
so η is |1 + βs|‖r‖/w(s) plus terms of order ε and ‖E‖/‖P‖: the directly evaluated η of the
same pair (tests/test_proportional_fast.py) up to the rounding of either evaluation.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..numerics import colnorm as _colnorm_fast

__all__ = [
    "EPS",
    "backward_errors",
    "better_half",
    "colnorm",
    "componentwise",
    "conditions",
    "expand_pairs",
    "fro",
    "is_symmetric",
    "pow2_scale",
    "proportional_real_error",
    "rayleigh_fit",
    "undamped_pairs",
    "undamped_roots",
    "unit_columns",
]

EPS = np.finfo(float).eps
_BIG, _SMALL = 1e150, 1e-150  # beyond these, norms are computed on a scaled copy


def pow2_scale(X, e):
    """X · 2^e (e broadcast against X), exactly and without the overflow that a complex
    division by a subnormal number meets."""
    if np.iscomplexobj(X):
        return np.ldexp(X.real, e) + 1j * np.ldexp(X.imag, e)
    return np.ldexp(X, e)


def colnorm(X):
    """Column 2-norms without underflow or overflow of the squares (entries beyond 1e±150 are
    scaled per column first; the others take the fast path)."""
    X = np.asarray(X)
    if X.size == 0:
        return np.zeros(X.shape[1] if X.ndim == 2 else 0)
    m = np.max(np.abs(X), axis=0)
    odd = (m > _BIG) | ((m < _SMALL) & (m > 0))
    if not np.any(odd):
        return _colnorm_fast(X)
    out = np.zeros(X.shape[1])
    ok = ~odd
    if np.any(ok):
        out[ok] = _colnorm_fast(X[:, ok])
    e = np.frexp(m[odd])[1]  # scale by 2^-e: exact, no overflow even for a subnormal m
    Xs = pow2_scale(X[:, odd], -e[None, :])
    with np.errstate(over="ignore"):  # ≤ √n · 2 per column: the product is the true norm
        out[odd] = np.ldexp(_colnorm_fast(Xs), e)
    return out


def unit_columns(X):
    """X with unit columns (zero columns left as they are)."""
    nrm = colnorm(X)
    nrm[nrm == 0] = 1.0
    return X / nrm


def _sumsq(x):
    """Σ|x|² of a flat array by one BLAS dot (no temporaries); ∞ or NaN when it overflows
    (the callers then take the scaled path)."""
    with np.errstate(over="ignore", invalid="ignore", under="ignore"):
        return float(np.vdot(x, x).real) if np.iscomplexobj(x) else float(np.dot(x, x))


# Σ|x|² by one dot is exact to rounding when it lands in [_SUMSQ_LO, _SUMSQ_HI]: nothing
# overflowed, and squares that underflowed (|x| < 1.5e-154) add at most 1e8 · 2e-308 against
# at least 1e-200, far below one rounding error (the dense paths stay below 1e8 entries)
_SUMSQ_LO, _SUMSQ_HI = 1e-200, 1e300


def fro(A) -> float:
    """Frobenius norm of a dense or sparse matrix, without overflow or underflow of the squares."""
    data = A.data if sp.issparse(A) else np.asarray(A)
    if data.size == 0:
        return 0.0
    if not sp.issparse(A) and data.size <= 10**8:
        flat = data.reshape(-1) if data.flags.c_contiguous or data.flags.f_contiguous else np.ravel(data)
        ss = _sumsq(flat)
        if _SUMSQ_LO <= ss <= _SUMSQ_HI:
            return float(np.sqrt(ss))
    big = float(np.max(np.abs(data)))
    if big == 0.0:
        return 0.0
    if _SMALL < big < _BIG:
        if sp.issparse(A):  # duplicates summed first: their squares do not add
            B = A.tocsr(copy=True)
            B.sum_duplicates()
            return float(np.linalg.norm(B.data))
        return float(np.linalg.norm(A))
    return big * float(np.linalg.norm(np.ravel(data) / big))


def _antisymmetric_sumsq(A, block=64):
    """‖A − Aᵀ‖_F² of a dense square A by row slabs of the upper triangle (cache-friendly: no
    strided n × n transpose); None when a partial sum leaves the safe range of :func:`_sumsq`."""
    n = A.shape[0]
    total = 0.0
    for i in range(0, n, block):
        j = min(i + block, n)
        D = A[i:j, i:] - A[i:, i:j].T  # rows i..j, columns ≥ i
        d = _sumsq(np.ascontiguousarray(D[:, : j - i]).reshape(-1))  # diagonal block: once
        o = _sumsq(np.ascontiguousarray(D[:, j - i:]).reshape(-1))  # above it: mirrored below
        total += d + 2.0 * o
    if not np.isfinite(total) or total > _SUMSQ_HI:
        return None
    return total


def is_symmetric(A, tol) -> bool:
    """‖A − Aᵀ‖_F ≤ tol ‖A‖_F (a zero matrix is symmetric)."""
    nA = fro(A)
    if nA == 0:
        return True
    # fast path when the threshold (tol‖A‖)² is far above what underflowed squares can add
    if not sp.issparse(A) and A.ndim == 2 and A.shape[0] == A.shape[1] and \
            nA * nA <= _SUMSQ_HI and (tol * nA) ** 2 >= 1e-190:
        ss = _antisymmetric_sumsq(np.asarray(A))
        if ss is not None:
            return float(np.sqrt(ss)) <= tol * nA
    return fro(A - A.T) <= tol * nA


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
    else:
        V = np.random.default_rng(seed).standard_normal((M.shape[0], probes))
        cols, b = [(M @ V).ravel(), (Q @ V).ravel()], (P @ V).ravel()
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
    aa, qq, bb = _sumsq(a), _sumsq(q), _sumsq(b)
    if not all(x == 0.0 or _SUMSQ_LO <= x <= _SUMSQ_HI for x in (aa, qq, bb)) or aa == 0.0:
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
        rn2 = _sumsq(r)
    if not np.isfinite(rn2):
        return None
    rn = float(np.sqrt(rn2))
    return (float(alpha), float(beta), rn) if rn <= tol * np.sqrt(bb) else None


#: entries of one block of rows in the measures (≈ 16 MB of complex numbers): the per-column
#: sums are accumulated over blocks of rows, so that temporaries stay small and every operation
#: runs on contiguous memory (a block of columns of a C-ordered n × k array is strided: at
#: 10⁶ rows the column-blocked residual took twice as long)
ROW_BLOCK = 1 << 20


def _row_blocks(X):
    """Slices of X's rows with at most ``ROW_BLOCK`` entries each (at least one row)."""
    n = X.shape[0]
    k = X.shape[1] if X.ndim == 2 else 1
    step = max(1, ROW_BLOCK // max(k, 1))
    return [slice(i, min(i + step, n)) for i in range(0, n, step)] or [slice(0, 0)]


def _row_sliceable(ops):
    """M, P, Q as arrays or CSR matrices (their rows are taken block by block)."""
    return tuple(A.tocsr() if sp.issparse(A) and A.format != "csr" else A for A in ops)


def _add_colnorm(acc, nb):
    """Column norms of stacked row blocks from each block's norms (hypot: no overflow)."""
    return nb if acc is None else np.hypot(acc, nb)


def _reversal(s):
    """(t, big): t = 1/s where |s| > 1 (reversed polynomial), else s; big marks those columns."""
    s = np.asarray(s)
    big = np.abs(s) > 1.0
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(big, 1.0 / np.where(big, s, 1.0), s)
    return t, big


def _coefficients(s, derivative=False):
    """Per-column coefficients of M, P, Q in the (reversed where |s| > 1) polynomial:
    (s², s, 1) or (1, t, t²); with ``derivative``, those of M and P in 2sM + P or 2M + tP."""
    t, big = _reversal(s)
    one = np.ones_like(t)
    if derivative:
        return np.where(big, 2.0, 2.0 * t), np.where(big, t, one)
    return np.where(big, one, t * t), t, np.where(big, t * t, one)


def _unreverse(kappa, s, den):
    """κ of the reversed evaluation times |s| (undo its 1/|s|); ∞ where yᴴ(2sM + P)x = 0."""
    _, big = _reversal(s)
    with np.errstate(over="ignore", invalid="ignore"):
        kappa = np.where(big, kappa * np.abs(s), kappa)
    return np.where(den > 0, kappa, np.inf)


def _weights(s, norms):
    """w(s) = |s|²‖M‖ + |s|‖P‖ + ‖Q‖, or w(s)/|s|² where |s| > 1 (reversed)."""
    nM, nP, nQ = norms
    t, big = _reversal(s)
    a = np.abs(t)
    return np.where(big, nM + a * nP + a * a * nQ, a * a * nM + a * nP + nQ)


def _residual(MX, PX, QX, s):
    """(s²M + sP + Q)X, or (M + tP + t²Q)X with t = 1/s where |s| > 1, per column."""
    cM, cP, cQ = _coefficients(s)
    # MX·cM + PX·cP + QX·cQ in that order (bitwise the plain expression) with one temporary
    acc = MX * cM
    tmp = np.multiply(PX, cP, dtype=acc.dtype) if acc.dtype == np.result_type(PX, cP) else PX * cP
    if tmp.dtype != acc.dtype:
        return acc + tmp + QX * cQ
    acc += tmp
    res = np.result_type(QX, cQ)
    if res != acc.dtype:
        return acc + QX * cQ
    np.multiply(QX, cQ, out=tmp)
    acc += tmp
    return acc


def _derivative(MX, PX, s):
    """(2sM + P)X, or (2M + tP)X with t = 1/s where |s| > 1 (the scaling of _residual / |s|)."""
    cM, cP = _coefficients(s, derivative=True)
    return MX * cM + PX * cP


def _ratio(num, den):
    """num/den with 0/0 = 0 and x/0 = ∞ (a pair with zero residual has η = 0); a quotient
    beyond the double range is ∞ as well (a condition number that large bounds nothing)."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        return np.where(den > 0, num / np.where(den > 0, den, 1.0), np.where(num == 0, 0.0, np.inf))


def backward_errors(ops, s, X, norms):
    """(η, M X, P X): backward errors and the products reused for the condition numbers.

    A pair with zero residual has η = 0 even where the weights vanish (s = 0 with Q = 0).
    """
    M, P, Q = _row_sliceable(ops)
    X = np.ascontiguousarray(X)  # each block's Q[r] @ X would otherwise copy the whole X
    MX, PX = M @ X, P @ X
    s = np.asarray(s)
    rn = None
    for r in _row_blocks(X):  # Q X and the residual one block of rows at a time
        rn = _add_colnorm(rn, colnorm(_residual(MX[r], PX[r], Q[r] @ X, s)))
    xn = colnorm(X)
    eta = np.where(xn > 0, _ratio(rn, _weights(s, norms) * xn), np.inf)  # x = 0: no eigenvector
    return eta, MX, PX


def conditions(s, X, Yc, MX, PX, norms):
    """κ per pair, with ``Yc`` the conjugated left vectors (yᴴ = Ycᵀ) and MX, PX the products."""
    s = np.asarray(s)
    num = _weights(s, norms) * colnorm(X) * colnorm(Yc)
    den = np.zeros(s.size, complex)
    for r in _row_blocks(X):
        den += np.einsum("ij,ij->j", Yc[r], _derivative(MX[r], PX[r], s))
    den = np.abs(den)
    return _unreverse(_ratio(num, den), s, den)


def componentwise(ops, s, X, Yc, *, abs_ops=None):
    """(η_c, κ_c) per pair: componentwise backward errors and condition numbers (module doc).

    ops : (M, P, Q), dense or sparse; abs_ops : their entrywise absolute values if already formed.
    Yc : conjugated left vectors (yᴴ = Ycᵀ), or None for y = x̄ (symmetric M, P, Q).
    """
    M, P, Q = ops = _row_sliceable(ops)
    aM, aP, aQ = _row_sliceable(abs_ops if abs_ops is not None else tuple(abs(A) for A in ops))
    s = np.asarray(s)
    Yc = X if Yc is None else Yc
    X = np.ascontiguousarray(X)  # each block's products would otherwise copy the whole X
    t, big = _reversal(s)
    a = np.abs(t)
    AX = np.abs(X)
    eta_c = np.zeros(s.size)
    num = np.zeros(s.size)
    den = np.zeros(s.size, complex)
    for r in _row_blocks(X):  # the products, residual and |·| bound one block of rows at a time
        MX, PX = M[r] @ X, P[r] @ X
        R = np.abs(_residual(MX, PX, Q[r] @ X, s))
        D = np.where(big, aM[r] @ AX + (aP[r] @ AX) * a + (aQ[r] @ AX) * (a * a),
                     (aM[r] @ AX) * (a * a) + (aP[r] @ AX) * a + aQ[r] @ AX)
        eta_c = np.maximum(eta_c, np.max(_ratio(R, D), axis=0, initial=0.0))
        num += np.einsum("ij,ij->j", np.abs(Yc[r]), D)
        den += np.einsum("ij,ij->j", Yc[r], _derivative(MX, PX, s))
    den = np.abs(den)
    kappa_c = _unreverse(_ratio(num, den), s, den)
    kappa_c = np.where((den == 0) & (num == 0), 0.0, kappa_c)  # 0/0: s fixed by the zero pattern
    return eta_c, kappa_c


def better_half(ops, s, X1, X2, norms):
    """Of the two halves of companion eigenvectors, the one with the smaller η per column.

    Returns (X, η, M X, P X, number of columns taken from the second half), X with unit columns.
    Both halves are brought to one dtype first (a real half and a complex one of a real problem
    with real eigenvalues), so no imaginary part is cast away.
    """
    dtype = np.result_type(X1, X2)
    same = X2 is X1
    X1 = np.ascontiguousarray(unit_columns(X1), dtype=dtype)
    if same:  # one vector per pair (a path without companion halves)
        eta, MX, PX = backward_errors(ops, s, X1, norms)
        return X1, eta, MX, PX, 0
    X2 = np.ascontiguousarray(unit_columns(X2), dtype=dtype)
    if X1.size > ROW_BLOCK:  # large: η of both halves first, products of the kept one only
        e1, e2 = (backward_errors(ops, s, X, norms)[0] for X in (X1, X2))
        take2 = e2 < e1
        X1[:, take2] = X2[:, take2]
        del X2
        eta, MX, PX = backward_errors(ops, s, X1, norms)
        return X1, eta, MX, PX, int(np.sum(take2))
    e1, MX1, PX1 = backward_errors(ops, s, X1, norms)
    e2, MX2, PX2 = backward_errors(ops, s, X2, norms)
    take2 = e2 < e1
    for a, b in ((X1, X2), (MX1, MX2), (PX1, PX2)):
        a[:, take2] = b[:, take2]
    return X1, np.minimum(e1, e2), MX1, PX1, int(np.sum(take2))


def expand_pairs(Xu, pos, partner, rows=8192):
    """Columns Xu[:, pos], conjugated where ``partner``: every eigenpair of a real problem from
    one measured column per conjugate pair.  A block of rows at a time, so that the gather and
    the sign flip stay in cache (10⁶ rows, 40 columns: 0.45 s, against 1.2–2 s for one gather
    and a conjugated copy of the whole array)."""
    out = np.empty((Xu.shape[0], len(pos)), np.result_type(Xu), order="C")
    flip = np.flatnonzero(partner) if np.iscomplexobj(out) else np.zeros(0, int)
    for r in range(0, Xu.shape[0], rows):
        blk = Xu[r:r + rows][:, pos]
        if flip.size:
            blk.imag[:, flip] *= -1.0
        out[r:r + rows] = blk
    return out


def undamped_roots(w, alpha, beta):
    """Both roots of s² + (α + βω²)s + ω² = 0 per undamped mode ω² = w, [s₊; s₋] (stable form).

    Solved as u² + (c/r)u + w/r² = 0 with s = r u, r = max(|c|, √|w|), so that no c² or
    c·c − 4w overflows whatever the magnitudes."""
    w = np.asarray(w, float)
    with np.errstate(over="ignore", invalid="ignore"):
        c = alpha + beta * w
    r = np.maximum(np.abs(c), np.sqrt(np.abs(w)))
    r = np.where((r > 0) & np.isfinite(r), r, 1.0)
    cu, wu = c / r, (w / r) / r
    disc = cu * cu - 4.0 * wu
    s1 = np.empty(w.size, complex)
    s2 = np.empty(w.size, complex)
    osc = disc < 0
    s1[osc] = r[osc] * (-cu[osc] / 2 + 0.5j * np.sqrt(-disc[osc]))
    s2[osc] = np.conj(s1[osc])
    re = ~osc
    root = np.sqrt(disc[re])
    cr = cu[re]
    big = -(cr + np.copysign(root, cr)) / 2  # the root of larger magnitude, no cancellation
    small = np.divide(wu[re], big, out=np.zeros_like(big), where=big != 0)
    s1[re], s2[re] = r[re] * big, r[re] * small
    return np.concatenate([s1, s2])


_LD = np.longdouble
_EPS_LD = float(np.finfo(np.longdouble).eps)


def undamped_pairs(w, mv_norm, r_norm, a, vr, alpha, beta, fit_residual, norms):
    """s₊, s₋ of each undamped mode (ω² = w, unit real v) with s² + (α + βω²)s + ω² = 0, and
    η and κ of both, from the real residual r = Qv − ω²Mv of the undamped pair (module doc,
    "Undamped and proportional pairs"): no complex T(s)v is formed.

    mv_norm, r_norm : ‖Mv‖, ‖r‖ per mode; a : vᵀMv; vr : vᵀr; fit_residual : ‖E‖_F of
    E = P − αM − βQ (0 for P = 0).  Returns (s, η, κ), s = [s₊, s₋], y = x = v for κ.
    The scalar algebra runs in extended precision (np.longdouble where the platform has it),
    which also keeps |s|² w(s) free of overflow.
    """
    s = undamped_roots(w, alpha, beta)
    twice = lambda x: np.tile(np.asarray(x, dtype=_LD), 2)  # s₊ and s₋ share v
    with np.errstate(over="ignore", invalid="ignore", divide="ignore", under="ignore"):
        S = s.astype(np.clongdouble)
        W = twice(w)
        al, be, fit = _LD(alpha), _LD(beta), _LD(fit_residual)
        c = al + be * W
        rho = (S * S + c * S) + W  # s's own residual in its quadratic: rounding level
        A = np.abs(S)
        rho_bound = np.abs(rho) + 8 * _EPS_LD * (A * A + (abs(al) + abs(be) * np.abs(W)) * A
                                                 + np.abs(W))  # + the rounding of ρ itself
        num = rho_bound * twice(mv_norm) + np.abs(1 + be * S) * twice(r_norm) + A * fit
        nM, nP, nQ = (_LD(x) for x in norms)
        weight = A * A * nM + A * nP + nQ
        eta = np.where(weight > 0, num / np.where(weight > 0, weight, 1),
                       np.where(num == 0, 0, np.inf))
        # vᵀ(2sM + P)v = (2s + α + βω²) vᵀMv + β vᵀr + vᵀEv, |vᵀEv| ≤ ‖E‖_F: the smallest it
        # can be, so that κ is never understated by the fit
        den = np.abs((2 * S + c) * twice(a) + be * twice(vr)) - fit
        kappa = np.where(den > 0, weight / np.where(den > 0, den, 1), np.inf)
        return s, eta.astype(float), kappa.astype(float)


def proportional_real_error(s, kappa, eta, norms, alpha, beta, fit_residual):
    """Error bound of Re s on the proportional path, oscillatory roots (Re s = −(α + βω²)/2).

    ω² = −s s̄ for the pair; its error is at most 2|s|·κη (first order, undamped pencil), so
    |Δ Re s| ≤ |β| |s| κη + κ |s| ‖P − αM − βQ‖ / w(s) + ε |α + βω²|, w(s) the η weight.
    Real (overdamped) roots get no bound here (κη applies).
    """
    a = np.abs(s)
    _, big = _reversal(s)
    weight = _weights(s, norms)  # w(s), or w(s)/|s|² where |s| > 1
    ke = kappa * np.maximum(eta, EPS)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        scale = np.where(big, 1.0 / a, a)  # κ|s|·fit/w(s) in either form
        fit = np.where(weight > 0, kappa * scale * fit_residual / weight, np.inf)
        err = np.abs(beta) * a * ke + fit + EPS * 2 * np.abs(s.real)
    return np.where(np.abs(s.imag) > 0, err, np.inf)
