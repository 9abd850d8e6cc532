"""Structure tests and accuracy measures of eigenpairs, for dense and sparse M, P, Q alike.

Backward error of a pair (s, x) (Tisseur 2000, Frobenius-norm weights)::

    η = ‖(s²M + sP + Q)x‖ / (w(s) ‖x‖),    w(s) = |s|²‖M‖ + |s|‖P‖ + ‖Q‖

Absolute condition number from the left vector y (yᴴ(s²M + sP + Q) = 0)::

    κ = w(s) ‖x‖ ‖y‖ / |yᴴ(2sM + P)x|

so that κ·η bounds the error of s to first order (docs/design.md, "Eigenpair errors").

The componentwise pair (Higham & Higham 1998) perturbs each entry relative to itself, so a zero
entry stays zero::

    η_c = maxᵢ |r|ᵢ / ((|s|²|M| + |s||P| + |Q|)|x|)ᵢ,
    κ_c = |y|ᵀ(|s|²|M| + |s||P| + |Q|)|x| / |yᴴ(2sM + P)x|

and κ_c·η_c is an error bound of s as valid as κ·η (the computed pair is exact for a perturbation
of M, P, Q bounded entrywise by η_c); it is much sharper for badly scaled models and structured
zeros (an exact zero eigenvalue of a coordinate without stiffness has κ_c = 0).

For |s| > 1 every quantity is evaluated on the reversed polynomial (t = 1/s:
M + tP + t²Q, the same ratios divided by |s|²), so |s| up to the overflow threshold gives finite
η and κ: no |s|² is ever formed.

Undamped and proportional pairs: :mod:`mbseig.eigen.undamped` (its module docstring).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..numerics import colnorm as _colnorm_fast
from .structure import BIG, SMALL, fro, is_symmetric, rayleigh_fit, sumsq  # noqa: F401

__all__ = [
    "EPS", "backward_errors", "backward_errors_norms", "better_half", "better_half_norms",
    "colnorm", "componentwise", "conditions", "eta_kappa", "expand_pairs", "fro", "is_symmetric",
    "plain_norms", "pow2_scale", "rayleigh_fit", "unit_columns",
]

EPS = np.finfo(float).eps


def pow2_scale(X, e):
    """X · 2^e (e broadcast against X), exactly and without the overflow that a complex
    division by a subnormal number meets."""
    if np.iscomplexobj(X):
        return np.ldexp(X.real, e) + 1j * np.ldexp(X.imag, e)
    return np.ldexp(X, e)


def colnorm(X, m=None):
    """Column 2-norms without underflow or overflow of the squares (entries beyond 1e±150 are
    scaled per column first; the others take the fast path).  ``m``: max |X| per column, if
    already formed."""
    X = np.asarray(X)
    if X.size == 0:
        return np.zeros(X.shape[1] if X.ndim == 2 else 0)
    if m is None:
        fast = _colnorm_fast(X)
        if np.all(_plain(fast, X.shape[0])):  # max |X| provably within (SMALL, BIG): no |X|
            return fast
        m = np.max(np.abs(X), axis=0)
    odd = (m > BIG) | ((m < SMALL) & (m > 0))
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


def _plain(fast, rows):
    """Columns whose computed 2-norm ``fast`` proves max |x| inside [SMALL, BIG] (‖x‖/√rows ≤
    max |x| ≤ ‖x‖, with a factor 2 of margin for the rounding of ``fast``): no scaling needed,
    so ``fast`` is the norm and no |X| pass is made."""
    return (fast <= 0.5 * BIG) & (fast >= 2.0 * SMALL * np.sqrt(rows))


def plain_norms(X):
    """The divisors of :func:`unit_columns` (column norms, 1 for a zero column) where no column
    needs the power-of-2 scaling first, else None: X / plain_norms(X) is unit_columns(X)."""
    X = np.asarray(X)
    if X.ndim != 2 or not X.size:
        return None
    nrm = _colnorm_fast(X)
    if not np.all(_plain(nrm, X.shape[0])):
        m = np.max(np.abs(X), axis=0)
        if np.any(((m > BIG) | (m < SMALL)) & (m > 0)):
            return None
        nrm = colnorm(X, m)
    nrm[nrm == 0] = 1.0
    return nrm


def unit_columns(X, inplace=False):
    """X with unit columns (zero columns left as they are).  Columns beyond 1e±150 are first
    scaled by a power of 2 (exact): a complex division by a subnormal norm would overflow.
    ``inplace``: X (a float or complex array the caller owns) is overwritten where it can be."""
    X = np.asarray(X)
    nrm = plain_norms(X)
    if nrm is None:
        if X.ndim == 2 and X.size:
            m = np.max(np.abs(X), axis=0)
            odd = ((m > BIG) | (m < SMALL)) & (m > 0)
            X = X.copy()
            X[:, odd] = pow2_scale(X[:, odd], -np.frexp(m[odd])[1][None, :])
            inplace = True
        nrm = colnorm(X)
        nrm[nrm == 0] = 1.0
    if inplace and X.dtype.kind in "fc" and X.flags.writeable:
        X /= nrm
        return X
    return X / nrm


#: entries of one block of rows in the measures (≈ 16 MB of complex numbers): the per-column
#: sums are accumulated over blocks of rows, so that temporaries stay small and every operation
#: runs on contiguous memory (a block of columns of a C-ordered n × k array is strided: at
#: 10⁶ rows the column-blocked residual took twice as long)
ROW_BLOCK = 1 << 20
#: the same for :func:`eta_kappa`, whose block temporaries (M X, P X, Q X, residual,
#: derivative) stay in cache at 1 MB: 1.1·10⁴ × 21 pairs 24 → 10 ms, 1.1·10⁶ × 21 0.73 → 0.61 s
FUSED_BLOCK = 1 << 16


def _row_blocks(X, entries=None):
    """Slices of X's rows with at most ``entries`` (``ROW_BLOCK``) entries each (≥ one row)."""
    n = X.shape[0]
    k = X.shape[1] if X.ndim == 2 else 1
    step = max(1, (entries or ROW_BLOCK) // max(k, 1))
    return [slice(i, min(i + step, n)) for i in range(0, n, step)] or [slice(0, 0)]


def _row_sliceable(ops):
    """M, P, Q as arrays or CSR matrices (their rows are taken block by block)."""
    return tuple(A.tocsr() if sp.issparse(A) and A.format != "csr" else A for A in ops)


def _add_colnorm(acc, nb):
    """Column norms of stacked row blocks from each block's norms (hypot: no overflow)."""
    return nb if acc is None else np.hypot(acc, nb)


def reversal(s):
    """(t, big): t = 1/s where |s| > 1 (reversed polynomial), else s; big marks those columns."""
    s = np.asarray(s)
    big = np.abs(s) > 1.0
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(big, 1.0 / np.where(big, s, 1.0), s)
    return t, big


def _coefficients(s, derivative=False):
    """Per-column coefficients of M, P, Q in the (reversed where |s| > 1) polynomial:
    (s², s, 1) or (1, t, t²); with ``derivative``, those of M and P in 2sM + P or 2M + tP."""
    t, big = reversal(s)
    one = np.ones_like(t)
    if derivative:
        return np.where(big, 2.0, 2.0 * t), np.where(big, t, one)
    return np.where(big, one, t * t), t, np.where(big, t * t, one)


def _unreverse(kappa, s, den):
    """κ of the reversed evaluation times |s| (undo its 1/|s|); ∞ where yᴴ(2sM + P)x = 0."""
    _, big = reversal(s)
    with np.errstate(over="ignore", invalid="ignore"):
        kappa = np.where(big, kappa * np.abs(s), kappa)
    return np.where(den > 0, kappa, np.inf)


def weights(s, norms):
    """w(s) = |s|²‖M‖ + |s|‖P‖ + ‖Q‖, or w(s)/|s|² where |s| > 1 (reversed)."""
    nM, nP, nQ = norms
    t, big = reversal(s)
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
    return backward_errors_norms(ops, s, X, norms)[:3]


def backward_errors_norms(ops, s, X, norms):
    """(η, M X, P X, ‖x‖ per column): :func:`backward_errors` and the column norms of X, for
    :func:`conditions` to reuse."""
    M, P, Q = _row_sliceable(ops)
    X = np.ascontiguousarray(X)  # each block's Q[r] @ X would otherwise copy the whole X
    MX, PX = M @ X, P @ X
    s = np.asarray(s)
    rn = None
    for r in _row_blocks(X):  # Q X and the residual one block of rows at a time
        rn = _add_colnorm(rn, colnorm(_residual(MX[r], PX[r], Q[r] @ X, s)))
    xn = colnorm(X)
    return _eta(rn, weights(s, norms), xn), MX, PX, xn


def _eta(rn, w, xn):
    """η from the residual norms, the weights w(s) and ‖x‖ (x = 0: no eigenvector, η = ∞)."""
    return np.where(xn > 0, _ratio(rn, w * xn), np.inf)


def _kappa(den, s, w, xn, X, Yc):
    """κ from the summed yᴴ(2sM + P)x (``den``), the weights, ‖x‖ and ‖y‖ (that of X where
    Yc is X)."""
    num = w * xn * (xn if Yc is X else colnorm(Yc))
    den = np.abs(den)
    return fixed_zero(_unreverse(_ratio(num, den), s, den), w)


def conditions(s, X, Yc, MX, PX, norms, xn=None):
    """κ per pair, with ``Yc`` the conjugated left vectors (yᴴ = Ycᵀ) and MX, PX the products;
    ``xn``: the column norms of X if already formed (those of Yc too where Yc is X)."""
    s = np.asarray(s)
    xn = colnorm(X) if xn is None else xn
    den = np.zeros(s.size, complex)
    for r in _row_blocks(X):
        den += np.einsum("ij,ij->j", Yc[r], _derivative(MX[r], PX[r], s))
    return _kappa(den, s, weights(s, norms), xn, X, Yc)


def eta_kappa(ops, s, X, Yc, norms):
    """(η, κ, ‖x‖ per column): :func:`backward_errors_norms` then :func:`conditions` in one
    pass over blocks of ``FUSED_BLOCK`` entries, so that M X and P X are never formed whole (at
    10⁶ rows the first touch of those two n × k arrays cost more than the products); with
    blocks of the same rows, bitwise their result.  ``Yc``: conjugated left vectors, or X."""
    M, P, Q = _row_sliceable(ops)
    same = Yc is X
    X = np.ascontiguousarray(X)
    Yc = X if same else Yc
    s = np.asarray(s)
    rn, den = None, np.zeros(s.size, complex)
    for r in _row_blocks(X, FUSED_BLOCK):
        MX, PX = M[r] @ X, P[r] @ X
        rn = _add_colnorm(rn, colnorm(_residual(MX, PX, Q[r] @ X, s)))
        den += np.einsum("ij,ij->j", Yc[r], _derivative(MX, PX, s))
    xn = colnorm(X)
    w = weights(s, norms)
    return _eta(rn, w, xn), _kappa(den, s, w, xn, X, Yc), xn


def fixed_zero(kappa, w):
    """κ = 0 where w(s) = 0: s = 0 with Q = 0 (or M = P = Q = 0) stays an eigenvalue of every
    perturbation of the normwise class (‖ΔQ‖ ≤ η‖Q‖ = 0), whatever yᴴ(2sM + P)x (0 at a
    defective zero: the ratio 0/0), so its condition number is 0, not ∞."""
    return np.where(w == 0, 0.0, kappa)


def componentwise(ops, s, X, Yc, *, abs_ops=None):
    """(η_c, κ_c) per pair: componentwise backward errors and condition numbers (module doc).

    ops : (M, P, Q), dense or sparse; abs_ops : their entrywise absolute values if already formed.
    Yc : conjugated left vectors (yᴴ = Ycᵀ), or None for y = x̄ (symmetric M, P, Q).
    """
    M, P, Q = ops = _row_sliceable(ops)
    aM, aP, aQ = _row_sliceable(abs_ops if abs_ops is not None else tuple(abs(A) for A in ops))
    s = np.asarray(s)
    same = Yc is None or Yc is X
    X = np.ascontiguousarray(X)  # each block's products would otherwise copy the whole X
    Yc = X if same else Yc
    t, big = reversal(s)
    a = np.abs(t)
    # the coefficients of |M|, |P|, |Q| in |s|²|M| + |s||P| + |Q| (or its reversal): a factor 1
    # where a term has none (exact, so the sums are those of the two branches written out)
    cM, cQ = np.where(big, 1.0, a * a), np.where(big, a * a, 1.0)
    AX = np.abs(X)
    eta_c = np.zeros(s.size)
    num = np.zeros(s.size)
    den = np.zeros(s.size, complex)
    for r in _row_blocks(X):  # the products, residual and |·| bound one block of rows at a time
        MX, PX = M[r] @ X, P[r] @ X
        R = np.abs(_residual(MX, PX, Q[r] @ X, s))
        D = aM[r] @ AX  # each product once, both forms
        D *= cM
        D += (aP[r] @ AX) * a
        D += (aQ[r] @ AX) * cQ
        eta_c = np.maximum(eta_c, np.max(_ratio(R, D), axis=0, initial=0.0))
        num += np.einsum("ij,ij->j", AX[r] if same else np.abs(Yc[r]), D)
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
    return better_half_norms(ops, s, X1, X2, norms)[:5]


def better_half_norms(ops, s, X1, X2, norms, own=False):
    """:func:`better_half` and the column norms of X; ``own``: X1 and X2 may be overwritten."""
    dtype = np.result_type(X1, X2)
    same = X2 is X1

    def unit(X):
        inplace = own and X.dtype == dtype and X.flags.c_contiguous
        return np.ascontiguousarray(unit_columns(X, inplace=inplace), dtype=dtype)

    X1 = unit(X1)
    if same:  # one vector per pair (a path without companion halves)
        eta, MX, PX, xn = backward_errors_norms(ops, s, X1, norms)
        return X1, eta, MX, PX, 0, xn
    X2 = unit(X2)
    if X1.size > ROW_BLOCK:  # large: η of both halves first, products of the kept one only
        e1, e2 = (backward_errors(ops, s, X, norms)[0] for X in (X1, X2))
        take2 = e2 < e1
        X1[:, take2] = X2[:, take2]
        del X2
        eta, MX, PX, xn = backward_errors_norms(ops, s, X1, norms)
        return X1, eta, MX, PX, int(np.sum(take2)), xn
    e1, MX1, PX1 = backward_errors(ops, s, X1, norms)
    e2, MX2, PX2 = backward_errors(ops, s, X2, norms)
    take2 = e2 < e1
    for a, b in ((X1, X2), (MX1, MX2), (PX1, PX2)):
        a[:, take2] = b[:, take2]
    return X1, np.minimum(e1, e2), MX1, PX1, int(np.sum(take2)), colnorm(X1)


def expand_pairs(Xu, pos, partner, rows=512, divide=None):
    """Columns Xu[:, pos], conjugated where ``partner``: every eigenpair of a real problem from
    one measured column per conjugate pair.  A block of rows at a time, so that the gather and
    the sign flip stay in cache (10⁶ rows, 40 columns: 0.45 s, against 1.2–2 s for one gather
    and a conjugated copy of the whole array), and few pages at a time: gathering 21 of
    1.1·10⁶ × 23 column-major vectors in a partial-slepc process, blocks of 8192 rows took
    0.84–0.89 s a call and blocks of 512 rows 0.11 s (in a fresh process both 0.12 s; from
    the mapped file the search now gathers from, both 0.11 s after a first call of 0.75 s).
    ``divide``: per column of Xu, divisors applied on the way ((Xu / divide)[:, pos] with no
    intermediate copy, e.g. :func:`plain_norms`)."""
    pos = np.asarray(pos, int)
    out = np.empty((Xu.shape[0], len(pos)), np.result_type(Xu), order="C")
    flip = np.flatnonzero(partner) if np.iscomplexobj(out) else np.zeros(0, int)
    d = None if divide is None else np.asarray(divide)[pos]
    direct = Xu.flags.f_contiguous and not Xu.flags.c_contiguous  # take() is fast from there
    for r in range(0, Xu.shape[0], rows):
        if direct:  # gathered straight into the output (no temporary block)
            blk = out[r:r + rows]
            np.take(Xu[r:r + rows], pos, axis=1, out=blk)
        else:
            blk = Xu[r:r + rows][:, pos]
        if d is not None:
            blk /= d
        if flip.size:
            blk.imag[:, flip] *= -1.0
        if not direct:
            out[r:r + rows] = blk
    return out


LD = np.longdouble
EPS_LD = float(np.finfo(np.longdouble).eps)
